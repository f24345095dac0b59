//! The pose-input flags: one spelling per setting, the old spellings as hidden aliases, and the
//! checks both commands share.

use std::net::{Ipv4Addr, SocketAddr, UdpSocket};
use std::time::Duration;

use aerie_config::RenderConfig;
use aerie_sim_bridge::codec::{xplane, Protocol, ProtocolChoice};
use aerie_sim_bridge::udp::RposRequest;
use clap::{CommandFactory, Parser};

use crate::app::commands::input_args::{InputArgs, DEFAULT_XPLANE_RATE};
use crate::app::commands::run::args::RunArgs;
use crate::app::commands::run::settings::resolve_settings;
use crate::sim::pose_input::{InputProtocol, SimInput};

#[derive(Parser)]
struct Cli {
    #[command(flatten)]
    input: InputArgs,
}

fn parse(args: &[&str]) -> InputArgs {
    Cli::try_parse_from(std::iter::once("cmd").chain(args.iter().copied()))
        .unwrap_or_else(|e| panic!("{args:?}: {e}"))
        .input
}

#[test]
fn old_spellings_parse_to_the_same_values_as_the_new_ones() {
    for (old, new) in [
        (
            &["--bind", "0.0.0.0:5000"][..],
            &["--listen", "0.0.0.0:5000"][..],
        ),
        (&["--shm", "sim"], &["--shm-name", "sim"]),
        (&["--cap-ms", "40"], &["--max-extrapolation-ms", "40"]),
        (&["--protocol", "aerie"], &["--protocol", "native"]),
        (&["--protocol=AERIE"], &["--protocol=native"]),
    ] {
        assert_eq!(parse(old), parse(new), "{old:?} vs {new:?}");
    }
    let a = parse(&[
        "--bind",
        "127.0.0.1:47999",
        "--protocol",
        "aerie",
        "--cap-ms",
        "25",
    ]);
    assert_eq!(a.listen, Some("127.0.0.1:47999".parse().unwrap()));
    assert_eq!(
        a.protocol,
        Some(InputProtocol::Udp(ProtocolChoice::Only(Protocol::Aerie)))
    );
    assert_eq!(a.max_extrapolation_ms, Some(25.0));
    assert_eq!(parse(&["--shm", "x"]).shm_name.as_deref(), Some("x"));
}

#[test]
fn every_protocol_word_parses_and_a_wrong_one_lists_them() {
    for (word, want) in [
        ("auto", InputProtocol::Udp(ProtocolChoice::Auto)),
        (
            "native",
            InputProtocol::Udp(ProtocolChoice::Only(Protocol::Aerie)),
        ),
        (
            "cigi",
            InputProtocol::Udp(ProtocolChoice::Only(Protocol::Cigi)),
        ),
        (
            "xplane",
            InputProtocol::Udp(ProtocolChoice::Only(Protocol::XPlane)),
        ),
        (
            "fgfs",
            InputProtocol::Udp(ProtocolChoice::Only(Protocol::Fgfs)),
        ),
        ("shm", InputProtocol::Shm),
    ] {
        assert_eq!(parse(&["--protocol", word]).protocol, Some(want), "{word}");
    }
    let e = Cli::try_parse_from(["cmd", "--protocol", "ftp"])
        .err()
        .expect("refused")
        .to_string();
    assert!(
        e.contains("expected auto, native, cigi, xplane, fgfs or shm"),
        "{e}"
    );
}

#[test]
fn help_shows_only_the_new_names() {
    let help = Cli::command().render_long_help().to_string();
    for name in [
        "--listen",
        "--protocol",
        "--shm-name",
        "--multicast",
        "--multicast-if",
        "--allow",
        "--max-extrapolation-ms",
        "native, cigi, xplane, fgfs, or shm",
    ] {
        assert!(help.contains(name), "{name} missing from\n{help}");
    }
    for old in ["--bind", "--cap-ms", "--shm ", "aerie,", "aerie)"] {
        assert!(!help.contains(old), "{old} shown in\n{help}");
    }
}

#[test]
fn transport_flags_that_contradict_each_other_are_refused() {
    let refused = |args: &[&str], udp_only: &[(&str, bool)]| {
        parse(args)
            .check(udp_only)
            .err()
            .map(|f| (f.code, f.message))
    };
    assert_eq!(
        refused(&["--protocol", "shm", "--listen", "127.0.0.1:9"], &[]),
        Some((
            2,
            "--protocol shm reads shared memory: --listen, --multicast, --allow and --xplane apply to UDP only"
                .into()
        ))
    );
    // --shm-name alone means shared memory; a command's own UDP-only flag is named.
    assert_eq!(
        refused(&["--shm-name", "sim"], &[("--record", true)]),
        Some((
            2,
            "--protocol shm reads shared memory: --listen, --multicast, --allow, --xplane and --record apply to UDP only"
                .into()
        ))
    );
    assert_eq!(
        refused(&["--protocol", "cigi", "--shm-name", "x"], &[]),
        Some((2, "--shm-name: only with --protocol shm".into()))
    );
    assert_eq!(refused(&["--shm-name", "x"], &[("--record", false)]), None);
    assert_eq!(refused(&["--multicast", "239.1.2.3"], &[]), None);
    assert_eq!(refused(&[], &[]), None);
}

#[test]
fn what_turns_the_input_on_and_which_transport() {
    assert!(!parse(&[]).any());
    assert!(!parse(&["--max-extrapolation-ms", "5"]).any());
    for args in [
        &["--listen", "127.0.0.1:1"][..],
        &["--protocol", "auto"],
        &["--shm-name", "x"],
        &["--multicast", "239.1.2.3"],
        &["--allow", "127.0.0.2,127.0.0.3"],
        &["--xplane", "127.0.0.1:49000"],
    ] {
        assert!(parse(args).any(), "{args:?}");
    }
    assert!(parse(&["--xplane", "127.0.0.1:49000"]).wants_udp());
    assert!(parse(&["--shm-name", "x"]).wants_shm());
    assert!(parse(&["--protocol", "shm"]).wants_shm());
    assert!(!parse(&["--protocol", "native", "--shm-name", "x"]).wants_shm());
    assert_eq!(parse(&["--allow", "127.0.0.2,127.0.0.3"]).allow.len(), 2);
}

#[test]
fn the_default_address_is_loopback_or_every_interface_for_multicast() {
    let port = aerie_sim_bridge::DEFAULT_PORT;
    assert_eq!(
        InputArgs::listen_or_default(None, false),
        SocketAddr::from((Ipv4Addr::LOCALHOST, port))
    );
    assert_eq!(
        InputArgs::listen_or_default(None, true),
        SocketAddr::from((Ipv4Addr::UNSPECIFIED, port))
    );
    let given: SocketAddr = "127.0.0.1:9".parse().unwrap();
    assert_eq!(InputArgs::listen_or_default(Some(given), true), given);
}

#[test]
fn xplane_flags_ask_for_rpos_and_refuse_what_contradicts_them() {
    let xp: SocketAddr = "127.0.0.1:49000".parse().unwrap();
    assert_eq!(parse(&[]).rpos_request(), None);
    assert_eq!(
        parse(&["--xplane", "127.0.0.1:49000"]).rpos_request(),
        Some(RposRequest {
            xplane: xp,
            rate_hz: DEFAULT_XPLANE_RATE
        })
    );
    let a = parse(&["--xplane", "127.0.0.1:49000", "--xplane-rate", "20"]);
    assert_eq!(a.rpos_request().map(|r| r.rate_hz), Some(20));
    a.check(&[]).unwrap();
    parse(&["--xplane", "127.0.0.1:49000", "--protocol", "xplane"])
        .check(&[])
        .unwrap();
    parse(&["--xplane", "127.0.0.1:49000", "--protocol", "auto"])
        .check(&[])
        .unwrap();
    for (args, says) in [
        (
            &["--protocol", "shm", "--xplane", "127.0.0.1:49000"][..],
            "--protocol shm reads shared memory: --listen, --multicast, --allow and --xplane apply to UDP only",
        ),
        (
            &["--shm-name", "sim", "--xplane", "127.0.0.1:49000"],
            "--xplane apply to UDP only",
        ),
        (
            &["--protocol", "cigi", "--xplane", "127.0.0.1:49000"],
            "--xplane with --protocol cigi",
        ),
        (&["--xplane-rate", "30"], "--xplane-rate: only with --xplane"),
        (
            &["--xplane", "127.0.0.1:49000", "--xplane-rate", "0"],
            "--xplane-rate 0",
        ),
    ] {
        let f = parse(args).check(&[]).expect_err("refused");
        assert_eq!(f.code, 2, "{args:?}");
        assert!(f.message.contains(says), "{args:?}: {}", f.message);
    }
    let help = Cli::command().render_long_help().to_string();
    assert!(
        help.contains("--xplane <IP:PORT>") && help.contains("--xplane-rate"),
        "{help}"
    );
}

#[derive(Parser)]
struct RunCli {
    #[command(flatten)]
    args: RunArgs,
}

/// `aerie run --xplane`: the run command's input path (flags → settings → `SimInput`) sends a
/// fake X-Plane the RPOS request from the pose port, and sends it again when no RPOS arrives
/// (the receive loop renews it after 2 s without one).
#[test]
fn run_asks_xplane_for_rpos_and_renews_the_request() {
    let xplane = UdpSocket::bind("127.0.0.1:0").unwrap();
    xplane
        .set_read_timeout(Some(Duration::from_secs(10)))
        .unwrap();
    let xp = xplane.local_addr().unwrap().to_string();
    let argv = [
        "run",
        "--dem",
        "x",
        "--listen",
        "127.0.0.1:0",
        "--xplane",
        &xp,
        "--xplane-rate",
        "30",
    ];
    let args = RunCli::try_parse_from(argv).unwrap().args;
    let spec = resolve_settings(&args, &RenderConfig::default())
        .unwrap()
        .input
        .expect("--xplane turns the input on");
    assert_eq!(spec.protocol, InputProtocol::Udp(ProtocolChoice::Auto));
    let input = SimInput::open(&spec, Err("no geo-reference".into())).unwrap();
    let port = input.local_addr().unwrap();
    let mut buf = [0u8; 64];
    let mut requests = 0;
    while requests < 2 {
        let (n, from) = match xplane.recv_from(&mut buf) {
            Ok(x) => x,
            // An ICMP error for some other socket's datagram on this port: not an answer.
            Err(e) if e.kind() == std::io::ErrorKind::ConnectionRefused => continue,
            Err(e) => panic!("no RPOS request within 10 s: {e}"),
        };
        assert_eq!(&buf[..n], &xplane::rpos_request(30)[..]);
        // From the pose port, so that X-Plane streams to it.
        assert_eq!(from, port);
        requests += 1;
    }
    drop(input);
}
