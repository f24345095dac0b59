// cigi-host: the command line. See README.md in this folder for the commands and their output.
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

#include <CigiExceptions.h>

#include "host.h"

namespace {

const char* const kUsage =
    "usage: cigi-host COMMAND --ig HOST:PORT [options]\n"
    "commands:\n"
    "  poses   ownship Entity Control every message (--move steps it per message)\n"
    "  hot     HAT/HOT requests of every type at --at points and --entity-at offsets\n"
    "  los     LOS segment and vector requests (--segment, --vector), basic and extended\n"
    "  modes   Operate, then Reset for --reset-frames IG frames, then Operate again\n"
    "  traffic other entities: created, moved, attached, clamped, in Standby, destroyed\n"
    "  sync    a synchronous host: each message only after the IG's Start of Frame\n"
    "options (every command takes the request options, so one run can serve several checks):\n"
    "  --version 3.0|3.1|3.2|3.3      CIGI version of the host session (default 3.3)\n"
    "  --rate HZ                      asynchronous hosts: messages per second (default 60)\n"
    "  --seconds S                    stop after S seconds (default 60)\n"
    "  --wait-s S                     fail when no Start of Frame arrives within S (default 60)\n"
    "  --idle-exit-s S                stop when the IG is silent S after answering (default 2)\n"
    "  --quiet                        print only the closing summary line\n"
    "  --start LAT,LON,ALT[,YAW,PITCH,ROLL]   ownship start (default 47.3,11.4,3000,0,0,0)\n"
    "  --move DLAT,DLON,DALT[,DYAW]   ownship step per message sent\n"
    "  --at LAT,LON,ALT               HAT, HOT and extended requests, geodetic (repeatable)\n"
    "  --entity-at X,Y,Z              the same relative to the ownship, body axes (repeatable)\n"
    "  --period N --cancel-after M    3.2+: periodic requests at the first --at every N\n"
    "                                 frames, cancelled (period 0) after M more IG frames\n"
    "  --segment LAT,LON,ALT,LAT,LON,ALT            LOS segment (repeatable)\n"
    "  --vector LAT,LON,ALT,AZ,EL,MIN,MAX           LOS vector (repeatable)\n"
    "  --operate-frames N --reset-frames M          modes: the Reset window\n"
    "  --request-frame K              host frame after the first Start of Frame for requests\n"
    "  --standby FROM,TO --destroy-frame K         traffic: entity 1's Standby window, its end\n";

[[noreturn]] void bad(const std::string& why) {
  std::fprintf(stderr, "cigi-host: %s\n%s", why.c_str(), kUsage);
  std::exit(2);
}

double number(const std::string& flag, const std::string& s) {
  errno = 0;
  char* end = nullptr;
  double v = std::strtod(s.c_str(), &end);
  if (s.empty() || *end != '\0' || errno != 0) bad(flag + ": not a number: '" + s + "'");
  return v;
}

std::vector<double> numbers(const std::string& flag, const std::string& s, size_t min,
                            size_t max) {
  std::vector<double> out;
  size_t pos = 0;
  for (;;) {
    size_t comma = s.find(',', pos);
    out.push_back(number(flag, s.substr(pos, comma == std::string::npos ? comma : comma - pos)));
    if (comma == std::string::npos) break;
    pos = comma + 1;
  }
  if (out.size() < min || out.size() > max)
    bad(flag + ": expected " + std::to_string(min) +
        (max > min ? " to " + std::to_string(max) : "") + " comma-separated numbers, got '" + s +
        "'");
  return out;
}

Options parse(int argc, char** argv) {
  if (argc < 2) bad("no command");
  Options o;
  o.command = argv[1];
  if (o.command == "-h" || o.command == "--help") {
    std::fputs(kUsage, stdout);
    std::exit(0);
  }
  const std::vector<std::string> commands = {"poses", "hot", "los", "modes", "sync",
                                                "traffic"};
  bool known = false;
  for (auto& c : commands) known |= c == o.command;
  if (!known) bad("unknown command '" + o.command + "'");
  for (int i = 2; i < argc; ++i) {
    std::string f = argv[i];
    if (f == "--quiet") {
      Json::quiet = true;
      continue;
    }
    if (i + 1 >= argc) bad(f + ": missing value");
    std::string v = argv[++i];
    if (f == "--ig") {
      size_t colon = v.rfind(':');
      if (colon == std::string::npos) bad("--ig: expected HOST:PORT, got '" + v + "'");
      o.ig_host = v.substr(0, colon);
      double port = number(f, v.substr(colon + 1));
      if (port < 1 || port > 65535 || port != static_cast<int>(port))
        bad("--ig: port outside 1..65535: '" + v + "'");
      o.ig_port = static_cast<int>(port);
    } else if (f == "--version") {
      if (v != "3.0" && v != "3.1" && v != "3.2" && v != "3.3")
        bad("--version: 3.0, 3.1, 3.2 or 3.3, got '" + v + "'");
      o.minor = v[2] - '0';
    } else if (f == "--rate") {
      o.rate_hz = number(f, v);
      if (!(o.rate_hz > 0 && o.rate_hz <= 10000)) bad("--rate: outside (0, 10000]");
    } else if (f == "--seconds") {
      o.seconds = number(f, v);
    } else if (f == "--wait-s") {
      o.wait_s = number(f, v);
    } else if (f == "--idle-exit-s") {
      o.idle_exit_s = number(f, v);
    } else if (f == "--start") {
      auto n = numbers(f, v, 3, 6);
      o.start = {n[0], n[1], n[2]};
      if (n.size() > 3) o.yaw = static_cast<float>(n[3]);
      if (n.size() > 4) o.pitch = static_cast<float>(n[4]);
      if (n.size() > 5) o.roll = static_cast<float>(n[5]);
    } else if (f == "--move") {
      auto n = numbers(f, v, 3, 4);
      o.dlat = n[0];
      o.dlon = n[1];
      o.dalt = n[2];
      if (n.size() > 3) o.dyaw = static_cast<float>(n[3]);
    } else if (f == "--at") {
      auto n = numbers(f, v, 3, 3);
      o.at.push_back({n[0], n[1], n[2]});
    } else if (f == "--entity-at") {
      auto n = numbers(f, v, 3, 3);
      o.entity_at.push_back({n[0], n[1], n[2]});
    } else if (f == "--period") {
      o.period = static_cast<int>(number(f, v));
      if (o.period < 0 || o.period > 255) bad("--period: outside 0..255");
    } else if (f == "--cancel-after") {
      o.cancel_after = static_cast<int>(number(f, v));
    } else if (f == "--segment") {
      auto n = numbers(f, v, 6, 6);
      o.segments.push_back({n[0], n[1], n[2], n[3], n[4], n[5]});
    } else if (f == "--vector") {
      auto n = numbers(f, v, 7, 7);
      o.vectors.push_back({n[0], n[1], n[2], n[3], n[4], n[5], n[6]});
    } else if (f == "--operate-frames") {
      o.operate_frames = static_cast<int>(number(f, v));
    } else if (f == "--reset-frames") {
      o.reset_frames = static_cast<int>(number(f, v));
    } else if (f == "--destroy-frame") {
      o.destroy_frame = static_cast<int>(number(f, v));
    } else if (f == "--standby") {
      auto n = numbers(f, v, 2, 2);
      o.standby_from = static_cast<int>(n[0]);
      o.standby_to = static_cast<int>(n[1]);
    } else if (f == "--request-frame") {
      o.request_frame = static_cast<int>(number(f, v));
    } else {
      bad("unknown option '" + f + "'");
    }
  }
  if (o.ig_port == 0) bad("--ig HOST:PORT is required");
  if (o.command == "hot" && o.at.empty() && o.entity_at.empty())
    bad("hot: give at least one --at or --entity-at");
  if (o.command == "los" && o.segments.empty() && o.vectors.empty())
    bad("los: give at least one --segment or --vector");
  return o;
}

}  // namespace

int main(int argc, char** argv) {
  Options o = parse(argc, argv);
  try {
    Link link(o);
    return o.command == "sync" ? run_sync(link) : run_async(link);
  } catch (CigiException& e) {
    // The CCL refuses an out-of-range value (its bounds checks) by throwing.
    std::fprintf(stderr, "cigi-host: CCL: %s\n", e.what());
  } catch (std::exception& e) {
    std::fprintf(stderr, "cigi-host: %s\n", e.what());
  }
  return 1;
}
