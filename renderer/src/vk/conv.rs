//! Pure mappings from our plain vocabulary to Vulkan flags (wgpu-hal's `conv.rs` idea): no
//! device, no command buffer, unit-tested. Recording lives next to the objects it records on.

use ash::vk;

use super::access::Access;

/// What one [`Access`] means to a barrier: the stages that do it, the memory accesses they make,
/// and the image layout it needs (`UNDEFINED` for accesses that are not to an image).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct AccessInfo {
    pub stage: vk::PipelineStageFlags,
    pub access: vk::AccessFlags,
    pub layout: vk::ImageLayout,
}

/// The stages, accesses and layout of one named use (kajiya's `AccessType` table, cut to the
/// uses aerie has).
pub fn map_access(a: Access) -> AccessInfo {
    use vk::AccessFlags as A;
    use vk::ImageLayout as L;
    use vk::PipelineStageFlags as S;
    let (stage, access, layout) = match a {
        Access::Nothing => (S::TOP_OF_PIPE, A::empty(), L::UNDEFINED),
        Access::TransferRead => (S::TRANSFER, A::TRANSFER_READ, L::TRANSFER_SRC_OPTIMAL),
        Access::TransferWrite => (S::TRANSFER, A::TRANSFER_WRITE, L::TRANSFER_DST_OPTIMAL),
        Access::ColourAttachmentWrite => (
            S::COLOR_ATTACHMENT_OUTPUT,
            A::COLOR_ATTACHMENT_WRITE,
            L::COLOR_ATTACHMENT_OPTIMAL,
        ),
        Access::DepthAttachmentReadWrite => (
            S::EARLY_FRAGMENT_TESTS | S::LATE_FRAGMENT_TESTS,
            A::DEPTH_STENCIL_ATTACHMENT_READ | A::DEPTH_STENCIL_ATTACHMENT_WRITE,
            L::DEPTH_ATTACHMENT_OPTIMAL,
        ),
        Access::VertexShaderReadSampledImage => (
            S::VERTEX_SHADER,
            A::SHADER_READ,
            L::SHADER_READ_ONLY_OPTIMAL,
        ),
        Access::FragmentShaderReadSampledImage => (
            S::FRAGMENT_SHADER,
            A::SHADER_READ,
            L::SHADER_READ_ONLY_OPTIMAL,
        ),
        Access::VertexShaderReadStorageBuffer => (S::VERTEX_SHADER, A::SHADER_READ, L::UNDEFINED),
        Access::AnyShaderReadUniformBuffer => (
            S::VERTEX_SHADER | S::FRAGMENT_SHADER,
            A::UNIFORM_READ,
            L::UNDEFINED,
        ),
        Access::IndirectBuffer => (S::DRAW_INDIRECT, A::INDIRECT_COMMAND_READ, L::UNDEFINED),
        Access::IndexBuffer => (S::VERTEX_INPUT, A::INDEX_READ, L::UNDEFINED),
        Access::HostRead => (S::HOST, A::HOST_READ, L::UNDEFINED),
        Access::Present => (S::BOTTOM_OF_PIPE, A::empty(), L::PRESENT_SRC_KHR),
    };
    AccessInfo {
        stage,
        access,
        layout,
    }
}

/// The union of several uses that happen together (e.g. the uniform, storage and indirect reads
/// of one draw). The layout is the one they share; image uses of different layouts cannot
/// happen at once, which [`super::access`] checks in debug builds.
pub fn map_accesses(uses: &[Access]) -> AccessInfo {
    let mut out = AccessInfo {
        stage: vk::PipelineStageFlags::empty(),
        access: vk::AccessFlags::empty(),
        layout: vk::ImageLayout::UNDEFINED,
    };
    for &a in uses {
        let i = map_access(a);
        out.stage |= i.stage;
        out.access |= i.access;
        if i.layout != vk::ImageLayout::UNDEFINED {
            debug_assert!(
                out.layout == vk::ImageLayout::UNDEFINED || out.layout == i.layout,
                "accesses {uses:?} need different image layouts"
            );
            out.layout = i.layout;
        }
    }
    if out.stage.is_empty() {
        // No previous use (or none next): a barrier still needs one stage.
        out.stage = vk::PipelineStageFlags::TOP_OF_PIPE;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    const ALL: [Access; 13] = [
        Access::Nothing,
        Access::TransferRead,
        Access::TransferWrite,
        Access::ColourAttachmentWrite,
        Access::DepthAttachmentReadWrite,
        Access::VertexShaderReadSampledImage,
        Access::FragmentShaderReadSampledImage,
        Access::VertexShaderReadStorageBuffer,
        Access::AnyShaderReadUniformBuffer,
        Access::IndirectBuffer,
        Access::IndexBuffer,
        Access::HostRead,
        Access::Present,
    ];

    #[test]
    fn every_access_names_a_stage_and_only_writes_what_it_says() {
        for a in ALL {
            let i = map_access(a);
            assert!(!i.stage.is_empty(), "{a:?} has no stage");
            let writes = vk::AccessFlags::TRANSFER_WRITE
                | vk::AccessFlags::COLOR_ATTACHMENT_WRITE
                | vk::AccessFlags::DEPTH_STENCIL_ATTACHMENT_WRITE;
            assert_eq!(
                i.access.intersects(writes),
                a.is_write(),
                "{a:?}: write flags {:?} disagree with is_write",
                i.access
            );
        }
    }

    #[test]
    fn image_uses_have_their_layout_and_buffer_uses_none() {
        assert_eq!(
            map_access(Access::TransferWrite).layout,
            vk::ImageLayout::TRANSFER_DST_OPTIMAL
        );
        assert_eq!(
            map_access(Access::VertexShaderReadSampledImage).layout,
            vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL
        );
        assert_eq!(
            map_access(Access::Present).layout,
            vk::ImageLayout::PRESENT_SRC_KHR
        );
        for a in [
            Access::IndirectBuffer,
            Access::IndexBuffer,
            Access::AnyShaderReadUniformBuffer,
            Access::VertexShaderReadStorageBuffer,
            Access::HostRead,
        ] {
            assert_eq!(map_access(a).layout, vk::ImageLayout::UNDEFINED, "{a:?}");
        }
    }

    #[test]
    fn a_union_ors_stages_and_accesses() {
        let u = map_accesses(&[
            Access::AnyShaderReadUniformBuffer,
            Access::VertexShaderReadStorageBuffer,
            Access::IndirectBuffer,
        ]);
        assert_eq!(
            u.stage,
            vk::PipelineStageFlags::DRAW_INDIRECT
                | vk::PipelineStageFlags::VERTEX_SHADER
                | vk::PipelineStageFlags::FRAGMENT_SHADER
        );
        assert_eq!(
            u.access,
            vk::AccessFlags::UNIFORM_READ
                | vk::AccessFlags::SHADER_READ
                | vk::AccessFlags::INDIRECT_COMMAND_READ
        );
        assert_eq!(map_accesses(&[]).stage, vk::PipelineStageFlags::TOP_OF_PIPE);
    }
}
