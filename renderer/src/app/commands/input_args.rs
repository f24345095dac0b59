//! The pose-input flags, one clap struct flattened into `aerie listen` and `aerie run` so both
//! commands (and `aerie-send`, which mirrors them) speak one vocabulary: `--listen`,
//! `--protocol auto|native|cigi|xplane|fgfs|shm`, `--shm-name`, `--multicast`,
//! `--multicast-if`, `--allow`, `--max-extrapolation-ms`, `--world-bound-m`, `--xplane`,
//! `--xplane-rate`. The spellings `listen` used before
//! (`--bind`, `--shm`, `--cap-ms`, `--protocol aerie`) still parse, hidden from `--help`.

use std::net::{IpAddr, Ipv4Addr, SocketAddr, SocketAddrV4};

use aerie_sim_bridge::codec::{Protocol, ProtocolChoice};
use aerie_sim_bridge::udp::RposRequest;
use aerie_sim_bridge::DEFAULT_PORT;
use clap::Args;

use crate::app::failure::{bad_input, Failure};
use crate::sim::pose_input::InputProtocol;

// Where a simulator's poses come from: a UDP port (optionally a multicast group) or the
// shared-memory file. Every field is optional so a command can tell "not given" from a
// default (`aerie run` then falls back to the config's `[input]`). A plain comment, not a doc
// comment: clap would make a doc comment the about text of every command that flattens this.
// Flatten it last: its help heading also applies to the fields after it.
#[derive(Debug, Clone, Default, PartialEq, Args)]
#[command(next_help_heading = "Pose input")]
pub struct InputArgs {
    /// UDP address to receive poses on (default 127.0.0.1:47800; 0.0.0.0:47800 with
    /// --multicast, or to hear other machines).
    #[arg(long, alias = "bind", value_name = "ADDR:PORT")]
    pub listen: Option<SocketAddr>,
    /// Pose protocol: auto (detected per datagram), native, cigi, xplane, fgfs, or shm (shared
    /// memory, see --shm-name). In `aerie run` any of these flags replaces the built-in pass
    /// by the simulator's stream.
    #[arg(long, value_name = "PROTOCOL", value_parser = parse_protocol)]
    pub protocol: Option<InputProtocol>,
    /// Shared-memory pose file: a name in /dev/shm or a path (implies --protocol shm; default
    /// aerie-pose).
    #[arg(long, alias = "shm", value_name = "NAME")]
    pub shm_name: Option<String>,
    /// Join this IPv4 multicast group (several channel machines on one stream).
    #[arg(long, value_name = "GROUP")]
    pub multicast: Option<Ipv4Addr>,
    /// With --multicast: local interface address to join on (default: the kernel chooses;
    /// 127.0.0.1 for processes on one host without a multicast route).
    #[arg(long, value_name = "IPV4")]
    pub multicast_if: Option<Ipv4Addr>,
    /// Accept poses only from these source addresses (comma-separated); others are dropped
    /// and counted.
    #[arg(long, value_delimiter = ',', value_name = "IP,...")]
    pub allow: Vec<IpAddr>,
    /// Carry a pose forward to the frame's display time by at most this much, milliseconds
    /// (run: 0 draws poses as received); also how long without a pose before the stream counts
    /// as lost. Default: 100 (run: input.max_extrapolation_ms first).
    #[arg(long, alias = "cap-ms", value_name = "MS", allow_hyphen_values = true)]
    pub max_extrapolation_ms: Option<f64>,
    /// Drop local (ENU) poses with any axis beyond ±this many metres as implausible, (0, 1e9].
    /// Default: 1e7 (run: input.world_bound_m first).
    #[arg(
        long,
        value_name = "M",
        value_parser = parse_world_bound,
        allow_hyphen_values = true
    )]
    pub world_bound_m: Option<f64>,
    /// Ask the X-Plane at this address (its UDP port, usually 49000) to stream RPOS to the
    /// --listen port: at start, and again after 2 s without RPOS (X-Plane restarted).
    #[arg(long, value_name = "IP:PORT")]
    pub xplane: Option<SocketAddr>,
    /// With --xplane: the RPOS rate to ask for, positions per second (default 60).
    #[arg(long, value_name = "HZ")]
    pub xplane_rate: Option<u32>,
}

/// `--xplane-rate` default, positions per second.
pub const DEFAULT_XPLANE_RATE: u32 = 60;

/// `--world-bound-m`: metres in (0, 1e9].
pub fn parse_world_bound(s: &str) -> Result<f64, String> {
    let v: f64 = s
        .trim()
        .parse()
        .map_err(|_| format!("expected a number of metres, got {s:?}"))?;
    aerie_sim_bridge::PoseLimits::with_world_bound(v).map(|l| l.world_bound_m)
}

/// `--protocol`: the command-line words (`aerie` is the old name of `native`).
pub fn parse_protocol(s: &str) -> Result<InputProtocol, String> {
    s.parse()
}

impl InputArgs {
    /// True when any flag asks for a pose input.
    pub fn any(&self) -> bool {
        self.wants_udp() || self.protocol.is_some() || self.shm_name.is_some()
    }

    /// True when a flag only UDP has is given (`--listen`, `--multicast`, `--allow`,
    /// `--xplane`).
    pub fn wants_udp(&self) -> bool {
        self.listen.is_some()
            || self.multicast.is_some()
            || !self.allow.is_empty()
            || self.xplane.is_some()
    }

    /// The RPOS request `--xplane` (and `--xplane-rate`) ask for.
    pub fn rpos_request(&self) -> Option<RposRequest> {
        self.xplane.map(|xplane| RposRequest {
            xplane,
            rate_hz: self.xplane_rate.unwrap_or(DEFAULT_XPLANE_RATE),
        })
    }

    /// The protocol the flags pick: `--protocol`, else shared memory for `--shm-name`.
    pub fn chosen_protocol(&self) -> Option<InputProtocol> {
        self.protocol
            .or(self.shm_name.is_some().then_some(InputProtocol::Shm))
    }

    /// True when the flags choose shared memory.
    pub fn wants_shm(&self) -> bool {
        self.chosen_protocol() == Some(InputProtocol::Shm)
    }

    /// Refuses flags that contradict each other: shared memory with a UDP flag (`udp_only`
    /// adds a command's own UDP-only flags, e.g. `listen --record`), `--shm-name` with a UDP
    /// protocol, `--xplane` with a protocol other than auto or xplane, `--xplane-rate` without
    /// `--xplane` or 0 (which asks X-Plane to stop). Whether `--multicast-if` has a group is
    /// the command's check (`run` also accepts the config's group).
    pub fn check(&self, udp_only: &[(&str, bool)]) -> Result<(), Failure> {
        let shm = self.wants_shm();
        let mut flags = vec![
            ("--listen", self.listen.is_some()),
            ("--multicast", self.multicast.is_some()),
            ("--allow", !self.allow.is_empty()),
            ("--xplane", self.xplane.is_some()),
        ];
        flags.extend_from_slice(udp_only);
        if shm && flags.iter().any(|&(_, given)| given) {
            let names: Vec<&str> = flags.iter().map(|&(name, _)| name).collect();
            let list = match names.split_last() {
                Some((last, [])) => last.to_string(),
                Some((last, rest)) => format!("{} and {last}", rest.join(", ")),
                None => String::new(),
            };
            return Err(bad_input(format!(
                "--protocol shm reads shared memory: {list} apply to UDP only"
            )));
        }
        if !shm && self.shm_name.is_some() {
            return Err(bad_input("--shm-name: only with --protocol shm"));
        }
        if let (Some(_), Some(InputProtocol::Udp(ProtocolChoice::Only(p)))) =
            (self.xplane, self.protocol)
        {
            if p != Protocol::XPlane {
                return Err(bad_input(format!(
                    "--xplane with --protocol {p}: the RPOS stream asked for would be dropped (use --protocol xplane or auto)"
                )));
            }
        }
        match (self.xplane, self.xplane_rate) {
            (None, Some(_)) => return Err(bad_input("--xplane-rate: only with --xplane")),
            (Some(_), Some(0)) => {
                return Err(bad_input(
                    "--xplane-rate 0: a rate of 0 asks X-Plane to stop sending; give 1 or more",
                ))
            }
            _ => {}
        }
        Ok(())
    }

    /// The UDP address to bind: `--listen`, else the default port on loopback, or on every
    /// interface when joining a multicast group (a socket bound to loopback never sees a
    /// group's datagrams).
    pub fn listen_or_default(listen: Option<SocketAddr>, multicast: bool) -> SocketAddr {
        let host = if multicast {
            Ipv4Addr::UNSPECIFIED
        } else {
            Ipv4Addr::LOCALHOST
        };
        listen.unwrap_or(SocketAddr::V4(SocketAddrV4::new(host, DEFAULT_PORT)))
    }
}

#[cfg(test)]
#[path = "input_args_tests.rs"]
mod tests;
