//! Window surfaces and swapchains for windowed presentation (issue 7).
//!
//! [`Surface`] owns one `VkSurfaceKHR` made from a window's raw handles. [`Swapchain`] owns the
//! swapchain, the list of its images and two kinds of binary semaphores:
//!
//! - **acquire** (a ring of `FRAMES_IN_FLIGHT + 1`): signaled by the presentation engine when
//!   `vkAcquireNextImageKHR` hands out an image; waited by the frame's queue submission at
//!   [`ACQUIRE_WAIT_STAGE`], before the blit into the image.
//! - **rendered** (one per image): signaled by that same submission when it completes; waited by
//!   `vkQueuePresentKHR` of the image.
//!
//! Both are created in one function and destroyed explicitly, in reverse order: swapchain, then
//! surface, then (by the renderer) device and instance.
//!
//! The renderer draws offscreen and blits into the swapchain image, so images need
//! `TRANSFER_DST` usage and a format the device can blit into; an sRGB format is preferred so
//! that the blit from the sRGB colour target keeps the colours.

use ash::{khr, vk};
use raw_window_handle::{RawDisplayHandle, RawWindowHandle};

use super::conv::{
    choose_composite_alpha, choose_extent, choose_image_count, choose_surface_format,
};
use super::device::Device;
use super::error::{VkError, VkResultExt};
use super::instance::Instance;
use super::FRAMES_IN_FLIGHT;

pub use super::conv::{choose_present_mode, present_mode_name};

/// The stage at which a frame's submission waits for [`PresentTarget::acquired`]: the blit into
/// the swapchain image is a transfer, and its barrier (from `Access::SwapchainAcquired`)
/// starts at this stage so that it chains to the wait.
pub const ACQUIRE_WAIT_STAGE: vk::PipelineStageFlags = vk::PipelineStageFlags::TRANSFER;

/// A window's Vulkan surface. Destroy it after its swapchain and before the instance. Between
/// [`Surface::new`] and [`Surface::destroy`], `raw` is a live surface of the instance `loader`
/// was made from.
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
        // SAFETY: the handles are valid and the instance has the extensions (this function's
        // contract); the instance is live.
        let raw = ash_window::create_surface(&instance.entry, &instance.raw, display, window, None)
            .call("vkCreate*SurfaceKHR")?;
        Ok(Self {
            loader: khr::surface::Instance::new(&instance.entry, &instance.raw),
            raw,
        })
    }

    /// Whether the device's queue family can present to this surface.
    pub fn supports_queue(&self, device: &Device) -> Result<bool, VkError> {
        // `device.physical` belongs to the surface's instance; `queue_family` is one of its families.
        // SAFETY: the surface is live (see `Surface`) and the query names valid handles.
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
        // SAFETY: the surface is live and `device.physical` belongs to the same instance.
        unsafe {
            self.loader
                .get_physical_device_surface_present_modes(device.physical, self.raw)
        }
        .call("vkGetPhysicalDeviceSurfacePresentModesKHR")
    }

    pub fn capabilities(&self, device: &Device) -> Result<vk::SurfaceCapabilitiesKHR, VkError> {
        // SAFETY: the surface is live and `device.physical` belongs to the same instance.
        unsafe {
            self.loader
                .get_physical_device_surface_capabilities(device.physical, self.raw)
        }
        .call("vkGetPhysicalDeviceSurfaceCapabilitiesKHR")
    }

    /// Idempotent. The swapchain made on it must be destroyed first.
    pub fn destroy(&mut self) {
        if self.raw != vk::SurfaceKHR::null() {
            // Its swapchain is gone (contract above), so nothing else uses it.
            // SAFETY: the surface is live and destroyed once (nulled right after).
            unsafe { self.loader.destroy_surface(self.raw, None) };
            self.raw = vk::SurfaceKHR::null();
        }
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
    /// One per image: signaled by the frame's submission when its copy into the image is done,
    /// waited by the present of that image. Reused when the image is acquired again (that
    /// present has then consumed the signal).
    rendered: Vec<vk::Semaphore>,
    /// Ring of acquire semaphores, signaled by the acquire and waited by the frame's submission:
    /// FRAMES_IN_FLIGHT + 1 of them, so that a semaphore is acquired again only after the
    /// renderer has waited for the frame that consumed it (the renderer waits for frame
    /// n − FRAMES_IN_FLIGHT before recording frame n).
    acquire: Vec<vk::Semaphore>,
    next_acquire: usize,
    /// A recreate found the window without area: the images no longer match it, so
    /// [`Swapchain::acquire`] answers `OutOfDate` until a recreate succeeds.
    needs_recreate: bool,
}

/// Semaphores created so far are destroyed if a later one fails.
fn create_semaphores(device: &Device, n: usize) -> Result<Vec<vk::Semaphore>, VkError> {
    let mut out = Vec::with_capacity(n);
    for _ in 0..n {
        // SAFETY: the device is live; a default create-info makes a binary semaphore.
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

/// The caller has waited for the device, so no submission or present still uses them.
fn destroy_semaphores(device: &Device, semaphores: &mut Vec<vk::Semaphore>) {
    for s in semaphores.drain(..) {
        // No pending operation waits on or signals it (contract above).
        // SAFETY: `s` was created on this device by `create_semaphores` and is drained, so it is destroyed once.
        unsafe { device.raw.destroy_semaphore(s, None) };
    }
}

impl Swapchain {
    /// Creates a swapchain of `window` size (pixels) on `surface` presenting with
    /// `present_mode`; an error names the supported modes when it is not one of them (see
    /// [`choose_present_mode`]), or says that the device's queue cannot present to `surface`. Returns `Ok(None)` when the surface's extent is zero
    /// (minimised window).
    pub fn new(
        instance: &Instance,
        device: &Device,
        surface: &Surface,
        window: (u32, u32),
        present_mode: vk::PresentModeKHR,
    ) -> Result<Option<Self>, VkError> {
        if !surface.supports_queue(device)? {
            return Err(VkError::Other(
                "the device's graphics queue cannot present to this window's surface".into(),
            ));
        }
        let supported = surface.present_modes(device)?;
        let present_mode = choose_present_mode(present_mode, &supported).map_err(VkError::Other)?;
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
        let unwind = |loader: &khr::swapchain::Device| {
            // SAFETY: `raw` was just created by `loader` and no image of it was acquired yet.
            unsafe { loader.destroy_swapchain(raw, None) }
        };
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
            needs_recreate: false,
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
        // SAFETY: the surface is live and `device.physical` belongs to its instance.
        let formats = unsafe {
            surface
                .loader
                .get_physical_device_surface_formats(device.physical, surface.raw)
        }
        .call("vkGetPhysicalDeviceSurfaceFormatsKHR")?;
        let format = choose_surface_format(&formats)
            .ok_or_else(|| VkError::Other("the window's surface offers no format".into()))?;
        // SAFETY: `instance` is live and `device.physical` was enumerated from it.
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
        let alpha = choose_composite_alpha(caps.supported_composite_alpha);
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
        // The device's queue family can present to the surface (checked in `new`: a swapchain's
        // surface never changes); extent, image count, usage, format and present mode come from
        // this surface's capabilities, formats and modes; `old`, when given, is this surface's
        // live swapchain, retired by this call.
        // SAFETY: the surface and device are live and the create-info is valid for them.
        let raw = unsafe { loader.create_swapchain(&info, None) }.call("vkCreateSwapchainKHR")?;
        // SAFETY: `raw` was just created by `loader`.
        let images = match unsafe { loader.get_swapchain_images(raw) } {
            Ok(i) => i,
            Err(result) => {
                // SAFETY: `raw` is live and none of its images was acquired.
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
    /// (minimised): the swapchain is then left as it was, and [`Self::acquire`] answers
    /// `OutOfDate` until a later recreate succeeds.
    pub fn recreate(
        &mut self,
        device: &Device,
        surface: &Surface,
        window: (u32, u32),
    ) -> Result<bool, VkError> {
        if self.acquire.is_empty() {
            return Err(VkError::Other("recreate of a destroyed swapchain".into()));
        }
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
            self.needs_recreate = true;
            return Ok(false);
        };
        self.needs_recreate = false;
        // It was retired by `create_raw` and is destroyed once.
        // SAFETY: the device is idle (waited above), so no frame still uses the old swapchain's images or presents it.
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
        if self.needs_recreate || self.images.is_empty() {
            return Ok(Acquire::OutOfDate);
        }
        let semaphore = self.acquire[self.next_acquire];
        // `semaphore` is unsignaled with no pending wait: the ring is one longer than the frames in
        // flight and the renderer waits for frame n − FRAMES_IN_FLIGHT (which consumed it) before
        // acquiring for frame n.
        // SAFETY: the swapchain is live (not destroyed: `destroy` empties `images`, checked above).
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
        // `index` was acquired (callers pass `AcquiredImage::index`) and its `rendered` semaphore
        // is signaled by the submission that copied into it; the arrays live until the call
        // returns.
        // SAFETY: the swapchain and `device.queue` are live.
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
            // It is destroyed once (nulled right after), before its surface (see
            // `Surface::destroy`).
            // SAFETY: the device is idle, so no frame or present uses the swapchain.
            unsafe { self.loader.destroy_swapchain(self.raw, None) };
            self.raw = vk::SwapchainKHR::null();
        }
        self.images.clear();
    }
}

/// A swapchain image to present a frame in (the renderer records a copy into it).
#[derive(Debug, Clone, Copy)]
pub struct PresentTarget {
    pub image: vk::Image,
    pub extent: vk::Extent2D,
    /// Signaled by the presentation engine when the image is acquired; the frame's submission
    /// waits for it at [`ACQUIRE_WAIT_STAGE`], before the copy.
    pub acquired: vk::Semaphore,
    /// Signaled by the frame's submission when the copy is done; the present waits for it.
    pub rendered: vk::Semaphore,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vk::access_type::Access;
    use crate::vk::conv::map_access;

    #[test]
    fn the_acquire_wait_and_the_blit_barrier_share_a_stage() {
        assert_eq!(
            map_access(Access::SwapchainAcquired).stage,
            ACQUIRE_WAIT_STAGE
        );
    }
}
