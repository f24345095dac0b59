//! UDP transport: a receiver thread per port, handing the newest valid pose to the frame loop
//! through a [`PoseReader`] (lock-free), answering CIGI hosts with Start of Frame, optionally
//! joining a multicast group, filtering senders and recording every datagram.

use std::io;
use std::net::{IpAddr, Ipv4Addr, SocketAddr, SocketAddrV4, UdpSocket};
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::Duration;

use crate::codec::ProtocolChoice;
use crate::ingest::{input_channel, Ingest, InputParams, PoseReader, Verdict};
use crate::record::Recorder;
use crate::stats::{Counters, StatsSnapshot};
use crate::timing::{monotonic_s, ExtrapolationParams, SequenceParams};

/// aerie's default pose port.
pub const DEFAULT_PORT: u16 = 47800;

/// `127.0.0.1:47800`.
pub fn default_bind() -> SocketAddr {
    SocketAddr::V4(SocketAddrV4::new(Ipv4Addr::LOCALHOST, DEFAULT_PORT))
}

/// Where CIGI Start of Frame answers go.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub enum CigiReply {
    /// Never answer.
    Off,
    /// To the address the host's message came from.
    #[default]
    ToSender,
    /// To a fixed address (hosts that listen on another port than they send from).
    To(SocketAddr),
}

/// Ask an X-Plane instance to stream `RPOS` to this port.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RposRequest {
    /// X-Plane's UDP address (its receive port, 49000 by default).
    pub xplane: SocketAddr,
    /// Positions per second to ask for.
    pub rate_hz: u32,
}

/// How long without an `RPOS` before the request is sent again (X-Plane restarted).
const RPOS_RETRY: Duration = Duration::from_secs(2);

/// One UDP input port.
#[derive(Clone, Debug)]
pub struct UdpConfig {
    /// Local address to bind (`0.0.0.0:<port>` to listen on every interface, required for
    /// multicast). Port 0 picks a free port ([`UdpReceiver::local_addr`] tells which).
    pub bind: SocketAddr,
    /// Accepted protocol(s).
    pub protocol: ProtocolChoice,
    /// IPv4 multicast group to join (several channel machines on one stream).
    pub multicast: Option<Ipv4Addr>,
    /// Local interface address for the multicast join (`0.0.0.0`: the kernel chooses).
    pub multicast_interface: Ipv4Addr,
    /// When non-empty, datagrams from other source addresses are dropped and counted.
    pub allow: Vec<IpAddr>,
    /// CIGI Start of Frame answers.
    pub cigi_reply: CigiReply,
    /// Record every received datagram to this file.
    pub record: Option<PathBuf>,
    /// Request `RPOS` from X-Plane (from this port, so X-Plane answers here), at start and
    /// again whenever no `RPOS` arrived for 2 s.
    pub xplane_rpos: Option<RposRequest>,
    /// Sequence resync rules.
    pub sequence: SequenceParams,
    /// Extrapolation limits for the reader.
    pub extrapolation: ExtrapolationParams,
}

impl Default for UdpConfig {
    fn default() -> Self {
        Self {
            bind: default_bind(),
            protocol: ProtocolChoice::Auto,
            multicast: None,
            multicast_interface: Ipv4Addr::UNSPECIFIED,
            allow: Vec::new(),
            cigi_reply: CigiReply::ToSender,
            record: None,
            xplane_rpos: None,
            sequence: SequenceParams::default(),
            extrapolation: ExtrapolationParams::default(),
        }
    }
}

/// A running receiver thread. Dropping it stops the thread.
pub struct UdpReceiver {
    local: SocketAddr,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<Result<(), String>>>,
    counters: Arc<Counters>,
}

/// How long a blocked `recv` waits before checking for a stop request.
const POLL: Duration = Duration::from_millis(20);

fn ctx(what: String) -> impl FnOnce(io::Error) -> io::Error {
    move |e| io::Error::new(e.kind(), format!("{what}: {e}"))
}

fn canonical(ip: IpAddr) -> IpAddr {
    match ip {
        IpAddr::V6(v6) => v6
            .to_ipv4_mapped()
            .map(IpAddr::V4)
            .unwrap_or(IpAddr::V6(v6)),
        v4 => v4,
    }
}

impl UdpReceiver {
    /// Binds, joins the multicast group, creates the recording, and starts the thread.
    /// Errors name the address or file.
    pub fn spawn(cfg: UdpConfig) -> io::Result<(UdpReceiver, PoseReader)> {
        let socket = UdpSocket::bind(cfg.bind).map_err(ctx(format!("bind {}", cfg.bind)))?;
        if let Some(group) = cfg.multicast {
            socket
                .join_multicast_v4(&group, &cfg.multicast_interface)
                .map_err(ctx(format!(
                    "join multicast group {group} on {}",
                    cfg.multicast_interface
                )))?;
        }
        socket
            .set_read_timeout(Some(POLL))
            .map_err(ctx("set read timeout".into()))?;
        let local = socket.local_addr()?;
        let recorder = match &cfg.record {
            Some(path) => Some(
                Recorder::create(path, monotonic_s())
                    .map_err(|e| io::Error::other(e.to_string()))?,
            ),
            None => None,
        };
        let name = match cfg.multicast {
            Some(g) => format!("udp {local} (multicast {g})"),
            None => format!("udp {local}"),
        };
        let (ingest, reader) = input_channel(InputParams {
            name,
            protocol: cfg.protocol,
            sequence: cfg.sequence,
            extrapolation: cfg.extrapolation,
        });
        let counters = ingest.counters().clone();
        let stop = Arc::new(AtomicBool::new(false));
        let thread = {
            let stop = stop.clone();
            let opts = LoopOptions {
                allow: cfg.allow.iter().copied().map(canonical).collect(),
                reply: cfg.cigi_reply.clone(),
                rpos: cfg.xplane_rpos,
            };
            std::thread::Builder::new()
                .name(format!("aerie-udp-{}", local.port()))
                .spawn(move || receive_loop(socket, ingest, stop, opts, recorder))?
        };
        Ok((
            UdpReceiver {
                local,
                stop,
                thread: Some(thread),
                counters,
            },
            reader,
        ))
    }

    /// The bound address.
    pub fn local_addr(&self) -> SocketAddr {
        self.local
    }

    /// Counters now.
    pub fn stats(&self) -> StatsSnapshot {
        self.counters.snapshot()
    }

    /// Stops the thread and waits for it (≤ 20 ms). Returns the recording error if recording
    /// failed on the way.
    pub fn stop(mut self) -> Result<(), String> {
        self.stop_and_join()
    }

    fn stop_and_join(&mut self) -> Result<(), String> {
        self.stop.store(true, Ordering::Relaxed);
        match self.thread.take() {
            Some(t) => t
                .join()
                .unwrap_or_else(|_| Err("receiver thread panicked".into())),
            None => Ok(()),
        }
    }
}

impl Drop for UdpReceiver {
    fn drop(&mut self) {
        let _ = self.stop_and_join();
    }
}

struct LoopOptions {
    allow: Vec<IpAddr>,
    reply: CigiReply,
    rpos: Option<RposRequest>,
}

fn receive_loop(
    socket: UdpSocket,
    mut ingest: Ingest,
    stop: Arc<AtomicBool>,
    opts: LoopOptions,
    mut recorder: Option<Recorder>,
) -> Result<(), String> {
    let LoopOptions { allow, reply, rpos } = opts;
    let mut buf = vec![0u8; 65_536];
    let mut ig_frame: u32 = 0;
    let mut record_error = None;
    let counters = ingest.counters().clone();
    let mut last_rpos: Option<std::time::Instant> = None;
    while !stop.load(Ordering::Relaxed) {
        if let Some(req) = rpos {
            if last_rpos.map_or(true, |t| t.elapsed() > RPOS_RETRY) {
                let bytes = crate::codec::xplane::rpos_request(req.rate_hz);
                if let Err(e) = socket.send_to(&bytes, req.xplane) {
                    tracing::debug!("RPOS request to {}: {e}", req.xplane);
                }
                last_rpos = Some(std::time::Instant::now());
            }
        }
        let (n, from) = match socket.recv_from(&mut buf) {
            Ok(x) => x,
            Err(e) => match e.kind() {
                io::ErrorKind::WouldBlock
                | io::ErrorKind::TimedOut
                | io::ErrorKind::Interrupted => continue,
                // An ICMP "port unreachable" for an earlier answer: not about this socket.
                io::ErrorKind::ConnectionRefused | io::ErrorKind::ConnectionReset => continue,
                _ => {
                    tracing::error!("udp {:?}: receive failed: {e}", socket.local_addr());
                    std::thread::sleep(POLL);
                    continue;
                }
            },
        };
        let arrival = monotonic_s();
        let bytes = &buf[..n];
        if let Some(r) = recorder.as_mut() {
            if let Err(e) = r.record(arrival, bytes) {
                tracing::error!("recording stopped: {e}");
                record_error = Some(e.to_string());
                recorder = None;
            }
        }
        if !allow.is_empty() && !allow.contains(&canonical(from.ip())) {
            ingest.not_allowed(&from);
            continue;
        }
        let out = ingest.datagram(bytes, arrival);
        if rpos.is_some()
            && matches!(out.verdict, Verdict::Accepted(_))
            && bytes.starts_with(crate::codec::xplane::HEADER)
        {
            last_rpos = Some(std::time::Instant::now());
        }
        if let (Verdict::Accepted(_) | Verdict::NoPose, Some(m)) = (out.verdict, &out.cigi) {
            let to = match reply {
                CigiReply::Off => continue,
                CigiReply::ToSender => from,
                CigiReply::To(a) => a,
            };
            ig_frame = ig_frame.wrapping_add(1);
            let ticks = (monotonic_s() * 1e5) as u64 as u32;
            match socket.send_to(&m.answer(ig_frame, ticks), to) {
                Ok(_) => counters.reply(),
                Err(e) => tracing::debug!("CIGI Start of Frame to {to}: {e}"),
            }
        }
    }
    match record_error {
        Some(e) => Err(e),
        None => Ok(()),
    }
}
