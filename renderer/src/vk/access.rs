//! Barriers named by use (kajiya's `AccessType` idea): a barrier says what the resource was last
//! used for and what it is used for next; [`super::conv::map_barrier`] turns the uses into
//! stages, accesses and layouts. No hand-written (layout, stage, access) triplets elsewhere.

use ash::vk;

use super::conv::{map_barrier, map_memory_barrier, subresource_range};
use super::device::Device;

pub use super::access_type::Access;

/// Records an image barrier from the `prev` uses to the `next` uses of the whole image (mip 0,
/// every array layer: see [`subresource_range`]). With `discard` the old contents are not kept
/// (old layout `UNDEFINED`), but the execution dependency on `prev` still holds, so a later
/// write cannot overtake an earlier read (write-after-read).
///
/// `cmd` must be a command buffer of `device` in the recording state and `image` a live image
/// of `device`; both are checked by the validation layer, and neither is dereferenced here.
pub fn image_barrier(
    device: &Device,
    cmd: vk::CommandBuffer,
    image: vk::Image,
    aspect: vk::ImageAspectFlags,
    prev: &[Access],
    next: &[Access],
    discard: bool,
) {
    let range = subresource_range(aspect);
    image_range_barrier(device, cmd, image, range, prev, next, discard);
}

/// [`image_barrier`] over `range` of the image (its mips, its layers), the same contract.
pub fn image_range_barrier(
    device: &Device,
    cmd: vk::CommandBuffer,
    image: vk::Image,
    range: vk::ImageSubresourceRange,
    prev: &[Access],
    next: &[Access],
    discard: bool,
) {
    let b = map_barrier(prev, next, discard);
    let barrier = vk::ImageMemoryBarrier::default()
        .old_layout(b.old_layout)
        .new_layout(b.new_layout)
        .src_access_mask(b.src_access)
        .dst_access_mask(b.dst_access)
        .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .image(image)
        .subresource_range(range);
    // `cmd` is recording on it and `image` is one of its images (this function's contract above).
    // The barrier struct and the slice outlive the call, and the layouts come from the named uses.
    // SAFETY: `device.raw` is a live device (a `Device` is usable until its `destroy`).
    unsafe {
        device.raw.cmd_pipeline_barrier(
            cmd,
            b.src_stage,
            b.dst_stage,
            vk::DependencyFlags::empty(),
            &[],
            &[],
            &[barrier],
        )
    };
}

/// Records a global memory barrier from the `prev` uses to the `next` uses (buffers: uploads
/// before draws, copies before host reads). `cmd` as for [`image_barrier`].
pub fn memory_barrier(device: &Device, cmd: vk::CommandBuffer, prev: &[Access], next: &[Access]) {
    let b = map_memory_barrier(prev, next);
    let barrier = vk::MemoryBarrier::default()
        .src_access_mask(b.src_access)
        .dst_access_mask(b.dst_access);
    // A global memory barrier names no resource.
    // SAFETY: as in `image_barrier`: the device is live and `cmd` is recording on it.
    unsafe {
        device.raw.cmd_pipeline_barrier(
            cmd,
            b.src_stage,
            b.dst_stage,
            vk::DependencyFlags::empty(),
            &[barrier],
            &[],
            &[],
        )
    };
}
