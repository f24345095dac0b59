//! One small error enum for the Vulkan layer; every failing call is named.

use ash::vk;

#[derive(Debug, thiserror::Error)]
pub enum VkError {
    #[error("cannot load the Vulkan library: {0} (install libvulkan1 and a driver, e.g. mesa-vulkan-drivers)")]
    Loader(String),
    #[error("{call} failed: {result:?}")]
    Call {
        call: &'static str,
        result: vk::Result,
    },
    #[error("the validation layer VK_LAYER_KHRONOS_validation is not installed (Debian: apt-get install vulkan-validationlayers)")]
    ValidationLayerMissing,
    #[error("no suitable Vulkan device: {0}")]
    NoSuitableDevice(String),
    #[error("device memory allocation for {what} failed: {source}")]
    Allocation {
        what: String,
        source: gpu_allocator::AllocationError,
    },
    #[error("staging ring: {0}")]
    Staging(String),
    /// The input (data, bake, rasters, a choice of flags) cannot be drawn as asked: the
    /// commands answer it as bad input (exit 2), not as a runtime failure.
    #[error("{0}")]
    Input(String),
    #[error("{0}")]
    Other(String),
}

/// Names the Vulkan call that produced a `vk::Result` error.
pub trait VkResultExt<T> {
    fn call(self, call: &'static str) -> Result<T, VkError>;
}

impl<T> VkResultExt<T> for Result<T, vk::Result> {
    fn call(self, call: &'static str) -> Result<T, VkError> {
        self.map_err(|result| VkError::Call { call, result })
    }
}
