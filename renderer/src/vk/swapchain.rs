//! Window surfaces and swapchains for windowed presentation (issue 7).
//!
//! [`Surface`] owns one `VkSurfaceKHR` made from a window's raw handles. [`Swapchain`] owns the
//! swapchain, the list of its images, one render-finished semaphore per image (signaled by the
//! frame's submission, waited by the present) and a small ring of acquire semaphores (signaled by
//! the acquire, waited by the frame's copy into the image). Both are created in one function and
//! destroyed explicitly, in reverse order: swapchain, then surface, then (by the renderer) device
//! and instance.
//!
//! The renderer draws offscreen and blits into the swapchain image, so images need
//! `TRANSFER_DST` usage and a format the device can blit into; an sRGB format is preferred so
//! that the blit from the sRGB colour target keeps the colours.

use ash::{khr, vk};
use raw_window_handle::{RawDisplayHandle, RawWindowHandle};

use super::{Device, Instance, VkError, VkResultExt, FRAMES_IN_FLIGHT};

/// A window's Vulkan surface. Destroy it after its swapchain and before the instance.
pub struct Surface {
    pub loader: khr::surface::Instance,
    pub raw: vk::SurfaceKHR,
}

impl Surface {
    /// Creates the surface of a window.
    ///
    /// # Safety
    /// The handles must be valid and stay valid (the window alive) until [`Surface::destroy`];
    /// the instance must have been created with the extensions
    /// `ash_window::enumerate_required_extensions` lists for this display.
    pub unsafe fn new(
        instance: &Instance,
        display: RawDisplayHandle,
        window: RawWindowHandle,
    ) -> Result<Self, VkError> {
        let raw = ash_window::create_surface(&instance.entry, &instance.raw, display, window, None)
            .call("vkCreate*SurfaceKHR")?;
        Ok(Self {
            loader: khr::surface::Instance::new(&instance.entry, &instance.raw),
            raw,
        })
    }

    /// Whether the device's queue family can present to this surface.
    pub fn supports_queue(&self, device: &Device) -> Result<bool, VkError> {
        unsafe {
            self.loader.get_physical_device_surface_support(
                device.physical,
                device.queue_family,
                self.raw,
            )
        }
        .call("vkGetPhysicalDeviceSurfaceSupportKHR")
    }

    /// Present modes the surface offers on this device.
    pub fn present_modes(&self, device: &Device) -> Result<Vec<vk::PresentModeKHR>, VkError> {
        unsafe {
            self.loader
                .get_physical_device_surface_present_modes(device.physical, self.raw)
        }
        .call("vkGetPhysicalDeviceSurfacePresentModesKHR")
    }

    pub fn capabilities(&self, device: &Device) -> Result<vk::SurfaceCapabilitiesKHR, VkError> {
        unsafe {
            self.loader
                .get_physical_device_surface_capabilities(device.physical, self.raw)
        }
        .call("vkGetPhysicalDeviceSurfaceCapabilitiesKHR")
    }

    pub fn destroy(&mut self) {
        if self.raw != vk::SurfaceKHR::null() {
            unsafe { self.loader.destroy_surface(self.raw, None) };
            self.raw = vk::SurfaceKHR::null();
        }
    }
}

/// Lower-case name of a present mode, as written in config files.
pub fn present_mode_name(mode: vk::PresentModeKHR) -> String {
    match mode {
        vk::PresentModeKHR::FIFO => "fifo".into(),
        vk::PresentModeKHR::MAILBOX => "mailbox".into(),
        vk::PresentModeKHR::IMMEDIATE => "immediate".into(),
        vk::PresentModeKHR::FIFO_RELAXED => "fifo_relaxed".into(),
        other => format!("{other:?}").to_lowercase(),
    }
}

/// Checks that `wanted` is among the surface's `supported` modes; the error lists them.
pub fn choose_present_mode(
    wanted: vk::PresentModeKHR,
    supported: &[vk::PresentModeKHR],
) -> Result<vk::PresentModeKHR, String> {
    if supported.contains(&wanted) {
        return Ok(wanted);
    }
    let list: Vec<String> = supported.iter().map(|&m| present_mode_name(m)).collect();
    Err(format!(
        "present mode {} is not supported by this window's surface (supported: {})",
        present_mode_name(wanted),
        if list.is_empty() {
            "none".to_owned()
        } else {
            list.join(", ")
        }
    ))
}

/// Picks the swapchain format: an 8-bit sRGB format in the sRGB colour space if offered (the
/// blit from the sRGB target then keeps colours exact), else the first format listed.
pub fn choose_surface_format(formats: &[vk::SurfaceFormatKHR]) -> Option<vk::SurfaceFormatKHR> {
    let preferred = [vk::Format::B8G8R8A8_SRGB, vk::Format::R8G8B8A8_SRGB];
    preferred
        .iter()
        .find_map(|&p| {
            formats
                .iter()
                .find(|f| f.format == p && f.color_space == vk::ColorSpaceKHR::SRGB_NONLINEAR)
        })
        .or_else(|| formats.first())
        .copied()
}

/// The swapchain extent: the surface's current extent when it dictates one, else the window's
/// size clamped to what the surface allows. A zero side means "minimised: do not render".
pub fn choose_extent(caps: &vk::SurfaceCapabilitiesKHR, window: (u32, u32)) -> vk::Extent2D {
    if caps.current_extent.width != u32::MAX {
        return caps.current_extent;
    }
    vk::Extent2D {
        width: window
            .0
            .clamp(caps.min_image_extent.width, caps.max_image_extent.width),
        height: window
            .1
            .clamp(caps.min_image_extent.height, caps.max_image_extent.height),
    }
}

/// Images to ask for: one more than the minimum (so acquiring never waits on the driver's
/// own image), within the maximum (0 = none).
pub fn choose_image_count(caps: &vk::SurfaceCapabilitiesKHR) -> u32 {
    let n = caps.min_image_count + 1;
    if caps.max_image_count > 0 {
        n.min(caps.max_image_count)
    } else {
        n
    }
}

/// An acquired swapchain image, ready to be drawn through `target` and presented.
#[derive(Debug, Clone, Copy)]
pub struct AcquiredImage {
    pub index: u32,
    pub target: PresentTarget,
    /// The swapchain no longer matches the surface exactly: present this image, then recreate.
    pub suboptimal: bool,
}

/// What an acquire gave.
#[derive(Debug, Clone, Copy)]
pub enum Acquire {
    Image(AcquiredImage),
    /// The swapchain must be recreated before it can be used (nothing was acquired).
    OutOfDate,
}

/// What a present said about the swapchain.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Presented {
    Optimal,
    /// Shown, but the swapchain should be recreated (resized window...).
    Suboptimal,
    /// Not shown: recreate.
    OutOfDate,
}

/// A swapchain with its images and semaphores. Destroyed explicitly with
/// [`Swapchain::destroy`] after the device is idle.
pub struct Swapchain {
    instance: ash::Instance,
    loader: khr::swapchain::Device,
    pub raw: vk::SwapchainKHR,
    pub format: vk::SurfaceFormatKHR,
    pub extent: vk::Extent2D,
    pub present_mode: vk::PresentModeKHR,
    pub images: Vec<vk::Image>,
    /// One per image: signaled when the frame's copy into the image is done, waited by the
    /// present of that image. Reused when the image is acquired again.
    rendered: Vec<vk::Semaphore>,
    /// Ring of acquire semaphores: FRAMES_IN_FLIGHT + 1 of them, so that a semaphore is acquired
    /// again only after the renderer has waited for the frame that consumed it (the renderer
    /// waits for frame n − FRAMES_IN_FLIGHT before recording frame n).
    acquire: Vec<vk::Semaphore>,
    next_acquire: usize,
}

/// Semaphores created so far are destroyed if a later one fails.
fn create_semaphores(device: &Device, n: usize) -> Result<Vec<vk::Semaphore>, VkError> {
    let mut out = Vec::with_capacity(n);
    for _ in 0..n {
        match unsafe {
            device
                .raw
                .create_semaphore(&vk::SemaphoreCreateInfo::default(), None)
        } {
            Ok(s) => out.push(s),
            Err(result) => {
                destroy_semaphores(device, &mut out);
                return Err(VkError::Call {
                    call: "vkCreateSemaphore",
                    result,
                });
            }
        }
    }
    Ok(out)
}

fn destroy_semaphores(device: &Device, semaphores: &mut Vec<vk::Semaphore>) {
    for s in semaphores.drain(..) {
        unsafe { device.raw.destroy_semaphore(s, None) };
    }
}

impl Swapchain {
    /// Creates a swapchain of `window` size (pixels) on `surface` presenting with
    /// `present_mode` (which must be supported: see [`choose_present_mode`]). Returns
    /// `Ok(None)` when the surface's extent is zero (minimised window).
    pub fn new(
        instance: &Instance,
        device: &Device,
        surface: &Surface,
        window: (u32, u32),
        present_mode: vk::PresentModeKHR,
    ) -> Result<Option<Self>, VkError> {
        let loader = khr::swapchain::Device::new(&instance.raw, &device.raw);
        let Some((raw, format, extent, images)) = Self::create_raw(
            &instance.raw,
            &loader,
            device,
            surface,
            window,
            present_mode,
            None,
        )?
        else {
            return Ok(None);
        };
        let unwind =
            |loader: &khr::swapchain::Device| unsafe { loader.destroy_swapchain(raw, None) };
        let rendered = match create_semaphores(device, images.len()) {
            Ok(s) => s,
            Err(e) => {
                unwind(&loader);
                return Err(e);
            }
        };
        let acquire = match create_semaphores(device, FRAMES_IN_FLIGHT + 1) {
            Ok(s) => s,
            Err(e) => {
                let mut rendered = rendered;
                destroy_semaphores(device, &mut rendered);
                unwind(&loader);
                return Err(e);
            }
        };
        Ok(Some(Self {
            instance: instance.raw.clone(),
            loader,
            raw,
            format,
            extent,
            present_mode,
            images,
            rendered,
            acquire,
            next_acquire: 0,
        }))
    }

    /// The swapchain and its images; `old` is handed to the driver for a smooth transition
    /// (the caller destroys it afterwards).
    #[allow(clippy::type_complexity)]
    fn create_raw(
        instance: &ash::Instance,
        loader: &khr::swapchain::Device,
        device: &Device,
        surface: &Surface,
        window: (u32, u32),
        present_mode: vk::PresentModeKHR,
        old: Option<vk::SwapchainKHR>,
    ) -> Result<
        Option<(
            vk::SwapchainKHR,
            vk::SurfaceFormatKHR,
            vk::Extent2D,
            Vec<vk::Image>,
        )>,
        VkError,
    > {
        let caps = surface.capabilities(device)?;
        let extent = choose_extent(&caps, window);
        if extent.width == 0 || extent.height == 0 {
            return Ok(None);
        }
        if !caps
            .supported_usage_flags
            .contains(vk::ImageUsageFlags::TRANSFER_DST)
        {
            return Err(VkError::Other(
                "the window's surface does not accept transfer writes (TRANSFER_DST), which the presentation blit needs".into(),
            ));
        }
        let formats = unsafe {
            surface
                .loader
                .get_physical_device_surface_formats(device.physical, surface.raw)
        }
        .call("vkGetPhysicalDeviceSurfaceFormatsKHR")?;
        let format = choose_surface_format(&formats)
            .ok_or_else(|| VkError::Other("the window's surface offers no format".into()))?;
        let features = unsafe {
            instance.get_physical_device_format_properties(device.physical, format.format)
        }
        .optimal_tiling_features;
        if !features.contains(vk::FormatFeatureFlags::BLIT_DST) {
            return Err(VkError::Other(format!(
                "swapchain format {:?} cannot be a blit destination on this device",
                format.format
            )));
        }
        let alpha = [
            vk::CompositeAlphaFlagsKHR::OPAQUE,
            vk::CompositeAlphaFlagsKHR::INHERIT,
            vk::CompositeAlphaFlagsKHR::PRE_MULTIPLIED,
            vk::CompositeAlphaFlagsKHR::POST_MULTIPLIED,
        ]
        .into_iter()
        .find(|&a| caps.supported_composite_alpha.contains(a))
        .unwrap_or(vk::CompositeAlphaFlagsKHR::OPAQUE);
        let info = vk::SwapchainCreateInfoKHR::default()
            .surface(surface.raw)
            .min_image_count(choose_image_count(&caps))
            .image_format(format.format)
            .image_color_space(format.color_space)
            .image_extent(extent)
            .image_array_layers(1)
            .image_usage(vk::ImageUsageFlags::TRANSFER_DST)
            .image_sharing_mode(vk::SharingMode::EXCLUSIVE)
            .pre_transform(caps.current_transform)
            .composite_alpha(alpha)
            .present_mode(present_mode)
            .clipped(true)
            .old_swapchain(old.unwrap_or_default());
        let raw = unsafe { loader.create_swapchain(&info, None) }.call("vkCreateSwapchainKHR")?;
        let images = match unsafe { loader.get_swapchain_images(raw) } {
            Ok(i) => i,
            Err(result) => {
                unsafe { loader.destroy_swapchain(raw, None) };
                return Err(VkError::Call {
                    call: "vkGetSwapchainImagesKHR",
                    result,
                });
            }
        };
        Ok(Some((raw, format, extent, images)))
    }

    /// Recreates the swapchain for a new window size (after a resize, out-of-date or
    /// suboptimal). Waits for the device first. Returns false when the extent is zero
    /// (minimised): the swapchain is then left as it was and should not be used.
    pub fn recreate(
        &mut self,
        device: &Device,
        surface: &Surface,
        window: (u32, u32),
    ) -> Result<bool, VkError> {
        device.wait_idle();
        let Some((raw, format, extent, images)) = Self::create_raw(
            &self.instance,
            &self.loader,
            device,
            surface,
            window,
            self.present_mode,
            Some(self.raw),
        )?
        else {
            return Ok(false);
        };
        unsafe { self.loader.destroy_swapchain(self.raw, None) };
        self.raw = raw;
        self.format = format;
        self.extent = extent;
        if images.len() != self.rendered.len() {
            destroy_semaphores(device, &mut self.rendered);
            self.rendered = create_semaphores(device, images.len())?;
        }
        self.images = images;
        Ok(true)
    }

    /// Acquires the next image (waits for one to be available).
    pub fn acquire(&mut self) -> Result<Acquire, VkError> {
        let semaphore = self.acquire[self.next_acquire];
        let result = unsafe {
            self.loader
                .acquire_next_image(self.raw, u64::MAX, semaphore, vk::Fence::null())
        };
        let (index, suboptimal) = match result {
            Ok(r) => r,
            Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => return Ok(Acquire::OutOfDate),
            Err(result) => {
                return Err(VkError::Call {
                    call: "vkAcquireNextImageKHR",
                    result,
                })
            }
        };
        self.next_acquire = (self.next_acquire + 1) % self.acquire.len();
        Ok(Acquire::Image(AcquiredImage {
            index,
            target: PresentTarget {
                image: self.images[index as usize],
                extent: self.extent,
                acquired: semaphore,
                rendered: self.rendered[index as usize],
            },
            suboptimal,
        }))
    }

    /// Presents image `index` once its `rendered` semaphore is signaled.
    pub fn present(&self, device: &Device, index: u32) -> Result<Presented, VkError> {
        let wait = [self.rendered[index as usize]];
        let swapchains = [self.raw];
        let indices = [index];
        let info = vk::PresentInfoKHR::default()
            .wait_semaphores(&wait)
            .swapchains(&swapchains)
            .image_indices(&indices);
        match unsafe { self.loader.queue_present(device.queue, &info) } {
            Ok(false) => Ok(Presented::Optimal),
            Ok(true) => Ok(Presented::Suboptimal),
            Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => Ok(Presented::OutOfDate),
            Err(result) => Err(VkError::Call {
                call: "vkQueuePresentKHR",
                result,
            }),
        }
    }

    /// Destroys the semaphores and the swapchain (after waiting for the device). Idempotent.
    pub fn destroy(&mut self, device: &Device) {
        device.wait_idle();
        destroy_semaphores(device, &mut self.acquire);
        destroy_semaphores(device, &mut self.rendered);
        if self.raw != vk::SwapchainKHR::null() {
            unsafe { self.loader.destroy_swapchain(self.raw, None) };
            self.raw = vk::SwapchainKHR::null();
        }
        self.images.clear();
    }
}

/// A swapchain image to present a frame in (the renderer records a copy into it; see `render::frame`).
#[derive(Debug, Clone, Copy)]
pub struct PresentTarget {
    pub image: vk::Image,
    pub extent: vk::Extent2D,
    /// Signaled by the presentation engine when the image is acquired; waited before the copy.
    pub acquired: vk::Semaphore,
    /// Signaled when the copy is done; the present waits for it.
    pub rendered: vk::Semaphore,
}

#[cfg(test)]
mod tests {
    use super::*;

    fn caps(current: (u32, u32), min: (u32, u32), max: (u32, u32)) -> vk::SurfaceCapabilitiesKHR {
        vk::SurfaceCapabilitiesKHR {
            min_image_count: 2,
            max_image_count: 3,
            current_extent: vk::Extent2D {
                width: current.0,
                height: current.1,
            },
            min_image_extent: vk::Extent2D {
                width: min.0,
                height: min.1,
            },
            max_image_extent: vk::Extent2D {
                width: max.0,
                height: max.1,
            },
            ..Default::default()
        }
    }

    #[test]
    fn unsupported_present_mode_lists_the_supported_ones() {
        let supported = [vk::PresentModeKHR::FIFO, vk::PresentModeKHR::IMMEDIATE];
        assert_eq!(
            choose_present_mode(vk::PresentModeKHR::IMMEDIATE, &supported),
            Ok(vk::PresentModeKHR::IMMEDIATE)
        );
        let e = choose_present_mode(vk::PresentModeKHR::MAILBOX, &supported).unwrap_err();
        assert_eq!(
            e,
            "present mode mailbox is not supported by this window's surface (supported: fifo, immediate)"
        );
    }

    #[test]
    fn srgb_format_is_preferred() {
        let f = |format| vk::SurfaceFormatKHR {
            format,
            color_space: vk::ColorSpaceKHR::SRGB_NONLINEAR,
        };
        let list = [
            f(vk::Format::B8G8R8A8_UNORM),
            f(vk::Format::R8G8B8A8_SRGB),
            f(vk::Format::B8G8R8A8_SRGB),
        ];
        assert_eq!(
            choose_surface_format(&list).unwrap().format,
            vk::Format::B8G8R8A8_SRGB
        );
        assert_eq!(
            choose_surface_format(&list[..1]).unwrap().format,
            vk::Format::B8G8R8A8_UNORM
        );
        assert!(choose_surface_format(&[]).is_none());
    }

    #[test]
    fn extent_follows_the_surface_or_the_clamped_window() {
        let fixed = caps((800, 600), (1, 1), (4096, 4096));
        let e = choose_extent(&fixed, (1024, 768));
        assert_eq!((e.width, e.height), (800, 600));
        let free = caps((u32::MAX, u32::MAX), (16, 16), (2048, 1024));
        let e = choose_extent(&free, (4000, 8));
        assert_eq!((e.width, e.height), (2048, 16));
        let minimised = caps((0, 0), (0, 0), (4096, 4096));
        assert_eq!(choose_extent(&minimised, (640, 480)).width, 0);
        assert_eq!(choose_image_count(&fixed), 3);
        let unbounded = vk::SurfaceCapabilitiesKHR {
            max_image_count: 0,
            ..fixed
        };
        assert_eq!(choose_image_count(&unbounded), 3);
    }
}
