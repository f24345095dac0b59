//! Thin, explicit Vulkan plumbing: each struct owns one Vulkan object or one coherent group,
//! is created in one function and destroyed by an explicit `destroy` in reverse order.

pub mod access;
pub mod buffer;
pub mod conv;
pub mod descriptors;
pub mod device;
pub mod error;
pub mod frame_context;
pub mod frame_slot;
pub mod image;
pub mod instance;
pub mod pipeline;
pub mod staging;
pub mod swapchain;
pub mod target;
pub mod timestamps;

pub use buffer::Buffer;
pub use device::{Device, DeviceDesc};
pub use error::{VkError, VkResultExt};
pub use instance::{Instance, ValidationCounters};

/// Frames the CPU may record ahead of the GPU. Every per-frame resource (command buffer, fence,
/// descriptor pool, staging region, timestamp queries) exists this many times.
pub const FRAMES_IN_FLIGHT: usize = 2;
