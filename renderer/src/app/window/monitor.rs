//! Monitors, video modes and present modes: pure choices from what the window system offers,
//! with error messages that list the alternatives.

use aerie_config::{MonitorSelector, PresentMode};
use ash::vk;
use winit::monitor::MonitorHandle;

/// A monitor as the window system describes it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct MonitorInfo {
    pub name: Option<String>,
    pub size: (u32, u32),
    pub position: (i32, i32),
}

/// What the window system says about `m`.
pub fn monitor_info(m: &MonitorHandle) -> MonitorInfo {
    let size = m.size();
    let pos = m.position();
    MonitorInfo {
        name: m.name(),
        size: (size.width, size.height),
        position: (pos.x, pos.y),
    }
}

/// "0: \"DP-1\" 1920x1080 at (0, 0); 1: …", for error messages.
pub fn describe_monitors(monitors: &[MonitorInfo]) -> String {
    if monitors.is_empty() {
        return "no monitors found".into();
    }
    let list: Vec<String> = monitors
        .iter()
        .enumerate()
        .map(|(i, m)| {
            format!(
                "{i}: {} {}x{} at ({}, {})",
                m.name
                    .as_deref()
                    .map(|n| format!("{n:?}"))
                    .unwrap_or_else(|| "(unnamed)".into()),
                m.size.0,
                m.size.1,
                m.position.0,
                m.position.1
            )
        })
        .collect();
    format!("monitors found: {}", list.join("; "))
}

/// The index of the monitor `sel` names (exact name first, then ignoring case), or an error
/// listing the monitors found.
pub fn select_monitor(sel: &MonitorSelector, monitors: &[MonitorInfo]) -> Result<usize, String> {
    let found = match sel {
        MonitorSelector::Index(i) => Some(*i as usize).filter(|&i| i < monitors.len()),
        MonitorSelector::Name(n) => monitors
            .iter()
            .position(|m| m.name.as_deref() == Some(n.as_str()))
            .or_else(|| {
                monitors.iter().position(|m| {
                    m.name
                        .as_deref()
                        .is_some_and(|mn| mn.eq_ignore_ascii_case(n))
                })
            }),
    };
    found.ok_or_else(|| format!("unknown monitor {sel}; {}", describe_monitors(monitors)))
}

/// The video mode for exclusive fullscreen: `(width, height, refresh mHz)` of each mode; the
/// one of size `wanted` with the highest refresh rate, or the largest mode when no size is
/// asked for. The error lists the sizes offered.
pub fn choose_video_mode(
    modes: &[(u32, u32, u32)],
    wanted: Option<(u32, u32)>,
) -> Result<usize, String> {
    let best = modes
        .iter()
        .enumerate()
        .filter(|(_, m)| wanted.is_none_or(|w| (m.0, m.1) == w))
        .max_by_key(|(_, m)| (m.0 as u64 * m.1 as u64, m.2))
        .map(|(i, _)| i);
    best.ok_or_else(|| {
        let mut sizes: Vec<String> = modes.iter().map(|m| format!("{}x{}", m.0, m.1)).collect();
        sizes.dedup();
        match wanted {
            Some((w, h)) => format!(
                "the monitor has no {w}x{h} video mode for exclusive fullscreen (modes: {})",
                if sizes.is_empty() {
                    "none".into()
                } else {
                    sizes.join(", ")
                }
            ),
            None => "the monitor offers no video mode for exclusive fullscreen".into(),
        }
    })
}

/// The Vulkan present mode of a config value.
pub fn vk_present_mode(mode: PresentMode) -> vk::PresentModeKHR {
    match mode {
        PresentMode::Fifo => vk::PresentModeKHR::FIFO,
        PresentMode::Mailbox => vk::PresentModeKHR::MAILBOX,
        PresentMode::Immediate => vk::PresentModeKHR::IMMEDIATE,
    }
}
