//! Barriers named by use (kajiya's `AccessType` idea): a barrier says what the resource was last
//! used for and what it is used for next; [`super::conv::map_access`] turns each use into its
//! stages, accesses and layout. No hand-written (layout, stage, access) triplets elsewhere.

use ash::vk;

use super::conv::map_accesses;
use super::image::subresource_range;
use super::Device;

/// One way the GPU uses a buffer or an image.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Access {
    /// No use (before the first, or contents not needed).
    Nothing,
    /// Source of a copy or blit.
    TransferRead,
    /// Destination of a copy, blit or clear.
    TransferWrite,
    /// Written as a colour attachment.
    ColourAttachmentWrite,
    /// Depth-tested and written as a depth attachment.
    DepthAttachmentReadWrite,
    /// Sampled in the vertex shader (the height textures).
    VertexShaderReadSampledImage,
    /// Sampled in the fragment shader.
    FragmentShaderReadSampledImage,
    /// Read as a storage buffer in the vertex shader (tile instances).
    VertexShaderReadStorageBuffer,
    /// Read as a uniform buffer by the vertex and fragment shaders.
    AnyShaderReadUniformBuffer,
    /// Read as indirect draw commands.
    IndirectBuffer,
    /// Read as an index buffer.
    IndexBuffer,
    /// Read by the host after the fence.
    HostRead,
    /// Handed to the presentation engine.
    Present,
}

impl Access {
    /// Whether this use writes memory (a barrier after it must make the writes available).
    pub fn is_write(self) -> bool {
        matches!(
            self,
            Access::TransferWrite
                | Access::ColourAttachmentWrite
                | Access::DepthAttachmentReadWrite
        )
    }
}

/// Records an image barrier from the `prev` uses to the `next` uses of the whole image (mip 0,
/// every array layer: see [`subresource_range`]). With `discard` the
/// old contents are not kept (old layout `UNDEFINED`), but the execution dependency on `prev`
/// still holds, so a later write cannot overtake an earlier read (write-after-read).
pub fn image_barrier(
    device: &Device,
    cmd: vk::CommandBuffer,
    image: vk::Image,
    aspect: vk::ImageAspectFlags,
    prev: &[Access],
    next: &[Access],
    discard: bool,
) {
    let from = map_accesses(prev);
    let to = map_accesses(next);
    let old_layout = if discard {
        vk::ImageLayout::UNDEFINED
    } else {
        from.layout
    };
    let barrier = vk::ImageMemoryBarrier::default()
        .old_layout(old_layout)
        .new_layout(to.layout)
        .src_access_mask(from.access)
        .dst_access_mask(to.access)
        .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .image(image)
        .subresource_range(subresource_range(aspect));
    // SAFETY: `cmd` is in the recording state (callers record between begin and end of their
    // frame's command buffer) and `image` is a live image of `device`; the barrier's layouts
    // are valid for the uses named.
    unsafe {
        device.raw.cmd_pipeline_barrier(
            cmd,
            from.stage,
            to.stage,
            vk::DependencyFlags::empty(),
            &[],
            &[],
            &[barrier],
        )
    };
}

/// Records a global memory barrier from the `prev` uses to the `next` uses (buffers: uploads
/// before draws, copies before host reads).
pub fn memory_barrier(device: &Device, cmd: vk::CommandBuffer, prev: &[Access], next: &[Access]) {
    let from = map_accesses(prev);
    let to = map_accesses(next);
    let barrier = vk::MemoryBarrier::default()
        .src_access_mask(from.access)
        .dst_access_mask(to.access);
    // SAFETY: `cmd` is in the recording state (see `image_barrier`); a global memory barrier
    // names no resource.
    unsafe {
        device.raw.cmd_pipeline_barrier(
            cmd,
            from.stage,
            to.stage,
            vk::DependencyFlags::empty(),
            &[barrier],
            &[],
            &[],
        )
    };
}
