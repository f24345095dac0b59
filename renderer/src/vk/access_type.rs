//! The vocabulary of barriers: one way the GPU (or the host, or the presentation engine) uses a
//! buffer or an image. Its own file so that `conv.rs` (which maps it to Vulkan flags) and
//! `access.rs` (which records barriers with it) both depend on it and not on each other.

/// One way the GPU uses a buffer or an image.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Access {
    /// No use (before the first, or contents not needed).
    Nothing,
    /// A swapchain image just acquired: the presentation engine's use of it ends at the acquire
    /// semaphore, which the frame's submission waits at the transfer stage (see
    /// `vk::swapchain::ACQUIRE_WAIT_STAGE`); a barrier after this use chains to that wait.
    SwapchainAcquired,
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
    /// Sampled (texel fetches) in a compute shader (the GPU normal pass reads the heights).
    ComputeShaderReadSampledImage,
    /// Written as a storage buffer by a compute shader (the GPU normal pass's texels).
    ComputeShaderWriteStorageBuffer,
    /// Read as a storage buffer in the vertex shader (tile instances).
    VertexShaderReadStorageBuffer,
    /// Read as a uniform buffer by the vertex and fragment shaders.
    AnyShaderReadUniformBuffer,
    /// Read as uniform or storage buffers by the tessellation control and evaluation shaders
    /// (the tessellation baseline's frame uniforms, patches and heights).
    TessellationShaderRead,
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
    /// Every use, for tests and tables.
    pub const ALL: [Access; 17] = [
        Access::Nothing,
        Access::SwapchainAcquired,
        Access::TransferRead,
        Access::TransferWrite,
        Access::ColourAttachmentWrite,
        Access::DepthAttachmentReadWrite,
        Access::VertexShaderReadSampledImage,
        Access::FragmentShaderReadSampledImage,
        Access::ComputeShaderReadSampledImage,
        Access::ComputeShaderWriteStorageBuffer,
        Access::VertexShaderReadStorageBuffer,
        Access::AnyShaderReadUniformBuffer,
        Access::TessellationShaderRead,
        Access::IndirectBuffer,
        Access::IndexBuffer,
        Access::HostRead,
        Access::Present,
    ];

    /// Whether this use writes memory (a barrier after it must make the writes available).
    pub fn is_write(self) -> bool {
        matches!(
            self,
            Access::TransferWrite
                | Access::ComputeShaderWriteStorageBuffer
                | Access::ColourAttachmentWrite
                | Access::DepthAttachmentReadWrite
        )
    }
}
