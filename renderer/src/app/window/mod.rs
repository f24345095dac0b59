//! Windowed presentation (issue 7): one winit window per display channel, each with its own
//! surface and swapchain, all drawn by one [`TerrainRenderer`](crate::render::frame::TerrainRenderer) (one device) from one aircraft
//! pose sample per frame.
//!
//! The flow of one frame: the pose source gives the aircraft pose; for every channel that can be
//! drawn, its swapchain image is acquired, the terrain is rendered from the channel's camera
//! ([`channel_camera`](crate::sim::channel::channel_camera)) and blitted into the image by
//! [`TerrainRenderer::render_frame`](crate::render::frame::TerrainRenderer::render_frame), and
//! the image is presented.
//!
//! - Swapchains are recreated after a resize, an out-of-date or a suboptimal result.
//! - Minimised windows (or a zero-sized surface) are skipped; when nothing can be drawn the loop
//!   waits for window events (waking at most every 100 ms) instead of spinning.
//! - Fullscreen is borderless on the chosen monitor, or exclusive with the video mode of the
//!   channel's resolution; the cursor is hidden in fullscreen.
//! - Esc or closing a window ends the run; every swapchain and surface is destroyed before
//!   returning, so the renderer can then be destroyed with nothing left over.
//! - Bad input found only when the windows open (unknown monitor, unsupported present mode, no
//!   video mode of the requested size) stops everything before the first frame, as a
//!   [`WindowError::Channel`] naming the channel's key.
//!
//! - With several channels, one tile selection serves all of them
//!   ([`TerrainRenderer::set_channels`](crate::render::frame::TerrainRenderer::set_channels)), so shared tiles match across seams. The renderer has
//!   one offscreen target: channels of one process should share a render resolution, otherwise
//!   the target is recreated (after a device wait) whenever consecutive channels differ.
//!
//! A session runs on a caller-owned [`EventLoop`] through `run_app_on_demand`, so one process
//! (e.g. a test binary) can run several sessions; winit allows one event loop per process.

pub mod channel_window;
pub mod display;
pub mod monitor;
pub mod pose_source;
pub mod report;
pub mod session;

pub use display::{new_event_loop, required_instance_extensions, EventLoop};
pub use monitor::{
    choose_video_mode, describe_monitors, select_monitor, vk_present_mode, MonitorInfo,
};
pub use pose_source::PoseSource;
pub use report::{
    Action, ChannelReport, ExitReason, RunOptions, RunReport, ScheduledAction, WindowError,
};
pub use session::{is_overlay_toggle, run_channels};

#[cfg(test)]
mod tests;
