//! GPU timestamp queries around each pass, per frame in flight, read back after the frame's fence.

use ash::vk;

use super::{Device, VkError, VkResultExt, FRAMES_IN_FLIGHT};

/// Passes timed per frame. Each has a begin and an end query.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Pass {
    Upload = 0,
    Terrain = 1,
}
pub const PASS_COUNT: u32 = 2;
const QUERIES_PER_FRAME: u32 = PASS_COUNT * 2;

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
            unsafe { device.raw.create_query_pool(&info, None) }.call("vkCreateQueryPool")?;
        Ok(Self {
            pool,
            period_ns: device.timestamp_period_ns,
        })
    }

    /// Resets frame `frame`'s queries; recorded at the start of its command buffer.
    pub fn reset(&self, device: &Device, cmd: vk::CommandBuffer, frame: usize) {
        unsafe {
            device.raw.cmd_reset_query_pool(
                cmd,
                self.pool,
                frame as u32 * QUERIES_PER_FRAME,
                QUERIES_PER_FRAME,
            )
        };
    }

    pub fn begin(&self, device: &Device, cmd: vk::CommandBuffer, frame: usize, pass: Pass) {
        self.write(
            device,
            cmd,
            frame,
            pass as u32 * 2,
            vk::PipelineStageFlags::TOP_OF_PIPE,
        );
    }

    pub fn end(&self, device: &Device, cmd: vk::CommandBuffer, frame: usize, pass: Pass) {
        self.write(
            device,
            cmd,
            frame,
            pass as u32 * 2 + 1,
            vk::PipelineStageFlags::BOTTOM_OF_PIPE,
        );
    }

    fn write(
        &self,
        device: &Device,
        cmd: vk::CommandBuffer,
        frame: usize,
        slot: u32,
        stage: vk::PipelineStageFlags,
    ) {
        unsafe {
            device.raw.cmd_write_timestamp(
                cmd,
                stage,
                self.pool,
                frame as u32 * QUERIES_PER_FRAME + slot,
            )
        };
    }

    /// Milliseconds per pass of frame `frame`. Only call after that frame's fence signaled and
    /// when every pass's queries were written.
    pub fn read_ms(
        &self,
        device: &Device,
        frame: usize,
    ) -> Result<[f64; PASS_COUNT as usize], VkError> {
        let Some(period) = self.period_ns else {
            return Ok([0.0; PASS_COUNT as usize]);
        };
        let mut ticks = [0u64; QUERIES_PER_FRAME as usize];
        unsafe {
            device.raw.get_query_pool_results(
                self.pool,
                frame as u32 * QUERIES_PER_FRAME,
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

    pub fn destroy(&mut self, device: &Device) {
        unsafe { device.raw.destroy_query_pool(self.pool, None) };
        self.pool = vk::QueryPool::null();
    }
}
