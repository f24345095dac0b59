//! Hand-managed descriptors: one pool per frame in flight, reset when the frame starts (its
//! fence has signaled), sets allocated from explicit layouts. No per-draw pools, no bindless.

use ash::vk;

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

    /// Frees every set of frame `frame`'s pool. Only call after that frame's fence signaled.
    pub fn reset(&self, device: &Device, frame: usize) -> Result<(), VkError> {
        unsafe {
            device
                .raw
                .reset_descriptor_pool(self.pools[frame], vk::DescriptorPoolResetFlags::empty())
        }
        .call("vkResetDescriptorPool")
    }

    pub fn allocate(
        &self,
        device: &Device,
        frame: usize,
        layout: vk::DescriptorSetLayout,
    ) -> Result<vk::DescriptorSet, VkError> {
        let layouts = [layout];
        let info = vk::DescriptorSetAllocateInfo::default()
            .descriptor_pool(self.pools[frame])
            .set_layouts(&layouts);
        unsafe { device.raw.allocate_descriptor_sets(&info) }
            .call("vkAllocateDescriptorSets")
            .map(|s| s[0])
    }

    pub fn destroy(&mut self, device: &Device) {
        for p in self.pools.drain(..) {
            unsafe { device.raw.destroy_descriptor_pool(p, None) };
        }
    }
}
