//! A windowed session: the winit application that opens every channel's window, draws one
//! frame per loop turn from one pose, handles keys and resizes, and tears everything down.

use std::time::{Duration, Instant};

use aerie_config::{Channel, ChannelDisplay, FullscreenMode};
use winit::application::ApplicationHandler;
use winit::dpi::PhysicalSize;
use winit::event::{ElementState, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::keyboard::{Key, NamedKey};
use winit::monitor::MonitorHandle;
use winit::platform::run_on_demand::EventLoopExtRunOnDemand;
use winit::window::WindowId;

use crate::app::window::channel_window::{draw_channel, open_window, ChannelWindow};
use crate::app::window::monitor::{monitor_info, select_monitor, MonitorInfo};
use crate::app::window::pose_source::PoseSource;
use crate::app::window::report::{
    Action, ChannelReport, ExitReason, RunOptions, RunReport, WindowError,
};
use crate::render::frame::TerrainRenderer;
use crate::sim::channel::AircraftPose;
use crate::sim::host_view::LiveChannel;
use crate::tools::overlay::{OverlayInfo, OverlayState};

/// How long an idle loop (every window minimised) sleeps between checks when no event comes.
const IDLE_WAIT: Duration = Duration::from_millis(100);

/// Opens one window per channel on `event_loop`, renders every frame from `pose` until Esc, a
/// closed window, `opts.max_frames` or `opts.max_seconds`, and destroys every window, swapchain
/// and surface before returning. `renderer` must have been created with
/// [`required_instance_extensions`](crate::app::window::display::required_instance_extensions) and `device.swapchain = true`, and have its terrain loaded.
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
        self.pose
            .begin_frame(self.frames, self.renderer)
            .map_err(WindowError::System)?;
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
