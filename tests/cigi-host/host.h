// A CIGI host written with the CIGI Class Library (CCL) host API, for aerie's end-to-end tests:
// it drives `aerie run --headless` the way a simulator host would and prints, one JSON object
// per line on stdout, everything it sent and everything it received (decoded by the CCL's own
// packet classes). See README.md in this folder.
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include <CigiBaseEventProcessor.h>
#include <CigiBaseIGCtrl.h>
#include <CigiEntityCtrlV3_3.h>
#include <CigiHostSession.h>
#include <CigiIGCtrlV3_3.h>

// A JSON object on one line, built field by field (numbers keep every digit: %.17g).
class Json {
 public:
  Json& str(const char* key, const std::string& value);
  Json& num(const char* key, double value);
  Json& integer(const char* key, long long value);
  Json& boolean(const char* key, bool value);
  // A pre-formatted JSON value (an array or object).
  Json& raw(const char* key, const std::string& json);
  // Prints the object and a newline to stdout and flushes (a killed host loses nothing);
  // when `quiet` is set only lines printed with `always` (summaries) are.
  void print(bool always = false) const;
  static bool quiet;

 private:
  void key(const char* k);
  std::string body_;
};

// JSON array of integers.
std::string json_array(const std::vector<long long>& v);
// JSON object {"k": v, ...} of integer counts.
std::string json_counts(const std::map<long long, long long>& m);

struct Geo {
  double lat = 0, lon = 0, alt = 0;
};

// The command line: what to send, to whom, for how long.
struct Options {
  std::string command;
  std::string ig_host = "127.0.0.1";
  int ig_port = 0;
  int minor = 3;             // CIGI 3.<minor>
  double rate_hz = 60;       // asynchronous hosts: messages per second
  double seconds = 60;       // stop after this long whatever happens
  double wait_s = 60;        // fail when no Start of Frame arrives within this
  double idle_exit_s = 2;    // stop when the IG has been silent this long after answering
  Geo start{47.3, 11.4, 3000};
  float yaw = 0, pitch = 0, roll = 0;
  // poses: added per message sent.
  double dlat = 0, dlon = 0, dalt = 0;
  float dyaw = 0;
  // hot: geodetic points and ownship-relative offsets (x forward, y right, z down, metres).
  std::vector<Geo> at;
  std::vector<std::array<double, 3>> entity_at;
  int period = 0;        // > 0: also periodic requests at the first point, every `period` frames
  // IG Start of Frames (received after the periodic requests were sent) after which the host
  // cancels them: counted in the IG's frames, not the host's, so a slow IG still answers them.
  int cancel_after = 20;
  // los: segments (lat, lon, alt, lat, lon, alt) and vectors (lat, lon, alt, az, el, min, max).
  std::vector<std::array<double, 6>> segments;
  std::vector<std::array<double, 7>> vectors;
  // modes: IG Start of Frames (counted from the first) in Operate, then in Reset.
  int operate_frames = 10, reset_frames = 10;
  // Host frame (from the first Start of Frame) at which requests are sent.
  int request_frame = 2;
  // traffic: host frames of entity 1's Standby window and of its destruction.
  int standby_from = 20, standby_to = 30, destroy_frame = 60;
};

// What a host has seen, for the closing summary line.
struct Counts {
  long long sent = 0, received = 0, sof = 0, sof_swapped = 0, exceptions = 0;
  long long hot = 0, hotx = 0, los = 0, losx = 0;
  std::map<long long, long long> sof_sizes, sof_minors, sent_igc_sizes, sent_minors;
  std::map<long long, long long> other_packets;  // packet ID → count
  std::map<long long, long long> latency_msgs;   // one-shot requests: IG messages until answered
  std::map<long long, long long> ig_frame_steps; // IG frame counter step between Start of Frames
  long long first_ig_frame = -1, last_ig_frame = -1, timeouts = 0;
};

// One host session: a UDP socket to the IG, the CCL host session, and the printers of what
// arrives.
class Link {
 public:
  explicit Link(const Options& o);
  ~Link();
  Link(const Link&) = delete;
  Link& operator=(const Link&) = delete;

  // Starts the next message: IG Control in `mode`, then the ownship's Entity Control.
  CigiOutgoingMsg& begin(CigiBaseIGCtrl::IGModeGrp mode);
  // Packages the message (the CCL fills the frame counters), sends it, prints what was sent.
  void send();
  // Processes every datagram that arrives within `timeout_s` (returning early after the
  // first message when `until_first`); returns how many messages arrived.
  int receive(double timeout_s, bool until_first);

  // A request ID sent now: its answer's latency is counted in IG messages from here.
  void requested(int id);

  double now() const;            // seconds since start
  bool got_sof() const { return counts.sof > 0; }
  double last_sof_at() const { return last_sof_at_; }
  long frames_since_first_sof() const { return frames_since_sof_; }
  // Why to stop now ("" to go on): the time limit, the IG gone silent, or no IG at all.
  std::string stop_reason() const;
  void summary(const std::string& why) const;

  CigiEntityCtrlV3_3 ownship;
  Counts counts;
  // Start of Frames received when the periodic requests were sent (-1: not yet), and whether
  // they have been cancelled.
  long long periodic_sent_at_sof = -1;
  bool periodic_cancelled = false;
  const Options& opt;

  // Called by the packet printers.
  void on_sof(CigiBasePacket* p);
  void on_response(CigiBasePacket* p);
  void on_other(CigiBasePacket* p);

 private:
  void latency(int id);

  int sock_ = -1;
  double t0_ = 0;
  CigiHostSession* session_ = nullptr;
  CigiIGCtrlV3_3 igc_;
  std::vector<CigiBaseEventProcessor*> processors_;
  std::vector<unsigned char> in_, last_sof_;
  size_t in_len_ = 0;
  long ig_frame_ = -1;
  double last_sof_at_ = 0;
  long frames_since_sof_ = -1;
  std::map<int, long long> pending_;  // request ID → messages received when it was sent
};

// The commands (scripts.cpp).
int run_async(Link& link);
int run_sync(Link& link);

// The `traffic` script's packets for host frame `k` (traffic.cpp).
void traffic(Link& link, CigiOutgoingMsg& out, long k);
