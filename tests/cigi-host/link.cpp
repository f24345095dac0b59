// The host's side of the wire: a UDP socket, the CCL host session that builds every outgoing
// message and decodes every incoming one, and the printers of what was sent and received.
#include "host.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <stdexcept>

#include <CigiExceptions.h>
#include <CigiHatHotRespV3.h>
#include <CigiHatHotRespV3_2.h>
#include <CigiHatHotXRespV3.h>
#include <CigiHatHotXRespV3_2.h>
#include <CigiLosRespV3.h>
#include <CigiLosRespV3_2.h>
#include <CigiLosXRespV3.h>
#include <CigiLosXRespV3_2.h>
#include <CigiSOFV3.h>
#include <CigiSOFV3_2.h>

// ---- JSON lines ----

void Json::key(const char* k) {
  body_ += body_.empty() ? "{" : ",";
  body_ += "\"";
  body_ += k;
  body_ += "\":";
}

Json& Json::str(const char* k, const std::string& v) {
  key(k);
  body_ += "\"";
  for (char c : v) {
    if (c == '"' || c == '\\') {
      body_ += '\\';
      body_ += c;
    } else if (static_cast<unsigned char>(c) < 0x20) {
      body_ += ' ';
    } else {
      body_ += c;
    }
  }
  body_ += "\"";
  return *this;
}

Json& Json::num(const char* k, double v) {
  key(k);
  if (!std::isfinite(v)) {
    body_ += "null";  // JSON has no NaN or infinity
    return *this;
  }
  char b[40];
  std::snprintf(b, sizeof b, "%.17g", v);
  body_ += b;
  return *this;
}

Json& Json::integer(const char* k, long long v) {
  key(k);
  body_ += std::to_string(v);
  return *this;
}

Json& Json::boolean(const char* k, bool v) {
  key(k);
  body_ += v ? "true" : "false";
  return *this;
}

Json& Json::raw(const char* k, const std::string& json) {
  key(k);
  body_ += json;
  return *this;
}

bool Json::quiet = false;

void Json::print(bool always) const {
  if (quiet && !always) return;
  std::fputs(body_.empty() ? "{}" : body_.c_str(), stdout);
  std::fputs(body_.empty() ? "\n" : "}\n", stdout);
  std::fflush(stdout);
}

std::string json_array(const std::vector<long long>& v) {
  std::string s = "[";
  for (size_t i = 0; i < v.size(); ++i) s += (i ? "," : "") + std::to_string(v[i]);
  return s + "]";
}

std::string json_counts(const std::map<long long, long long>& m) {
  std::string s = "{";
  bool first = true;
  for (auto& [k, v] : m) {
    s += (first ? "\"" : ",\"") + std::to_string(k) + "\":" + std::to_string(v);
    first = false;
  }
  return s + "}";
}

// ---- packet printers (CCL event processors) ----

namespace {

enum class Kind { Sof, Response, Other };

// Hands each packet the CCL decoded to the link, by kind.
class Printer : public CigiBaseEventProcessor {
 public:
  Printer(Link* l, Kind k) : link_(l), kind_(k) {}
  void OnPacketReceived(CigiBasePacket* p) override {
    switch (kind_) {
      case Kind::Sof: link_->on_sof(p); break;
      case Kind::Response: link_->on_response(p); break;
      case Kind::Other: link_->on_other(p); break;
    }
  }

 private:
  Link* link_;
  Kind kind_;
};

const char* mode_name(int m) {
  switch (m) {
    case 0: return "standby";  // also Reset: the same value on the wire
    case 1: return "operate";
    case 2: return "debug";
    case 3: return "offline";
    default: return "?";
  }
}

}  // namespace

// ---- the link ----

Link::Link(const Options& o) : opt(o), in_(65536) {
  t0_ = now();
  sock_ = socket(AF_INET, SOCK_DGRAM, 0);
  if (sock_ < 0) throw std::runtime_error(std::string("socket: ") + std::strerror(errno));
  sockaddr_in local{};
  local.sin_family = AF_INET;
  local.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (bind(sock_, reinterpret_cast<sockaddr*>(&local), sizeof local) != 0)
    throw std::runtime_error(std::string("bind: ") + std::strerror(errno));
  sockaddr_in ig{};
  ig.sin_family = AF_INET;
  ig.sin_port = htons(static_cast<uint16_t>(o.ig_port));
  if (inet_pton(AF_INET, o.ig_host.c_str(), &ig.sin_addr) != 1)
    throw std::runtime_error("--ig: not an IPv4 address: " + o.ig_host);
  // Connected: send() goes to the IG, recv() hears only it (aerie answers the sender).
  if (connect(sock_, reinterpret_cast<sockaddr*>(&ig), sizeof ig) != 0)
    throw std::runtime_error(std::string("connect: ") + std::strerror(errno));

  // As MiniHost: one incoming buffer of 32 KiB, two outgoing.
  session_ = new CigiHostSession(1, 32768, 2, 32768);
  session_->SetCigiVersion(3, o.minor);
  session_->SetSynchronous(o.command == "sync");
  CigiIncomingMsg& in = session_->GetIncomingMsgMgr();
  in.SetReaderCigiVersion(3, o.minor);
  in.UsingIteration(false);
  auto add = [&](Kind k) {
    processors_.push_back(new Printer(this, k));
    return processors_.back();
  };
  in.RegisterEventProcessor(CIGI_SOF_PACKET_ID_V3, add(Kind::Sof));
  CigiBaseEventProcessor* resp = add(Kind::Response);
  for (int id : {CIGI_HAT_HOT_RESP_PACKET_ID_V3, CIGI_HAT_HOT_XRESP_PACKET_ID_V3,
                 CIGI_LOS_RESP_PACKET_ID_V3, CIGI_LOS_XRESP_PACKET_ID_V3})
    in.RegisterEventProcessor(id, resp);
  CigiBaseEventProcessor* other = add(Kind::Other);
  in.RegisterUnhandledPacketEvent(other);
  in.RegisterUnrecognizedPacketEvent(other);

  igc_.SetDatabaseID(0);
  igc_.SetTimeStampValid(true);
  ownship.SetEntityID(0);
  ownship.SetEntityType(0);
  ownship.SetEntityState(CigiBaseEntityCtrl::Active);
  ownship.SetLat(o.start.lat);
  ownship.SetLon(o.start.lon);
  ownship.SetAlt(o.start.alt);
  ownship.SetYaw(o.yaw);
  ownship.SetPitch(o.pitch);
  ownship.SetRoll(o.roll);
  session_->GetOutgoingMsgMgr().BeginMsg();
}

Link::~Link() {
  delete session_;
  for (auto* p : processors_) delete p;
  if (sock_ >= 0) close(sock_);
}

double Link::now() const {
  using namespace std::chrono;
  return duration<double>(steady_clock::now().time_since_epoch()).count() - t0_;
}

CigiOutgoingMsg& Link::begin(CigiBaseIGCtrl::IGModeGrp mode) {
  CigiOutgoingMsg& out = session_->GetOutgoingMsgMgr();
  igc_.SetIGMode(mode);
  // Timestamp in 10 µs ticks: the message's scheduled time at the host's rate.
  igc_.SetTimeStamp(static_cast<Cigi_uint32>(std::llround(counts.sent * 1e5 / opt.rate_hz)));
  out << igc_;
  out << ownship;
  return out;
}

void Link::send() {
  CigiOutgoingMsg& out = session_->GetOutgoingMsgMgr();
  Cigi_uint8* buf = nullptr;
  int len = 0;
  out.PackageMsg(&buf, len);
  if (buf == nullptr) throw std::runtime_error("CCL: PackageMsg returned no message");
  // The CCL fills the host frame counter (and, 3.2+, the last IG frame received).
  out.UpdateIGCtrl(buf, last_sof_.empty() ? nullptr : last_sof_.data());
  // What actually went out, read back from the packaged bytes (host byte order).
  const int igc_size = buf[1];
  const int minor = igc_size >= 24 ? (buf[4] >> 4) & 0x0f : 0;
  Cigi_uint32 host_frame = 0;
  std::memcpy(&host_frame, buf + 8, 4);
  const int mode = buf[4] & 0x03;
  ssize_t n = ::send(sock_, buf, static_cast<size_t>(len), 0);
  out.FreeMsg();
  Json()
      .str("sent", "msg")
      .integer("n", counts.sent)
      .integer("host_frame", host_frame)
      .integer("k", frames_since_sof_)
      .str("mode", mode_name(mode))
      .integer("igc_size", igc_size)
      .integer("major", buf[2])
      .integer("minor", minor)
      .integer("bytes", len)
      .boolean("delivered", n == len)
      .num("lat", ownship.GetLat())
      .num("lon", ownship.GetLon())
      .num("alt", ownship.GetAlt())
      .num("yaw", ownship.GetYaw())
      .num("pitch", ownship.GetPitch())
      .num("roll", ownship.GetRoll())
      .num("t", now())
      .print();
  counts.sent++;
  counts.sent_igc_sizes[igc_size]++;
  counts.sent_minors[minor]++;
  if (frames_since_sof_ >= 0) frames_since_sof_++;
}

int Link::receive(double timeout_s, bool until_first) {
  int messages = 0;
  double deadline = now() + timeout_s;
  for (;;) {
    double left = deadline - now();
    pollfd p{sock_, POLLIN, 0};
    int wait_ms = left > 0 ? static_cast<int>(std::ceil(left * 1000)) : 0;
    if (poll(&p, 1, wait_ms) <= 0) break;
    ssize_t n = recv(sock_, in_.data(), in_.size(), 0);
    if (n <= 0) {
      // ECONNREFUSED: the IG's port is closed (not started yet, or finished).
      if (left <= 0) break;
      continue;
    }
    in_len_ = static_cast<size_t>(n);
    counts.received++;
    messages++;
    try {
      session_->GetIncomingMsgMgr().ProcessIncomingMsg(in_.data(), static_cast<int>(n));
    } catch (CigiException& e) {
      counts.exceptions++;
      Json().str("recv", "error").integer("msg", counts.received).str("what", e.what()).print();
    }
    if (until_first && messages > 0) break;
  }
  return messages;
}

void Link::requested(int id) { pending_[id] = counts.received; }

void Link::latency(int id) {
  auto it = pending_.find(id);
  if (it == pending_.end()) return;
  // Only the first answer after the request is timed (periodic requests keep answering).
  counts.latency_msgs[counts.received - it->second]++;
  pending_.erase(it);
}

void Link::on_sof(CigiBasePacket* p) {
  auto* base = static_cast<CigiBaseSOF*>(p);
  const unsigned char* raw = in_.data();
  Json j;
  j.str("recv", "sof")
      .integer("msg", counts.received)
      .integer("size", raw[1])
      .integer("major", raw[2]);
  // The minor version is in byte 5's upper nibble from 3.2 on (16-byte SOFs have none).
  if (raw[1] >= 24) j.integer("minor", (raw[5] >> 4) & 0x0f);
  j.integer("ig_frame", base->GetFrameCntr())
      .str("mode", mode_name(base->GetIGMode()))
      .integer("database", base->GetDatabaseID())
      .integer("ig_status", base->GetIGStatus())
      .boolean("swapped", base->GetSwap());
  if (auto* s = dynamic_cast<CigiSOFV3_2*>(p)) {
    j.integer("last_host_frame", s->GetLastRcvdHostFrame())
        .integer("timestamp", s->GetTimeStamp())
        .boolean("timestamp_valid", s->GetTimeStampValid());
  } else if (auto* s3 = dynamic_cast<CigiSOFV3*>(p)) {
    j.integer("timestamp", s3->GetTimeStamp()).boolean("timestamp_valid", s3->GetTimeStampValid());
  }
  j.num("t", now()).print();
  counts.sof++;
  counts.sof_sizes[raw[1]]++;
  counts.sof_minors[raw[1] >= 24 ? (raw[5] >> 4) & 0x0f : 0]++;
  if (base->GetSwap()) counts.sof_swapped++;
  const long long f = base->GetFrameCntr();
  if (counts.first_ig_frame < 0) counts.first_ig_frame = f;
  if (counts.last_ig_frame >= 0) counts.ig_frame_steps[f - counts.last_ig_frame]++;
  counts.last_ig_frame = f;
  ig_frame_ = static_cast<long>(f);
  last_sof_.assign(in_.begin(), in_.begin() + static_cast<long>(in_len_));
  last_sof_at_ = now();
  if (frames_since_sof_ < 0) frames_since_sof_ = 0;
}

void Link::on_response(CigiBasePacket* p) {
  Json j;
  const int id = p->GetPacketID();
  auto common = [&](const char* what, int req_id, bool valid) {
    j.str("recv", what)
        .integer("msg", counts.received)
        .integer("ig_frame", ig_frame_)
        .integer("id", req_id)
        .boolean("valid", valid);
    auto it = pending_.find(req_id);
    if (it != pending_.end()) j.integer("latency_msgs", counts.received - it->second);
    latency(req_id);
  };
  if (id == CIGI_HAT_HOT_RESP_PACKET_ID_V3) {
    counts.hot++;
    auto* b = static_cast<CigiBaseHatHotResp*>(p);
    common("hot", b->GetHatHotID(), b->GetValid());
    if (auto* r = dynamic_cast<CigiHatHotRespV3_2*>(p)) {
      bool hat = r->GetReqType() == CigiBaseHatHotResp::HAT;
      j.str("type", hat ? "hat" : "hot")
          .num("height", hat ? r->GetHat() : r->GetHot())
          .integer("host_frame_lsn", r->GetHostFrame());
    } else if (auto* r3 = dynamic_cast<CigiHatHotRespV3*>(p)) {
      bool hat = r3->GetReqType() == CigiBaseHatHotResp::HAT;
      j.str("type", hat ? "hat" : "hot").num("height", hat ? r3->GetHat() : r3->GetHot());
    }
  } else if (id == CIGI_HAT_HOT_XRESP_PACKET_ID_V3) {
    counts.hotx++;
    auto* b = static_cast<CigiBaseHatHotResp*>(p);
    common("hotx", b->GetHatHotID(), b->GetValid());
    if (auto* r = dynamic_cast<CigiHatHotXRespV3_2*>(p)) {
      j.num("hat", r->GetHat())
          .num("hot", r->GetHot())
          .integer("material", r->GetMaterial())
          .num("norm_az", r->GetNormAz())
          .num("norm_el", r->GetNormEl())
          .integer("host_frame_lsn", r->GetHostFrame());
    } else if (auto* r3 = dynamic_cast<CigiHatHotXRespV3*>(p)) {
      j.num("hat", r3->GetHat())
          .num("hot", r3->GetHot())
          .integer("material", r3->GetMaterial())
          .num("norm_az", r3->GetNormAz())
          .num("norm_el", r3->GetNormEl());
    }
  } else if (id == CIGI_LOS_RESP_PACKET_ID_V3) {
    counts.los++;
    auto* b = static_cast<CigiBaseLosResp*>(p);
    common("los", b->GetLosID(), b->GetValid());
    j.boolean("visible", b->GetVisible()).num("range", b->GetRange());
    if (auto* r = dynamic_cast<CigiLosRespV3_2*>(p)) {
      j.boolean("entity_id_valid", r->GetEntityIDValid())
          .integer("entity_id", r->GetEntityID())
          .integer("count", r->GetRespCount())
          .integer("host_frame_lsn", r->GetHostFrame());
    } else if (auto* r3 = dynamic_cast<CigiLosRespV3*>(p)) {
      j.boolean("entity_id_valid", r3->GetEntityIDValid())
          .integer("entity_id", r3->GetEntityID())
          .integer("count", r3->GetRespCount());
    }
  } else if (id == CIGI_LOS_XRESP_PACKET_ID_V3) {
    counts.losx++;
    auto* b = static_cast<CigiBaseLosResp*>(p);
    common("losx", b->GetLosID(), b->GetValid());
    j.boolean("visible", b->GetVisible())
        .num("range", b->GetRange())
        .num("lat", b->GetLatitude())
        .num("lon", b->GetLongitude())
        .num("alt", b->GetAltitude());
    if (auto* r = dynamic_cast<CigiLosXRespV3_2*>(p)) {
      j.boolean("range_valid", r->GetRangeValid())
          .boolean("entity_id_valid", r->GetEntityIDValid())
          .integer("count", r->GetRespCount())
          .integer("material", r->GetMaterial())
          .num("norm_az", r->GetNormalAz())
          .num("norm_el", r->GetNormalEl())
          .integer("alpha", r->GetAlpha())
          .integer("host_frame_lsn", r->GetHostFrame());
    } else if (auto* r3 = dynamic_cast<CigiLosXRespV3*>(p)) {
      j.boolean("range_valid", r3->GetRangeValid())
          .boolean("entity_id_valid", r3->GetEntityIDValid())
          .integer("count", r3->GetRespCount())
          .integer("material", r3->GetMaterial())
          .num("norm_az", r3->GetNormalAz())
          .num("norm_el", r3->GetNormalEl())
          .integer("alpha", r3->GetAlpha());
    }
  }
  j.num("t", now()).print();
}

void Link::on_other(CigiBasePacket* p) {
  counts.other_packets[p ? p->GetPacketID() : -1]++;
}

std::string Link::stop_reason() const {
  double t = now();
  if (t > opt.seconds) return "time limit";
  if (!got_sof() && t > opt.wait_s) return "no start of frame";
  if (got_sof() && t - last_sof_at_ > opt.idle_exit_s) return "ig silent";
  return "";
}

void Link::summary(const std::string& why) const {
  const uint16_t one = 1;
  unsigned char first = 0;
  std::memcpy(&first, &one, 1);
  Json()
      .str("summary", opt.command)
      .str("stopped", why)
      .str("version", "3." + std::to_string(opt.minor))
      .str("byte_order", first ? "little" : "big")
      .integer("sent", counts.sent)
      .integer("received", counts.received)
      .integer("sof", counts.sof)
      .integer("sof_swapped", counts.sof_swapped)
      .integer("exceptions", counts.exceptions)
      .integer("hot", counts.hot)
      .integer("hotx", counts.hotx)
      .integer("los", counts.los)
      .integer("losx", counts.losx)
      .raw("sof_sizes", json_counts(counts.sof_sizes))
      .raw("sof_minors", json_counts(counts.sof_minors))
      .raw("sent_igc_sizes", json_counts(counts.sent_igc_sizes))
      .raw("sent_minors", json_counts(counts.sent_minors))
      .raw("other_packets", json_counts(counts.other_packets))
      .raw("latency_msgs", json_counts(counts.latency_msgs))
      .raw("ig_frame_steps", json_counts(counts.ig_frame_steps))
      .integer("first_ig_frame", counts.first_ig_frame)
      .integer("last_ig_frame", counts.last_ig_frame)
      .integer("timeouts", counts.timeouts)
      .integer("unanswered", static_cast<long long>(pending_.size()))
      .num("t", now())
      .print(true);
}
