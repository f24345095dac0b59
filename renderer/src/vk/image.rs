//! A 2-D image (optionally an array) with its memory and one view: one coherent group, created
//! in [`Image2d::new`] and destroyed in reverse (view, image, memory) by [`Image2d::destroy`].

use ash::vk;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};
use gpu_allocator::MemoryLocation;

use super::access::{image_barrier, Access};
use super::device::Device;
use super::error::{VkError, VkResultExt};

pub use super::conv::subresource_range;

#[derive(Debug, Clone, Copy)]
pub struct ImageDesc {
    pub width: u32,
    pub height: u32,
    pub format: vk::Format,
    pub usage: vk::ImageUsageFlags,
    pub aspect: vk::ImageAspectFlags,
    /// Array layers; when > 0 the view is a 2-D array view (0 = a plain 2-D image).
    pub layers: u32,
    /// Mip levels (0 counts as 1); the view covers them all.
    pub mips: u32,
}

pub struct Image2d {
    pub raw: vk::Image,
    pub view: vk::ImageView,
    pub desc: ImageDesc,
    /// Device bytes of the image (its memory requirements: every mip and layer).
    pub bytes: u64,
    allocation: Option<Allocation>,
}

impl Image2d {
    pub fn new(device: &Device, name: &str, desc: ImageDesc) -> Result<Self, VkError> {
        let info = vk::ImageCreateInfo::default()
            .image_type(vk::ImageType::TYPE_2D)
            .format(desc.format)
            .extent(vk::Extent3D {
                width: desc.width,
                height: desc.height,
                depth: 1,
            })
            .mip_levels(desc.mips.max(1))
            .array_layers(desc.layers.max(1))
            .samples(vk::SampleCountFlags::TYPE_1)
            .tiling(vk::ImageTiling::OPTIMAL)
            .usage(desc.usage)
            .sharing_mode(vk::SharingMode::EXCLUSIVE)
            .initial_layout(vk::ImageLayout::UNDEFINED);
        // `info` is a fully initialised create-info that outlives the call (at least one mip and
        // layer, a 2-D extent).
        // SAFETY: the device is live.
        let raw = unsafe { device.raw.create_image(&info, None) }.call("vkCreateImage")?;
        // SAFETY: `raw` was just created on this device and is not yet destroyed.
        let requirements = unsafe { device.raw.get_image_memory_requirements(raw) };
        let allocation = device.allocator().allocate(&AllocationCreateDesc {
            name,
            requirements,
            location: MemoryLocation::GpuOnly,
            linear: false,
            allocation_scheme: AllocationScheme::GpuAllocatorManaged,
        });
        let allocation = match allocation {
            Ok(a) => a,
            Err(source) => {
                // SAFETY: `raw` is ours, unbound and unused by any command: nothing else has it.
                unsafe { device.raw.destroy_image(raw, None) };
                return Err(VkError::Allocation {
                    what: name.into(),
                    source,
                });
            }
        };
        let mut image = Self {
            raw,
            view: vk::ImageView::null(),
            desc,
            bytes: requirements.size,
            allocation: None,
        };
        // The allocation was made for its memory requirements, so memory and offset satisfy size
        // and alignment.
        // SAFETY: `raw` is a live, not yet bound image of this device.
        let bound = unsafe {
            device
                .raw
                .bind_image_memory(raw, allocation.memory(), allocation.offset())
        };
        image.allocation = Some(allocation);
        if let Err(result) = bound {
            image.destroy(device);
            return Err(VkError::Call {
                call: "vkBindImageMemory",
                result,
            });
        }
        let view_info = vk::ImageViewCreateInfo::default()
            .image(raw)
            .view_type(if desc.layers > 0 {
                vk::ImageViewType::TYPE_2D_ARRAY
            } else {
                vk::ImageViewType::TYPE_2D
            })
            .format(desc.format)
            .subresource_range(image.range());
        // The view's format and range match its creation (same format, its aspect, its layer
        // and mip counts).
        // SAFETY: `raw` is live and bound to memory.
        match unsafe { device.raw.create_image_view(&view_info, None) } {
            Ok(v) => image.view = v,
            Err(result) => {
                image.destroy(device);
                return Err(VkError::Call {
                    call: "vkCreateImageView",
                    result,
                });
            }
        }
        Ok(image)
    }

    /// Records a barrier over the image (mip 0, every layer) from the `prev` uses to the `next`
    /// ([`image_barrier`]'s contract: `cmd` recording on `device`, the image live).
    pub fn barrier(
        &self,
        device: &Device,
        cmd: vk::CommandBuffer,
        prev: &[Access],
        next: &[Access],
        discard: bool,
    ) {
        image_barrier(device, cmd, self.raw, self.desc.aspect, prev, next, discard);
    }

    /// Every mip and layer of the image.
    pub fn range(&self) -> vk::ImageSubresourceRange {
        vk::ImageSubresourceRange {
            level_count: self.desc.mips.max(1),
            layer_count: self.desc.layers.max(1),
            ..subresource_range(self.desc.aspect)
        }
    }

    /// View first, then image, then memory. Idempotent: handles are nulled as they go. The
    /// caller must no longer have commands using the image in flight (the owners destroy after
    /// `Device::wait_idle`).
    pub fn destroy(&mut self, device: &Device) {
        if self.view != vk::ImageView::null() {
            // No command using it is pending (see above).
            // SAFETY: the view was created by `new` on this device and is destroyed once (nulled right after).
            unsafe { device.raw.destroy_image_view(self.view, None) };
            self.view = vk::ImageView::null();
        }
        if let Some(a) = self.allocation.take() {
            // The allocation is taken, so this runs once per image, and the memory is freed only
            // after the image bound to it is gone.
            // SAFETY: as for the view.
            unsafe { device.raw.destroy_image(self.raw, None) };
            let _ = device.allocator().free(a);
            self.raw = vk::Image::null();
        }
    }
}
