//! GPU timestamp queries around each pass, per frame in flight, read back after the frame's fence.

use ash::vk;

use super::frame_slot::SignalledFrame;
use super::{Device, VkError, VkResultExt, FRAMES_IN_FLIGHT};

/// Passes timed per frame. Each has a begin and an end query.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Pass {
    Upload = 0,
    Terrain = 1,
    /// `--normals gpu`: the normal pass's dispatches and its copy into the normal texture
    /// (begin and end written back to back otherwise).
    Normals = 2,
}
pub const PASS_COUNT: u32 = 3;
const QUERIES_PER_FRAME: u32 = PASS_COUNT * 2;

/// Milliseconds per [`Pass`], indexed by `Pass as usize`.
pub type PassTimes = [f64; PASS_COUNT as usize];

pub struct GpuTimer {
    pool: vk::QueryPool,
    /// Nanoseconds per tick; `None` disables timing (queue without timestamp support).
    period_ns: Option<f64>,
}

impl GpuTimer {
    pub fn new(device: &Device) -> Result<Self, VkError> {
        let info = vk::QueryPoolCreateInfo::default()
            .query_type(vk::QueryType::TIMESTAMP)
            .query_count(QUERIES_PER_FRAME * FRAMES_IN_FLIGHT as u32);
        let pool =
            // SAFETY: `device` is live and `info` outlives the call.
            unsafe { device.raw.create_query_pool(&info, None) }.call("vkCreateQueryPool")?;
        Ok(Self {
            pool,
            period_ns: device.timestamp_period_ns,
        })
    }

    fn first_query(frame: &SignalledFrame) -> u32 {
        frame.index() as u32 * QUERIES_PER_FRAME
    }

    /// Resets `frame`'s queries; recorded at the start of its command buffer.
    pub fn reset(&self, device: &Device, cmd: vk::CommandBuffer, frame: &SignalledFrame) {
        // The queries reset are `frame`'s, whose previous submission has completed (the token), so
        // no pending command writes them.
        // SAFETY: `cmd` is recording.
        unsafe {
            device.raw.cmd_reset_query_pool(
                cmd,
                self.pool,
                Self::first_query(frame),
                QUERIES_PER_FRAME,
            )
        };
    }

    pub fn begin(&self, device: &Device, cmd: vk::CommandBuffer, frame: &SignalledFrame, p: Pass) {
        self.write(
            device,
            cmd,
            Self::first_query(frame) + p as u32 * 2,
            vk::PipelineStageFlags::TOP_OF_PIPE,
        );
    }

    pub fn end(&self, device: &Device, cmd: vk::CommandBuffer, frame: &SignalledFrame, p: Pass) {
        self.write(
            device,
            cmd,
            Self::first_query(frame) + p as u32 * 2 + 1,
            vk::PipelineStageFlags::BOTTOM_OF_PIPE,
        );
    }

    fn write(
        &self,
        device: &Device,
        cmd: vk::CommandBuffer,
        query: u32,
        stage: vk::PipelineStageFlags,
    ) {
        // The query was reset earlier in the same command buffer.
        // SAFETY: `cmd` is recording and `query` is inside the pool (frame index < FRAMES_IN_FLIGHT, slot < QUERIES_PER_FRAME).
        unsafe { device.raw.cmd_write_timestamp(cmd, stage, self.pool, query) };
    }

    /// Milliseconds per pass of `frame`'s last submission, which must have written every pass's
    /// queries (the frame ring tracks that).
    pub fn read_ms(&self, device: &Device, frame: &SignalledFrame) -> Result<PassTimes, VkError> {
        let Some(period) = self.period_ns else {
            return Ok([0.0; PASS_COUNT as usize]);
        };
        let mut ticks = [0u64; QUERIES_PER_FRAME as usize];
        // `ticks` holds exactly QUERIES_PER_FRAME 64-bit results (TYPE_64).
        // SAFETY: `frame`'s fence has signalled (the token), so its queries are available.
        unsafe {
            device.raw.get_query_pool_results(
                self.pool,
                Self::first_query(frame),
                &mut ticks,
                vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT,
            )
        }
        .call("vkGetQueryPoolResults")?;
        let mut ms = [0.0; PASS_COUNT as usize];
        for (p, out) in ms.iter_mut().enumerate() {
            let (a, b) = (ticks[p * 2], ticks[p * 2 + 1]);
            *out = b.saturating_sub(a) as f64 * period / 1e6;
        }
        Ok(ms)
    }

    /// Call after the device is idle.
    pub fn destroy(&mut self, device: &Device) {
        // It is nulled so a second destroy is a no-op (destroying VK_NULL_HANDLE is allowed).
        // SAFETY: the device is idle (caller), so no command uses the pool.
        unsafe { device.raw.destroy_query_pool(self.pool, None) };
        self.pool = vk::QueryPool::null();
    }
}
