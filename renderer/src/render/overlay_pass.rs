//! The overlay's GPU side: a small RGBA8 panel, staged with the frame, copied into the top-left
//! corner of the colour target after the terrain pass (a copy cannot blend: the panel is
//! opaque). What the panel shows is composed in `tools::overlay`.

use ash::vk;

use crate::vk::access::{image_barrier, Access};
use crate::vk::Device;

/// An RGBA8 picture, rows top to bottom.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Panel {
    pub width: u32,
    pub height: u32,
    pub rgba: Vec<u8>,
}

impl Panel {
    pub fn pixel(&self, x: u32, y: u32) -> [u8; 4] {
        let o = ((y * self.width + x) * 4) as usize;
        [
            self.rgba[o],
            self.rgba[o + 1],
            self.rgba[o + 2],
            self.rgba[o + 3],
        ]
    }

    pub fn bytes(&self) -> u64 {
        self.rgba.len() as u64
    }
}

/// Records the copy of `panel` (staged at `offset` of `src`) into the top-left corner of the
/// colour target `image`, which is in COLOR_ATTACHMENT_OPTIMAL after the terrain pass; leaves it
/// in that layout so the read-back or present blit that follows is unchanged. The image needs
/// TRANSFER_DST usage. The copy is clipped to `extent`.
pub fn record_panel_copy(
    device: &Device,
    cmd: vk::CommandBuffer,
    src: vk::Buffer,
    offset: u64,
    image: vk::Image,
    extent: (u32, u32),
    panel: &Panel,
) {
    let (w, h) = (panel.width.min(extent.0), panel.height.min(extent.1));
    if w == 0 || h == 0 {
        return;
    }
    let colour = vk::ImageAspectFlags::COLOR;
    let attachment = [Access::ColourAttachmentWrite];
    let transfer = [Access::TransferWrite];
    image_barrier(device, cmd, image, colour, &attachment, &transfer, false);
    let region = vk::BufferImageCopy::default()
        .buffer_offset(offset)
        .buffer_row_length(panel.width)
        .buffer_image_height(panel.height)
        .image_subresource(vk::ImageSubresourceLayers {
            aspect_mask: colour,
            mip_level: 0,
            base_array_layer: 0,
            layer_count: 1,
        })
        .image_extent(vk::Extent3D {
            width: w,
            height: h,
            depth: 1,
        });
    // `image` is the live colour target, in TRANSFER_DST_OPTIMAL after the barrier above; the
    // region is clipped to the image and reads `panel.width × panel.height` texels the caller
    // staged at `offset` of the live buffer `src`.
    // SAFETY: `cmd` is recording.
    unsafe {
        device.raw.cmd_copy_buffer_to_image(
            cmd,
            src,
            image,
            vk::ImageLayout::TRANSFER_DST_OPTIMAL,
            &[region],
        )
    };
    image_barrier(device, cmd, image, colour, &transfer, &attachment, false);
}
