//! The one failure type of every command, with its exit code: 0 success, 2 bad input
//! (arguments, DEM files, configs), 1 runtime (Vulkan, I/O).

/// A failure with its exit code: 2 = bad input, 1 = runtime.
#[derive(Debug)]
pub struct Failure {
    pub code: i32,
    pub message: String,
}

pub fn bad_input(message: impl ToString) -> Failure {
    Failure {
        code: 2,
        message: message.to_string(),
    }
}

pub fn runtime(message: impl ToString) -> Failure {
    Failure {
        code: 1,
        message: message.to_string(),
    }
}

/// A renderer failure: bad input where the renderer found the input could not be drawn
/// ([`VkError::Input`]: a bake that does not fit, rasters that do not register), else runtime.
pub fn renderer_failure(e: crate::vk::VkError) -> Failure {
    match e {
        crate::vk::VkError::Input(m) => bad_input(m),
        e => runtime(e),
    }
}
