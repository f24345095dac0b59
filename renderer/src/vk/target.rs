//! The offscreen render target: colour RGBA8 sRGB + depth D32 (reversed-Z: clear 0, GREATER),
//! and a host-visible buffer the colour is copied into for PNG output.

use ash::vk;
use gpu_allocator::MemoryLocation;

use super::image::{transition, Image2d, ImageDesc};
use super::{Buffer, Device, VkError};

pub const COLOUR_FORMAT: vk::Format = vk::Format::R8G8B8A8_SRGB;
pub const DEPTH_FORMAT: vk::Format = vk::Format::D32_SFLOAT;
/// Reversed-Z: the far plane (at infinity) is depth 0.
pub const DEPTH_CLEAR: f32 = 0.0;

pub struct OffscreenTarget {
    pub width: u32,
    pub height: u32,
    pub colour: Image2d,
    pub depth: Image2d,
    readback: Buffer,
    depth_readback: Buffer,
}

impl OffscreenTarget {
    pub fn new(device: &Device, width: u32, height: u32) -> Result<Self, VkError> {
        let max = device.properties.limits.max_image_dimension2_d;
        if width == 0 || height == 0 || width > max || height > max {
            return Err(VkError::Other(format!(
                "render size {width}x{height} is outside this device's limits (1..={max} per side)"
            )));
        }
        let mut colour = Image2d::new(
            device,
            "colour target",
            ImageDesc {
                width,
                height,
                format: COLOUR_FORMAT,
                // TRANSFER_DST: the overlay panel is copied into the top-left corner.
                usage: vk::ImageUsageFlags::COLOR_ATTACHMENT
                    | vk::ImageUsageFlags::TRANSFER_SRC
                    | vk::ImageUsageFlags::TRANSFER_DST,
                aspect: vk::ImageAspectFlags::COLOR,
                layers: 0,
            },
        )?;
        let depth = Image2d::new(
            device,
            "depth target",
            ImageDesc {
                width,
                height,
                format: DEPTH_FORMAT,
                usage: vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT
                    | vk::ImageUsageFlags::TRANSFER_SRC,
                aspect: vk::ImageAspectFlags::DEPTH,
                layers: 0,
            },
        );
        let mut depth = match depth {
            Ok(d) => d,
            Err(e) => {
                colour.destroy(device);
                return Err(e);
            }
        };
        let bytes = width as u64 * height as u64 * 4;
        let usage = vk::BufferUsageFlags::TRANSFER_DST;
        let readback = Buffer::new(
            device,
            "colour readback",
            bytes,
            usage,
            MemoryLocation::GpuToCpu,
        );
        let mut readback = match readback {
            Ok(b) => b,
            Err(e) => {
                depth.destroy(device);
                colour.destroy(device);
                return Err(e);
            }
        };
        let depth_readback = Buffer::new(
            device,
            "depth readback",
            bytes,
            usage,
            MemoryLocation::GpuToCpu,
        );
        let depth_readback = match depth_readback {
            Ok(b) => b,
            Err(e) => {
                readback.destroy(device);
                depth.destroy(device);
                colour.destroy(device);
                return Err(e);
            }
        };
        Ok(Self {
            width,
            height,
            colour,
            depth,
            readback,
            depth_readback,
        })
    }

    /// Transitions both attachments for rendering (contents discarded: they are cleared).
    pub fn record_begin(&self, device: &Device, cmd: vk::CommandBuffer) {
        transition(
            device,
            cmd,
            self.colour.raw,
            vk::ImageAspectFlags::COLOR,
            (
                vk::ImageLayout::UNDEFINED,
                vk::PipelineStageFlags::TRANSFER,
                vk::AccessFlags::empty(),
            ),
            (
                vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
                vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT,
                vk::AccessFlags::COLOR_ATTACHMENT_WRITE,
            ),
        );
        transition(
            device,
            cmd,
            self.depth.raw,
            vk::ImageAspectFlags::DEPTH,
            (
                vk::ImageLayout::UNDEFINED,
                vk::PipelineStageFlags::TRANSFER,
                vk::AccessFlags::empty(),
            ),
            (
                vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL,
                vk::PipelineStageFlags::EARLY_FRAGMENT_TESTS
                    | vk::PipelineStageFlags::LATE_FRAGMENT_TESTS,
                vk::AccessFlags::DEPTH_STENCIL_ATTACHMENT_WRITE
                    | vk::AccessFlags::DEPTH_STENCIL_ATTACHMENT_READ,
            ),
        );
    }

    /// Copies colour and depth into the readback buffers, visible to the host after the fence.
    pub fn record_readback(&self, device: &Device, cmd: vk::CommandBuffer) {
        transition(
            device,
            cmd,
            self.colour.raw,
            vk::ImageAspectFlags::COLOR,
            (
                vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
                vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT,
                vk::AccessFlags::COLOR_ATTACHMENT_WRITE,
            ),
            (
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                vk::PipelineStageFlags::TRANSFER,
                vk::AccessFlags::TRANSFER_READ,
            ),
        );
        transition(
            device,
            cmd,
            self.depth.raw,
            vk::ImageAspectFlags::DEPTH,
            (
                vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL,
                vk::PipelineStageFlags::LATE_FRAGMENT_TESTS,
                vk::AccessFlags::DEPTH_STENCIL_ATTACHMENT_WRITE,
            ),
            (
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                vk::PipelineStageFlags::TRANSFER,
                vk::AccessFlags::TRANSFER_READ,
            ),
        );
        let region = |aspect| {
            vk::BufferImageCopy::default()
                .image_subresource(vk::ImageSubresourceLayers {
                    aspect_mask: aspect,
                    mip_level: 0,
                    base_array_layer: 0,
                    layer_count: 1,
                })
                .image_extent(vk::Extent3D {
                    width: self.width,
                    height: self.height,
                    depth: 1,
                })
        };
        unsafe {
            device.raw.cmd_copy_image_to_buffer(
                cmd,
                self.colour.raw,
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                self.readback.raw,
                &[region(vk::ImageAspectFlags::COLOR)],
            );
            device.raw.cmd_copy_image_to_buffer(
                cmd,
                self.depth.raw,
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                self.depth_readback.raw,
                &[region(vk::ImageAspectFlags::DEPTH)],
            );
            let to_host = vk::MemoryBarrier::default()
                .src_access_mask(vk::AccessFlags::TRANSFER_WRITE)
                .dst_access_mask(vk::AccessFlags::HOST_READ);
            device.raw.cmd_pipeline_barrier(
                cmd,
                vk::PipelineStageFlags::TRANSFER,
                vk::PipelineStageFlags::HOST,
                vk::DependencyFlags::empty(),
                &[to_host],
                &[],
                &[],
            );
        }
    }

    /// Blits the rendered colour into a swapchain image (scaled to its extent) and leaves that
    /// image ready to present.
    pub fn record_blit_to(
        &self,
        device: &Device,
        cmd: vk::CommandBuffer,
        image: vk::Image,
        extent: vk::Extent2D,
    ) {
        transition(
            device,
            cmd,
            self.colour.raw,
            vk::ImageAspectFlags::COLOR,
            (
                vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
                vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT,
                vk::AccessFlags::COLOR_ATTACHMENT_WRITE,
            ),
            (
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                vk::PipelineStageFlags::TRANSFER,
                vk::AccessFlags::TRANSFER_READ,
            ),
        );
        transition(
            device,
            cmd,
            image,
            vk::ImageAspectFlags::COLOR,
            (
                vk::ImageLayout::UNDEFINED,
                vk::PipelineStageFlags::TRANSFER,
                vk::AccessFlags::empty(),
            ),
            (
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                vk::PipelineStageFlags::TRANSFER,
                vk::AccessFlags::TRANSFER_WRITE,
            ),
        );
        let layers = vk::ImageSubresourceLayers {
            aspect_mask: vk::ImageAspectFlags::COLOR,
            mip_level: 0,
            base_array_layer: 0,
            layer_count: 1,
        };
        let corner = |w: u32, h: u32| vk::Offset3D {
            x: w as i32,
            y: h as i32,
            z: 1,
        };
        let blit = vk::ImageBlit {
            src_subresource: layers,
            src_offsets: [vk::Offset3D::default(), corner(self.width, self.height)],
            dst_subresource: layers,
            dst_offsets: [vk::Offset3D::default(), corner(extent.width, extent.height)],
        };
        unsafe {
            device.raw.cmd_blit_image(
                cmd,
                self.colour.raw,
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                image,
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                &[blit],
                vk::Filter::LINEAR,
            )
        };
        transition(
            device,
            cmd,
            image,
            vk::ImageAspectFlags::COLOR,
            (
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                vk::PipelineStageFlags::TRANSFER,
                vk::AccessFlags::TRANSFER_WRITE,
            ),
            (
                vk::ImageLayout::PRESENT_SRC_KHR,
                vk::PipelineStageFlags::BOTTOM_OF_PIPE,
                vk::AccessFlags::empty(),
            ),
        );
    }

    /// RGBA8 (sRGB-encoded) pixels, rows top to bottom. Valid after the frame's fence.
    pub fn colour_rgba(&self) -> Vec<u8> {
        self.readback
            .mapped()
            .map(|m| m.to_vec())
            .unwrap_or_default()
    }

    /// Reversed-Z depth per pixel (1 = near plane, 0 = infinitely far / sky).
    pub fn depth(&self) -> Vec<f32> {
        self.depth_readback
            .mapped()
            .map(bytemuck::pod_collect_to_vec)
            .unwrap_or_default()
    }

    pub fn destroy(&mut self, device: &Device) {
        self.depth_readback.destroy(device);
        self.readback.destroy(device);
        self.depth.destroy(device);
        self.colour.destroy(device);
    }
}
