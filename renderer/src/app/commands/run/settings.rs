//! The settings `aerie run` runs with: each flag, else the config's key (`[input]`,
//! `render.fps`), else the default. Pure: no socket, no file.

use std::net::Ipv4Addr;

use aerie_config::{InputProtocolName, RenderConfig};
use aerie_sim_bridge::codec::ProtocolChoice;
use aerie_sim_bridge::pose::DEFAULT_WORLD_BOUND_M;
use aerie_sim_bridge::shm::DEFAULT_SHM_NAME;

use crate::app::commands::input_args::InputArgs;
use crate::app::commands::run::args::RunArgs;
use crate::app::failure::{bad_input, Failure};
use crate::sim::pose_input::{HostHeights, InputProtocol, InputSpec};

/// Default `--max-extrapolation-ms` / `input.max_extrapolation_ms`.
pub const DEFAULT_MAX_EXTRAPOLATION_MS: f64 = 100.0;
/// Default `--wait-pose-s` / `input.wait_pose_s`.
pub const DEFAULT_WAIT_POSE_S: f64 = 10.0;
/// Default `--fps` / `render.fps`.
pub const DEFAULT_FPS: f64 = 60.0;

/// The run settings in effect: each command-line flag, else the config's key, else the default.
#[derive(Debug, Clone)]
pub struct RunSettings {
    /// The simulator input, if any flag or `[input]` key asks for one.
    pub input: Option<InputSpec>,
    pub max_extrapolation_ms: f64,
    pub wait_pose_s: f64,
    pub fps: f64,
}

fn config_protocol(p: InputProtocolName) -> InputProtocol {
    // The config names are a subset of what --protocol parses.
    p.as_str().parse().expect("config protocol names parse")
}

/// Merges the input flags over the config's `[input]` (and `render.fps`): a flag given wins,
/// a key the file gives comes next, then the defaults. A flag that picks the transport
/// (`--protocol`, `--shm-name` for shared memory, `--listen`/`--multicast`/`--allow` for UDP)
/// also drops the config keys of the other transport. Pure: no socket, no file.
pub fn resolve_settings(a: &RunArgs, config: &RenderConfig) -> Result<RunSettings, Failure> {
    let c = &config.input;
    let max_extrapolation_ms = a
        .input
        .max_extrapolation_ms
        .or(c.max_extrapolation_ms)
        .unwrap_or(DEFAULT_MAX_EXTRAPOLATION_MS);
    let wait_pose_s = a
        .wait_pose_s
        .or(c.wait_pose_s)
        .unwrap_or(DEFAULT_WAIT_POSE_S);
    let fps = a.fps.or(config.render.fps).unwrap_or(DEFAULT_FPS);
    let sync_frames = a.sync_frames.or(c.sync_frames);
    let host_heights = a
        .host_heights
        .or(c.host_heights.map(HostHeights::of_config))
        .unwrap_or_default();
    let world_bound_m = a
        .input
        .world_bound_m
        .or(c.world_bound_m)
        .unwrap_or(DEFAULT_WORLD_BOUND_M);
    let cli_udp = a.input.wants_udp();
    let wanted = a.input.any() || c.wants_input();
    if let Some(k) = sync_frames.filter(|&k| k > aerie_config::MAX_SYNC_FRAMES) {
        return Err(bad_input(format!(
            "--sync-frames: {k} is more than the {} host frames kept (0..={})",
            aerie_config::MAX_SYNC_FRAMES + 1,
            aerie_config::MAX_SYNC_FRAMES
        )));
    }
    if !wanted {
        if sync_frames.is_some() {
            return Err(bad_input(
                "--sync-frames: needs a pose input (--listen, --protocol, --multicast or --shm-name, or an [input] protocol in the config)",
            ));
        }
        if a.host_heights.is_some() {
            return Err(bad_input(
                "--host-heights: needs a pose input (--listen, --protocol, --multicast or --shm-name, or an [input] protocol in the config)",
            ));
        }
        return Ok(RunSettings {
            input: None,
            max_extrapolation_ms,
            wait_pose_s,
            fps,
        });
    }
    let cli_protocol = a.input.chosen_protocol();
    let config_protocol = c
        .protocol
        .map(config_protocol)
        .or(c.shm_name.is_some().then_some(InputProtocol::Shm));
    let protocol = cli_protocol
        .or(config_protocol.filter(|p| !(cli_udp && *p == InputProtocol::Shm)))
        .unwrap_or(InputProtocol::Udp(ProtocolChoice::Auto));
    let shm = protocol == InputProtocol::Shm;
    // Keys of the other transport do not apply (the config itself refuses mixing them).
    let (cfg_listen, cfg_multicast, cfg_if, cfg_allow, cfg_shm) = if shm {
        (None, None, None, Vec::new(), c.shm_name.clone())
    } else {
        (c.listen, c.multicast, c.multicast_if, c.allow.clone(), None)
    };
    let multicast = a.input.multicast.or(cfg_multicast);
    let multicast_if = a.input.multicast_if.or(cfg_if);
    if multicast_if.is_some() && multicast.is_none() {
        return Err(bad_input(
            "--multicast-if: only with --multicast (or input.multicast)",
        ));
    }
    Ok(RunSettings {
        input: Some(InputSpec {
            protocol,
            listen: InputArgs::listen_or_default(
                a.input.listen.or(cfg_listen),
                multicast.is_some(),
            ),
            multicast,
            multicast_interface: multicast_if.unwrap_or(Ipv4Addr::UNSPECIFIED),
            allow: if a.input.allow.is_empty() {
                cfg_allow
            } else {
                a.input.allow.clone()
            },
            shm_name: a
                .input
                .shm_name
                .clone()
                .or(cfg_shm)
                .unwrap_or_else(|| DEFAULT_SHM_NAME.to_string()),
            cap_s: max_extrapolation_ms / 1e3,
            sync_frames,
            world_bound_m,
            xplane_rpos: a.input.rpos_request(),
            host_heights,
        }),
        max_extrapolation_ms,
        wait_pose_s,
        fps,
    })
}
