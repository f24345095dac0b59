//! Frames in flight (kajiya's `DeviceFrame`, Granite's frame context): [`FrameRing`] owns every
//! per-frame resource — command pool and buffer, fence, staging region, descriptor pool,
//! timestamp queries and a deferred-destroy list — and [`FrameRing::begin_frame`] hands out a
//! [`FrameContext`] for the next frame only once that frame's fence has signalled. The context
//! is the one thing that carries the frame-in-flight index; submitting consumes it.
//!
//! Invariants:
//! - a frame's staging region, descriptor pool and queries are reset only while its
//!   [`SignalledFrame`] is held, i.e. after its fence was waited for and before its next submit;
//! - a buffer handed to [`FrameContext::defer_destroy`] is destroyed the next time that frame's
//!   fence is seen signalled (or at [`FrameRing::destroy`]), never while a submission may use it;
//! - timestamps are read only from a submission that wrote them ([`FrameContext::reset_timestamps`]
//!   marks it), once, after its fence.

use ash::vk;

use super::descriptors::FrameDescriptorPools;
use super::frame_slot::SignalledFrame;
use super::staging::StagingRing;
use super::timestamps::{GpuTimer, Pass, PassTimes};
use super::{Buffer, Device, VkError, VkResultExt, FRAMES_IN_FLIGHT};

/// The command recording state of one frame in flight.
struct InFlight {
    pool: vk::CommandPool,
    cmd: vk::CommandBuffer,
    /// Signaled by the queue when this frame's submission completes; waited by the CPU before
    /// anything the frame used is reused. Created signaled so the first wait returns at once.
    fence: vk::Fence,
    /// The last submission wrote this frame's timestamp queries and they were not read yet.
    timestamps_pending: bool,
    /// Objects the last submission may still use, destroyed once `fence` has signalled.
    deferred: Vec<Buffer>,
}

/// Every per-frame-in-flight resource, one set per frame.
pub struct FrameRing {
    frames: Vec<InFlight>,
    next: usize,
    staging: StagingRing,
    /// Times the staging region grew (`grow_staging`).
    staging_growths: u32,
    descriptors: FrameDescriptorPools,
    timer: GpuTimer,
}

/// A frame submitted and perhaps still in flight; [`FrameRing::wait`] blocks on it.
#[must_use = "wait for the frame, or drop it to leave it in flight"]
#[derive(Debug)]
pub struct Submitted {
    index: usize,
}

/// Exclusive access to one frame's resources, handed out once its fence has signalled.
pub struct FrameContext<'a> {
    ring: &'a mut FrameRing,
    frame: SignalledFrame,
    /// GPU pass times of this context's previous submission, when it was timed and not read.
    previous_gpu_ms: Option<PassTimes>,
    timed: bool,
}

impl FrameRing {
    /// `staging_budget` bytes per frame; each frame's descriptor pool holds `max_sets` sets of
    /// the given descriptor counts.
    pub fn new(
        device: &Device,
        staging_budget: u64,
        max_sets: u32,
        sizes: &[vk::DescriptorPoolSize],
    ) -> Result<Self, VkError> {
        let mut frames = Vec::new();
        let fail = |device: &Device, frames: &mut Vec<InFlight>| {
            for f in frames.drain(..) {
                f.destroy(device);
            }
        };
        for _ in 0..FRAMES_IN_FLIGHT {
            match InFlight::new(device) {
                Ok(f) => frames.push(f),
                Err(e) => {
                    fail(device, &mut frames);
                    return Err(e);
                }
            }
        }
        let mut staging = match StagingRing::new(device, staging_budget) {
            Ok(s) => s,
            Err(e) => {
                fail(device, &mut frames);
                return Err(e);
            }
        };
        let mut descriptors = match FrameDescriptorPools::new(device, max_sets, sizes) {
            Ok(d) => d,
            Err(e) => {
                staging.destroy(device);
                fail(device, &mut frames);
                return Err(e);
            }
        };
        let timer = match GpuTimer::new(device) {
            Ok(t) => t,
            Err(e) => {
                descriptors.destroy(device);
                staging.destroy(device);
                fail(device, &mut frames);
                return Err(e);
            }
        };
        Ok(Self {
            frames,
            next: 0,
            staging,
            staging_growths: 0,
            descriptors,
            timer,
        })
    }

    /// Bytes one frame may stage (the size of one staging region).
    pub fn staging_budget(&self) -> u64 {
        self.staging.budget()
    }

    /// Replaces the staging ring with one of `budget` bytes a region when that is more than
    /// now; true when it did. The new ring is made first (on failure the old one stays), then
    /// the device is waited idle, so no submission still reads a region of the old one: a
    /// one-off stall, when a frame's selection outgrows the region
    /// (`render::jobs::staging_to_hold`).
    pub fn grow_staging(&mut self, device: &Device, budget: u64) -> Result<bool, VkError> {
        if budget <= self.staging.budget() {
            return Ok(false);
        }
        let grown = StagingRing::new(device, budget)?;
        device.wait_idle();
        let mut old = std::mem::replace(&mut self.staging, grown);
        old.destroy(device);
        self.staging_growths += 1;
        Ok(true)
    }

    /// How often [`Self::grow_staging`] grew the region.
    pub fn staging_growths(&self) -> u32 {
        self.staging_growths
    }

    /// Alignment of every staging allocation.
    pub fn staging_alignment(&self) -> u64 {
        self.staging.alignment()
    }

    /// Waits for the next frame's fence, then: destroys its deferred objects, reads the
    /// timestamps its last submission wrote, opens its staging region and resets its descriptor
    /// pool, and hands out its context.
    pub fn begin_frame(&mut self, device: &Device) -> Result<FrameContext<'_>, VkError> {
        let i = self.next;
        let f = &mut self.frames[i];
        // SAFETY: the fence is live (destroyed only in `destroy`); waiting has no other effect.
        unsafe { device.raw.wait_for_fences(&[f.fence], true, u64::MAX) }
            .call("vkWaitForFences")?;
        let frame = SignalledFrame::after_fence_wait(i);
        for mut b in f.deferred.drain(..) {
            b.destroy(device);
        }
        let previous_gpu_ms = if std::mem::take(&mut f.timestamps_pending) {
            Some(self.timer.read_ms(device, &frame)?)
        } else {
            None
        };
        self.staging.begin_frame(&frame);
        self.descriptors.reset(device, &frame)?;
        Ok(FrameContext {
            ring: self,
            frame,
            previous_gpu_ms,
            timed: false,
        })
    }

    /// Blocks until `submitted` has completed; returns its GPU pass times when it was timed.
    pub fn wait(
        &mut self,
        device: &Device,
        submitted: Submitted,
    ) -> Result<Option<PassTimes>, VkError> {
        let f = &mut self.frames[submitted.index];
        // SAFETY: the fence is live; waiting has no other effect.
        unsafe { device.raw.wait_for_fences(&[f.fence], true, u64::MAX) }
            .call("vkWaitForFences")?;
        let frame = SignalledFrame::after_fence_wait(submitted.index);
        if std::mem::take(&mut f.timestamps_pending) {
            return self.timer.read_ms(device, &frame).map(Some);
        }
        Ok(None)
    }

    /// Waits for every frame, then destroys everything (deferred objects included).
    pub fn destroy(&mut self, device: &Device) {
        for f in self.frames.drain(..) {
            f.destroy(device);
        }
        self.timer.destroy(device);
        self.descriptors.destroy(device);
        self.staging.destroy(device);
    }
}

impl InFlight {
    fn new(device: &Device) -> Result<Self, VkError> {
        let pool_info = vk::CommandPoolCreateInfo::default()
            .queue_family_index(device.queue_family)
            .flags(vk::CommandPoolCreateFlags::TRANSIENT);
        // SAFETY: `device` is live and `pool_info` outlives the call.
        let pool = unsafe { device.raw.create_command_pool(&pool_info, None) }
            .call("vkCreateCommandPool")?;
        let alloc = vk::CommandBufferAllocateInfo::default()
            .command_pool(pool)
            .level(vk::CommandBufferLevel::PRIMARY)
            .command_buffer_count(1);
        // SAFETY: `pool` was just created; one buffer is asked for and one returned.
        let cmd = match unsafe { device.raw.allocate_command_buffers(&alloc) } {
            Ok(c) => c[0],
            Err(result) => {
                // SAFETY: `pool` has no buffers in use.
                unsafe { device.raw.destroy_command_pool(pool, None) };
                return Err(VkError::Call {
                    call: "vkAllocateCommandBuffers",
                    result,
                });
            }
        };
        let fence_info = vk::FenceCreateInfo::default().flags(vk::FenceCreateFlags::SIGNALED);
        // SAFETY: `device` is live and `fence_info` outlives the call.
        let fence = match unsafe { device.raw.create_fence(&fence_info, None) } {
            Ok(f) => f,
            Err(result) => {
                // SAFETY: `cmd` was never submitted, so the pool is not in use.
                unsafe { device.raw.destroy_command_pool(pool, None) };
                return Err(VkError::Call {
                    call: "vkCreateFence",
                    result,
                });
            }
        };
        Ok(Self {
            pool,
            cmd,
            fence,
            timestamps_pending: false,
            deferred: Vec::new(),
        })
    }

    fn destroy(mut self, device: &Device) {
        // Waiting first makes the last submission complete; `self` is consumed.
        // SAFETY: the fence, the pool's command buffer and the deferred objects are unused here.
        unsafe {
            let _ = device.raw.wait_for_fences(&[self.fence], true, u64::MAX);
            device.raw.destroy_fence(self.fence, None);
            device.raw.destroy_command_pool(self.pool, None);
        }
        for mut b in self.deferred.drain(..) {
            b.destroy(device);
        }
    }
}

impl FrameContext<'_> {
    /// The frame-in-flight index, for per-frame objects owned elsewhere (one per index).
    pub fn index(&self) -> usize {
        self.frame.index()
    }

    /// This frame's staging region, open from its start.
    pub fn staging(&mut self) -> &mut StagingRing {
        &mut self.ring.staging
    }

    /// The staging buffer (the source of every upload copy).
    pub fn staging_buffer(&self) -> vk::Buffer {
        self.ring.staging.raw()
    }

    /// GPU pass times of the previous submission of this context, when it was timed and not
    /// read since (frames left in flight by windowed presentation).
    pub fn previous_gpu_ms(&self) -> Option<PassTimes> {
        self.previous_gpu_ms
    }

    /// A descriptor set from this frame's pool, valid until this frame is next begun.
    pub fn allocate_set(
        &self,
        device: &Device,
        layout: vk::DescriptorSetLayout,
    ) -> Result<vk::DescriptorSet, VkError> {
        self.ring.descriptors.allocate(device, &self.frame, layout)
    }

    /// Destroys `buffer` once this frame's current submission has completed (when the frame is
    /// next begun): for per-frame buffers replaced while the GPU may still read the old one.
    pub fn defer_destroy(&mut self, buffer: Buffer) {
        self.ring.frames[self.frame.index()].deferred.push(buffer);
    }

    /// Resets the command pool and begins the command buffer. The fence stays signalled until
    /// [`Self::submit_with`] resets it right before the submission, so a frame abandoned between
    /// here and its submission (an error while recording) leaves nothing that waits forever.
    pub fn begin_recording(&mut self, device: &Device) -> Result<vk::CommandBuffer, VkError> {
        let f = &self.ring.frames[self.frame.index()];
        // The context holds the proof that the fence signalled; recording begins on a reset buffer.
        // SAFETY: the command buffer is not pending, so the pool may be reset.
        unsafe {
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

    /// Resets this frame's timestamp queries in `cmd`; the submission then counts as timed and
    /// must write every pass's begin and end.
    pub fn reset_timestamps(&mut self, device: &Device, cmd: vk::CommandBuffer) {
        self.ring.timer.reset(device, cmd, &self.frame);
        self.timed = true;
    }

    pub fn time_begin(&self, device: &Device, cmd: vk::CommandBuffer, pass: Pass) {
        self.ring.timer.begin(device, cmd, &self.frame, pass);
    }

    pub fn time_end(&self, device: &Device, cmd: vk::CommandBuffer, pass: Pass) {
        self.ring.timer.end(device, cmd, &self.frame, pass);
    }

    /// Ends and submits the command buffer, signaling the frame's fence; the next
    /// [`FrameRing::begin_frame`] gets the following frame.
    pub fn submit(self, device: &Device) -> Result<Submitted, VkError> {
        self.submit_with(device, &[], &[], &[])
    }

    /// As [`Self::submit`], waiting for `waits` (at `wait_stages`) before the work and signaling
    /// `signals` after it (e.g. a swapchain image's acquire and render-finished semaphores).
    pub fn submit_with(
        self,
        device: &Device,
        waits: &[vk::Semaphore],
        wait_stages: &[vk::PipelineStageFlags],
        signals: &[vk::Semaphore],
    ) -> Result<Submitted, VkError> {
        let i = self.frame.index();
        let ring = self.ring;
        let f = &mut ring.frames[i];
        // `f.cmd` was begun by `begin_recording`; the fence is signalled (the context's proof)
        // and no submission uses it, so it may be reset here, right before the one that will
        // signal it again.
        // SAFETY: the buffer is recording, the semaphore slices outlive the calls.
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
            device.raw.reset_fences(&[f.fence]).call("vkResetFences")?;
            if let Err(result) = device.raw.queue_submit(device.queue, &[submit], f.fence) {
                // The fence is unsignalled and nothing would signal it: an empty submission
                // does, so later waits on this frame return (or report a lost device) instead
                // of blocking forever.
                let _ = device.raw.queue_submit(device.queue, &[], f.fence);
                return Err(VkError::Call {
                    call: "vkQueueSubmit",
                    result,
                });
            }
        }
        f.timestamps_pending = self.timed;
        ring.next = (i + 1) % ring.frames.len();
        Ok(Submitted { index: i })
    }
}
