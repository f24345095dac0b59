//! Physical-device choice, logical device, the graphics queue and the memory allocator.

use std::mem::ManuallyDrop;
use std::sync::Mutex;

use ash::vk;
use gpu_allocator::vulkan::{Allocator, AllocatorCreateDesc};

use super::{Instance, VkError, VkResultExt};

/// What the renderer needs from a device, and how to pick one.
#[derive(Debug, Clone, Default)]
pub struct DeviceDesc {
    /// `--gpu <substring>`: only devices whose name contains this (case-insensitive).
    pub name_filter: Option<String>,
    /// Enable `VK_KHR_swapchain` (windowed presentation); devices without it are unsuitable.
    pub swapchain: bool,
}

/// Plain description of one physical device, for the (pure) choice below.
#[derive(Debug, Clone)]
pub struct DeviceCandidate {
    pub name: String,
    pub kind: vk::PhysicalDeviceType,
    /// Features and properties the renderer requires that this device lacks.
    pub missing: Vec<&'static str>,
}

/// Preference order: discrete > integrated > virtual > CPU > other.
fn kind_rank(kind: vk::PhysicalDeviceType) -> u32 {
    match kind {
        vk::PhysicalDeviceType::DISCRETE_GPU => 0,
        vk::PhysicalDeviceType::INTEGRATED_GPU => 1,
        vk::PhysicalDeviceType::VIRTUAL_GPU => 2,
        vk::PhysicalDeviceType::CPU => 3,
        _ => 4,
    }
}

/// Picks the best suitable candidate (index), or explains why none is: every device found with
/// its type and what it lacks.
pub fn choose_device(
    candidates: &[DeviceCandidate],
    filter: Option<&str>,
) -> Result<usize, String> {
    let filter_lc = filter.map(|f| f.to_lowercase());
    let best = candidates
        .iter()
        .enumerate()
        .filter(|(_, c)| c.missing.is_empty())
        .filter(|(_, c)| {
            filter_lc
                .as_ref()
                .is_none_or(|f| c.name.to_lowercase().contains(f))
        })
        .min_by_key(|(i, c)| (kind_rank(c.kind), *i))
        .map(|(i, _)| i);
    best.ok_or_else(|| {
        let list = if candidates.is_empty() {
            "no Vulkan devices found".to_string()
        } else {
            candidates
                .iter()
                .map(|c| {
                    let lacks = if c.missing.is_empty() {
                        String::from("suitable")
                    } else {
                        format!("missing {}", c.missing.join(", "))
                    };
                    format!("'{}' ({:?}: {lacks})", c.name, c.kind)
                })
                .collect::<Vec<_>>()
                .join("; ")
        };
        match filter {
            Some(f) => format!("none matches --gpu '{f}'; devices found: {list}"),
            None => format!("devices found: {list}"),
        }
    })
}

/// The logical device with its one graphics queue and the allocator. Destroyed explicitly.
pub struct Device {
    pub raw: ash::Device,
    pub physical: vk::PhysicalDevice,
    pub name: String,
    pub queue: vk::Queue,
    pub queue_family: u32,
    pub properties: vk::PhysicalDeviceProperties,
    /// Nanoseconds per timestamp tick; `None` when the queue cannot write timestamps.
    pub timestamp_period_ns: Option<f64>,
    allocator: ManuallyDrop<Mutex<Allocator>>,
}

fn candidate(
    instance: &ash::Instance,
    pd: vk::PhysicalDevice,
    desc: &DeviceDesc,
) -> (DeviceCandidate, Option<u32>) {
    let props = unsafe { instance.get_physical_device_properties(pd) };
    let name = props
        .device_name_as_c_str()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|_| "?".into());
    let mut missing = Vec::new();
    if props.api_version < vk::API_VERSION_1_3 {
        missing.push("Vulkan 1.3");
    }
    let families = unsafe { instance.get_physical_device_queue_family_properties(pd) };
    let family = families
        .iter()
        .position(|f| f.queue_flags.contains(vk::QueueFlags::GRAPHICS))
        .map(|i| i as u32);
    if family.is_none() {
        missing.push("a graphics queue");
    }
    if desc.swapchain {
        let exts =
            unsafe { instance.enumerate_device_extension_properties(pd) }.unwrap_or_default();
        let has = exts
            .iter()
            .any(|e| e.extension_name_as_c_str().ok() == Some(ash::khr::swapchain::NAME));
        if !has {
            missing.push("VK_KHR_swapchain");
        }
    }
    let features = unsafe { instance.get_physical_device_features(pd) };
    if features.multi_draw_indirect == vk::FALSE {
        missing.push("multiDrawIndirect");
    }
    if features.draw_indirect_first_instance == vk::FALSE {
        missing.push("drawIndirectFirstInstance");
    }
    if props.api_version >= vk::API_VERSION_1_3 {
        let mut f13 = vk::PhysicalDeviceVulkan13Features::default();
        let mut f2 = vk::PhysicalDeviceFeatures2::default().push_next(&mut f13);
        unsafe { instance.get_physical_device_features2(pd, &mut f2) };
        if f13.dynamic_rendering == vk::FALSE {
            missing.push("dynamicRendering");
        }
    }
    let fmt = unsafe { instance.get_physical_device_format_properties(pd, vk::Format::D32_SFLOAT) };
    if !fmt
        .optimal_tiling_features
        .contains(vk::FormatFeatureFlags::DEPTH_STENCIL_ATTACHMENT)
    {
        missing.push("D32_SFLOAT depth");
    }
    (
        DeviceCandidate {
            name,
            kind: props.device_type,
            missing,
        },
        family,
    )
}

impl Device {
    pub fn new(instance: &Instance, desc: &DeviceDesc) -> Result<Self, VkError> {
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
        let properties = unsafe { instance.raw.get_physical_device_properties(physical) };
        let families = unsafe {
            instance
                .raw
                .get_physical_device_queue_family_properties(physical)
        };
        let timestamp_period_ns = (families[queue_family as usize].timestamp_valid_bits > 0
            && properties.limits.timestamp_period > 0.0)
            .then_some(properties.limits.timestamp_period as f64);

        let priorities = [1.0f32];
        let queue_infos = [vk::DeviceQueueCreateInfo::default()
            .queue_family_index(queue_family)
            .queue_priorities(&priorities)];
        let features = vk::PhysicalDeviceFeatures::default()
            .multi_draw_indirect(true)
            .draw_indirect_first_instance(true);
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
        let raw = unsafe { instance.raw.create_device(physical, &create_info, None) }
            .call("vkCreateDevice")?;
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
            allocator: ManuallyDrop::new(Mutex::new(allocator)),
        })
    }

    /// The allocator; poisoned locks are recovered because the allocator has no invariants a
    /// panicking caller could have broken half-way.
    pub fn allocator(&self) -> std::sync::MutexGuard<'_, Allocator> {
        self.allocator.lock().unwrap_or_else(|p| p.into_inner())
    }

    pub fn wait_idle(&self) {
        // Teardown path: a lost device leaves nothing better to do than continue destroying.
        let _ = unsafe { self.raw.device_wait_idle() };
    }

    /// Drops the allocator (frees its memory blocks), then destroys the device. Every buffer and
    /// image must have been destroyed first.
    pub fn destroy(&mut self) {
        self.wait_idle();
        unsafe {
            ManuallyDrop::drop(&mut self.allocator);
            self.raw.destroy_device(None);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn c(name: &str, kind: vk::PhysicalDeviceType, missing: &[&'static str]) -> DeviceCandidate {
        DeviceCandidate {
            name: name.into(),
            kind,
            missing: missing.to_vec(),
        }
    }

    #[test]
    fn prefers_discrete_then_integrated_then_virtual_then_cpu() {
        let list = vec![
            c("llvmpipe", vk::PhysicalDeviceType::CPU, &[]),
            c("virt", vk::PhysicalDeviceType::VIRTUAL_GPU, &[]),
            c("igpu", vk::PhysicalDeviceType::INTEGRATED_GPU, &[]),
            c("dgpu", vk::PhysicalDeviceType::DISCRETE_GPU, &[]),
        ];
        assert_eq!(choose_device(&list, None), Ok(3));
        assert_eq!(choose_device(&list[..3], None), Ok(2));
        assert_eq!(choose_device(&list[..2], None), Ok(1));
        assert_eq!(choose_device(&list[..1], None), Ok(0));
    }

    #[test]
    fn unsuitable_devices_are_skipped_and_listed() {
        let list = vec![
            c(
                "dgpu",
                vk::PhysicalDeviceType::DISCRETE_GPU,
                &["multiDrawIndirect"],
            ),
            c("llvmpipe", vk::PhysicalDeviceType::CPU, &[]),
        ];
        assert_eq!(choose_device(&list, None), Ok(1));
        let err = choose_device(&list[..1], None).unwrap_err();
        assert!(
            err.contains("dgpu") && err.contains("missing multiDrawIndirect"),
            "{err}"
        );
    }

    #[test]
    fn gpu_filter_overrides_preference() {
        let list = vec![
            c("NVIDIA RTX", vk::PhysicalDeviceType::DISCRETE_GPU, &[]),
            c("llvmpipe (LLVM)", vk::PhysicalDeviceType::CPU, &[]),
        ];
        assert_eq!(choose_device(&list, Some("LLVMPIPE")), Ok(1));
        let err = choose_device(&list, Some("radeon")).unwrap_err();
        assert!(
            err.contains("--gpu 'radeon'")
                && err.contains("NVIDIA RTX")
                && err.contains("llvmpipe"),
            "{err}"
        );
        assert!(choose_device(&[], None)
            .unwrap_err()
            .contains("no Vulkan devices"));
    }
}
