//! The staging ring: one persistently mapped host-visible buffer split into one region per frame
//! in flight. A region is written only after the fence of the submission that last read it has
//! signaled ([`StagingRing::begin_frame`] takes the proof), and each region is a hard per-frame
//! byte budget. Every upload in the program goes through here.

use ash::vk;
use gpu_allocator::MemoryLocation;

use super::frame_slot::SignalledFrame;
use super::{Buffer, Device, VkError, FRAMES_IN_FLIGHT};

/// The pure bookkeeping of the ring (no Vulkan): which region is open and how far it is filled.
#[derive(Debug, Clone)]
pub struct RingCursor {
    region_size: u64,
    regions: usize,
    /// Every offset handed out is a multiple of this (a power of two).
    base_alignment: u64,
    current: Option<usize>,
    head: u64,
}

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum StagingError {
    #[error("upload of {requested} bytes exceeds this frame's staging budget ({remaining} of {budget} bytes left)")]
    OverBudget {
        requested: u64,
        remaining: u64,
        budget: u64,
    },
    #[error("no staging region is open: call begin_frame first")]
    NotOpen,
    #[error("alignment {0} is not a power of two")]
    BadAlignment(u64),
}

impl RingCursor {
    pub fn new(region_size: u64, regions: usize, base_alignment: u64) -> Self {
        assert!(base_alignment.is_power_of_two());
        // Regions start on aligned offsets.
        let region_size = region_size / base_alignment * base_alignment;
        Self {
            region_size,
            regions,
            base_alignment,
            current: None,
            head: 0,
        }
    }

    pub fn open(&mut self, region: usize) {
        assert!(region < self.regions);
        self.current = Some(region);
        self.head = 0;
    }

    /// Reserves `size` bytes aligned to `align` in the open region; returns the offset in the
    /// whole buffer.
    pub fn alloc(&mut self, size: u64, align: u64) -> Result<u64, StagingError> {
        if !align.is_power_of_two() {
            return Err(StagingError::BadAlignment(align));
        }
        let region = self.current.ok_or(StagingError::NotOpen)?;
        let align = align.max(self.base_alignment);
        // Align the absolute offset: region bases need not be multiples of `align`.
        let base = region as u64 * self.region_size;
        let start = (base + self.head).div_ceil(align) * align - base;
        if start + size > self.region_size {
            return Err(StagingError::OverBudget {
                requested: size,
                remaining: self.region_size.saturating_sub(start),
                budget: self.region_size,
            });
        }
        self.head = start + size;
        Ok(base + start)
    }

    pub fn remaining(&self) -> u64 {
        self.region_size.saturating_sub(self.head)
    }
    pub fn used(&self) -> u64 {
        self.head
    }
    pub fn budget(&self) -> u64 {
        self.region_size
    }
    /// Every offset handed out is a multiple of this, whatever smaller alignment was asked.
    pub fn alignment(&self) -> u64 {
        self.base_alignment
    }
}

pub struct StagingRing {
    buffer: Buffer,
    cursor: RingCursor,
}

impl StagingRing {
    /// `per_frame_budget` bytes per frame in flight.
    pub fn new(device: &Device, per_frame_budget: u64) -> Result<Self, VkError> {
        let limits = &device.properties.limits;
        let base_alignment = 16u64
            .max(limits.optimal_buffer_copy_offset_alignment)
            .max(limits.non_coherent_atom_size)
            .next_power_of_two();
        let cursor = RingCursor::new(per_frame_budget, FRAMES_IN_FLIGHT, base_alignment);
        let buffer = Buffer::new(
            device,
            "staging ring",
            cursor.budget() * FRAMES_IN_FLIGHT as u64,
            vk::BufferUsageFlags::TRANSFER_SRC,
            MemoryLocation::CpuToGpu,
        )?;
        if buffer.mapped().is_none() {
            let mut b = buffer;
            b.destroy(device);
            return Err(VkError::Staging("staging memory is not host-mapped".into()));
        }
        Ok(Self { buffer, cursor })
    }

    pub fn raw(&self) -> vk::Buffer {
        self.buffer.raw
    }

    /// Opens `frame`'s region for this frame's uploads (from its start): the submission that
    /// last read the region has completed, which the token proves.
    pub fn begin_frame(&mut self, frame: &SignalledFrame) {
        self.cursor.open(frame.index());
    }

    /// Copies `data` into the open region; returns its offset in [`Self::raw`].
    pub fn push<T: bytemuck::Pod>(&mut self, data: &[T], align: u64) -> Result<u64, VkError> {
        let bytes: &[u8] = bytemuck::cast_slice(data);
        let dst = self.alloc(bytes.len() as u64, align)?;
        dst.1.copy_from_slice(bytes);
        Ok(dst.0)
    }

    /// Reserves `size` bytes to be filled by the caller.
    pub fn alloc(&mut self, size: u64, align: u64) -> Result<(u64, &mut [u8]), VkError> {
        let offset = self
            .cursor
            .alloc(size, align)
            .map_err(|e| VkError::Staging(e.to_string()))?;
        let mapped = self
            .buffer
            .mapped_mut()
            .expect("staging ring is persistently mapped");
        Ok((
            offset,
            &mut mapped[offset as usize..(offset + size) as usize],
        ))
    }

    pub fn remaining(&self) -> u64 {
        self.cursor.remaining()
    }
    pub fn used(&self) -> u64 {
        self.cursor.used()
    }
    pub fn budget(&self) -> u64 {
        self.cursor.budget()
    }
    /// The alignment of every allocation (see [`RingCursor::alignment`]).
    pub fn alignment(&self) -> u64 {
        self.cursor.alignment()
    }

    /// Call after the device is idle.
    pub fn destroy(&mut self, device: &Device) {
        self.buffer.destroy(device);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn offsets_are_aligned_and_inside_the_open_region() {
        let mut c = RingCursor::new(1000, 2, 16);
        assert_eq!(c.budget(), 992);
        assert_eq!(c.alloc(4, 4), Err(StagingError::NotOpen));
        c.open(1);
        let a = c.alloc(3, 4).unwrap();
        let b = c.alloc(5, 64).unwrap();
        assert_eq!(a, 992);
        assert_eq!(b % 64, 0);
        assert!(b >= a + 3 && b < 2 * 992);
        c.open(0);
        assert_eq!(c.alloc(1, 1).unwrap(), 0);
        assert_eq!(c.alloc(1, 1).unwrap(), 16);
    }

    #[test]
    fn budget_is_hard() {
        let mut c = RingCursor::new(256, 2, 16);
        c.open(0);
        c.alloc(200, 16).unwrap();
        let err = c.alloc(100, 16).unwrap_err();
        assert_eq!(
            err,
            StagingError::OverBudget {
                requested: 100,
                remaining: 48,
                budget: 256
            }
        );
        // A failed request leaves the cursor where it was.
        assert_eq!(c.alloc(48, 16).unwrap(), 208);
        assert_eq!(c.remaining(), 0);
        // Reopening the region (after its fence) starts it afresh.
        c.open(0);
        assert_eq!(c.remaining(), 256);
        assert_eq!(c.alloc(3, 3), Err(StagingError::BadAlignment(3)));
    }
}
