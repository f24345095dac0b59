use super::*;

use vk::AccessFlags as A;
use vk::ImageLayout as L;
use vk::PipelineStageFlags as S;

#[test]
fn every_access_names_a_stage_and_only_writes_what_it_says() {
    for a in Access::ALL {
        let i = map_access(a);
        assert!(!i.stage.is_empty(), "{a:?} has no stage");
        let writes = A::TRANSFER_WRITE
            | A::COLOR_ATTACHMENT_WRITE
            | A::DEPTH_STENCIL_ATTACHMENT_WRITE
            | A::SHADER_WRITE;
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
        L::TRANSFER_DST_OPTIMAL
    );
    assert_eq!(
        map_access(Access::VertexShaderReadSampledImage).layout,
        L::SHADER_READ_ONLY_OPTIMAL
    );
    assert_eq!(map_access(Access::Present).layout, L::PRESENT_SRC_KHR);
    for a in [
        Access::IndirectBuffer,
        Access::IndexBuffer,
        Access::AnyShaderReadUniformBuffer,
        Access::VertexShaderReadStorageBuffer,
        Access::HostRead,
    ] {
        assert_eq!(map_access(a).layout, L::UNDEFINED, "{a:?}");
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
        S::DRAW_INDIRECT | S::VERTEX_SHADER | S::FRAGMENT_SHADER
    );
    assert_eq!(
        u.access,
        A::UNIFORM_READ | A::SHADER_READ | A::INDIRECT_COMMAND_READ
    );
    assert_eq!(map_accesses(&[]).stage, S::TOP_OF_PIPE);
}

/// A barrier as the hand-written (layout, stage, access) pairs the target used to record.
fn triplets(from: (L, S, A), to: (L, S, A)) -> BarrierInfo {
    BarrierInfo {
        src_stage: from.1,
        dst_stage: to.1,
        src_access: from.2,
        dst_access: to.2,
        old_layout: from.0,
        new_layout: to.0,
    }
}

#[test]
fn a_discarding_barrier_keeps_the_dependency_on_the_previous_read() {
    // The colour target is cleared each frame after the last frame's copy out of it.
    assert_eq!(
        map_barrier(
            &[Access::TransferRead],
            &[Access::ColourAttachmentWrite],
            true
        ),
        triplets(
            (L::UNDEFINED, S::TRANSFER, A::empty()),
            (
                L::COLOR_ATTACHMENT_OPTIMAL,
                S::COLOR_ATTACHMENT_OUTPUT,
                A::COLOR_ATTACHMENT_WRITE
            ),
        )
    );
    assert_eq!(
        map_barrier(
            &[Access::TransferRead],
            &[Access::DepthAttachmentReadWrite],
            true
        ),
        triplets(
            (L::UNDEFINED, S::TRANSFER, A::empty()),
            (
                L::DEPTH_ATTACHMENT_OPTIMAL,
                S::EARLY_FRAGMENT_TESTS | S::LATE_FRAGMENT_TESTS,
                A::DEPTH_STENCIL_ATTACHMENT_WRITE | A::DEPTH_STENCIL_ATTACHMENT_READ,
            ),
        )
    );
    // Without discard the layout is kept.
    assert_eq!(
        map_barrier(
            &[Access::TransferRead],
            &[Access::ColourAttachmentWrite],
            false
        )
        .old_layout,
        L::TRANSFER_SRC_OPTIMAL
    );
}

#[test]
fn copies_out_of_the_target_wait_for_its_writes() {
    assert_eq!(
        map_barrier(
            &[Access::ColourAttachmentWrite],
            &[Access::TransferRead],
            false
        ),
        triplets(
            (
                L::COLOR_ATTACHMENT_OPTIMAL,
                S::COLOR_ATTACHMENT_OUTPUT,
                A::COLOR_ATTACHMENT_WRITE
            ),
            (L::TRANSFER_SRC_OPTIMAL, S::TRANSFER, A::TRANSFER_READ),
        )
    );
    let depth = map_barrier(
        &[Access::DepthAttachmentReadWrite],
        &[Access::TransferRead],
        false,
    );
    // Only the write is made available; the source stages cover the late tests that write.
    assert_eq!(depth.src_access, A::DEPTH_STENCIL_ATTACHMENT_WRITE);
    assert!(depth.src_stage.contains(S::LATE_FRAGMENT_TESTS));
    assert_eq!(
        (depth.old_layout, depth.new_layout),
        (L::DEPTH_ATTACHMENT_OPTIMAL, L::TRANSFER_SRC_OPTIMAL)
    );
    assert_eq!(
        map_memory_barrier(&[Access::TransferWrite], &[Access::HostRead]),
        triplets(
            (L::UNDEFINED, S::TRANSFER, A::TRANSFER_WRITE),
            (L::UNDEFINED, S::HOST, A::HOST_READ),
        )
    );
}

#[test]
fn the_swapchain_blit_chains_to_the_acquire_and_ends_ready_to_present() {
    assert_eq!(
        map_barrier(&[Access::SwapchainAcquired], &[Access::TransferWrite], true),
        triplets(
            (L::UNDEFINED, S::TRANSFER, A::empty()),
            (L::TRANSFER_DST_OPTIMAL, S::TRANSFER, A::TRANSFER_WRITE),
        )
    );
    assert_eq!(
        map_barrier(&[Access::TransferWrite], &[Access::Present], false),
        triplets(
            (L::TRANSFER_DST_OPTIMAL, S::TRANSFER, A::TRANSFER_WRITE),
            (L::PRESENT_SRC_KHR, S::BOTTOM_OF_PIPE, A::empty()),
        )
    );
}

#[test]
fn reads_never_appear_in_a_source_access_mask() {
    for a in Access::ALL {
        let b = map_barrier(&[a], &[Access::TransferWrite], true);
        assert_eq!(
            b.src_access.is_empty(),
            !a.is_write(),
            "{a:?}: {:?}",
            b.src_access
        );
    }
}

#[test]
fn aspect_follows_the_format() {
    assert_eq!(map_format_aspect(DEPTH_FORMAT), vk::ImageAspectFlags::DEPTH);
    assert_eq!(
        map_format_aspect(COLOUR_FORMAT),
        vk::ImageAspectFlags::COLOR
    );
    assert_eq!(
        map_format_aspect(vk::Format::D24_UNORM_S8_UINT),
        vk::ImageAspectFlags::DEPTH | vk::ImageAspectFlags::STENCIL
    );
    assert_eq!(
        map_format_aspect(vk::Format::R16_UNORM),
        vk::ImageAspectFlags::COLOR
    );
    let r = subresource_range(vk::ImageAspectFlags::DEPTH);
    assert_eq!(
        (r.level_count, r.layer_count),
        (1, vk::REMAINING_ARRAY_LAYERS)
    );
}

#[test]
fn message_severity_is_the_most_severe_bit() {
    use vk::DebugUtilsMessageSeverityFlagsEXT as F;
    assert_eq!(
        map_message_severity(F::ERROR | F::WARNING),
        MessageSeverity::Error
    );
    assert_eq!(
        map_message_severity(F::WARNING | F::INFO),
        MessageSeverity::Warning
    );
    assert_eq!(map_message_severity(F::INFO), MessageSeverity::Info);
    assert_eq!(map_message_severity(F::VERBOSE), MessageSeverity::Info);
}

fn c(name: &str, kind: vk::PhysicalDeviceType, missing: &[&'static str]) -> DeviceCandidate {
    DeviceCandidate {
        name: name.into(),
        kind,
        missing: missing.to_vec(),
    }
}

#[test]
fn prefers_discrete_then_integrated_then_virtual_then_cpu() {
    let list = vec![
        c("llvmpipe", vk::PhysicalDeviceType::CPU, &[]),
        c("virt", vk::PhysicalDeviceType::VIRTUAL_GPU, &[]),
        c("igpu", vk::PhysicalDeviceType::INTEGRATED_GPU, &[]),
        c("dgpu", vk::PhysicalDeviceType::DISCRETE_GPU, &[]),
    ];
    assert_eq!(choose_device(&list, None), Ok(3));
    assert_eq!(choose_device(&list[..3], None), Ok(2));
    assert_eq!(choose_device(&list[..2], None), Ok(1));
    assert_eq!(choose_device(&list[..1], None), Ok(0));
}

#[test]
fn unsuitable_devices_are_skipped_and_listed() {
    let list = vec![
        c(
            "dgpu",
            vk::PhysicalDeviceType::DISCRETE_GPU,
            &["multiDrawIndirect"],
        ),
        c("llvmpipe", vk::PhysicalDeviceType::CPU, &[]),
    ];
    assert_eq!(choose_device(&list, None), Ok(1));
    let err = choose_device(&list[..1], None).unwrap_err();
    assert!(
        err.contains("dgpu") && err.contains("missing multiDrawIndirect"),
        "{err}"
    );
}

#[test]
fn gpu_filter_overrides_preference() {
    let list = vec![
        c("NVIDIA RTX", vk::PhysicalDeviceType::DISCRETE_GPU, &[]),
        c("llvmpipe (LLVM)", vk::PhysicalDeviceType::CPU, &[]),
    ];
    assert_eq!(choose_device(&list, Some("LLVMPIPE")), Ok(1));
    let err = choose_device(&list, Some("radeon")).unwrap_err();
    assert!(
        err.contains("--gpu 'radeon'") && err.contains("NVIDIA RTX") && err.contains("llvmpipe"),
        "{err}"
    );
    assert!(choose_device(&[], None)
        .unwrap_err()
        .contains("no Vulkan devices"));
}

fn full_offer() -> DeviceOffer {
    DeviceOffer {
        api_version: vk::API_VERSION_1_3,
        graphics_queue: true,
        swapchain_extension: None,
        multi_draw_indirect: true,
        draw_indirect_first_instance: true,
        dynamic_rendering: true,
        depth_format_features: vk::FormatFeatureFlags::DEPTH_STENCIL_ATTACHMENT
            | vk::FormatFeatureFlags::SAMPLED_IMAGE,
    }
}

#[test]
fn each_missing_requirement_is_named() {
    assert!(missing_requirements(&full_offer()).is_empty());
    let old = DeviceOffer {
        api_version: vk::API_VERSION_1_2,
        dynamic_rendering: false,
        ..full_offer()
    };
    // Dynamic rendering is not asked of a device that is not 1.3 at all.
    assert_eq!(missing_requirements(&old), vec!["Vulkan 1.3"]);
    let poor = DeviceOffer {
        graphics_queue: false,
        swapchain_extension: Some(false),
        multi_draw_indirect: false,
        draw_indirect_first_instance: false,
        dynamic_rendering: false,
        depth_format_features: vk::FormatFeatureFlags::SAMPLED_IMAGE,
        ..full_offer()
    };
    assert_eq!(
        missing_requirements(&poor),
        vec![
            "a graphics queue",
            "VK_KHR_swapchain",
            "multiDrawIndirect",
            "drawIndirectFirstInstance",
            "dynamicRendering",
            "D32_SFLOAT depth",
        ]
    );
    let with_swapchain = DeviceOffer {
        swapchain_extension: Some(true),
        ..full_offer()
    };
    assert!(missing_requirements(&with_swapchain).is_empty());
}

#[test]
fn timestamps_need_valid_bits_and_a_period() {
    assert_eq!(map_timestamp_period(64, 1.5), Some(1.5));
    assert_eq!(map_timestamp_period(0, 1.5), None);
    assert_eq!(map_timestamp_period(64, 0.0), None);
}

fn caps(current: (u32, u32), min: (u32, u32), max: (u32, u32)) -> vk::SurfaceCapabilitiesKHR {
    vk::SurfaceCapabilitiesKHR {
        min_image_count: 2,
        max_image_count: 3,
        current_extent: vk::Extent2D {
            width: current.0,
            height: current.1,
        },
        min_image_extent: vk::Extent2D {
            width: min.0,
            height: min.1,
        },
        max_image_extent: vk::Extent2D {
            width: max.0,
            height: max.1,
        },
        ..Default::default()
    }
}

#[test]
fn unsupported_present_mode_lists_the_supported_ones() {
    let supported = [vk::PresentModeKHR::FIFO, vk::PresentModeKHR::IMMEDIATE];
    assert_eq!(
        choose_present_mode(vk::PresentModeKHR::IMMEDIATE, &supported),
        Ok(vk::PresentModeKHR::IMMEDIATE)
    );
    let e = choose_present_mode(vk::PresentModeKHR::MAILBOX, &supported).unwrap_err();
    assert_eq!(
        e,
        "present mode mailbox is not supported by this window's surface (supported: fifo, immediate)"
    );
    let e = choose_present_mode(vk::PresentModeKHR::FIFO, &[]).unwrap_err();
    assert!(e.ends_with("(supported: none)"), "{e}");
}

#[test]
fn srgb_format_is_preferred() {
    let f = |format| vk::SurfaceFormatKHR {
        format,
        color_space: vk::ColorSpaceKHR::SRGB_NONLINEAR,
    };
    let list = [
        f(vk::Format::B8G8R8A8_UNORM),
        f(vk::Format::R8G8B8A8_SRGB),
        f(vk::Format::B8G8R8A8_SRGB),
    ];
    assert_eq!(
        choose_surface_format(&list).unwrap().format,
        vk::Format::B8G8R8A8_SRGB
    );
    assert_eq!(
        choose_surface_format(&list[..1]).unwrap().format,
        vk::Format::B8G8R8A8_UNORM
    );
    assert!(choose_surface_format(&[]).is_none());
}

#[test]
fn extent_follows_the_surface_or_the_clamped_window() {
    let fixed = caps((800, 600), (1, 1), (4096, 4096));
    let e = choose_extent(&fixed, (1024, 768));
    assert_eq!((e.width, e.height), (800, 600));
    let free = caps((u32::MAX, u32::MAX), (16, 16), (2048, 1024));
    let e = choose_extent(&free, (4000, 8));
    assert_eq!((e.width, e.height), (2048, 16));
    let minimised = caps((0, 0), (0, 0), (4096, 4096));
    assert_eq!(choose_extent(&minimised, (640, 480)).width, 0);
    assert_eq!(choose_image_count(&fixed), 3);
    let unbounded = vk::SurfaceCapabilitiesKHR {
        max_image_count: 0,
        ..fixed
    };
    assert_eq!(choose_image_count(&unbounded), 3);
}

#[test]
fn composite_alpha_prefers_opaque() {
    use vk::CompositeAlphaFlagsKHR as C;
    assert_eq!(choose_composite_alpha(C::OPAQUE | C::INHERIT), C::OPAQUE);
    assert_eq!(
        choose_composite_alpha(C::PRE_MULTIPLIED | C::INHERIT),
        C::INHERIT
    );
    assert_eq!(
        choose_composite_alpha(C::POST_MULTIPLIED),
        C::POST_MULTIPLIED
    );
    assert_eq!(choose_composite_alpha(C::empty()), C::OPAQUE);
}

#[test]
fn a_texel_copy_names_its_mip_layer_rectangle_and_offset() {
    let c = map_texel_copy(4096, 2, 5, [17, 3], [64, 8]);
    assert_eq!(c.buffer_offset, 4096);
    assert_eq!(
        (c.buffer_row_length, c.buffer_image_height),
        (0, 0),
        "rows packed"
    );
    let s = c.image_subresource;
    assert_eq!(
        (
            s.aspect_mask,
            s.mip_level,
            s.base_array_layer,
            s.layer_count
        ),
        (vk::ImageAspectFlags::COLOR, 2, 5, 1)
    );
    assert_eq!(
        (c.image_offset.x, c.image_offset.y, c.image_offset.z),
        (17, 3, 0)
    );
    let e = c.image_extent;
    assert_eq!((e.width, e.height, e.depth), (64, 8, 1));
}
