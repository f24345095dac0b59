//! The offscreen render target: colour RGBA8 sRGB + depth D32 (reversed-Z: clear 0, GREATER),
//! and host-visible buffers colour and depth are copied into for PNG output. Owns the two images
//! and the two readback buffers; destroyed in reverse order of creation.

use ash::vk;
use gpu_allocator::MemoryLocation;

use super::access::{image_barrier, memory_barrier, Access};
use super::buffer::Buffer;
use super::conv::map_format_aspect;
use super::device::Device;
use super::error::VkError;
use super::image::{Image2d, ImageDesc};

pub use super::conv::{COLOUR_FORMAT, DEPTH_FORMAT};

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
                aspect: map_format_aspect(COLOUR_FORMAT),
                layers: 0,
                mips: 1,
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
                aspect: map_format_aspect(DEPTH_FORMAT),
                layers: 0,
                mips: 1,
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

    /// Transitions both attachments for rendering (contents discarded: they are cleared). The
    /// last use of both was the previous frame's copy out of them ([`Self::record_readback`] or
    /// [`Self::record_blit_to`]); the clear must not overtake it.
    pub fn record_begin(&self, device: &Device, cmd: vk::CommandBuffer) {
        self.colour.barrier(
            device,
            cmd,
            &[Access::TransferRead],
            &[Access::ColourAttachmentWrite],
            true,
        );
        self.depth.barrier(
            device,
            cmd,
            &[Access::TransferRead],
            &[Access::DepthAttachmentReadWrite],
            true,
        );
    }

    /// Begins dynamic rendering over the whole target, colour and depth, with the viewport and
    /// scissor covering it: `clear` gives the colour (linear RGBA) and depth to start from,
    /// None keeps what an earlier pass drew. The target must be in its attachment layouts
    /// ([`Self::record_begin`]); end with [`Self::end_rendering`].
    pub fn begin_rendering(
        &self,
        device: &Device,
        cmd: vk::CommandBuffer,
        clear: Option<([f32; 4], f32)>,
    ) {
        let (load, colour_clear, depth_clear) = match clear {
            Some((c, z)) => (vk::AttachmentLoadOp::CLEAR, c, z),
            None => (vk::AttachmentLoadOp::LOAD, [0.0; 4], 0.0),
        };
        let colour = [vk::RenderingAttachmentInfo::default()
            .image_view(self.colour.view)
            .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
            .load_op(load)
            .store_op(vk::AttachmentStoreOp::STORE)
            .clear_value(vk::ClearValue {
                color: vk::ClearColorValue {
                    float32: colour_clear,
                },
            })];
        let depth = vk::RenderingAttachmentInfo::default()
            .image_view(self.depth.view)
            .image_layout(vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL)
            .load_op(load)
            .store_op(vk::AttachmentStoreOp::STORE)
            .clear_value(vk::ClearValue {
                depth_stencil: vk::ClearDepthStencilValue {
                    depth: depth_clear,
                    stencil: 0,
                },
            });
        let area = vk::Rect2D {
            offset: vk::Offset2D { x: 0, y: 0 },
            extent: vk::Extent2D {
                width: self.width,
                height: self.height,
            },
        };
        let rendering = vk::RenderingInfo::default()
            .render_area(area)
            .layer_count(1)
            .color_attachments(&colour)
            .depth_attachment(&depth);
        let viewport = vk::Viewport {
            x: 0.0,
            y: 0.0,
            width: self.width as f32,
            height: self.height as f32,
            min_depth: 0.0,
            max_depth: 1.0,
        };
        // The views are live and in the attachment layouts named (this function's contract);
        // the structs outlive the calls.
        // SAFETY: `cmd` is recording on `device` outside any rendering.
        unsafe {
            device.raw.cmd_begin_rendering(cmd, &rendering);
            device.raw.cmd_set_viewport(cmd, 0, &[viewport]);
            device.raw.cmd_set_scissor(cmd, 0, &[area]);
        }
    }

    /// Ends the rendering [`Self::begin_rendering`] began.
    pub fn end_rendering(&self, device: &Device, cmd: vk::CommandBuffer) {
        // SAFETY: `cmd` is recording inside the rendering begun on this target.
        unsafe { device.raw.cmd_end_rendering(cmd) };
    }

    /// Copies colour and depth into the readback buffers, visible to the host after the fence.
    pub fn record_readback(&self, device: &Device, cmd: vk::CommandBuffer) {
        self.colour.barrier(
            device,
            cmd,
            &[Access::ColourAttachmentWrite],
            &[Access::TransferRead],
            false,
        );
        self.depth.barrier(
            device,
            cmd,
            &[Access::DepthAttachmentReadWrite],
            &[Access::TransferRead],
            false,
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
        // Callers record between the begin and end of a frame's command buffer; the images and
        // buffers are owned by `self` until `destroy`; each buffer holds width × height × 4 bytes,
        // one RGBA8 or D32 copy of the extent; the images are in TRANSFER_SRC_OPTIMAL (above).
        // SAFETY: the device is live, `cmd` is recording on it and every copy fits its buffer.
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
        }
        memory_barrier(device, cmd, &[Access::TransferWrite], &[Access::HostRead]);
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
        self.colour.barrier(
            device,
            cmd,
            &[Access::ColourAttachmentWrite],
            &[Access::TransferRead],
            false,
        );
        // The swapchain image's old contents are not needed; its last use ends at the acquire.
        image_barrier(
            device,
            cmd,
            image,
            vk::ImageAspectFlags::COLOR,
            &[Access::SwapchainAcquired],
            &[Access::TransferWrite],
            true,
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
        // `self.colour` is owned by `self` and in TRANSFER_SRC_OPTIMAL, `image` is the caller's
        // acquired swapchain image (`PresentTarget::image`, live until the swapchain is recreated,
        // which waits for the device) in TRANSFER_DST_OPTIMAL (barriers above); the regions lie
        // within both extents.
        // SAFETY: the device is live and `cmd` is recording on it.
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
        image_barrier(
            device,
            cmd,
            image,
            vk::ImageAspectFlags::COLOR,
            &[Access::TransferWrite],
            &[Access::Present],
            false,
        );
    }

    /// RGBA8 (sRGB-encoded) pixels, rows top to bottom: what the last completed
    /// [`Self::record_readback`] copied, read from persistently mapped memory; the frame's
    /// fence (waited by the renderer before reading) orders the copy before this read, and the
    /// memory barrier in `record_readback` makes it visible to the host.
    pub fn colour_rgba(&self) -> Vec<u8> {
        self.readback
            .mapped()
            .map(|m| m.to_vec())
            .unwrap_or_default()
    }

    /// Reversed-Z depth per pixel (1 = near plane, 0 = infinitely far / sky), from the same
    /// copy as [`Self::colour_rgba`].
    pub fn depth(&self) -> Vec<f32> {
        self.depth_readback
            .mapped()
            .map(bytemuck::pod_collect_to_vec)
            .unwrap_or_default()
    }

    /// Reverse of creation. Idempotent (each part is). The frame that used the target must have
    /// completed (the renderer waits for the device first).
    pub fn destroy(&mut self, device: &Device) {
        self.depth_readback.destroy(device);
        self.readback.destroy(device);
        self.depth.destroy(device);
        self.colour.destroy(device);
    }
}
