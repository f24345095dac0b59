//! `aerie-send`: sends a scripted flight to aerie the way a flight simulator would — over UDP in
//! any supported protocol, or through the shared-memory file. See README.md ("Driving aerie
//! from a simulator") and `aerie-send --help`.

use std::io::Write;
use std::net::{IpAddr, Ipv4Addr, SocketAddr, ToSocketAddrs, UdpSocket};
use std::path::PathBuf;
use std::time::{Duration, Instant};

use aerie_sim_bridge::codec::cigi::StartOfFrame;
use aerie_sim_bridge::geodesy::{Geodetic, LocalTangentPlane};
use aerie_sim_bridge::script::{Script, ScriptSample, Straight, WaypointFrame, Waypoints};
use aerie_sim_bridge::send::query::{
    answer_json, answer_line, ask, exit_status, json_string, parse_hot, parse_los,
    parse_los_vector, QueryPlan, DEFAULT_TIMEOUT, RESEND_EVERY,
};
use aerie_sim_bridge::send::{
    datagram, packet_count, parse_view_control, parse_view_definition, pose_for, SendProtocol,
    CIGI_ORDER,
};
use aerie_sim_bridge::shm::{shm_path, ShmWriter, DEFAULT_SHM_NAME};
use aerie_sim_bridge::udp::multicast_sender;
use aerie_sim_bridge::{Pose, PosePosition, Protocol, DEFAULT_PORT};

const HELP: &str = "\
aerie-send: send a scripted flight to aerie, as a flight simulator would

usage: aerie-send (--path <waypoints.csv> | --straight x,y,z,heading,pitch,roll,speed_mps)
                  [--protocol native|cigi|xplane|fgfs|shm] [--to <addr:port>]
                  [--shm-name <name>] [--rate <Hz>] [--seconds <S> | --count <N>]
                  [--origin lat,lon,alt] [--start-frame <n>]
                  [--realtime | --as-fast-as-possible] [--multicast-if <ipv4>]
                  [--json <file>] [--log <file.csv>] [--quiet]
                  [--view id,heading,pitch,roll[,x,y,z]]... [--view-frustum id,l,r,b,t[,near,far]]...
       aerie-send (--hot lat,lon[,alt] | --hot-local x,y[,z] | --los lat,lon,alt,lat,lon,alt
                   | --los-vector lat,lon,alt,azimuth,elevation,min_m,max_m) [--local]
                  [--to <addr:port>] [--timeout-ms <ms>] [--json <file> | --json -]

  --path         timed waypoints `t_s,x_m,y_m,z_m,heading_deg,pitch_deg,roll_deg` (aerie fly's)
  --straight     level pass along the heading at speed_mps from x,y,z (local ENU metres)
  --protocol     native (default), cigi, xplane, fgfs (UDP) or shm (shared memory): the words
                 of `aerie run --protocol` and `aerie listen --protocol`
  --to           UDP destination, default 127.0.0.1:47800 (the receiver's --listen address);
                 a multicast group is fine
  --multicast-if local IPv4 address to send multicast from (e.g. 127.0.0.1)
  --shm-name     shared-memory file for --protocol shm (default aerie-pose: /dev/shm/aerie-pose),
                 as the receiver's --shm-name
  --rate         packets per second (default 60); packet i carries script time i/rate
  --seconds      script seconds to send, both ends included (default: the path's duration;
                 10 s for --straight)
  --count        number of packets instead of --seconds
  --origin       WGS84 origin of the script's ENU frame; required for cigi/xplane/fgfs; native
                 and shm send geodetic positions when it is given, else local x/y/z
  --start-frame  first sequence number / CIGI host frame (default 1), +1 per packet
  --as-fast-as-possible  do not pace by --rate (the script time still steps by 1/rate)
  --json         also write the summary as JSON to this file
  --log          one CSV row per packet: the pose sent (script and wire position)
  --quiet        no progress lines
  --view         cigi: a View Control in every message: view id's offset from the ownship,
                 degrees (and eye offset x forward, y right, z down, metres); repeatable
  --view-frustum cigi: a View Definition in every message: view id's left, right, bottom, top
                 half-angles, degrees (and near, far clip, metres); repeatable

terrain queries (aerie native AERQ → AERA, answered by `aerie run` from the full-resolution
terrain; one query per call, sent to --to, resent with the same id every 250 ms until answered):
  --hot          height of terrain at lat,lon (degrees); with alt (metres), HAT as well
  --hot-local    the same at local ENU x,y metres (z for HAT)
  --los          first terrain intersection along the segment between two points
  --los-vector   ... along the vector from a point: azimuth (clockwise from north) and elevation
                 (up from the horizontal), degrees, between min_m and max_m metres
  --local        --los / --los-vector points are local ENU x,y,z metres instead of lat,lon,alt
  --timeout-ms   how long to wait for the answer (default 1000)
  --json         write the answer as a JSON object to this file; `-`: print it instead of the line

exit status: 0 sent (a query: answered), 1 nothing could be sent (a query: no answer in time, no
terrain there, or terrain not resident in time), 2 bad arguments or input";

struct Args {
    script: Script,
    protocol: SendProtocol,
    to: SocketAddr,
    multicast_if: Option<Ipv4Addr>,
    shm_name: String,
    rate: f64,
    count: u64,
    origin: Option<Geodetic>,
    start_frame: u32,
    realtime: bool,
    json: Option<PathBuf>,
    log: Option<PathBuf>,
    quiet: bool,
    /// CIGI View Control / View Definition packets appended to every message.
    view_packets: Vec<u8>,
}

fn number<T: std::str::FromStr>(flag: &str, v: &str) -> Result<T, String>
where
    T::Err: std::fmt::Display,
{
    v.parse::<T>().map_err(|e| format!("{flag} {v:?}: {e}"))
}

fn parse_origin(v: &str) -> Result<Geodetic, String> {
    let parts: Vec<f64> = v
        .split(',')
        .map(|s| s.trim().parse::<f64>().ok().filter(|x| x.is_finite()))
        .collect::<Option<_>>()
        .ok_or_else(|| format!("--origin {v:?}: expected three numbers lat,lon,alt"))?;
    let [lat, lon, alt] = parts[..] else {
        return Err(format!(
            "--origin {v:?}: expected three numbers lat,lon,alt"
        ));
    };
    if !(-90.0..=90.0).contains(&lat) || !(-180.0..360.0).contains(&lon) {
        return Err(format!(
            "--origin {v:?}: latitude must be in [-90, 90], longitude in [-180, 360)"
        ));
    }
    Ok(Geodetic::new(lat, lon, alt))
}

fn resolve(v: &str) -> Result<SocketAddr, String> {
    v.to_socket_addrs()
        .map_err(|e| format!("--to {v:?}: bad address ({e})"))?
        .next()
        .ok_or_else(|| format!("--to {v:?}: bad address (resolves to nothing)"))
}

/// A terrain query from the command line.
struct QueryArgs {
    plan: QueryPlan,
    to: SocketAddr,
    timeout: Duration,
    json: Option<PathBuf>,
}

const QUERY_FLAGS: [&str; 4] = ["--hot", "--hot-local", "--los", "--los-vector"];

/// The query, when the command line asks one (any of [`QUERY_FLAGS`]); `None` for a flight.
fn parse_query_args(argv: &[String]) -> Option<Result<QueryArgs, String>> {
    if !argv.iter().any(|a| QUERY_FLAGS.contains(&a.as_str())) {
        return None;
    }
    Some(parse_query(argv))
}

fn parse_query(argv: &[String]) -> Result<QueryArgs, String> {
    let mut query: Option<(String, String)> = None;
    let mut local = false;
    let mut to = format!("127.0.0.1:{DEFAULT_PORT}");
    let mut timeout = DEFAULT_TIMEOUT;
    let mut json = None;
    let mut it = argv.iter();
    while let Some(flag) = it.next() {
        let mut value = || {
            it.next()
                .cloned()
                .ok_or_else(|| format!("{flag}: missing value"))
        };
        match flag.as_str() {
            f if QUERY_FLAGS.contains(&f) => {
                let v = value()?;
                if let Some((first, _)) = &query {
                    return Err(format!("{first} and {f}: one query per call"));
                }
                query = Some((f.to_string(), v));
            }
            "--local" => local = true,
            "--to" => to = value()?,
            "--timeout-ms" => {
                let ms: u64 = number(flag, &value()?)?;
                if ms == 0 {
                    return Err("--timeout-ms 0: must be at least 1".into());
                }
                timeout = Duration::from_millis(ms);
            }
            "--json" => json = Some(PathBuf::from(value()?)),
            "--protocol" => {
                let p: SendProtocol = value()?.parse().map_err(|e| format!("--protocol: {e}"))?;
                if p != SendProtocol::Udp(Protocol::Aerie) {
                    return Err(format!(
                        "--protocol {} with a terrain query: queries are native (aerie) packets",
                        p.name()
                    ));
                }
            }
            other => {
                return Err(format!(
                    "{other} with a terrain query: a query takes only --local, --to, \
                     --timeout-ms, --json (see --help)"
                ))
            }
        }
    }
    let Some((flag, v)) = query else {
        unreachable!("parse_query is called only when a query flag is present")
    };
    let plan = match flag.as_str() {
        "--hot" => parse_hot(&flag, &v, local)?,
        "--hot-local" => parse_hot(&flag, &v, true)?,
        "--los" => parse_los(&flag, &v, local)?,
        _ => parse_los_vector(&flag, &v, local)?,
    };
    Ok(QueryArgs {
        plan,
        to: resolve(&to)?,
        timeout,
        json,
    })
}

/// Sends the query, waits, prints; the process's exit status.
fn run_query(q: &QueryArgs) -> i32 {
    let any: SocketAddr = if q.to.is_ipv4() {
        (Ipv4Addr::UNSPECIFIED, 0).into()
    } else {
        (std::net::Ipv6Addr::UNSPECIFIED, 0).into()
    };
    let socket = match UdpSocket::bind(any) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("aerie-send: bind {any}: {e}");
            return 1;
        }
    };
    // Request ids only need to differ between concurrent askers on one IG.
    let nanos = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.subsec_nanos());
    let id = std::process::id().rotate_left(16) ^ nanos;
    let asked = match ask(&socket, q.to, id, &q.plan.request, q.timeout, RESEND_EVERY) {
        Ok(a) => a,
        Err(e) => {
            eprintln!("aerie-send: query to {}: {e}", q.to);
            return 1;
        }
    };
    let line = match &asked.reply {
        Some(r) => answer_line(&q.plan, r),
        None => format!(
            "no answer from {} within {} ms ({} sends): is `aerie run` listening there?",
            q.to,
            q.timeout.as_millis(),
            asked.sends
        ),
    };
    let json = answer_json(&q.plan, id, q.to, &asked);
    match q.json.as_deref() {
        Some(p) if p == std::path::Path::new("-") => println!("{json}"),
        Some(p) => {
            println!("{line}");
            if let Err(e) = aerie_io::write_atomic(p, format!("{json}\n").as_bytes()) {
                eprintln!("aerie-send: --json {e}");
                return 1;
            }
        }
        None => println!("{line}"),
    }
    let status = exit_status(asked.reply.as_ref());
    if status != 0 {
        eprintln!("aerie-send: {line}");
    }
    status
}

fn parse_args(argv: &[String]) -> Result<Option<Args>, String> {
    let mut path = None;
    let mut straight = None;
    let mut protocol = SendProtocol::Udp(Protocol::Aerie);
    let mut to = format!("127.0.0.1:{DEFAULT_PORT}");
    let mut multicast_if = None;
    let mut shm_name = DEFAULT_SHM_NAME.to_string();
    let mut rate: f64 = 60.0;
    let (mut seconds, mut count) = (None::<f64>, None::<u64>);
    let mut origin = None;
    let mut start_frame = 1u32;
    let mut realtime = true;
    let mut json = None;
    let mut log = None;
    let mut quiet = false;
    let mut view_packets = Vec::new();
    let mut it = argv.iter();
    while let Some(flag) = it.next() {
        let mut value = || {
            it.next()
                .cloned()
                .ok_or_else(|| format!("{flag}: missing value"))
        };
        match flag.as_str() {
            "-h" | "--help" => return Ok(None),
            "--path" => path = Some(PathBuf::from(value()?)),
            "--straight" => {
                let v = value()?;
                straight = Some(Straight::parse(&v).map_err(|e| format!("--straight: {e}"))?);
            }
            "--protocol" => protocol = value()?.parse().map_err(|e| format!("--protocol: {e}"))?,
            "--to" => to = value()?,
            "--multicast-if" => multicast_if = Some(number::<Ipv4Addr>(flag, &value()?)?),
            "--shm-name" => shm_name = value()?,
            "--rate" => rate = number(flag, &value()?)?,
            "--seconds" => seconds = Some(number(flag, &value()?)?),
            "--count" => count = Some(number(flag, &value()?)?),
            "--origin" => origin = Some(parse_origin(&value()?)?),
            "--start-frame" => start_frame = number(flag, &value()?)?,
            "--realtime" => realtime = true,
            "--as-fast-as-possible" => realtime = false,
            "--json" => json = Some(PathBuf::from(value()?)),
            "--log" => log = Some(PathBuf::from(value()?)),
            "--quiet" => quiet = true,
            "--view" => view_packets.extend(parse_view_control(&value()?)?.encode(CIGI_ORDER)),
            "--view-frustum" => {
                view_packets.extend(parse_view_definition(&value()?)?.encode(CIGI_ORDER))
            }
            other => return Err(format!("unknown option {other:?} (see --help)")),
        }
    }
    if !(rate.is_finite() && rate > 0.0) {
        return Err(format!("--rate {rate}: must be a positive number of Hz"));
    }
    let script = match (path, straight) {
        (Some(p), None) => {
            let text =
                std::fs::read_to_string(&p).map_err(|e| format!("--path {}: {e}", p.display()))?;
            let w = Waypoints::parse(&text, &p.display().to_string())?;
            if w.frame() == WaypointFrame::Geodetic {
                return Err(format!(
                    "--path {}: a geo waypoint file (lat, lon, alt); aerie-send flies local ENU \
                     waypoints (with --origin for the geodetic protocols); `aerie fly --path` \
                     and `aerie bench --flight` read geo files",
                    p.display()
                ));
            }
            Script::Waypoints(w)
        }
        (None, Some(s)) => Script::Straight(s),
        (Some(_), Some(_)) => return Err("give either --path or --straight, not both".into()),
        (None, None) => return Err("a flight is needed: --path <file> or --straight ...".into()),
    };
    let count = match (seconds, count) {
        (Some(_), Some(_)) => return Err("give either --seconds or --count, not both".into()),
        (Some(s), None) if !(s.is_finite() && s >= 0.0) => {
            return Err(format!("--seconds {s}: must be a non-negative number"))
        }
        (Some(s), None) => packet_count(s, rate),
        (None, Some(n)) => n,
        (None, None) => packet_count(script.duration().unwrap_or(10.0), rate),
    };
    if protocol.needs_geodetic() && origin.is_none() {
        return Err(format!(
            "--protocol {} carries latitude/longitude: --origin lat,lon,alt is required",
            protocol.name()
        ));
    }
    if !view_packets.is_empty() && protocol != SendProtocol::Udp(Protocol::Cigi) {
        return Err("--view and --view-frustum: only with --protocol cigi".into());
    }
    let to = match protocol {
        SendProtocol::Udp(_) => resolve(&to)?,
        SendProtocol::Shm => SocketAddr::from(([127, 0, 0, 1], DEFAULT_PORT)),
    };
    Ok(Some(Args {
        script,
        protocol,
        to,
        multicast_if,
        shm_name,
        rate,
        count,
        origin,
        start_frame,
        realtime,
        json,
        log,
        quiet,
        view_packets,
    }))
}

/// Where the poses go.
enum Sink {
    Udp(UdpSocket),
    Shm(ShmWriter),
}

fn open_sink(a: &Args) -> Result<Sink, String> {
    match a.protocol {
        SendProtocol::Shm => ShmWriter::create(&shm_path(&a.shm_name))
            .map(Sink::Shm)
            .map_err(|e| format!("--shm-name: {e}")),
        SendProtocol::Udp(_) => {
            let any: SocketAddr = if a.to.is_ipv4() {
                (Ipv4Addr::UNSPECIFIED, 0).into()
            } else {
                (std::net::Ipv6Addr::UNSPECIFIED, 0).into()
            };
            let s = match a.to.ip() {
                IpAddr::V4(group) if group.is_multicast() => {
                    multicast_sender(a.multicast_if.unwrap_or(Ipv4Addr::UNSPECIFIED))
                        .map_err(|e| format!("--to {group}: {e}"))?
                }
                ip => {
                    let s = UdpSocket::bind(any).map_err(|e| format!("bind {any}: {e}"))?;
                    if matches!(ip, IpAddr::V4(v4) if v4.is_broadcast()) {
                        s.set_broadcast(true)
                            .map_err(|e| format!("--to {ip}: broadcast: {e}"))?;
                    }
                    s
                }
            };
            s.set_nonblocking(true)
                .map_err(|e| format!("non-blocking socket: {e}"))?;
            Ok(Sink::Udp(s))
        }
    }
}

const LOG_HEADER: &str = "packet,frame,t_s,x_m,y_m,z_m,lat_deg,lon_deg,alt_m,heading_deg,pitch_deg,roll_deg,ve_mps,vn_mps,vu_mps,sent";

/// One `--log` row: the script's local position and the wire pose (lat/lon/alt empty when
/// local), shortest round-trip notation so the values read back exactly.
fn log_row(i: u64, s: &ScriptSample, p: &Pose, sent: bool) -> String {
    let (lat, lon, alt) = match p.position {
        PosePosition::Geodetic {
            lat_deg,
            lon_deg,
            alt_m,
        } => (lat_deg.to_string(), lon_deg.to_string(), alt_m.to_string()),
        PosePosition::LocalEnu { .. } => Default::default(),
    };
    let [x, y, z] = s.position;
    let [h, pi, r] = p.attitude_deg;
    let [ve, vn, vu] = p.velocity_enu.unwrap_or([0.0; 3]);
    format!(
        "{i},{},{},{x},{y},{z},{lat},{lon},{alt},{h},{pi},{r},{ve},{vn},{vu},{}",
        p.frame,
        p.sim_time_s,
        u8::from(sent)
    )
}

#[derive(Default)]
struct Summary {
    sent: u64,
    errors: u64,
    first_error: Option<String>,
    cigi_answers: u64,
    elapsed_s: f64,
    last_frame: u32,
}

fn main() {
    let argv: Vec<String> = std::env::args().skip(1).collect();
    if argv.iter().any(|a| a == "-h" || a == "--help") {
        println!("{HELP}");
        return;
    }
    match parse_query_args(&argv) {
        Some(Ok(q)) => std::process::exit(run_query(&q)),
        Some(Err(e)) => {
            eprintln!("aerie-send: {e}");
            std::process::exit(2);
        }
        None => {}
    }
    let a = match parse_args(&argv) {
        Ok(Some(a)) => a,
        Ok(None) => {
            println!("{HELP}");
            return;
        }
        Err(e) => {
            eprintln!("aerie-send: {e}");
            std::process::exit(2);
        }
    };
    let mut sink = match open_sink(&a) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("aerie-send: {e}");
            std::process::exit(2);
        }
    };
    let ltp = a.origin.map(LocalTangentPlane::new);
    let dest = match (&sink, a.protocol) {
        (Sink::Shm(w), _) => w.path().display().to_string(),
        (Sink::Udp(_), _) => a.to.to_string(),
    };
    let mut sum = Summary::default();
    let start = Instant::now();
    let mut next_progress = 1.0;
    let mut buf = [0u8; 256];
    // Through the atomic writer: a full disk leaves no cut log (row errors are remembered by
    // the writer and reported when it is committed).
    let mut log = match a.log.as_ref().map(|p| (p, aerie_io::AtomicFile::create(p))) {
        None => None,
        Some((_, Ok(f))) => {
            let mut w = std::io::BufWriter::new(f);
            let _ = writeln!(w, "{LOG_HEADER}");
            Some(w)
        }
        Some((p, Err(e))) => {
            eprintln!("aerie-send: --log {}: {e}", p.display());
            std::process::exit(2);
        }
    };
    for i in 0..a.count {
        let t = i as f64 / a.rate;
        if a.realtime {
            let due = start + Duration::from_secs_f64(t);
            if let Some(d) = due.checked_duration_since(Instant::now()) {
                std::thread::sleep(d);
            }
        }
        let frame = a.start_frame.wrapping_add(i as u32);
        let sample = a.script.sample(t);
        let pose = pose_for(&sample, t, u64::from(frame), ltp.as_ref());
        let sent_before = sum.sent;
        match (&mut sink, a.protocol) {
            (Sink::Shm(w), _) => {
                w.write(&pose);
                sum.sent += 1;
            }
            (Sink::Udp(s), SendProtocol::Udp(p)) => {
                // Geodetic-only protocols always have an origin here (checked in parse_args).
                let Some(mut bytes) = datagram(p, &pose, frame) else {
                    unreachable!("{p} without --origin")
                };
                bytes.extend_from_slice(&a.view_packets);
                match s.send_to(&bytes, a.to) {
                    Ok(_) => sum.sent += 1,
                    Err(e) => {
                        sum.errors += 1;
                        sum.first_error
                            .get_or_insert_with(|| format!("send to {}: {e}", a.to));
                    }
                }
                // CIGI: count the IG's Start of Frame answers (never waits).
                while let Ok((n, _)) = s.recv_from(&mut buf) {
                    if StartOfFrame::decode(&buf[..n]).is_ok() {
                        sum.cigi_answers += 1;
                    }
                }
            }
            (Sink::Udp(_), SendProtocol::Shm) => unreachable!("shm protocol opens a shm sink"),
        }
        sum.last_frame = frame;
        if let Some(w) = log.as_mut() {
            let _ = writeln!(w, "{}", log_row(i, &sample, &pose, sum.sent > sent_before));
        }
        let now = start.elapsed().as_secs_f64();
        if !a.quiet && now >= next_progress {
            next_progress = now.floor() + 1.0;
            eprintln!(
                "aerie-send: {}/{} packets, script t {:.2} s, {} errors",
                i + 1,
                a.count,
                t,
                sum.errors
            );
        }
    }
    sum.elapsed_s = start.elapsed().as_secs_f64();
    if let Some(w) = log.take() {
        let done = w
            .into_inner()
            .map_err(|e| e.error().to_string())
            .and_then(|f| f.commit().map_err(|e| e.to_string()));
        if let Err(e) = done {
            eprintln!("aerie-send: --log {e}");
            std::process::exit(1);
        }
    }
    let achieved = if a.count > 1 && sum.elapsed_s > 0.0 {
        (a.count - 1) as f64 / sum.elapsed_s
    } else {
        0.0
    };
    let mut line = format!(
        "aerie-send: sent {} {} packets to {dest} in {:.2} s ({:.1} Hz achieved, {} Hz asked), {} errors",
        sum.sent,
        a.protocol.name(),
        sum.elapsed_s,
        achieved,
        a.rate,
        sum.errors
    );
    if a.protocol == SendProtocol::Udp(Protocol::Cigi) {
        line.push_str(&format!(", {} Start of Frame answers", sum.cigi_answers));
    }
    if let Some(e) = &sum.first_error {
        line.push_str(&format!(" (first: {e})"));
    }
    println!("{line}");
    if let Some(path) = &a.json {
        let json = format!(
            "{{\"protocol\":{},\"to\":{},\"packets\":{},\"sent\":{},\"errors\":{},\"first_error\":{},\"seconds\":{},\"rate_hz\":{},\"achieved_hz\":{},\"first_frame\":{},\"last_frame\":{},\"cigi_answers\":{},\"geodetic\":{}}}\n",
            json_string(a.protocol.name()),
            json_string(&dest),
            a.count,
            sum.sent,
            sum.errors,
            sum.first_error.as_deref().map_or("null".into(), json_string),
            sum.elapsed_s,
            a.rate,
            achieved,
            a.start_frame,
            sum.last_frame,
            sum.cigi_answers,
            a.origin.is_some()
        );
        if let Err(e) = aerie_io::write_atomic(path, json.as_bytes()) {
            eprintln!("aerie-send: --json {e}");
            std::process::exit(1);
        }
    }
    if sum.sent == 0 && a.count > 0 {
        std::process::exit(1);
    }
}
