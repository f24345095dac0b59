//! What a windowed session is asked to do and what it reports: options, scheduled actions,
//! why it ended, per-channel figures, and its error type.

use crate::vk::VkError;

/// Why windowed presentation failed.
#[derive(Debug, thiserror::Error)]
pub enum WindowError {
    /// Bad input only detectable with the windows open (unknown monitor, unsupported present
    /// mode, missing video mode): the channel's index in the config, the key and the reason.
    #[error("channel[{channel}].{key}: {message}")]
    Channel {
        channel: usize,
        key: &'static str,
        message: String,
    },
    /// The window system (no display, window creation failed...).
    #[error("{0}")]
    System(String),
    #[error(transparent)]
    Vulkan(#[from] VkError),
}

impl WindowError {
    /// True for errors caused by the configuration (exit code 2), false for run-time failures.
    pub fn is_bad_input(&self) -> bool {
        matches!(self, WindowError::Channel { .. })
    }
}

/// Something done to a window at a given frame (tests, demos).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Action {
    /// `Window::request_inner_size` on channel `channel`'s window.
    Resize {
        channel: usize,
        width: u32,
        height: u32,
    },
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ScheduledAction {
    /// Applied before drawing this frame (0-based).
    pub frame: u64,
    pub action: Action,
}

/// When a session ends, besides Esc and closing a window.
#[derive(Debug, Clone, Default)]
pub struct RunOptions {
    pub max_frames: Option<u64>,
    pub max_seconds: Option<f64>,
    pub actions: Vec<ScheduledAction>,
    /// Start with the statistics overlay shown (F1 or O toggles it).
    pub overlay: bool,
}

/// Why a session ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum ExitReason {
    Frames,
    Seconds,
    Escape,
    Closed,
}

/// What one channel's window did.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct ChannelReport {
    pub name: String,
    /// The monitor it was placed on (name or "#index"), when one was chosen.
    pub monitor: Option<String>,
    pub fullscreen: Option<String>,
    pub present_mode: String,
    /// Images presented.
    pub presented: u64,
    /// Frames this channel did not draw (minimised, zero-sized, out of date twice).
    pub skipped: u64,
    /// Swapchains created, the first one included.
    pub swapchain_builds: u32,
    /// Distinct swapchain extents in the order they were used.
    pub extents: Vec<[u32; 2]>,
    /// Render resolution of the last frame drawn.
    pub render_size: [u32; 2],
    /// Frames presented with the statistics overlay on.
    pub overlay_frames: u64,
}

/// What a session did.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct RunReport {
    /// Frames drawn (pose samples taken).
    pub frames: u64,
    /// Times the loop found nothing to draw and waited for events.
    pub idle_waits: u64,
    /// Wall time between the starts of consecutive frames, milliseconds.
    pub frame_ms: Vec<f64>,
    pub seconds: f64,
    pub exit: ExitReason,
    pub channels: Vec<ChannelReport>,
}
