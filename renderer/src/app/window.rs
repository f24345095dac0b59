//! Windowed presentation (issue 7): one winit window per display channel, each with its own
//! surface and swapchain, all drawn by one [`TerrainRenderer`] (one device) from one aircraft
//! pose sample per frame.
//!
//! The flow of one frame: the pose source gives the aircraft pose; for every channel that can be
//! drawn, its swapchain image is acquired, the terrain is rendered from the channel's camera
//! ([`channel_camera`]) and blitted into the image by
//! [`TerrainRenderer::render_frame`], and the image is presented.
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
//!   ([`TerrainRenderer::set_channels`]), so shared tiles match across seams. The renderer has
//!   one offscreen target: channels of one process should share a render resolution, otherwise
//!   the target is recreated (after a device wait) whenever consecutive channels differ.
//!
//! A session runs on a caller-owned [`EventLoop`] through `run_app_on_demand`, so one process
//! (e.g. a test binary) can run several sessions; winit allows one event loop per process.

use std::ffi::{CStr, CString};
use std::time::{Duration, Instant};

use aerie_config::{Channel, ChannelDisplay, FullscreenMode, MonitorSelector, PresentMode};
use ash::vk;
use raw_window_handle::{HasDisplayHandle, HasWindowHandle};
use winit::application::ApplicationHandler;
use winit::dpi::{PhysicalPosition, PhysicalSize};
use winit::event::{ElementState, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow};
use winit::keyboard::{Key, NamedKey};
use winit::monitor::{MonitorHandle, VideoModeHandle};
use winit::platform::run_on_demand::EventLoopExtRunOnDemand;
use winit::window::{Fullscreen, Window, WindowId};

use crate::render::frame::{FrameStats, TerrainRenderer};
use crate::sim::channel::AircraftPose;
use crate::sim::host_view::LiveChannel;
use crate::tools::overlay::{OverlayInfo, OverlayState};
use crate::vk::swapchain::{choose_present_mode, Acquire, Presented, Surface, Swapchain};
use crate::vk::{Device, Instance, VkError};

/// The winit event loop type sessions run on (re-exported so callers need no winit dependency).
pub use winit::event_loop::EventLoop;

/// How long an idle loop (every window minimised) sleeps between checks when no event comes.
const IDLE_WAIT: Duration = Duration::from_millis(100);

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

/// Where the aircraft is for each frame: the seam where the built-in flight, a recording or the
/// simulator's UDP stream plugs in. Called once per frame; every channel of that frame uses the
/// same pose.
pub trait PoseSource {
    /// The pose to draw for display frame `frame` (0-based), `t_s` seconds after the first
    /// frame began.
    fn pose(&mut self, frame: u64, t_s: f64) -> AircraftPose;

    /// Age of the pose last returned (its packet's arrival to the frame's predicted display
    /// time), milliseconds, for the overlay; `None` when the source is not a stream.
    fn pose_age_ms(&self) -> Option<f64> {
        None
    }

    /// Set when the source cannot go on (e.g. geodetic poses on a dataset without a
    /// geo-reference): checked after every pose, the session then ends with this error.
    fn failure(&mut self) -> Option<String> {
        None
    }

    /// The channels to draw this frame, called once per frame after [`PoseSource::pose`] and
    /// before selection: the configured ones, with the host's CIGI views applied when the
    /// source has any ([`crate::sim::host_view`]).
    fn channels(&mut self, configured: &[Channel]) -> Vec<LiveChannel> {
        configured.iter().map(LiveChannel::configured).collect()
    }

    /// The frame just drawn: the statistics of every channel drawn (empty when none was), so
    /// the source can complete its per-frame records (e.g. the `--stats` triangles).
    fn frame_drawn(&mut self, _frame: u64, _stats: &[FrameStats]) {}
}

impl<F: FnMut(u64, f64) -> AircraftPose> PoseSource for F {
    fn pose(&mut self, frame: u64, t_s: f64) -> AircraftPose {
        self(frame, t_s)
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

/// Creates the event loop (once per process: winit refuses a second one). `any_thread` allows
/// a loop off the main thread (tests; X11 only).
pub fn new_event_loop(any_thread: bool) -> Result<EventLoop<()>, WindowError> {
    if std::env::var_os("DISPLAY").is_none() {
        return Err(WindowError::System(
            "no X11 display: DISPLAY is not set (run under a desktop session or `xvfb-run -a`)"
                .into(),
        ));
    }
    use winit::platform::x11::EventLoopBuilderExtX11;
    EventLoop::builder()
        .with_any_thread(any_thread)
        .build()
        .map_err(|e| WindowError::System(format!("cannot open the display: {e}")))
}

/// The instance extensions a surface on this display needs
/// (`ash_window::enumerate_required_extensions`), for [`crate::render::frame::RendererDesc`].
pub fn required_instance_extensions(
    display: &impl HasDisplayHandle,
) -> Result<Vec<CString>, WindowError> {
    let raw = display
        .display_handle()
        .map_err(|e| WindowError::System(format!("no display handle: {e}")))?
        .as_raw();
    let names = ash_window::enumerate_required_extensions(raw).map_err(|e| {
        WindowError::System(format!("Vulkan cannot present on this display: {e:?}"))
    })?;
    // SAFETY: ash-window returns pointers to static NUL-terminated extension names.
    Ok(names
        .iter()
        .map(|&p| unsafe { CStr::from_ptr(p) }.to_owned())
        .collect())
}

/// A monitor as the window system describes it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct MonitorInfo {
    pub name: Option<String>,
    pub size: (u32, u32),
    pub position: (i32, i32),
}

fn monitor_info(m: &MonitorHandle) -> MonitorInfo {
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

/// Opens one window per channel on `event_loop`, renders every frame from `pose` until Esc, a
/// closed window, `opts.max_frames` or `opts.max_seconds`, and destroys every window, swapchain
/// and surface before returning. `renderer` must have been created with
/// [`required_instance_extensions`] and `device.swapchain = true`, and have its terrain loaded.
pub fn run_channels(
    event_loop: &mut EventLoop<()>,
    renderer: &mut TerrainRenderer,
    channels: &[Channel],
    pose: &mut dyn PoseSource,
    opts: &RunOptions,
) -> Result<RunReport, WindowError> {
    if channels.is_empty() {
        return Err(WindowError::System("no channel to open".into()));
    }
    let mut app = App {
        renderer,
        channels,
        pose,
        opts,
        windows: Vec::new(),
        reports: Vec::new(),
        started: false,
        finished: false,
        error: None,
        exit: None,
        frames: 0,
        idle_waits: 0,
        start: None,
        last_frame: None,
        frame_ms: Vec::new(),
        next_action: 0,
        overlays: channels
            .iter()
            .map(|_| OverlayState::new(opts.overlay))
            .collect(),
        live: channels.iter().map(LiveChannel::configured).collect(),
    };
    let loop_result = event_loop.run_app_on_demand(&mut app);
    app.teardown();
    if let Some(e) = app.error.take() {
        return Err(e);
    }
    loop_result.map_err(|e| WindowError::System(format!("event loop: {e}")))?;
    let seconds = match (app.start, app.last_frame) {
        (Some(s), Some(l)) => (l - s).as_secs_f64(),
        _ => 0.0,
    };
    Ok(RunReport {
        frames: app.frames,
        idle_waits: app.idle_waits,
        frame_ms: app.frame_ms,
        seconds,
        exit: app.exit.unwrap_or(ExitReason::Closed),
        channels: app.reports,
    })
}

/// One channel's window and its presentation objects.
struct ChannelWindow {
    /// Index into the channel list (and the reports).
    channel: usize,
    swapchain: Option<Swapchain>,
    surface: Surface,
    /// Declared last: dropped after the surface made from it is destroyed.
    window: Window,
    present_mode: vk::PresentModeKHR,
    /// The swapchain no longer matches the window (resize, suboptimal, out of date).
    stale: bool,
}

impl ChannelWindow {
    fn destroy(&mut self, device: &Device) {
        if let Some(mut s) = self.swapchain.take() {
            s.destroy(device);
        }
        self.surface.destroy();
    }
}

struct App<'a> {
    renderer: &'a mut TerrainRenderer,
    channels: &'a [Channel],
    pose: &'a mut dyn PoseSource,
    opts: &'a RunOptions,
    windows: Vec<ChannelWindow>,
    reports: Vec<ChannelReport>,
    started: bool,
    finished: bool,
    error: Option<WindowError>,
    exit: Option<ExitReason>,
    frames: u64,
    idle_waits: u64,
    start: Option<Instant>,
    last_frame: Option<Instant>,
    frame_ms: Vec<f64>,
    next_action: usize,
    /// Per channel: overlay on/off (toggled together) and its recent numbers.
    overlays: Vec<OverlayState>,
    /// Per channel: as drawn this frame (host views applied), from the pose source.
    live: Vec<LiveChannel>,
}

impl App<'_> {
    /// Ends the session: destroys every window's Vulkan objects and leaves the loop.
    fn finish(&mut self, event_loop: &ActiveEventLoop, reason: Option<ExitReason>) {
        if self.exit.is_none() {
            self.exit = reason;
        }
        self.finished = true;
        self.teardown();
        event_loop.exit();
    }

    /// Waits for the device, then destroys swapchains, surfaces and windows. Idempotent.
    fn teardown(&mut self) {
        if self.windows.is_empty() {
            return;
        }
        let (_, device) = self.renderer.vulkan();
        device.wait_idle();
        for mut w in self.windows.drain(..) {
            w.destroy(device);
        }
    }

    fn fail(&mut self, event_loop: &ActiveEventLoop, e: WindowError) {
        if self.error.is_none() {
            self.error = Some(e);
        }
        self.finish(event_loop, None);
    }

    fn open_all(&mut self, event_loop: &ActiveEventLoop) -> Result<(), WindowError> {
        let monitors: Vec<MonitorHandle> = event_loop.available_monitors().collect();
        let infos: Vec<MonitorInfo> = monitors.iter().map(monitor_info).collect();
        let primary = event_loop
            .primary_monitor()
            .or_else(|| monitors.first().cloned());
        for (i, ch) in self.channels.iter().enumerate() {
            let (instance, device) = self.renderer.vulkan();
            let monitor = match &ch.monitor {
                None => None,
                Some(sel) => {
                    let k =
                        select_monitor(sel, &infos).map_err(|message| WindowError::Channel {
                            channel: i,
                            key: "monitor",
                            message,
                        })?;
                    Some(k)
                }
            };
            let opened = open_window(
                event_loop,
                instance,
                device,
                i,
                ch,
                monitor.map(|k| &monitors[k]),
                primary.as_ref(),
            )?;
            let sc = opened.swapchain.as_ref();
            self.reports.push(ChannelReport {
                name: ch.name.clone(),
                monitor: monitor.map(|k| infos[k].name.clone().unwrap_or_else(|| format!("#{k}"))),
                fullscreen: match ch.display {
                    ChannelDisplay::Fullscreen(FullscreenMode::Borderless) => {
                        Some("borderless".into())
                    }
                    ChannelDisplay::Fullscreen(FullscreenMode::Exclusive) => {
                        Some("exclusive".into())
                    }
                    ChannelDisplay::Window { .. } => None,
                },
                present_mode: ch.present_mode.as_str().into(),
                swapchain_builds: sc.is_some() as u32,
                extents: sc
                    .map(|s| vec![[s.extent.width, s.extent.height]])
                    .unwrap_or_default(),
                ..Default::default()
            });
            self.windows.push(opened);
        }
        Ok(())
    }

    fn apply_actions(&mut self) {
        while let Some(a) = self
            .opts
            .actions
            .get(self.next_action)
            .filter(|a| a.frame <= self.frames)
        {
            match a.action {
                Action::Resize {
                    channel,
                    width,
                    height,
                } => {
                    if let Some(w) = self.windows.iter().find(|w| w.channel == channel) {
                        // Applied now or later; either way a Resized event follows.
                        let _ = w
                            .window
                            .request_inner_size(PhysicalSize::new(width, height));
                    }
                }
            }
            self.next_action += 1;
        }
    }

    /// With several channels drawn this frame, one tile selection covers all of them (per tile
    /// the largest projected error among the channels that see it) so seams match.
    fn share_selection(&mut self, drawable: &[bool], pose: &AircraftPose) {
        let views: Vec<_> = self
            .windows
            .iter()
            .zip(drawable)
            .filter(|(_, &d)| d)
            .map(|(w, _)| {
                let live = &self.live[w.channel];
                let ch = &live.channel;
                let size = match (&w.swapchain, w.stale) {
                    (Some(sc), false) => (sc.extent.width, sc.extent.height),
                    _ => {
                        let s = w.window.inner_size();
                        (s.width, s.height)
                    }
                };
                let (rw, rh) = ch.resolution.unwrap_or(size);
                let camera = live.camera(pose, rw as f64 / rh as f64);
                (camera, (rw, rh), ch.tau_px)
            })
            .collect();
        self.renderer
            .set_channels(if views.len() > 1 { views } else { Vec::new() });
    }

    /// One frame: one pose sample, every drawable channel drawn and presented.
    fn tick(&mut self, event_loop: &ActiveEventLoop) -> Result<(), WindowError> {
        self.apply_actions();
        let drawable: Vec<bool> = self
            .windows
            .iter()
            .map(|w| {
                let size = w.window.inner_size();
                w.window.is_minimized() != Some(true) && size.width > 0 && size.height > 0
            })
            .collect();
        if !drawable.iter().any(|&d| d) {
            // Nothing to draw: sleep until an event (or a periodic re-check) instead of spinning.
            self.idle_waits += 1;
            event_loop.set_control_flow(ControlFlow::WaitUntil(Instant::now() + IDLE_WAIT));
            return Ok(());
        }
        event_loop.set_control_flow(ControlFlow::Poll);
        let now = Instant::now();
        let start = *self.start.get_or_insert(now);
        if let Some(last) = self.last_frame {
            self.frame_ms.push((now - last).as_secs_f64() * 1e3);
        }
        self.last_frame = Some(now);
        let pose = self.pose.pose(self.frames, (now - start).as_secs_f64());
        if let Some(why) = self.pose.failure() {
            return Err(WindowError::System(why));
        }
        self.live = self.pose.channels(self.channels);
        self.share_selection(&drawable, &pose);
        let pose_age_ms = self.pose.pose_age_ms();
        // Frame time as seen by the pilot: between the starts of consecutive frames.
        let frame_ms = self.frame_ms.last().copied();
        let mut drawn = Vec::new();
        for (k, ok) in drawable.into_iter().enumerate() {
            let i = self.windows[k].channel;
            if !ok {
                self.reports[i].skipped += 1;
                continue;
            }
            let stats = draw_channel(
                self.renderer,
                &mut self.windows[k],
                &self.live[i],
                &mut self.reports[i],
                &pose,
                (&self.overlays[i], pose_age_ms),
            )?;
            if let Some(stats) = stats {
                let info = OverlayInfo::from_stats(&stats, self.channels[i].tau_px);
                match frame_ms {
                    Some(ms) => self.overlays[i].record(ms, info),
                    None => self.overlays[i].record_info(info),
                }
                drawn.push(stats);
            }
        }
        self.pose.frame_drawn(self.frames, &drawn);
        self.frames += 1;
        if self.opts.max_frames.is_some_and(|n| self.frames >= n) {
            self.finish(event_loop, Some(ExitReason::Frames));
        } else if self
            .opts
            .max_seconds
            .is_some_and(|s| (Instant::now() - start).as_secs_f64() >= s)
        {
            self.finish(event_loop, Some(ExitReason::Seconds));
        }
        Ok(())
    }
}

impl ApplicationHandler for App<'_> {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.started {
            return;
        }
        self.started = true;
        // All windows or none: a bad channel stops the session before any frame.
        if let Err(e) = self.open_all(event_loop) {
            self.fail(event_loop, e);
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, id: WindowId, event: WindowEvent) {
        if self.finished {
            return;
        }
        match event {
            WindowEvent::CloseRequested => self.finish(event_loop, Some(ExitReason::Closed)),
            WindowEvent::KeyboardInput { event, .. }
                if event.state == ElementState::Pressed
                    && event.logical_key == Key::Named(NamedKey::Escape) =>
            {
                self.finish(event_loop, Some(ExitReason::Escape))
            }
            WindowEvent::KeyboardInput { event, .. }
                if is_overlay_toggle(&event.logical_key, event.state, event.repeat) =>
            {
                for o in &mut self.overlays {
                    o.toggle();
                }
            }
            WindowEvent::Resized(_) | WindowEvent::ScaleFactorChanged { .. } => {
                if let Some(w) = self.windows.iter_mut().find(|w| w.window.id() == id) {
                    w.stale = true;
                }
            }
            _ => {}
        }
    }

    fn about_to_wait(&mut self, event_loop: &ActiveEventLoop) {
        if !self.started || self.finished {
            return;
        }
        if let Err(e) = self.tick(event_loop) {
            self.fail(event_loop, e);
        }
    }

    fn exiting(&mut self, _event_loop: &ActiveEventLoop) {
        self.teardown();
    }
}

/// Creates a channel's window (placed and sized, or fullscreen), its surface and its first
/// swapchain (none while the window has no area), checking that the device can present to it
/// in the channel's present mode.
fn open_window(
    event_loop: &ActiveEventLoop,
    instance: &Instance,
    device: &Device,
    index: usize,
    ch: &Channel,
    monitor: Option<&MonitorHandle>,
    primary: Option<&MonitorHandle>,
) -> Result<ChannelWindow, WindowError> {
    let bad = |key: &'static str, message: String| WindowError::Channel {
        channel: index,
        key,
        message,
    };
    let mut attrs = Window::default_attributes().with_title(format!("aerie — {}", ch.name));
    match ch.display {
        ChannelDisplay::Window {
            x,
            y,
            width,
            height,
        } => {
            attrs = attrs.with_inner_size(PhysicalSize::new(width, height));
            if x.is_some() || y.is_some() || monitor.is_some() {
                let origin = monitor.map(|m| m.position()).unwrap_or_default();
                attrs = attrs.with_position(PhysicalPosition::new(
                    origin.x + x.unwrap_or(0),
                    origin.y + y.unwrap_or(0),
                ));
            }
        }
        ChannelDisplay::Fullscreen(FullscreenMode::Borderless) => {
            attrs =
                attrs.with_fullscreen(Some(Fullscreen::Borderless(monitor.or(primary).cloned())));
        }
        ChannelDisplay::Fullscreen(FullscreenMode::Exclusive) => {
            let m = monitor.or(primary).ok_or_else(|| {
                bad(
                    "fullscreen",
                    "exclusive fullscreen needs a monitor and none was found".into(),
                )
            })?;
            let modes: Vec<VideoModeHandle> = m.video_modes().collect();
            let described: Vec<(u32, u32, u32)> = modes
                .iter()
                .map(|v| (v.size().width, v.size().height, v.refresh_rate_millihertz()))
                .collect();
            let k = choose_video_mode(&described, ch.resolution).map_err(|message| {
                bad(
                    if ch.resolution.is_some() {
                        "resolution"
                    } else {
                        "fullscreen"
                    },
                    message,
                )
            })?;
            attrs = attrs.with_fullscreen(Some(Fullscreen::Exclusive(modes[k].clone())));
        }
    }
    let window = event_loop.create_window(attrs).map_err(|e| {
        WindowError::System(format!(
            "channel {:?}: cannot create its window: {e}",
            ch.name
        ))
    })?;
    if ch.is_fullscreen() {
        window.set_cursor_visible(false);
    }
    let handles = window
        .display_handle()
        .and_then(|d| window.window_handle().map(|w| (d.as_raw(), w.as_raw())));
    let (display, handle) = handles.map_err(|e| {
        WindowError::System(format!("channel {:?}: no window handle: {e}", ch.name))
    })?;
    // SAFETY: the window outlives the surface (ChannelWindow::destroy runs before the window is
    // dropped) and the renderer's instance has the display's surface extensions.
    let mut surface = unsafe { Surface::new(instance, display, handle) }?;
    let present_mode = vk_present_mode(ch.present_mode);
    let checked = (|| {
        if !surface.supports_queue(device)? {
            return Err(WindowError::System(format!(
                "channel {:?}: queue family {} of {} cannot present to this window",
                ch.name, device.queue_family, device.name
            )));
        }
        let modes = surface.present_modes(device)?;
        choose_present_mode(present_mode, &modes).map_err(|m| bad("present_mode", m))?;
        let size = window.inner_size();
        Ok(Swapchain::new(
            instance,
            device,
            &surface,
            (size.width, size.height),
            present_mode,
        )?)
    })();
    match checked {
        Ok(swapchain) => Ok(ChannelWindow {
            channel: index,
            swapchain,
            surface,
            window,
            present_mode,
            stale: false,
        }),
        Err(e) => {
            surface.destroy();
            Err(e)
        }
    }
}

/// (Re)creates the swapchain for the window's current size. False when the window has no area.
fn rebuild(
    instance: &Instance,
    device: &Device,
    w: &mut ChannelWindow,
    report: &mut ChannelReport,
) -> Result<bool, WindowError> {
    let size = w.window.inner_size();
    if size.width == 0 || size.height == 0 {
        return Ok(false);
    }
    let size = (size.width, size.height);
    let built = match &mut w.swapchain {
        Some(sc) => sc.recreate(device, &w.surface, size)?,
        None => match Swapchain::new(instance, device, &w.surface, size, w.present_mode)? {
            Some(sc) => {
                w.swapchain = Some(sc);
                true
            }
            None => false,
        },
    };
    if !built {
        return Ok(false);
    }
    w.stale = false;
    report.swapchain_builds += 1;
    if let Some(sc) = &w.swapchain {
        let e = [sc.extent.width, sc.extent.height];
        if report.extents.last() != Some(&e) {
            report.extents.push(e);
        }
    }
    Ok(true)
}

/// True for the key event that toggles the statistics overlay: F1, or O (either case), pressed
/// (auto-repeat ignored, so holding the key does not make it flicker).
pub fn is_overlay_toggle(key: &Key, state: ElementState, repeat: bool) -> bool {
    if state != ElementState::Pressed || repeat {
        return false;
    }
    match key {
        Key::Named(NamedKey::F1) => true,
        Key::Character(c) => c.eq_ignore_ascii_case("o"),
        _ => false,
    }
}

/// Acquires, renders the channel's view (with the overlay panel when on) into the image and
/// presents it. Returns the frame's statistics when a frame was drawn.
fn draw_channel(
    renderer: &mut TerrainRenderer,
    w: &mut ChannelWindow,
    live: &LiveChannel,
    report: &mut ChannelReport,
    pose: &AircraftPose,
    (overlay, pose_age_ms): (&OverlayState, Option<f64>),
) -> Result<Option<FrameStats>, WindowError> {
    let acquired = {
        let (instance, device) = renderer.vulkan();
        if (w.stale || w.swapchain.is_none()) && !rebuild(instance, device, w, report)? {
            report.skipped += 1;
            return Ok(None);
        }
        let mut acquired = None;
        for _ in 0..2 {
            let Some(sc) = w.swapchain.as_mut() else {
                break;
            };
            match sc.acquire()? {
                Acquire::Image(a) => {
                    acquired = Some(a);
                    break;
                }
                Acquire::OutOfDate => {
                    if !rebuild(instance, device, w, report)? {
                        break;
                    }
                }
            }
        }
        acquired
    };
    let Some(image) = acquired else {
        report.skipped += 1;
        return Ok(None);
    };
    let ch = &live.channel;
    let extent = image.target.extent;
    let (rw, rh) = ch.resolution.unwrap_or((extent.width, extent.height));
    renderer.resize(rw, rh)?;
    let mut params = renderer.desc().select;
    if params.tau_px != ch.tau_px {
        params.tau_px = ch.tau_px;
        renderer.set_select_params(params);
    }
    let camera = live.camera(pose, rw as f64 / rh as f64);
    let panel = overlay.panel((rw, rh), pose_age_ms);
    let with_overlay = panel.is_some();
    renderer.set_overlay(panel);
    let stats = renderer.render_frame(&camera, Some(&image.target))?;
    renderer.set_overlay(None);
    let (_, device) = renderer.vulkan();
    let sc = w.swapchain.as_ref().expect("acquired from it");
    match sc.present(device, image.index)? {
        Presented::Optimal => {}
        Presented::Suboptimal | Presented::OutOfDate => w.stale = true,
    }
    if image.suboptimal {
        w.stale = true;
    }
    report.presented += 1;
    report.overlay_frames += with_overlay as u64;
    report.render_size = [rw, rh];
    Ok(Some(stats))
}

#[cfg(test)]
mod tests {
    use super::*;

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
}
