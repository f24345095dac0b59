//! `aerie listen`: receive aircraft poses the way the image generator does (UDP on a port, or
//! shared memory) without rendering — to check a simulator's output, measure its pose rate and
//! losses, and record datagrams for `aerie replay`. Prints a progress line (stderr) and a
//! summary (stdout; `--json` writes it as JSON too).

use std::collections::BTreeMap;
use std::io::IsTerminal;
use std::net::Ipv4Addr;
use std::path::PathBuf;
use std::time::{Duration, Instant};

use aerie_sim_bridge::codec::ProtocolChoice;
use aerie_sim_bridge::ig::{DatabaseStatus, IgFrame, IgLink, IgStats};
use aerie_sim_bridge::query::NoTerrain;
use aerie_sim_bridge::shm::{shm_path, ShmConfig, ShmSource, DEFAULT_SHM_NAME};
use aerie_sim_bridge::timing::{monotonic_s, ExtrapolationParams, StreamState};
use aerie_sim_bridge::udp::{CigiReply, UdpConfig, UdpReceiver};
use aerie_sim_bridge::{DropReason, PoseLimits, PosePosition, PoseReader, StatsSnapshot};
use clap::Args;

use crate::app::commands::input_args::InputArgs;
use crate::app::failure::{bad_input, runtime, Failure};
use crate::app::out_path::prepare_out_file;
use crate::sim::pose_input::InputProtocol;
use crate::tools::output::write_text;

/// Default `--max-extrapolation-ms`: the extrapolation cap and lost-stream threshold.
pub const DEFAULT_CAP_MS: f64 = 100.0;
/// Default `--ig-rate`, IG frames per second.
pub const DEFAULT_IG_RATE_HZ: f64 = 60.0;
/// The highest `--ig-rate` taken.
pub const MAX_IG_RATE_HZ: f64 = 1000.0;

/// Ticks the port's IG session at a fixed rate, as the renderer's frame loop would, without
/// terrain.
struct IgTicker {
    link: IgLink,
    period: Duration,
    next: Instant,
    frame: u32,
}

impl IgTicker {
    /// Begins every frame that is due at `now` (late ticks are not made up: the next one is
    /// a period after now).
    fn tick(&mut self, now: Instant) {
        if now < self.next {
            return;
        }
        self.frame = self.frame.wrapping_add(1);
        self.link.begin_frame(
            &IgFrame {
                ig_frame: self.frame,
                time_s: monotonic_s(),
                database: DatabaseStatus::Ready(0),
            },
            &NoTerrain,
        );
        self.next += self.period;
        if self.next <= now {
            self.next = now + self.period;
        }
    }
}

#[derive(Debug, Args)]
pub struct ListenArgs {
    /// Record every received datagram with its arrival time (for `aerie replay`).
    #[arg(long)]
    pub record: Option<PathBuf>,
    /// Stop after this many seconds and print the summary (default: until interrupted).
    #[arg(long)]
    pub seconds: Option<f64>,
    /// Also write the summary as JSON to this file.
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Do not answer CIGI hosts with Start of Frame.
    #[arg(long)]
    pub no_cigi_reply: bool,
    /// IG frames per second: a CIGI host gets one Start of Frame per frame (HAT/HOT and
    /// line-of-sight requests are answered "no terrain": listen loads none).
    #[arg(long, default_value_t = DEFAULT_IG_RATE_HZ)]
    pub ig_rate: f64,
    // Last: the flattened input section's heading applies to the fields after it.
    #[command(flatten)]
    pub input: InputArgs,
}

enum Source {
    Udp(UdpReceiver),
    Shm(ShmSource),
}

fn state_name(s: StreamState) -> &'static str {
    match s {
        StreamState::Waiting => "waiting",
        StreamState::Live => "live",
        StreamState::Lost => "lost",
    }
}

fn position_text(p: &PosePosition) -> String {
    match *p {
        PosePosition::Geodetic {
            lat_deg,
            lon_deg,
            alt_m,
        } => format!("lat {lat_deg:.6} lon {lon_deg:.6} alt {alt_m:.1} m"),
        PosePosition::LocalEnu { x, y, z } => format!("x {x:.2} y {y:.2} z {z:.2} m"),
    }
}

fn dropped_text(s: &StatsSnapshot) -> String {
    let parts: Vec<String> = s
        .dropped_by_reason()
        .into_iter()
        .map(|(r, n)| format!("{r} {n}"))
        .collect();
    if parts.is_empty() {
        "0 dropped".into()
    } else {
        format!("{} dropped ({})", s.dropped_total(), parts.join(", "))
    }
}

fn progress_line(elapsed: f64, s: &StatsSnapshot, reader: &mut PoseReader) -> String {
    let last = match reader.latest() {
        Some(p) => format!(
            "last {} hdg {:.1} (age {:.0} ms)",
            position_text(&p.latest.pose.position),
            p.latest.pose.attitude_deg[0],
            (monotonic_s() - p.latest.arrival_s) * 1e3
        ),
        None => "no pose yet".into(),
    };
    format!(
        "{elapsed:.1} s: {} packets, {} accepted, {}, {} gaps, {:.1} poses/s, {}; {last}",
        s.received,
        s.accepted,
        dropped_text(s),
        s.gaps,
        s.pose_rate_hz().unwrap_or(0.0),
        state_name(reader.state()),
    )
}

/// `{"1 IG Control": n, …}`: the CIGI packets received by ID.
fn cigi_packets_json(s: &StatsSnapshot) -> serde_json::Value {
    let mut m = serde_json::Map::new();
    for (id, n) in s.cigi_packets.nonzero() {
        let key = match aerie_sim_bridge::codec::cigi::packet_name(id) {
            Some(name) => format!("{id} {name}"),
            None => id.to_string(),
        };
        m.insert(key, n.into());
    }
    m.into()
}

fn ig_json(s: &IgStats, frames: u32) -> serde_json::Value {
    serde_json::json!({
        "frames": frames,
        "start_of_frames": s.start_of_frames,
        "host_messages": s.messages,
        "requests_received": s.requests_received,
        "answered": s.answered,
        "answered_invalid": s.answered_invalid,
        "timed_out": s.timed_out,
        "latency_max_frames": s.latency_max_frames,
        "latency_mean_frames": s.latency_mean_frames(),
        "native_queries": s.native_received,
        "native_answered": s.native_answered,
        "entities": s.entities,
        "ignored_in_standby": s.ignored_in_standby,
        "answer_cpu_us_mean": s.cpu_us_mean(),
        "answer_cpu_us_max": s.cpu_us_max,
    })
}

fn requests_text(s: &IgStats) -> String {
    format!(
        "{} requests ({} answered, {} invalid), {} native queries",
        s.requests_received, s.answered, s.answered_invalid, s.native_received
    )
}

pub fn run(a: ListenArgs) -> Result<(), Failure> {
    if let Some(s) = a.seconds {
        if !(s.is_finite() && s > 0.0) {
            return Err(bad_input(format!(
                "--seconds: {s} must be a positive number"
            )));
        }
    }
    if !(a.ig_rate.is_finite() && a.ig_rate > 0.0 && a.ig_rate <= MAX_IG_RATE_HZ) {
        return Err(bad_input(format!(
            "--ig-rate: {} must be a number of frames per second in (0, {MAX_IG_RATE_HZ}]",
            a.ig_rate
        )));
    }
    let cap_ms = a.input.max_extrapolation_ms.unwrap_or(DEFAULT_CAP_MS);
    if !(cap_ms.is_finite() && cap_ms > 0.0) {
        return Err(bad_input(format!(
            "--max-extrapolation-ms: {cap_ms} must be a positive number of milliseconds"
        )));
    }
    if let Some(j) = &a.json {
        prepare_out_file("--json", j)?;
    }
    if let Some(r) = &a.record {
        prepare_out_file("--record", r)?;
    }
    let input = &a.input;
    input.check(&[("--record", a.record.is_some())])?;
    if input.multicast_if.is_some() && input.multicast.is_none() {
        return Err(bad_input("--multicast-if: only with --multicast"));
    }
    let extrapolation = ExtrapolationParams {
        cap_s: cap_ms / 1e3,
        ..ExtrapolationParams::default()
    };
    let limits = match input.world_bound_m {
        Some(b) => PoseLimits::with_world_bound(b)
            .map_err(|e| bad_input(format!("--world-bound-m: {e}")))?,
        None => PoseLimits::default(),
    };
    let shm_name = input.wants_shm().then(|| {
        input
            .shm_name
            .clone()
            .unwrap_or_else(|| DEFAULT_SHM_NAME.to_string())
    });
    let protocol = match input.protocol {
        Some(InputProtocol::Udp(p)) => p,
        Some(InputProtocol::Shm) | None => ProtocolChoice::Auto,
    };
    let (source, mut reader, what) = match &shm_name {
        Some(name) => {
            let path = shm_path(name);
            let (src, reader) = ShmSource::spawn(ShmConfig {
                path: path.clone(),
                extrapolation,
                limits,
                ..ShmConfig::default()
            })
            .map_err(runtime)?;
            (
                Source::Shm(src),
                reader,
                format!("shared memory {}", path.display()),
            )
        }
        None => {
            let (rx, reader) = UdpReceiver::spawn(UdpConfig {
                bind: InputArgs::listen_or_default(input.listen, input.multicast.is_some()),
                protocol,
                multicast: input.multicast,
                multicast_interface: input.multicast_if.unwrap_or(Ipv4Addr::UNSPECIFIED),
                allow: input.allow.clone(),
                cigi_reply: if a.no_cigi_reply {
                    CigiReply::Off
                } else {
                    CigiReply::ToSender
                },
                record: a.record.clone(),
                xplane_rpos: input.rpos_request(),
                extrapolation,
                limits,
                ..UdpConfig::default()
            })
            .map_err(runtime)?;
            let protocol = match protocol {
                ProtocolChoice::Auto => "auto".to_string(),
                ProtocolChoice::Only(p) => p.to_string(),
            };
            let what = format!("udp {} ({protocol})", rx.local_addr());
            (Source::Udp(rx), reader, what)
        }
    };
    eprintln!(
        "listening on {what}{}",
        match a.seconds {
            Some(s) => format!(" for {s} s"),
            None => " (Ctrl-C to stop; --seconds N prints a summary)".into(),
        }
    );

    let tty = std::io::stderr().is_terminal();
    let start = Instant::now();
    let deadline = a.seconds.map(|s| start + Duration::from_secs_f64(s));
    let mut last_line = Instant::now();
    let mut ig = match &source {
        Source::Udp(rx) => Some(IgTicker {
            link: rx.ig_link(),
            period: Duration::from_secs_f64(1.0 / a.ig_rate),
            next: start,
            frame: 0,
        }),
        Source::Shm(_) => None,
    };
    let mut last_poll = start;
    loop {
        let now = Instant::now();
        if deadline.is_some_and(|d| now >= d) {
            break;
        }
        if let Some(t) = ig.as_mut() {
            t.tick(now);
        }
        let step = Duration::from_millis(50);
        let mut wake = now + step;
        if let Some(t) = &ig {
            wake = wake.min(t.next);
        }
        if let Some(d) = deadline {
            wake = wake.min(d);
        }
        std::thread::sleep(wake.saturating_duration_since(now));
        if last_poll.elapsed() < step {
            continue;
        }
        last_poll = Instant::now();
        // Drives the lost/regained detection (logged) exactly as a frame loop would.
        let _ = reader.pose_now();
        let every = if tty { 200 } else { 2000 };
        if last_line.elapsed() >= Duration::from_millis(every) {
            last_line = Instant::now();
            let line = progress_line(start.elapsed().as_secs_f64(), &reader.stats(), &mut reader);
            if tty {
                eprint!("\r{line}\x1b[K");
            } else {
                eprintln!("{line}");
            }
        }
    }
    if tty {
        eprintln!();
    }
    let listened_s = start.elapsed().as_secs_f64();
    let final_frame = reader.pose_now();
    let stats = reader.stats();
    let ig_frames = ig.as_ref().map_or(0, |t| t.frame);
    let ig_stats = ig.as_ref().map(|t| t.link.stats());
    let record_error = match source {
        Source::Udp(rx) => rx.stop().err(),
        Source::Shm(src) => {
            src.stop();
            None
        }
    };
    let latest = reader.latest();

    let mut dropped = BTreeMap::new();
    for r in DropReason::ALL {
        dropped.insert(r.name(), stats.dropped(r));
    }
    let last_pose = latest.map(|s| {
        let p = s.latest.pose;
        let position = match p.position {
            PosePosition::Geodetic {
                lat_deg,
                lon_deg,
                alt_m,
            } => serde_json::json!({"lat_deg": lat_deg, "lon_deg": lon_deg, "alt_m": alt_m}),
            PosePosition::LocalEnu { x, y, z } => serde_json::json!({"x_m": x, "y_m": y, "z_m": z}),
        };
        serde_json::json!({
            "position": position,
            "heading_deg": p.attitude_deg[0],
            "pitch_deg": p.attitude_deg[1],
            "roll_deg": p.attitude_deg[2],
            "frame": p.frame,
            "sim_time_s": p.sim_time_s,
            "velocity_enu": p.velocity_enu,
            "rates_deg_s": p.angular_rates_deg_s,
            "sample": s.latest.sample,
            "age_ms": final_frame.map(|f| f.age_s * 1e3),
        })
    });
    let summary = serde_json::json!({
        "source": what,
        "seconds": listened_s,
        "packets": stats.received,
        "accepted": stats.accepted,
        "no_pose": stats.no_pose,
        "dropped_total": stats.dropped_total(),
        "dropped": dropped,
        "gaps": stats.gaps,
        "missed": stats.missed,
        "resyncs": stats.resyncs,
        "cigi_replies": stats.replies,
        "cigi_packets": cigi_packets_json(&stats),
        "ig": ig_stats.as_ref().map(|s| ig_json(s, ig_frames)),
        "shm_torn_retries": stats.retries,
        "shm_busy": stats.busy,
        "shm_shrinks": stats.shm_shrinks,
        "pose_rate_hz": stats.pose_rate_hz(),
        "stream": state_name(reader.state()),
        "last_pose": last_pose,
        "record": a.record.as_ref().map(|p| p.display().to_string()),
    });
    let last = match latest {
        Some(s) => {
            let p = s.latest.pose;
            format!(
                "last pose {}, heading {:.2} pitch {:.2} roll {:.2}, frame {}",
                position_text(&p.position),
                p.attitude_deg[0],
                p.attitude_deg[1],
                p.attitude_deg[2],
                p.frame
            )
        }
        None => "no pose received".into(),
    };
    println!(
        "listened {listened_s:.1} s on {what}: {} packets, {} accepted, {} without pose, {}, {} gaps ({} missed), {}; stream {}; {last}",
        stats.received,
        stats.accepted,
        stats.no_pose,
        dropped_text(&stats),
        stats.gaps,
        stats.missed,
        match stats.pose_rate_hz() {
            Some(hz) => format!("{hz:.1} poses/s"),
            None => "pose rate n/a".into(),
        },
        state_name(reader.state()),
    );
    if stats.cigi_packets.total() > 0 || ig_stats.as_ref().is_some_and(|s| s.native_received > 0) {
        println!(
            "CIGI packets: {}; {} IG frames at {} Hz, {} Start of Frames, {}",
            stats.cigi_packets.summary(),
            ig_frames,
            a.ig_rate,
            stats.replies,
            ig_stats.as_ref().map_or(String::new(), requests_text),
        );
    }
    if let Some(j) = &a.json {
        write_text(j, &format!("{summary:#}\n")).map_err(runtime)?;
    }
    if let Some(e) = record_error {
        return Err(runtime(format!("--record: {e}")));
    }
    if let Some(r) = &a.record {
        eprintln!("recorded {} datagrams to {}", stats.received, r.display());
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use clap::{CommandFactory, Parser};

    use crate::app::commands::listen::{run, ListenArgs};

    #[derive(Parser)]
    struct Cli {
        #[command(flatten)]
        args: ListenArgs,
    }

    fn args(extra: &[&str]) -> ListenArgs {
        Cli::try_parse_from(std::iter::once("listen").chain(extra.iter().copied()))
            .unwrap_or_else(|e| panic!("{extra:?}: {e}"))
            .args
    }

    /// The spellings used before (`--bind`, `--shm`, `--cap-ms`, `--protocol aerie`) still
    /// parse to the same values as the shared names, and `--help` shows only the new ones.
    #[test]
    fn old_and_new_flag_names_mean_the_same() {
        let old = args(&[
            "--bind",
            "0.0.0.0:47801",
            "--protocol",
            "aerie",
            "--cap-ms",
            "50",
            "--multicast",
            "239.1.2.3",
        ]);
        let new = args(&[
            "--listen",
            "0.0.0.0:47801",
            "--protocol",
            "native",
            "--max-extrapolation-ms",
            "50",
            "--multicast",
            "239.1.2.3",
        ]);
        assert_eq!(old.input, new.input);
        assert_eq!(
            args(&["--shm", "sim"]).input,
            args(&["--shm-name", "sim"]).input
        );
        let help = Cli::command().render_long_help().to_string();
        for name in [
            "--listen",
            "--shm-name",
            "--max-extrapolation-ms",
            "--record",
        ] {
            assert!(help.contains(name), "{name} missing from\n{help}");
        }
        for old in ["--bind", "--cap-ms", "--shm "] {
            assert!(!help.contains(old), "{old} shown in\n{help}");
        }
    }

    /// Contradicting flags stop before anything is bound, naming the flags.
    #[test]
    fn bad_flag_combinations_are_refused_before_listening() {
        for (extra, says) in [
            (
                &["--shm-name", "x", "--record", "r.rec"][..],
                "--protocol shm reads shared memory: --listen, --multicast, --allow, --xplane and --record apply to UDP only",
            ),
            (
                &["--protocol", "shm", "--listen", "127.0.0.1:9"],
                "apply to UDP only",
            ),
            (
                &["--protocol", "cigi", "--shm-name", "x"],
                "--shm-name: only with --protocol shm",
            ),
            (
                &["--multicast-if", "127.0.0.1"],
                "--multicast-if: only with --multicast",
            ),
            (
                &["--cap-ms", "0"],
                "--max-extrapolation-ms: 0 must be a positive number",
            ),
            (&["--seconds", "0"], "--seconds: 0"),
            (&["--ig-rate", "0"], "--ig-rate: 0"),
            (&["--ig-rate", "5000"], "--ig-rate: 5000"),
        ] {
            let f = run(args(extra)).expect_err("refused");
            assert_eq!(f.code, 2, "{extra:?}: {}", f.message);
            assert!(f.message.contains(says), "{extra:?}: {}", f.message);
        }
    }

    /// A synchronous CIGI host against `aerie listen`: one Start of Frame per IG tick (the
    /// summary's counts), never one per host message; the summary lists the packets by ID.
    #[test]
    fn listen_ticks_the_ig_and_paces_a_synchronous_host() {
        use aerie_sim_bridge::codec::cigi::{decode_ig_message, IgControl};
        use aerie_sim_bridge::codec::ByteOrder;
        use std::net::UdpSocket;
        use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
        use std::sync::Arc;
        use std::time::Duration;

        let port = UdpSocket::bind("127.0.0.1:0")
            .unwrap()
            .local_addr()
            .unwrap()
            .port();
        let dir = tempfile::tempdir().unwrap();
        let json = dir.path().join("listen.json");
        let to = format!("127.0.0.1:{port}");
        let a = args(&[
            "--listen",
            &to,
            "--seconds",
            "1",
            "--ig-rate",
            "50",
            "--json",
            json.to_str().unwrap(),
        ]);
        let listener = std::thread::spawn(move || run(a));
        let stop = Arc::new(AtomicBool::new(false));
        let (sent, sofs) = (Arc::new(AtomicU64::new(0)), Arc::new(AtomicU64::new(0)));
        let host = {
            let (stop, sent, sofs) = (stop.clone(), sent.clone(), sofs.clone());
            std::thread::spawn(move || {
                let s = UdpSocket::bind("127.0.0.1:0").unwrap();
                s.set_read_timeout(Some(Duration::from_millis(50))).unwrap();
                let msg = |f: u32| {
                    IgControl {
                        ig_mode: 1,
                        host_frame: f,
                        ..IgControl::default()
                    }
                    .encode(ByteOrder::Little)
                };
                let mut f = 1;
                let mut buf = [0u8; 512];
                while !stop.load(Ordering::Relaxed) {
                    // Until the first Start of Frame, re-send (listen may not be bound yet).
                    if sofs.load(Ordering::Relaxed) == 0 {
                        s.send_to(&msg(f), &to).unwrap();
                        sent.fetch_add(1, Ordering::Relaxed);
                        f += 1;
                    }
                    if let Ok((n, _)) = s.recv_from(&mut buf) {
                        decode_ig_message(&buf[..n]).unwrap();
                        sofs.fetch_add(1, Ordering::Relaxed);
                        s.send_to(&msg(f), &to).unwrap();
                        sent.fetch_add(1, Ordering::Relaxed);
                        f += 1;
                    }
                }
            })
        };
        listener.join().unwrap().unwrap();
        stop.store(true, Ordering::Relaxed);
        host.join().unwrap();
        let j: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
        let frames = j["ig"]["frames"].as_u64().unwrap();
        let replies = j["cigi_replies"].as_u64().unwrap();
        let sofs = sofs.load(Ordering::Relaxed);
        assert!(sofs > 0, "{j:#}");
        assert!(
            replies <= frames,
            "{replies} Start of Frames in {frames} IG frames"
        );
        assert!(sofs <= replies);
        // A paced host: its messages number its Start of Frames (plus the retries before the
        // first one), never hundreds per frame.
        let received = j["cigi_packets"]["1 IG Control"].as_u64().unwrap();
        assert!(received <= sent.load(Ordering::Relaxed));
        assert!(
            received <= frames + 60,
            "{received} host messages, {frames} IG frames"
        );
    }
}
