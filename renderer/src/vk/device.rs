//! Physical-device choice, logical device, the graphics queue and the memory allocator. The
//! choice itself is pure ([`choose_device`], [`missing_requirements`] in `conv.rs`); this file
//! reads what each device offers and creates the chosen one.

use std::mem::ManuallyDrop;
use std::sync::Mutex;

use ash::vk;
use gpu_allocator::vulkan::{Allocator, AllocatorCreateDesc};

use super::conv::{
    choose_device, map_timestamp_period, missing_requirements, DeviceCandidate, DeviceOffer,
    DEPTH_FORMAT,
};
use super::error::{VkError, VkResultExt};
use super::instance::Instance;

/// What the renderer needs from a device, and how to pick one.
#[derive(Debug, Clone, Default)]
pub struct DeviceDesc {
    /// `--gpu <substring>`: only devices whose name contains this (case-insensitive).
    pub name_filter: Option<String>,
    /// Enable `VK_KHR_swapchain` (windowed presentation); devices without it are unsuitable.
    pub swapchain: bool,
}

/// The logical device with its one graphics queue and the allocator. Created by
/// [`Device::new`], destroyed by [`Device::destroy`] after every object made from it and before
/// the [`Instance`] it was made from. Between the two, `raw` is a live device: every safe
/// function of this layer taking a `&Device` relies on that.
pub struct Device {
    pub raw: ash::Device,
    pub physical: vk::PhysicalDevice,
    pub name: String,
    pub queue: vk::Queue,
    pub queue_family: u32,
    pub properties: vk::PhysicalDeviceProperties,
    /// Nanoseconds per timestamp tick; `None` when the queue cannot write timestamps.
    pub timestamp_period_ns: Option<f64>,
    /// `tessellationShader` is enabled (the device offers it): the tessellation baseline's
    /// pipeline can be made.
    pub tessellation: bool,
    allocator: ManuallyDrop<Mutex<Allocator>>,
    /// Set by `destroy`, so that a second call neither drops the allocator again nor destroys
    /// the device twice.
    destroyed: bool,
}

/// Reads what `pd` offers; also returns its first graphics queue family.
fn candidate(
    instance: &ash::Instance,
    pd: vk::PhysicalDevice,
    desc: &DeviceDesc,
) -> (DeviceCandidate, Option<u32>) {
    // Every call in this function: `instance` is borrowed from an `Instance` not yet destroyed
    // and `pd` was enumerated from it; the queries only fill plain structs.
    // SAFETY: `instance` is live and `pd` is one of its physical devices.
    let props = unsafe { instance.get_physical_device_properties(pd) };
    let name = props
        .device_name_as_c_str()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|_| "?".into());
    // SAFETY: see above.
    let families = unsafe { instance.get_physical_device_queue_family_properties(pd) };
    // Graphics and compute on one queue (the GPU normal pass is recorded between the uploads
    // and the draw); Vulkan guarantees such a family wherever graphics is offered.
    let family = families
        .iter()
        .position(|f| {
            f.queue_flags
                .contains(vk::QueueFlags::GRAPHICS | vk::QueueFlags::COMPUTE)
        })
        .map(|i| i as u32);
    let swapchain_extension = desc.swapchain.then(|| {
        let exts =
            // SAFETY: see the top of this function.
            unsafe { instance.enumerate_device_extension_properties(pd) }.unwrap_or_default();
        exts.iter()
            .any(|e| e.extension_name_as_c_str().ok() == Some(ash::khr::swapchain::NAME))
    });
    // SAFETY: see above.
    let features = unsafe { instance.get_physical_device_features(pd) };
    let dynamic_rendering = props.api_version >= vk::API_VERSION_1_3 && {
        let mut f13 = vk::PhysicalDeviceVulkan13Features::default();
        let mut f2 = vk::PhysicalDeviceFeatures2::default().push_next(&mut f13);
        // The device is 1.3, so the 1.3 feature struct in the chain is known to it, and both
        // structs outlive the call.
        // SAFETY: see above.
        unsafe { instance.get_physical_device_features2(pd, &mut f2) };
        f13.dynamic_rendering == vk::TRUE
    };
    // SAFETY: see above.
    let depth = unsafe { instance.get_physical_device_format_properties(pd, DEPTH_FORMAT) };
    let offer = DeviceOffer {
        api_version: props.api_version,
        graphics_queue: family.is_some(),
        swapchain_extension,
        multi_draw_indirect: features.multi_draw_indirect == vk::TRUE,
        draw_indirect_first_instance: features.draw_indirect_first_instance == vk::TRUE,
        dynamic_rendering,
        depth_format_features: depth.optimal_tiling_features,
    };
    (
        DeviceCandidate {
            name,
            kind: props.device_type,
            missing: missing_requirements(&offer),
        },
        family,
    )
}

impl Device {
    pub fn new(instance: &Instance, desc: &DeviceDesc) -> Result<Self, VkError> {
        // SAFETY: `instance.raw` is live (borrowed from an `Instance` not yet destroyed).
        let physicals = unsafe { instance.raw.enumerate_physical_devices() }
            .call("vkEnumeratePhysicalDevices")?;
        let described: Vec<_> = physicals
            .iter()
            .map(|&pd| candidate(&instance.raw, pd, desc))
            .collect();
        let candidates: Vec<_> = described.iter().map(|(c, _)| c.clone()).collect();
        let index = choose_device(&candidates, desc.name_filter.as_deref())
            .map_err(VkError::NoSuitableDevice)?;
        let physical = physicals[index];
        let queue_family = described[index]
            .1
            .expect("suitable device has a graphics queue");
        // SAFETY: the instance is live and `physical` was enumerated from it.
        let properties = unsafe { instance.raw.get_physical_device_properties(physical) };
        // SAFETY: as above.
        let families = unsafe {
            instance
                .raw
                .get_physical_device_queue_family_properties(physical)
        };
        let timestamp_period_ns = map_timestamp_period(
            families[queue_family as usize].timestamp_valid_bits,
            properties.limits.timestamp_period,
        );

        let priorities = [1.0f32];
        let queue_infos = [vk::DeviceQueueCreateInfo::default()
            .queue_family_index(queue_family)
            .queue_priorities(&priorities)];
        // SAFETY: as above.
        let offered = unsafe { instance.raw.get_physical_device_features(physical) };
        let tessellation = offered.tessellation_shader == vk::TRUE;
        let features = vk::PhysicalDeviceFeatures::default()
            .multi_draw_indirect(true)
            .draw_indirect_first_instance(true)
            .tessellation_shader(tessellation);
        let mut f13 = vk::PhysicalDeviceVulkan13Features::default().dynamic_rendering(true);
        let extensions = if desc.swapchain {
            vec![ash::khr::swapchain::NAME.as_ptr()]
        } else {
            Vec::new()
        };
        let create_info = vk::DeviceCreateInfo::default()
            .queue_create_infos(&queue_infos)
            .enabled_extension_names(&extensions)
            .enabled_features(&features)
            .push_next(&mut f13);
        // `physical` is its device and was found suitable, so it has the queue family, the features
        // and (when asked) the extension enabled here; every array and chained struct the
        // create-info points to lives until the call returns.
        // SAFETY: the instance is live.
        let raw = unsafe { instance.raw.create_device(physical, &create_info, None) }
            .call("vkCreateDevice")?;
        // SAFETY: queue 0 of `queue_family` was requested in `queue_infos` above.
        let queue = unsafe { raw.get_device_queue(queue_family, 0) };

        let allocator = Allocator::new(&AllocatorCreateDesc {
            instance: instance.raw.clone(),
            device: raw.clone(),
            physical_device: physical,
            debug_settings: Default::default(),
            buffer_device_address: false,
            allocation_sizes: gpu_allocator::AllocationSizes::new(64 << 20, 32 << 20),
        });
        let allocator = match allocator {
            Ok(a) => a,
            Err(source) => {
                // SAFETY: the device was just created and nothing was made from it yet.
                unsafe { raw.destroy_device(None) };
                return Err(VkError::Allocation {
                    what: "allocator".into(),
                    source,
                });
            }
        };
        Ok(Self {
            raw,
            physical,
            name: candidates[index].name.clone(),
            queue,
            queue_family,
            properties,
            timestamp_period_ns,
            tessellation,
            allocator: ManuallyDrop::new(Mutex::new(allocator)),
            destroyed: false,
        })
    }

    /// The allocator; poisoned locks are recovered because the allocator has no invariants a
    /// panicking caller could have broken half-way.
    pub fn allocator(&self) -> std::sync::MutexGuard<'_, Allocator> {
        assert!(!self.destroyed, "the allocator of a destroyed device");
        self.allocator.lock().unwrap_or_else(|p| p.into_inner())
    }

    pub fn wait_idle(&self) {
        if self.destroyed {
            return;
        }
        // Waiting touches no object. Teardown path: a lost device leaves nothing better to do than
        // continue destroying.
        // SAFETY: the device is live (not destroyed: checked above).
        let _ = unsafe { self.raw.device_wait_idle() };
    }

    /// Waits for the device, drops the allocator (frees its memory blocks; it reports leaked
    /// allocations in its log), then destroys the device. Every buffer, image and other object
    /// made from the device must have been destroyed first (the validation layer reports any
    /// left). Idempotent.
    pub fn destroy(&mut self) {
        if self.destroyed {
            return;
        }
        self.wait_idle();
        self.destroyed = true;
        // Nothing reads it afterwards (`allocator()` asserts). The device is idle, its memory blocks were freed by that drop, and
        // it is destroyed once, after them.
        // SAFETY: `destroyed` was false, so the allocator is still there and is dropped exactly once.
        unsafe {
            ManuallyDrop::drop(&mut self.allocator);
            self.raw.destroy_device(None);
        }
    }
}
