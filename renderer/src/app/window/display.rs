//! The display connection: the winit event loop and the Vulkan instance extensions a surface
//! on it needs.

use std::ffi::{CStr, CString};

use raw_window_handle::HasDisplayHandle;

use crate::app::window::report::WindowError;

/// The winit event loop type sessions run on (re-exported so callers need no winit dependency).
pub use winit::event_loop::EventLoop;

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
    Ok(names
        .iter()
        .map(|&p| {
            // SAFETY: ash-window returns pointers to static NUL-terminated extension names.
            unsafe { CStr::from_ptr(p) }.to_owned()
        })
        .collect())
}
