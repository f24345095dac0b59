//! Shader modules from the SPIR-V that `build.rs` compiled and the binary embeds.

use ash::vk;

use super::device::Device;
use super::error::{VkError, VkResultExt};

/// A shader module from embedded SPIR-V bytes; the caller destroys it once its pipelines exist.
pub fn shader_module(device: &Device, spv: &[u8]) -> Result<vk::ShaderModule, VkError> {
    let words = ash::util::read_spv(&mut std::io::Cursor::new(spv))
        .map_err(|e| VkError::Other(format!("embedded SPIR-V is malformed: {e}")))?;
    let info = vk::ShaderModuleCreateInfo::default().code(&words);
    // `read_spv` gave aligned, whole SPIR-V words (it checks the magic number and length), and the
    // shaders were validated by shaderc at build time.
    // SAFETY: the device is live.
    unsafe { device.raw.create_shader_module(&info, None) }.call("vkCreateShaderModule")
}
