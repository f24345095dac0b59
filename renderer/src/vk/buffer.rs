//! A buffer with its memory.

use ash::vk;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};
use gpu_allocator::MemoryLocation;

use super::{Device, VkError, VkResultExt};

pub struct Buffer {
    pub raw: vk::Buffer,
    pub size: u64,
    allocation: Option<Allocation>,
}

impl Buffer {
    pub fn new(
        device: &Device,
        name: &str,
        size: u64,
        usage: vk::BufferUsageFlags,
        location: MemoryLocation,
    ) -> Result<Self, VkError> {
        let info = vk::BufferCreateInfo::default()
            .size(size.max(4))
            .usage(usage)
            .sharing_mode(vk::SharingMode::EXCLUSIVE);
        // SAFETY: `device` is live and `info` outlives the call.
        let raw = unsafe { device.raw.create_buffer(&info, None) }.call("vkCreateBuffer")?;
        // SAFETY: `raw` was just created on `device`.
        let requirements = unsafe { device.raw.get_buffer_memory_requirements(raw) };
        let allocation = device.allocator().allocate(&AllocationCreateDesc {
            name,
            requirements,
            location,
            linear: true,
            allocation_scheme: AllocationScheme::GpuAllocatorManaged,
        });
        let allocation = match allocation {
            Ok(a) => a,
            Err(source) => {
                // SAFETY: `raw` is unbound and unused, created just above.
                unsafe { device.raw.destroy_buffer(raw, None) };
                return Err(VkError::Allocation {
                    what: name.into(),
                    source,
                });
            }
        };
        // SAFETY: `allocation` was made for `raw`'s requirements and is not bound elsewhere.
        let bound = unsafe {
            device
                .raw
                .bind_buffer_memory(raw, allocation.memory(), allocation.offset())
        };
        if let Err(result) = bound {
            let _ = device.allocator().free(allocation);
            // SAFETY: `raw` was never used by the GPU (binding failed).
            unsafe { device.raw.destroy_buffer(raw, None) };
            return Err(VkError::Call {
                call: "vkBindBufferMemory",
                result,
            });
        }
        Ok(Self {
            raw,
            size,
            allocation: Some(allocation),
        })
    }

    /// The persistently mapped bytes of a host-visible buffer.
    pub fn mapped(&self) -> Option<&[u8]> {
        self.allocation.as_ref()?.mapped_slice()
    }

    pub fn mapped_mut(&mut self) -> Option<&mut [u8]> {
        self.allocation.as_mut()?.mapped_slice_mut()
    }

    /// Frees the buffer once no submission can use it: after the device is idle, or — for a
    /// per-frame buffer replaced while frames are in flight — through the frame context's
    /// deferred-destroy list (`FrameContext::defer_destroy`). Idempotent.
    pub fn destroy(&mut self, device: &Device) {
        if let Some(a) = self.allocation.take() {
            let _ = device.allocator().free(a);
            // Taking the allocation makes this run once per buffer.
            // SAFETY: no pending submission uses the buffer (the caller's contract above).
            unsafe { device.raw.destroy_buffer(self.raw, None) };
            self.raw = vk::Buffer::null();
        }
    }
}
