// What the host sends, frame by frame: the asynchronous script (poses, HAT/HOT and LOS
// requests, IG modes, other traffic) and the synchronous host that sends only when a Start of Frame arrives.
#include <cmath>
#include <cstdio>

#include <CigiHatHotReqV3_2.h>
#include <CigiLosSegReqV3_2.h>
#include <CigiLosVectReqV3_2.h>

#include "host.h"

namespace {

// Request IDs: one-shot geodetic HAT/HOT 100 + 3i + type, entity-relative 200 + 3j + type,
// periodic 300 + type, LOS segments 400 + 2i (+1 extended), vectors 500 + 2j (+1 extended),
// the synchronous host's 1000 + n.
constexpr int kHotGeodetic = 100, kHotEntity = 200, kHotPeriodic = 300;
constexpr int kLosSegment = 400, kLosVector = 500, kSyncHot = 1000;

const char* const kTypeNames[] = {"hat", "hot", "ext"};

void hot_request(Link& link, CigiOutgoingMsg& out, int id, int type, bool entity,
                 const std::array<double, 3>& p, int period) {
  CigiHatHotReqV3_2 r;
  r.SetHatHotID(static_cast<Cigi_uint16>(id));
  r.SetReqType(static_cast<CigiBaseHatHotReq::ReqTypeGrp>(type));
  r.SetSrcCoordSys(entity ? CigiBaseHatHotReq::Entity : CigiBaseHatHotReq::Geodetic);
  // CIGI 3.0/3.1 have no update period: the CCL packs those versions without it.
  r.SetUpdatePeriod(static_cast<Cigi_uint8>(period));
  r.SetEntityID(0);
  if (entity) {
    r.SetXoff(p[0]);
    r.SetYoff(p[1]);
    r.SetZoff(p[2]);
  } else {
    r.SetLat(p[0]);
    r.SetLon(p[1]);
    r.SetAlt(p[2]);
  }
  out << r;
  link.requested(id);
  Json j;
  j.str("sent", "hot_req")
      .integer("id", id)
      .integer("n", link.counts.sent)
      .integer("rx", link.counts.received)
      .str("type", kTypeNames[type])
      .str("coord", entity ? "entity" : "geodetic");
  if (entity) {
    j.num("x", p[0]).num("y", p[1]).num("z", p[2]);
  } else {
    j.num("lat", p[0]).num("lon", p[1]).num("alt", p[2]);
  }
  j.integer("period", period).print();
}

void los_segment(Link& link, CigiOutgoingMsg& out, int id, bool extended,
                 const std::array<double, 6>& s) {
  CigiLosSegReqV3_2 r;
  r.SetLosID(static_cast<Cigi_uint16>(id));
  r.SetReqType(extended ? CigiBaseLosSegReq::Extended : CigiBaseLosSegReq::Basic);
  r.SetSrcCoordSys(CigiBaseLosSegReq::Geodetic);
  r.SetDstCoordSys(CigiBaseLosSegReq::Geodetic);
  r.SetResponseCoordSys(CigiBaseLosSegReq::Geodetic);
  r.SetAlphaThresh(0);
  r.SetEntityID(0);
  r.SetSrcLat(s[0]);
  r.SetSrcLon(s[1]);
  r.SetSrcAlt(s[2]);
  r.SetDstLat(s[3]);
  r.SetDstLon(s[4]);
  r.SetDstAlt(s[5]);
  // Every material: a cleared bit tells the IG to ignore that material.
  r.SetMask(0xFFFFFFFFu);
  r.SetUpdatePeriod(0);
  r.SetDestEntityIDValid(false);
  out << r;
  link.requested(id);
  Json()
      .str("sent", "los_seg")
      .integer("id", id)
      .integer("n", link.counts.sent)
      .integer("rx", link.counts.received)
      .boolean("extended", extended)
      .num("lat", s[0])
      .num("lon", s[1])
      .num("alt", s[2])
      .num("lat2", s[3])
      .num("lon2", s[4])
      .num("alt2", s[5])
      .print();
}

void los_vector(Link& link, CigiOutgoingMsg& out, int id, bool extended,
                const std::array<double, 7>& v) {
  CigiLosVectReqV3_2 r;
  r.SetLosID(static_cast<Cigi_uint16>(id));
  r.SetReqType(extended ? CigiBaseLosVectReq::Extended : CigiBaseLosVectReq::Basic);
  r.SetSrcCoordSys(CigiBaseLosVectReq::Geodetic);
  r.SetResponseCoordSys(CigiBaseLosVectReq::Geodetic);
  r.SetAlphaThresh(0);
  r.SetEntityID(0);
  r.SetSrcLat(v[0]);
  r.SetSrcLon(v[1]);
  r.SetSrcAlt(v[2]);
  r.SetVectAz(static_cast<float>(v[3]));
  r.SetVectEl(static_cast<float>(v[4]));
  r.SetMinRange(static_cast<float>(v[5]));
  r.SetMaxRange(static_cast<float>(v[6]));
  r.SetMask(0xFFFFFFFFu);
  r.SetUpdatePeriod(0);
  out << r;
  link.requested(id);
  // The wire carries the angles and ranges as f32: print those values, not the arguments.
  Json()
      .str("sent", "los_vect")
      .integer("id", id)
      .integer("n", link.counts.sent)
      .integer("rx", link.counts.received)
      .boolean("extended", extended)
      .num("lat", v[0])
      .num("lon", v[1])
      .num("alt", v[2])
      .num("az", r.GetVectAz())
      .num("el", r.GetVectEl())
      .num("min", r.GetMinRange())
      .num("max", r.GetMaxRange())
      .print();
}

// The requests due at host frame k (counted from the first Start of Frame).
void requests(Link& link, CigiOutgoingMsg& out, long k) {
  const Options& o = link.opt;
  if (k == o.request_frame) {
    for (size_t i = 0; i < o.at.size(); ++i)
      for (int t = 0; t < 3; ++t)
        hot_request(link, out, kHotGeodetic + 3 * static_cast<int>(i) + t, t, false,
                    {o.at[i].lat, o.at[i].lon, o.at[i].alt}, 0);
    for (size_t i = 0; i < o.entity_at.size(); ++i)
      for (int t = 0; t < 3; ++t)
        hot_request(link, out, kHotEntity + 3 * static_cast<int>(i) + t, t, true,
                    o.entity_at[i], 0);
    for (size_t i = 0; i < o.segments.size(); ++i)
      for (int x = 0; x < 2; ++x)
        los_segment(link, out, kLosSegment + 2 * static_cast<int>(i) + x, x == 1,
                    o.segments[i]);
    for (size_t i = 0; i < o.vectors.size(); ++i)
      for (int x = 0; x < 2; ++x)
        los_vector(link, out, kLosVector + 2 * static_cast<int>(i) + x, x == 1, o.vectors[i]);
  }
  // Periodic requests exist from CIGI 3.2 on; the same ID with period 0 ends them.
  if (o.period > 0 && o.minor >= 2 && !o.at.empty()) {
    const bool start = k == o.request_frame + 2;
    const bool cancel = !start && !link.periodic_cancelled && link.periodic_sent_at_sof >= 0 &&
                        link.counts.sof - link.periodic_sent_at_sof >= o.cancel_after;
    if (start) link.periodic_sent_at_sof = link.counts.sof;
    if (cancel) link.periodic_cancelled = true;
    if (start || cancel)
      for (int t = 0; t < 3; ++t)
        hot_request(link, out, kHotPeriodic + t, t, false, {o.at[0].lat, o.at[0].lon, o.at[0].alt},
                    start ? o.period : 0);
  }
}

// The ownship flies on: the per-message steps of --move, yaw kept in [0, 360).
void move(Link& link) {
  const Options& o = link.opt;
  CigiEntityCtrlV3_3& e = link.ownship;
  e.SetLat(e.GetLat() + o.dlat);
  e.SetLon(e.GetLon() + o.dlon);
  e.SetAlt(e.GetAlt() + o.dalt);
  float yaw = std::fmod(e.GetYaw() + o.dyaw, 360.0f);
  e.SetYaw(yaw < 0 ? yaw + 360.0f : yaw);
}

int finish(Link& link, const std::string& why) {
  link.summary(why);
  if (why == "no start of frame") {
    std::fprintf(stderr, "cigi-host: no Start of Frame from %s:%d within %.1f s\n",
                 link.opt.ig_host.c_str(), link.opt.ig_port, link.opt.wait_s);
    return 1;
  }
  return 0;
}

}  // namespace

int run_async(Link& link) {
  const Options& o = link.opt;
  const double period = 1.0 / o.rate_hz;
  double next = link.now();
  std::string why;
  while ((why = link.stop_reason()).empty()) {
    const long k = link.frames_since_first_sof();
    // The mode windows count the IG's Start of Frames, not the host's messages: a slow IG
    // still renders frames in each of them.
    const long long sofs = link.counts.sof;
    const bool reset = o.command == "modes" && sofs >= o.operate_frames &&
                       sofs < o.operate_frames + o.reset_frames;
    CigiOutgoingMsg& out = link.begin(reset ? CigiBaseIGCtrl::Reset : CigiBaseIGCtrl::Operate);
    if (k >= 0) requests(link, out, k);
    if (o.command == "traffic") traffic(link, out, k);
    link.send();
    move(link);
    next += period;
    const double left = next - link.now();
    link.receive(left > 0 ? left : 0, false);
  }
  return finish(link, why);
}

int run_sync(Link& link) {
  // As the CCL's MiniHost: send, wait (at most 1 s) for the IG's Start of Frame, send again.
  // Each message asks the height of terrain under the ownship, one-shot: in lock-step the
  // answer must come in the very next IG message.
  std::string why;
  auto send = [&] {
    CigiOutgoingMsg& out = link.begin(CigiBaseIGCtrl::Operate);
    const int id = kSyncHot + static_cast<int>(link.counts.sent % 30000);
    hot_request(link, out, id, 1, false,
                {link.ownship.GetLat(), link.ownship.GetLon(), link.ownship.GetAlt()}, 0);
    link.send();
    move(link);
  };
  send();
  while ((why = link.stop_reason()).empty()) {
    const long long sof_before = link.counts.sof;
    link.receive(1.0, true);
    if (link.counts.sof == sof_before) {
      link.counts.timeouts++;
      if (!link.stop_reason().empty()) break;
    }
    send();
  }
  return finish(link, why.empty() ? link.stop_reason() : why);
}
