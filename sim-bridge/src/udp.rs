//! UDP transport: a receiver thread per port, handing the newest valid pose to the frame loop
//! through a [`PoseReader`] (lock-free) and every CIGI message and native terrain query to the
//! port's IG session ([`UdpReceiver::ig_link`]: the frame loop answers through it, once per IG
//! frame, on this port's socket), optionally joining a multicast group (the port shared with
//! other processes on the host), filtering senders and recording every datagram.

use std::io;
use std::net::{IpAddr, Ipv4Addr, SocketAddr, SocketAddrV4, UdpSocket};
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::Duration;

use crate::codec::{native, ProtocolChoice};
use crate::ig::{IgConfig, IgLink};
use crate::ingest::{input_channel, Ingest, InputParams, PoseReader, Verdict};
use crate::pose::PoseLimits;
use crate::record::Recorder;
use crate::stats::{Counters, StatsSnapshot};
use crate::timing::{monotonic_s, ExtrapolationParams, SequenceParams};

/// aerie's default pose port.
pub const DEFAULT_PORT: u16 = 47800;

/// `127.0.0.1:47800`.
pub fn default_bind() -> SocketAddr {
    SocketAddr::V4(SocketAddrV4::new(Ipv4Addr::LOCALHOST, DEFAULT_PORT))
}

pub use crate::ig::CigiReply;

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
    /// Where the IG session's CIGI messages (Start of Frame and answers) go.
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
    /// Plausibility limits: poses beyond them are dropped as implausible.
    pub limits: PoseLimits,
    /// Kernel receive buffer (`SO_RCVBUF`) to ask for, bytes; `None` keeps the system default
    /// (≈ 200 kB on Linux, ~1,500 datagrams). The kernel may cap it (`net.core.rmem_max`).
    pub recv_buffer_bytes: Option<usize>,
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
            limits: PoseLimits::default(),
            recv_buffer_bytes: None,
        }
    }
}

/// Socket options a port needs before `bind`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BindOptions {
    /// `SO_REUSEADDR` (and `SO_REUSEPORT` where the platform has it): several processes on
    /// one host bind the same multicast port and each gets every group datagram. Only for
    /// multicast ports: on a unicast port it would let a second aerie silently share (and
    /// split) the stream instead of failing with "address in use".
    pub reuse: bool,
    /// `SO_RCVBUF`, bytes.
    pub recv_buffer_bytes: Option<usize>,
}

/// The options for `cfg` (plain decision; [`UdpReceiver::spawn`] applies them).
pub fn bind_options(cfg: &UdpConfig) -> BindOptions {
    BindOptions {
        reuse: cfg.multicast.is_some(),
        recv_buffer_bytes: cfg.recv_buffer_bytes,
    }
}

/// Creates the socket, applies `opts` and binds `addr`.
fn bind_socket(addr: SocketAddr, opts: BindOptions) -> io::Result<UdpSocket> {
    use socket2::{Domain, Socket, Type};
    let s = Socket::new(
        Domain::for_address(addr),
        Type::DGRAM,
        Some(socket2::Protocol::UDP),
    )?;
    if opts.reuse {
        s.set_reuse_address(true)
            .map_err(ctx("set SO_REUSEADDR".into()))?;
        #[cfg(all(unix, not(any(target_os = "solaris", target_os = "illumos"))))]
        s.set_reuse_port(true)
            .map_err(ctx("set SO_REUSEPORT".into()))?;
    }
    if let Some(n) = opts.recv_buffer_bytes {
        s.set_recv_buffer_size(n)
            .map_err(ctx(format!("set SO_RCVBUF {n}")))?;
    }
    s.bind(&addr.into())?;
    Ok(s.into())
}

/// A socket for sending to an IPv4 multicast group from `interface` (`0.0.0.0`: the kernel
/// chooses by its routes; `127.0.0.1`: stay on this host, the way tests and one-machine setups
/// want it), with `IP_MULTICAST_LOOP` on so receivers on the sending host get the datagrams.
pub fn multicast_sender(interface: Ipv4Addr) -> io::Result<UdpSocket> {
    let s = socket2::Socket::from(
        UdpSocket::bind((Ipv4Addr::UNSPECIFIED, 0)).map_err(ctx("bind 0.0.0.0:0".into()))?,
    );
    s.set_multicast_loop_v4(true)
        .map_err(ctx("set IP_MULTICAST_LOOP".into()))?;
    if !interface.is_unspecified() {
        s.set_multicast_if_v4(&interface)
            .map_err(ctx(format!("set IP_MULTICAST_IF {interface}")))?;
    }
    Ok(s.into())
}

/// The kernel's drop count for the IPv4 UDP socket bound to local `port`, from the text of
/// Linux's `/proc/net/udp` (the last column, `drops`: datagrams lost because the socket's
/// receive buffer was full). Sums every socket on the port. `None` if no line matches.
pub fn kernel_drops_in(proc_net_udp: &str, port: u16) -> Option<u64> {
    let want = format!(":{port:04X}");
    let mut total = None;
    for line in proc_net_udp.lines().skip(1) {
        let cols: Vec<&str> = line.split_whitespace().collect();
        if cols.len() < 2 || !cols[1].ends_with(&want) {
            continue;
        }
        if let Some(d) = cols.last().and_then(|d| d.parse::<u64>().ok()) {
            *total.get_or_insert(0) += d;
        }
    }
    total
}

/// [`kernel_drops_in`] on this host's `/proc/net/udp` (Linux; `None` elsewhere).
pub fn kernel_drops(port: u16) -> Option<u64> {
    let text = std::fs::read_to_string("/proc/net/udp").ok()?;
    kernel_drops_in(&text, port)
}

/// A running receiver thread. Dropping it stops the thread.
pub struct UdpReceiver {
    local: SocketAddr,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<Result<(), String>>>,
    counters: Arc<Counters>,
    link: IgLink,
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
        let socket =
            bind_socket(cfg.bind, bind_options(&cfg)).map_err(ctx(format!("bind {}", cfg.bind)))?;
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
            limits: cfg.limits,
        });
        let counters = ingest.counters().clone();
        let sender = socket
            .try_clone()
            .map_err(ctx(format!("clone the socket of {local}")))?;
        let link = IgLink::new(
            IgConfig {
                reply: cfg.cigi_reply.clone(),
            },
            Some(sender),
            Some(counters.clone()),
        );
        let stop = Arc::new(AtomicBool::new(false));
        let thread = {
            let stop = stop.clone();
            let opts = LoopOptions {
                allow: cfg.allow.iter().copied().map(canonical).collect(),
                rpos: cfg.xplane_rpos,
                link: link.clone(),
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
                link,
            },
            reader,
        ))
    }

    /// The port's IG session: the frame loop calls [`IgLink::begin_frame`] at the start of
    /// every frame (Start of Frame and the answers due go out on this port's socket).
    pub fn ig_link(&self) -> IgLink {
        self.link.clone()
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
    rpos: Option<RposRequest>,
    link: IgLink,
}

fn receive_loop(
    socket: UdpSocket,
    mut ingest: Ingest,
    stop: Arc<AtomicBool>,
    opts: LoopOptions,
    mut recorder: Option<Recorder>,
) -> Result<(), String> {
    let LoopOptions { allow, rpos, link } = opts;
    let mut buf = vec![0u8; 65_536];
    let mut record_error = None;
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
                tracing::error!("{e}");
                record_error = Some(e.to_string());
                recorder = None;
            }
        }
        if !allow.is_empty() && !allow.contains(&canonical(from.ip())) {
            ingest.not_allowed(&from);
            continue;
        }
        if native::is_query(bytes) {
            // A terrain question, not a pose: the IG session answers it in the next frame.
            match native::decode_query(bytes) {
                Ok((id, request)) => {
                    ingest.native_query();
                    link.receive_native(id, request, from);
                }
                Err(e) => ingest.count_drop(e.reason(), &e),
            }
            continue;
        }
        let out = ingest.datagram(bytes, arrival);
        if rpos.is_some()
            && matches!(out.verdict, Verdict::Accepted(_))
            && bytes.starts_with(crate::codec::xplane::HEADER)
        {
            last_rpos = Some(std::time::Instant::now());
        }
        // Answered by the frame loop (one Start of Frame per IG frame), not here.
        if let (Verdict::Accepted(_) | Verdict::NoPose, Some(m)) = (out.verdict, &out.cigi) {
            link.receive(m, from);
        }
    }
    match record_error {
        Some(e) => Err(e),
        None => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reuse_only_for_multicast_ports() {
        let mut cfg = UdpConfig::default();
        assert!(!bind_options(&cfg).reuse);
        cfg.multicast = Some(Ipv4Addr::new(239, 255, 0, 1));
        cfg.recv_buffer_bytes = Some(1 << 20);
        assert_eq!(
            bind_options(&cfg),
            BindOptions {
                reuse: true,
                recv_buffer_bytes: Some(1 << 20)
            }
        );
    }

    #[test]
    fn unicast_port_is_not_shared() {
        let a = bind_socket(
            "127.0.0.1:0".parse().unwrap(),
            bind_options(&UdpConfig::default()),
        )
        .unwrap();
        let taken = a.local_addr().unwrap();
        assert!(bind_socket(taken, bind_options(&UdpConfig::default())).is_err());
    }

    #[test]
    fn kernel_drops_are_read_from_proc_net_udp() {
        let text = "   sl  local_address rem_address   st tx_queue rx_queue tr tm->when retrnsmt   uid  timeout inode ref pointer drops\n\
  215: 0100007F:BAB8 00000000:0000 07 00000000:00000000 00:00000000 00000000  1000        0 123 2 0000000000000000 17\n\
  300: 00000000:BAB8 00000000:0000 07 00000000:00000000 00:00000000 00000000  1000        0 124 2 0000000000000000 3\n\
  301: 0100007F:0035 00000000:0000 07 00000000:00000000 00:00000000 00000000     0        0 125 2 0000000000000000 9\n";
        assert_eq!(kernel_drops_in(text, 0xBAB8), Some(20));
        assert_eq!(kernel_drops_in(text, 53), Some(9));
        assert_eq!(kernel_drops_in(text, 1), None);
    }
}
