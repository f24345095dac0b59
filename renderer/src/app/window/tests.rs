//! The window module's pure choices: monitors, video modes, present modes, the overlay key,
//! closures as pose sources.

use aerie_config::{MonitorSelector, PresentMode};
use ash::vk;
use winit::event::ElementState;
use winit::keyboard::{Key, NamedKey};

use crate::app::window::monitor::{
    choose_video_mode, select_monitor, vk_present_mode, MonitorInfo,
};
use crate::app::window::pose_source::PoseSource;
use crate::app::window::session::is_overlay_toggle;
use crate::sim::channel::AircraftPose;
use crate::tools::overlay::OverlayState;

fn monitors() -> Vec<MonitorInfo> {
    vec![
        MonitorInfo {
            name: Some("DP-1".into()),
            size: (1920, 1080),
            position: (0, 0),
        },
        MonitorInfo {
            name: Some("HDMI-A-1".into()),
            size: (2560, 1440),
            position: (1920, 0),
        },
        MonitorInfo {
            name: None,
            size: (800, 600),
            position: (0, 1080),
        },
    ]
}

#[test]
fn monitors_are_chosen_by_index_or_name() {
    let m = monitors();
    assert_eq!(select_monitor(&MonitorSelector::Index(2), &m), Ok(2));
    assert_eq!(
        select_monitor(&MonitorSelector::Name("HDMI-A-1".into()), &m),
        Ok(1)
    );
    assert_eq!(
        select_monitor(&MonitorSelector::Name("dp-1".into()), &m),
        Ok(0)
    );
}

#[test]
fn unknown_monitor_lists_the_monitors_found() {
    let m = monitors();
    let e = select_monitor(&MonitorSelector::Name("DVI-9".into()), &m).unwrap_err();
    assert_eq!(
        e,
        "unknown monitor \"DVI-9\"; monitors found: 0: \"DP-1\" 1920x1080 at (0, 0); 1: \"HDMI-A-1\" 2560x1440 at (1920, 0); 2: (unnamed) 800x600 at (0, 1080)"
    );
    let e = select_monitor(&MonitorSelector::Index(3), &m).unwrap_err();
    assert!(
        e.starts_with("unknown monitor 3; monitors found: 0: "),
        "{e}"
    );
    let e = select_monitor(&MonitorSelector::Index(0), &[]).unwrap_err();
    assert_eq!(e, "unknown monitor 0; no monitors found");
}

#[test]
fn video_mode_matches_the_resolution_at_the_best_refresh() {
    let modes = [
        (1920, 1080, 60_000),
        (1920, 1080, 144_000),
        (1280, 720, 60_000),
        (2560, 1440, 60_000),
    ];
    assert_eq!(choose_video_mode(&modes, Some((1920, 1080))), Ok(1));
    assert_eq!(choose_video_mode(&modes, None), Ok(3));
    let e = choose_video_mode(&modes, Some((1024, 768))).unwrap_err();
    assert_eq!(
        e,
        "the monitor has no 1024x768 video mode for exclusive fullscreen (modes: 1920x1080, 1280x720, 2560x1440)"
    );
}

#[test]
fn present_modes_map_to_vulkan() {
    assert_eq!(vk_present_mode(PresentMode::Fifo), vk::PresentModeKHR::FIFO);
    assert_eq!(
        vk_present_mode(PresentMode::Mailbox),
        vk::PresentModeKHR::MAILBOX
    );
    assert_eq!(
        vk_present_mode(PresentMode::Immediate),
        vk::PresentModeKHR::IMMEDIATE
    );
}

#[test]
fn f1_and_o_toggle_the_overlay_once_per_press() {
    use winit::keyboard::SmolStr;
    let pressed = ElementState::Pressed;
    let o = Key::Character(SmolStr::new("o"));
    let big_o = Key::Character(SmolStr::new("O"));
    let f1 = Key::Named(NamedKey::F1);
    assert!(is_overlay_toggle(&o, pressed, false));
    assert!(is_overlay_toggle(&big_o, pressed, false));
    assert!(is_overlay_toggle(&f1, pressed, false));
    // Releases and auto-repeat do nothing; other keys neither.
    assert!(!is_overlay_toggle(&f1, ElementState::Released, false));
    assert!(!is_overlay_toggle(&o, pressed, true));
    assert!(!is_overlay_toggle(
        &Key::Character(SmolStr::new("p")),
        pressed,
        false
    ));
    assert!(!is_overlay_toggle(
        &Key::Named(NamedKey::F2),
        pressed,
        false
    ));
    assert!(!is_overlay_toggle(
        &Key::Named(NamedKey::Escape),
        pressed,
        false
    ));
    // A press, its repeats and its release flip the state exactly once.
    let mut s = OverlayState::new(false);
    for (state, repeat) in [
        (pressed, false),
        (pressed, true),
        (pressed, true),
        (ElementState::Released, false),
    ] {
        if is_overlay_toggle(&o, state, repeat) {
            s.toggle();
        }
    }
    assert!(s.is_on());
}

#[test]
fn closures_are_pose_sources() {
    let mut calls = Vec::new();
    let mut src = |frame: u64, t: f64| {
        calls.push((frame, t));
        AircraftPose {
            position: glam::DVec3::new(frame as f64, 0.0, 0.0),
            attitude: aerie_terrain::camera::Attitude::from_degrees(0.0, 0.0, 0.0),
        }
    };
    let p = PoseSource::pose(&mut src, 7, 0.5);
    assert_eq!(p.position.x, 7.0);
    assert_eq!(calls, [(7, 0.5)]);
}
