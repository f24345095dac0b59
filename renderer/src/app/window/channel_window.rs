//! One channel's window and its presentation objects: opening it (placed, sized or
//! fullscreen) with its surface and swapchain, rebuilding the swapchain, and drawing and
//! presenting one frame into it.

use aerie_config::{Channel, ChannelDisplay, FullscreenMode};
use ash::vk;
use raw_window_handle::{HasDisplayHandle, HasWindowHandle};
use winit::dpi::{PhysicalPosition, PhysicalSize};
use winit::event_loop::ActiveEventLoop;
use winit::monitor::{MonitorHandle, VideoModeHandle};
use winit::window::{Fullscreen, Window};

use crate::app::window::monitor::{choose_video_mode, vk_present_mode};
use crate::app::window::report::{ChannelReport, WindowError};
use crate::render::frame::{FrameStats, TerrainRenderer};
use crate::sim::channel::AircraftPose;
use crate::sim::host_view::LiveChannel;
use crate::tools::overlay::OverlayState;
use crate::vk::swapchain::{choose_present_mode, Acquire, Presented, Surface, Swapchain};
use crate::vk::{Device, Instance};

/// One channel's window and its presentation objects.
pub(crate) struct ChannelWindow {
    /// Index into the channel list (and the reports).
    pub channel: usize,
    pub swapchain: Option<Swapchain>,
    surface: Surface,
    /// Declared last: dropped after the surface made from it is destroyed.
    pub window: Window,
    present_mode: vk::PresentModeKHR,
    /// The swapchain no longer matches the window (resize, suboptimal, out of date).
    pub stale: bool,
}

impl ChannelWindow {
    /// Destroys the swapchain and the surface (the window itself goes when dropped).
    pub fn destroy(&mut self, device: &Device) {
        if let Some(mut s) = self.swapchain.take() {
            s.destroy(device);
        }
        self.surface.destroy();
    }
}

/// Creates a channel's window (placed and sized, or fullscreen), its surface and its first
/// swapchain (none while the window has no area), checking that the device can present to it
/// in the channel's present mode.
pub(crate) fn open_window(
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
    // ChannelWindow::destroy runs before the window is dropped; the renderer's instance has the
    // display's surface extensions.
    // SAFETY: the window outlives the surface and the instance can make surfaces for it.
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

/// Acquires, renders the channel's view (with the overlay panel when on) into the image and
/// presents it. Returns the frame's statistics when a frame was drawn.
pub(crate) fn draw_channel(
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
