//! Hand-managed descriptors: one pool per frame in flight, reset when the frame starts (its
//! fence has signaled), sets allocated from explicit layouts. No per-draw pools, no bindless.

use ash::vk;

use super::frame_slot::SignalledFrame;
use super::{Device, VkError, VkResultExt, FRAMES_IN_FLIGHT};

pub struct FrameDescriptorPools {
    pools: Vec<vk::DescriptorPool>,
}

impl FrameDescriptorPools {
    /// Each pool holds `max_sets` sets and the given descriptor counts.
    pub fn new(
        device: &Device,
        max_sets: u32,
        sizes: &[vk::DescriptorPoolSize],
    ) -> Result<Self, VkError> {
        let mut this = Self { pools: Vec::new() };
        for _ in 0..FRAMES_IN_FLIGHT {
            let info = vk::DescriptorPoolCreateInfo::default()
                .max_sets(max_sets)
                .pool_sizes(sizes);
            // SAFETY: `device` is live and `info` (with `sizes`) outlives the call.
            match unsafe { device.raw.create_descriptor_pool(&info, None) } {
                Ok(p) => this.pools.push(p),
                Err(result) => {
                    this.destroy(device);
                    return Err(VkError::Call {
                        call: "vkCreateDescriptorPool",
                        result,
                    });
                }
            }
        }
        Ok(this)
    }

    /// Frees every set of `frame`'s pool: no submission that bound them is in flight.
    pub fn reset(&self, device: &Device, frame: &SignalledFrame) -> Result<(), VkError> {
        let pool = self.pools[frame.index()];
        // `frame`'s fence has signalled (the token says so); the pool is live.
        // SAFETY: no command buffer that uses a set of this pool is pending.
        unsafe {
            device
                .raw
                .reset_descriptor_pool(pool, vk::DescriptorPoolResetFlags::empty())
        }
        .call("vkResetDescriptorPool")
    }

    /// A set of `layout` from `frame`'s pool, valid until that frame's pool is next reset.
    pub fn allocate(
        &self,
        device: &Device,
        frame: &SignalledFrame,
        layout: vk::DescriptorSetLayout,
    ) -> Result<vk::DescriptorSet, VkError> {
        let layouts = [layout];
        let info = vk::DescriptorSetAllocateInfo::default()
            .descriptor_pool(self.pools[frame.index()])
            .set_layouts(&layouts);
        // Only the thread holding `frame` allocates from this pool (pools are externally
        // synchronised).
        // SAFETY: the pool and `layout` are live.
        unsafe { device.raw.allocate_descriptor_sets(&info) }
            .call("vkAllocateDescriptorSets")
            .map(|s| s[0])
    }

    /// Call after the device is idle.
    pub fn destroy(&mut self, device: &Device) {
        for p in self.pools.drain(..) {
            // `p` is dropped from the list, so it is destroyed once.
            // SAFETY: the device is idle (caller), so no set of `p` is in use.
            unsafe { device.raw.destroy_descriptor_pool(p, None) };
        }
    }
}
