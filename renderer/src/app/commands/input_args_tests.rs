//! The pose-input flags: one spelling per setting, the old spellings as hidden aliases, and the
//! checks both commands share.

use std::net::{Ipv4Addr, SocketAddr};

use aerie_sim_bridge::codec::{Protocol, ProtocolChoice};
use clap::{CommandFactory, Parser};

use crate::app::commands::input_args::InputArgs;
use crate::sim::pose_input::InputProtocol;

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
            "--protocol shm reads shared memory: --listen, --multicast and --allow apply to UDP only"
                .into()
        ))
    );
    // --shm-name alone means shared memory; a command's own UDP-only flag is named.
    assert_eq!(
        refused(&["--shm-name", "sim"], &[("--record", true)]),
        Some((
            2,
            "--protocol shm reads shared memory: --listen, --multicast, --allow and --record apply to UDP only"
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
    ] {
        assert!(parse(args).any(), "{args:?}");
    }
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
