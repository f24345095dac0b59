//! Thin, explicit Vulkan plumbing. The rules every file here follows:
//!
//! - Each struct owns one Vulkan object or one coherent group (an image with its memory and
//!   view, a swapchain with its images and semaphores), is created in one function and
//!   destroyed by an explicit `destroy`, which releases in reverse order of creation and is
//!   idempotent. Owners destroy in reverse order too: objects, then the device, then surfaces,
//!   then the instance.
//! - Barriers are named by use ([`access`]); pure mappings and choices live in [`conv`], tested.
//! - Every `unsafe` block says in a `// SAFETY:` comment why it is sound. A `&Device` is a live
//!   device until its `destroy`; handles a struct owns are live until its `destroy`.
//! - Nothing here imports the renderer, the simulator links, the tools or the application.

pub mod access;
pub mod access_type;
pub mod buffer;
pub mod compute_pipeline;
pub mod conv;
pub mod descriptors;
pub mod device;
pub mod entity_pipeline;
pub mod error;
pub mod frame_context;
pub mod frame_slot;
pub mod graphics_pipeline;
pub mod image;
pub mod instance;
pub mod pipeline;
pub mod set_layout;
pub mod shader;
pub mod sky_pipeline;
pub mod staging;
pub mod swapchain;
pub mod target;
pub mod tess_pipeline;
pub mod timestamps;

pub use buffer::Buffer;
pub use device::{Device, DeviceDesc};
pub use error::{VkError, VkResultExt};
pub use instance::{Instance, ValidationCounters};

/// Frames the CPU may record ahead of the GPU. Every per-frame resource (command buffer, fence,
/// descriptor pool, staging region, timestamp queries) exists this many times.
pub const FRAMES_IN_FLIGHT: usize = 2;
