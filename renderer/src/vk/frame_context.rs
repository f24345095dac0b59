//! Per-frame-in-flight command recording state: a command pool, its one primary command buffer
//! and the fence that says the GPU is done with everything the frame used.

use ash::vk;

use super::{Device, VkError, VkResultExt, FRAMES_IN_FLIGHT};

pub struct FrameContext {
    pub pool: vk::CommandPool,
    pub cmd: vk::CommandBuffer,
    /// Signaled by the queue when this frame's submission completes; waited by the CPU before
    /// the frame's command buffer, staging region, descriptor pool and queries are reused.
    /// Created signaled so the first wait returns at once.
    pub fence: vk::Fence,
    /// Whether the last submission of this context wrote timestamps that were not read yet.
    pub submitted: bool,
}

pub struct FrameContexts {
    pub frames: Vec<FrameContext>,
    next: usize,
}

impl FrameContexts {
    pub fn new(device: &Device) -> Result<Self, VkError> {
        let mut this = Self {
            frames: Vec::new(),
            next: 0,
        };
        for _ in 0..FRAMES_IN_FLIGHT {
            match Self::create_one(device) {
                Ok(f) => this.frames.push(f),
                Err(e) => {
                    this.destroy(device);
                    return Err(e);
                }
            }
        }
        Ok(this)
    }

    fn create_one(device: &Device) -> Result<FrameContext, VkError> {
        let pool_info = vk::CommandPoolCreateInfo::default()
            .queue_family_index(device.queue_family)
            .flags(vk::CommandPoolCreateFlags::TRANSIENT);
        let pool = unsafe { device.raw.create_command_pool(&pool_info, None) }
            .call("vkCreateCommandPool")?;
        let alloc = vk::CommandBufferAllocateInfo::default()
            .command_pool(pool)
            .level(vk::CommandBufferLevel::PRIMARY)
            .command_buffer_count(1);
        let cmd = match unsafe { device.raw.allocate_command_buffers(&alloc) } {
            Ok(c) => c[0],
            Err(result) => {
                unsafe { device.raw.destroy_command_pool(pool, None) };
                return Err(VkError::Call {
                    call: "vkAllocateCommandBuffers",
                    result,
                });
            }
        };
        let fence_info = vk::FenceCreateInfo::default().flags(vk::FenceCreateFlags::SIGNALED);
        let fence = match unsafe { device.raw.create_fence(&fence_info, None) } {
            Ok(f) => f,
            Err(result) => {
                unsafe { device.raw.destroy_command_pool(pool, None) };
                return Err(VkError::Call {
                    call: "vkCreateFence",
                    result,
                });
            }
        };
        Ok(FrameContext {
            pool,
            cmd,
            fence,
            submitted: false,
        })
    }

    /// Index of the context the next frame will use.
    pub fn next_index(&self) -> usize {
        self.next
    }

    /// Waits for the next context's fence (the GPU is done with it), then returns its index.
    /// The fence stays signaled until [`Self::begin_recording`].
    pub fn wait_next(&mut self, device: &Device) -> Result<usize, VkError> {
        let i = self.next;
        let f = &self.frames[i];
        unsafe { device.raw.wait_for_fences(&[f.fence], true, u64::MAX) }
            .call("vkWaitForFences")?;
        Ok(i)
    }

    /// Resets the fence and the command pool of context `i` and begins its command buffer.
    pub fn begin_recording(
        &mut self,
        device: &Device,
        i: usize,
    ) -> Result<vk::CommandBuffer, VkError> {
        let f = &self.frames[i];
        unsafe {
            device.raw.reset_fences(&[f.fence]).call("vkResetFences")?;
            device
                .raw
                .reset_command_pool(f.pool, vk::CommandPoolResetFlags::empty())
                .call("vkResetCommandPool")?;
            let begin = vk::CommandBufferBeginInfo::default()
                .flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT);
            device
                .raw
                .begin_command_buffer(f.cmd, &begin)
                .call("vkBeginCommandBuffer")?;
        }
        Ok(f.cmd)
    }

    /// Ends and submits context `i`'s command buffer, signaling its fence; advances to the next.
    pub fn submit(&mut self, device: &Device, i: usize) -> Result<(), VkError> {
        self.submit_with(device, i, &[], &[], &[])
    }

    /// As [`Self::submit`], waiting for `waits` (at `wait_stages`) before the work and signaling
    /// `signals` after it (e.g. a swapchain image's acquire and render-finished semaphores).
    pub fn submit_with(
        &mut self,
        device: &Device,
        i: usize,
        waits: &[vk::Semaphore],
        wait_stages: &[vk::PipelineStageFlags],
        signals: &[vk::Semaphore],
    ) -> Result<(), VkError> {
        let f = &mut self.frames[i];
        unsafe {
            device
                .raw
                .end_command_buffer(f.cmd)
                .call("vkEndCommandBuffer")?;
            let cmds = [f.cmd];
            let submit = vk::SubmitInfo::default()
                .command_buffers(&cmds)
                .wait_semaphores(waits)
                .wait_dst_stage_mask(wait_stages)
                .signal_semaphores(signals);
            device
                .raw
                .queue_submit(device.queue, &[submit], f.fence)
                .call("vkQueueSubmit")?;
        }
        f.submitted = true;
        self.next = (i + 1) % self.frames.len();
        Ok(())
    }

    /// Blocks until context `i`'s last submission has completed.
    pub fn wait(&self, device: &Device, i: usize) -> Result<(), VkError> {
        unsafe {
            device
                .raw
                .wait_for_fences(&[self.frames[i].fence], true, u64::MAX)
        }
        .call("vkWaitForFences")
    }

    pub fn destroy(&mut self, device: &Device) {
        for f in self.frames.drain(..) {
            unsafe {
                let _ = device.raw.wait_for_fences(&[f.fence], true, u64::MAX);
                device.raw.destroy_fence(f.fence, None);
                device.raw.destroy_command_pool(f.pool, None);
            }
        }
    }
}
