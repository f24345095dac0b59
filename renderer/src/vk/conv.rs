//! Pure mappings from our plain vocabulary to Vulkan values, and the vk layer's pure choices
//! (wgpu-hal's `conv.rs` idea): no device, no command buffer, plain data in and out,
//! unit-tested in `conv_tests.rs`. Recording and object creation live next to the objects.

use ash::vk;

use super::access_type::Access;

/// The offscreen colour format: 8-bit sRGB (the PNGs and the swapchain blit keep it exact).
pub const COLOUR_FORMAT: vk::Format = vk::Format::R8G8B8A8_SRGB;
/// The depth format; devices without it as an optimal-tiling depth attachment are unsuitable.
pub const DEPTH_FORMAT: vk::Format = vk::Format::D32_SFLOAT;

// ----------------------------------------------------------------------------- barriers

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
        // The acquire semaphore is waited at TRANSFER: the barrier's first scope must be that
        // stage for the two to chain (a TOP_OF_PIPE source would race the presentation engine).
        Access::SwapchainAcquired => (S::TRANSFER, A::empty(), L::UNDEFINED),
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
        Access::ComputeShaderReadSampledImage => (
            S::COMPUTE_SHADER,
            A::SHADER_READ,
            L::SHADER_READ_ONLY_OPTIMAL,
        ),
        Access::ComputeShaderWriteStorageBuffer => {
            (S::COMPUTE_SHADER, A::SHADER_WRITE, L::UNDEFINED)
        }
        Access::VertexShaderReadStorageBuffer => (S::VERTEX_SHADER, A::SHADER_READ, L::UNDEFINED),
        Access::AnyShaderReadUniformBuffer => (
            S::VERTEX_SHADER | S::FRAGMENT_SHADER,
            A::UNIFORM_READ,
            L::UNDEFINED,
        ),
        Access::TessellationShaderRead => (
            S::TESSELLATION_CONTROL_SHADER | S::TESSELLATION_EVALUATION_SHADER,
            A::UNIFORM_READ | A::SHADER_READ,
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
/// happen at once, which is checked in debug builds.
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

/// Access flags that write memory: only these need making available before a later use (reads
/// in a source access mask have no effect, so they are left out).
const WRITE_ACCESSES: vk::AccessFlags = vk::AccessFlags::from_raw(
    vk::AccessFlags::TRANSFER_WRITE.as_raw()
        | vk::AccessFlags::COLOR_ATTACHMENT_WRITE.as_raw()
        | vk::AccessFlags::DEPTH_STENCIL_ATTACHMENT_WRITE.as_raw()
        | vk::AccessFlags::SHADER_WRITE.as_raw()
        | vk::AccessFlags::HOST_WRITE.as_raw()
        | vk::AccessFlags::MEMORY_WRITE.as_raw(),
);

/// Every field of one pipeline barrier (for a memory barrier both layouts are `UNDEFINED`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BarrierInfo {
    pub src_stage: vk::PipelineStageFlags,
    pub dst_stage: vk::PipelineStageFlags,
    pub src_access: vk::AccessFlags,
    pub dst_access: vk::AccessFlags,
    pub old_layout: vk::ImageLayout,
    pub new_layout: vk::ImageLayout,
}

/// The barrier from the `prev` uses to the `next` uses. With `discard` the old contents are not
/// kept (old layout `UNDEFINED`), but the execution dependency on `prev` still holds, so a later
/// write cannot overtake an earlier read (write-after-read).
pub fn map_barrier(prev: &[Access], next: &[Access], discard: bool) -> BarrierInfo {
    let from = map_accesses(prev);
    let to = map_accesses(next);
    BarrierInfo {
        src_stage: from.stage,
        dst_stage: to.stage,
        src_access: from.access & WRITE_ACCESSES,
        dst_access: to.access,
        old_layout: if discard {
            vk::ImageLayout::UNDEFINED
        } else {
            from.layout
        },
        new_layout: to.layout,
    }
}

/// The global memory barrier from the `prev` uses to the `next` uses: as [`map_barrier`], with
/// no layouts (both `UNDEFINED`).
pub fn map_memory_barrier(prev: &[Access], next: &[Access]) -> BarrierInfo {
    BarrierInfo {
        old_layout: vk::ImageLayout::UNDEFINED,
        new_layout: vk::ImageLayout::UNDEFINED,
        ..map_barrier(prev, next, false)
    }
}

/// Mip 0 and every array layer of an image (aerie's images have one mip level).
pub fn subresource_range(aspect: vk::ImageAspectFlags) -> vk::ImageSubresourceRange {
    vk::ImageSubresourceRange {
        aspect_mask: aspect,
        base_mip_level: 0,
        level_count: 1,
        base_array_layer: 0,
        layer_count: vk::REMAINING_ARRAY_LAYERS,
    }
}

/// A copy of `size` colour texels staged at buffer byte `offset` (rows tightly packed) into
/// mip `mip`, array layer `layer` of an image at texel `texel`.
pub fn map_texel_copy(
    offset: u64,
    mip: u32,
    layer: u32,
    texel: [u32; 2],
    size: [u32; 2],
) -> vk::BufferImageCopy {
    vk::BufferImageCopy::default()
        .buffer_offset(offset)
        .image_subresource(vk::ImageSubresourceLayers {
            aspect_mask: vk::ImageAspectFlags::COLOR,
            mip_level: mip,
            base_array_layer: layer,
            layer_count: 1,
        })
        .image_offset(vk::Offset3D {
            x: texel[0] as i32,
            y: texel[1] as i32,
            z: 0,
        })
        .image_extent(vk::Extent3D {
            width: size[0],
            height: size[1],
            depth: 1,
        })
}

/// The aspect a view of (or barrier on) an image of `format` covers.
pub fn map_format_aspect(format: vk::Format) -> vk::ImageAspectFlags {
    use vk::Format as F;
    match format {
        F::D16_UNORM | F::X8_D24_UNORM_PACK32 | F::D32_SFLOAT => vk::ImageAspectFlags::DEPTH,
        F::S8_UINT => vk::ImageAspectFlags::STENCIL,
        F::D16_UNORM_S8_UINT | F::D24_UNORM_S8_UINT | F::D32_SFLOAT_S8_UINT => {
            vk::ImageAspectFlags::DEPTH | vk::ImageAspectFlags::STENCIL
        }
        _ => vk::ImageAspectFlags::COLOR,
    }
}

// ----------------------------------------------------------------------------- validation

/// How a debug-utils message counts: every error and warning fails a command; the rest is
/// logged only.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MessageSeverity {
    Error,
    Warning,
    Info,
}

/// The most severe bit of a debug-utils severity mask.
pub fn map_message_severity(flags: vk::DebugUtilsMessageSeverityFlagsEXT) -> MessageSeverity {
    if flags.contains(vk::DebugUtilsMessageSeverityFlagsEXT::ERROR) {
        MessageSeverity::Error
    } else if flags.contains(vk::DebugUtilsMessageSeverityFlagsEXT::WARNING) {
        MessageSeverity::Warning
    } else {
        MessageSeverity::Info
    }
}

// ----------------------------------------------------------------------------- device choice

/// Plain description of one physical device, for [`choose_device`].
#[derive(Debug, Clone)]
pub struct DeviceCandidate {
    pub name: String,
    pub kind: vk::PhysicalDeviceType,
    /// Features and properties the renderer requires that this device lacks.
    pub missing: Vec<&'static str>,
}

/// What a physical device offers of what the renderer requires (read from the device, judged by
/// [`missing_requirements`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DeviceOffer {
    pub api_version: u32,
    pub graphics_queue: bool,
    /// `None` when the swapchain extension was not asked for.
    pub swapchain_extension: Option<bool>,
    pub multi_draw_indirect: bool,
    pub draw_indirect_first_instance: bool,
    /// Only known (and required) on Vulkan 1.3 devices.
    pub dynamic_rendering: bool,
    /// Optimal-tiling features of [`DEPTH_FORMAT`].
    pub depth_format_features: vk::FormatFeatureFlags,
}

/// The requirements `offer` misses, named for the "no suitable device" message.
pub fn missing_requirements(offer: &DeviceOffer) -> Vec<&'static str> {
    let mut missing = Vec::new();
    let vulkan13 = offer.api_version >= vk::API_VERSION_1_3;
    if !vulkan13 {
        missing.push("Vulkan 1.3");
    }
    if !offer.graphics_queue {
        missing.push("a graphics queue");
    }
    if offer.swapchain_extension == Some(false) {
        missing.push("VK_KHR_swapchain");
    }
    if !offer.multi_draw_indirect {
        missing.push("multiDrawIndirect");
    }
    if !offer.draw_indirect_first_instance {
        missing.push("drawIndirectFirstInstance");
    }
    if vulkan13 && !offer.dynamic_rendering {
        missing.push("dynamicRendering");
    }
    if !offer
        .depth_format_features
        .contains(vk::FormatFeatureFlags::DEPTH_STENCIL_ATTACHMENT)
    {
        missing.push("D32_SFLOAT depth");
    }
    missing
}

/// Preference order: discrete > integrated > virtual > CPU > other.
fn device_type_rank(kind: vk::PhysicalDeviceType) -> u32 {
    match kind {
        vk::PhysicalDeviceType::DISCRETE_GPU => 0,
        vk::PhysicalDeviceType::INTEGRATED_GPU => 1,
        vk::PhysicalDeviceType::VIRTUAL_GPU => 2,
        vk::PhysicalDeviceType::CPU => 3,
        _ => 4,
    }
}

/// Picks the best suitable candidate (index), or explains why none is: every device found with
/// its type and what it lacks.
pub fn choose_device(
    candidates: &[DeviceCandidate],
    filter: Option<&str>,
) -> Result<usize, String> {
    let filter_lc = filter.map(|f| f.to_lowercase());
    let best = candidates
        .iter()
        .enumerate()
        .filter(|(_, c)| c.missing.is_empty())
        .filter(|(_, c)| {
            filter_lc
                .as_ref()
                .is_none_or(|f| c.name.to_lowercase().contains(f))
        })
        .min_by_key(|(i, c)| (device_type_rank(c.kind), *i))
        .map(|(i, _)| i);
    best.ok_or_else(|| {
        let list = if candidates.is_empty() {
            "no Vulkan devices found".to_string()
        } else {
            candidates
                .iter()
                .map(|c| {
                    let lacks = if c.missing.is_empty() {
                        String::from("suitable")
                    } else {
                        format!("missing {}", c.missing.join(", "))
                    };
                    format!("'{}' ({:?}: {lacks})", c.name, c.kind)
                })
                .collect::<Vec<_>>()
                .join("; ")
        };
        match filter {
            Some(f) => format!("none matches --gpu '{f}'; devices found: {list}"),
            None => format!("devices found: {list}"),
        }
    })
}

/// Nanoseconds per timestamp tick, or `None` when the queue family cannot write timestamps.
pub fn map_timestamp_period(valid_bits: u32, period_ns: f32) -> Option<f64> {
    (valid_bits > 0 && period_ns > 0.0).then_some(period_ns as f64)
}

// ----------------------------------------------------------------------------- swapchain

/// Lower-case name of a present mode, as written in config files.
pub fn present_mode_name(mode: vk::PresentModeKHR) -> String {
    match mode {
        vk::PresentModeKHR::FIFO => "fifo".into(),
        vk::PresentModeKHR::MAILBOX => "mailbox".into(),
        vk::PresentModeKHR::IMMEDIATE => "immediate".into(),
        vk::PresentModeKHR::FIFO_RELAXED => "fifo_relaxed".into(),
        other => format!("{other:?}").to_lowercase(),
    }
}

/// Checks that `wanted` is among the surface's `supported` modes; the error lists them.
pub fn choose_present_mode(
    wanted: vk::PresentModeKHR,
    supported: &[vk::PresentModeKHR],
) -> Result<vk::PresentModeKHR, String> {
    if supported.contains(&wanted) {
        return Ok(wanted);
    }
    let list: Vec<String> = supported.iter().map(|&m| present_mode_name(m)).collect();
    Err(format!(
        "present mode {} is not supported by this window's surface (supported: {})",
        present_mode_name(wanted),
        if list.is_empty() {
            "none".to_owned()
        } else {
            list.join(", ")
        }
    ))
}

/// Picks the swapchain format: an 8-bit sRGB format in the sRGB colour space if offered (the
/// blit from the sRGB target then keeps colours exact), else the first format listed.
pub fn choose_surface_format(formats: &[vk::SurfaceFormatKHR]) -> Option<vk::SurfaceFormatKHR> {
    let preferred = [vk::Format::B8G8R8A8_SRGB, vk::Format::R8G8B8A8_SRGB];
    preferred
        .iter()
        .find_map(|&p| {
            formats
                .iter()
                .find(|f| f.format == p && f.color_space == vk::ColorSpaceKHR::SRGB_NONLINEAR)
        })
        .or_else(|| formats.first())
        .copied()
}

/// The swapchain extent: the surface's current extent when it dictates one, else the window's
/// size clamped to what the surface allows. A zero side means "minimised: do not render".
pub fn choose_extent(caps: &vk::SurfaceCapabilitiesKHR, window: (u32, u32)) -> vk::Extent2D {
    if caps.current_extent.width != u32::MAX {
        return caps.current_extent;
    }
    vk::Extent2D {
        width: window
            .0
            .clamp(caps.min_image_extent.width, caps.max_image_extent.width),
        height: window
            .1
            .clamp(caps.min_image_extent.height, caps.max_image_extent.height),
    }
}

/// Images to ask for: one more than the minimum (so acquiring never waits on the driver's
/// own image), within the maximum (0 = none).
pub fn choose_image_count(caps: &vk::SurfaceCapabilitiesKHR) -> u32 {
    let n = caps.min_image_count + 1;
    if caps.max_image_count > 0 {
        n.min(caps.max_image_count)
    } else {
        n
    }
}

/// The first composite-alpha mode the surface supports, opaque preferred (the frame is opaque).
pub fn choose_composite_alpha(supported: vk::CompositeAlphaFlagsKHR) -> vk::CompositeAlphaFlagsKHR {
    [
        vk::CompositeAlphaFlagsKHR::OPAQUE,
        vk::CompositeAlphaFlagsKHR::INHERIT,
        vk::CompositeAlphaFlagsKHR::PRE_MULTIPLIED,
        vk::CompositeAlphaFlagsKHR::POST_MULTIPLIED,
    ]
    .into_iter()
    .find(|&a| supported.contains(a))
    .unwrap_or(vk::CompositeAlphaFlagsKHR::OPAQUE)
}

#[cfg(test)]
#[path = "conv_tests.rs"]
mod tests;
