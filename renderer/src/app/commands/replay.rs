//! `aerie replay <file>`: sends the datagrams of a recording (`aerie listen --record`) to a
//! UDP address, with their recorded timing or (`--fast`) back to back — deterministic flights
//! for tests and benchmarks.

use std::net::{SocketAddr, UdpSocket};
use std::path::PathBuf;

use aerie_sim_bridge::record::{read_recording, replay, ReplayTiming};
use clap::Args;

use crate::app::failure::{bad_input, runtime, Failure};
use crate::app::progress::human_bytes;

#[derive(Debug, Args)]
pub struct ReplayArgs {
    /// Recording written by `aerie listen --record`.
    pub file: PathBuf,
    /// Where to send the datagrams.
    #[arg(long, default_value = "127.0.0.1:47800")]
    pub to: SocketAddr,
    /// Send as fast as possible instead of with the recorded timing.
    #[arg(long)]
    pub fast: bool,
}

pub fn run(a: ReplayArgs) -> Result<(), Failure> {
    let packets = read_recording(&a.file).map_err(bad_input)?;
    if packets.is_empty() {
        println!("{}: no datagrams to replay", a.file.display());
        return Ok(());
    }
    let local = if a.to.is_ipv4() {
        "0.0.0.0:0"
    } else {
        "[::]:0"
    };
    let socket = UdpSocket::bind(local).map_err(|e| runtime(format!("bind {local}: {e}")))?;
    let bar = indicatif::ProgressBar::new(packets.len() as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{msg} [{bar:30}] {pos}/{len} datagrams, eta {eta}",
        )
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    bar.set_message("replaying");
    let timing = if a.fast {
        ReplayTiming::Fast
    } else {
        ReplayTiming::Original
    };
    let report = replay(&packets, &socket, a.to, timing, |n| {
        if n % 64 == 0 {
            bar.set_position(n as u64);
        }
    })
    .map_err(|e| runtime(format!("send to {}: {e}", a.to)))?;
    bar.finish_and_clear();
    let lateness = match timing {
        ReplayTiming::Original => format!(
            ", latest send {:.2} ms behind its time",
            report.max_late_s * 1e3
        ),
        ReplayTiming::Fast => " (--fast)".into(),
    };
    println!(
        "replayed {} datagrams ({}) from {} to {} in {:.3} s (recorded span {:.3} s){lateness}",
        report.packets,
        human_bytes(report.bytes),
        a.file.display(),
        a.to,
        report.elapsed_s,
        report.recorded_span_s,
    );
    Ok(())
}
