//! Vulkan instance, optional validation layer, and the debug-utils messenger that logs through
//! `tracing` and counts errors and warnings (tests fail on any).

use std::ffi::{c_void, CStr};
use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::{Arc, Mutex};

use ash::{ext, vk};

use super::conv::{map_message_severity, MessageSeverity};
use super::error::{VkError, VkResultExt};

const VALIDATION_LAYER: &CStr = c"VK_LAYER_KHRONOS_validation";

/// Counts what the validation layer reported. Shared with tests through [`Instance::counters`].
#[derive(Debug, Default)]
pub struct ValidationCounters {
    pub errors: AtomicU32,
    pub warnings: AtomicU32,
    /// The first few messages, kept so a failing test can say what went wrong.
    pub messages: Mutex<Vec<String>>,
}

impl ValidationCounters {
    pub fn errors(&self) -> u32 {
        self.errors.load(Ordering::SeqCst)
    }
    pub fn warnings(&self) -> u32 {
        self.warnings.load(Ordering::SeqCst)
    }
    pub fn messages(&self) -> Vec<String> {
        self.messages.lock().map(|m| m.clone()).unwrap_or_default()
    }
    /// Err naming the counts and the first message when anything was reported: every command
    /// fails on a validation error or warning.
    pub fn verdict(&self) -> Result<(), String> {
        if self.errors() + self.warnings() == 0 {
            return Ok(());
        }
        Err(format!(
            "validation reported {} errors and {} warnings; first: {}",
            self.errors(),
            self.warnings(),
            self.messages().first().cloned().unwrap_or_default()
        ))
    }
}

/// The loader entry, the instance and (with validation) the debug messenger. Created by
/// [`Instance::new`], destroyed by [`Instance::destroy`] after every device and surface made from
/// it. `entry` keeps the loader library loaded as long as `Self` lives, so the loader outlives
/// the instance, which `destroy` ends explicitly (an instance never destroyed is leaked).
pub struct Instance {
    pub entry: ash::Entry,
    pub raw: ash::Instance,
    debug: Option<(ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>,
    /// The messenger's user data points into this `Arc`; the instance holds it until the
    /// messenger is destroyed, and callers hold their own clones.
    counters: Arc<ValidationCounters>,
    pub validation: bool,
    /// Set by `destroy`, so that a second call does not destroy the instance twice.
    destroyed: bool,
}

/// Counts one message (the first 16 are kept verbatim) and logs it.
fn count_message(
    counters: Option<&ValidationCounters>,
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    kind: vk::DebugUtilsMessageTypeFlagsEXT,
    message: String,
) {
    let keep = |c: &ValidationCounters| {
        if let Ok(mut m) = c.messages.lock() {
            if m.len() < 16 {
                m.push(message.clone());
            }
        }
    };
    match map_message_severity(severity) {
        MessageSeverity::Error => {
            tracing::error!(target: "vulkan", ?kind, "{message}");
            if let Some(c) = counters {
                c.errors.fetch_add(1, Ordering::SeqCst);
                keep(c);
            }
        }
        MessageSeverity::Warning => {
            tracing::warn!(target: "vulkan", ?kind, "{message}");
            if let Some(c) = counters {
                c.warnings.fetch_add(1, Ordering::SeqCst);
                keep(c);
            }
        }
        MessageSeverity::Info => tracing::debug!(target: "vulkan", ?kind, "{message}"),
    }
}

/// The debug-utils callback.
///
/// # Safety
/// Called by the validation layer only: `data` is null or points to a valid callback-data
/// struct for the duration of the call, and `user` is the user data given at messenger
/// creation, a pointer to the `ValidationCounters` in the instance's `Arc`, which outlives the
/// messenger (see `Instance::destroy`).
unsafe extern "system" fn debug_callback(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    kind: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    user: *mut c_void,
) -> vk::Bool32 {
    let message = if data.is_null() {
        String::from("(no message)")
    } else {
        // The layer's contract (above) makes non-null `data` valid for this call.
        // SAFETY: its message is a NUL-terminated string or null (`message_as_c_str` handles it).
        unsafe { (*data).message_as_c_str() }
            .map(|m| m.to_string_lossy().into_owned())
            .unwrap_or_default()
    };
    // Only shared references are made, and the counters are atomics and a mutex.
    // SAFETY: `user` is null or points to the live `ValidationCounters` (contract above).
    let counters = unsafe { (user as *const ValidationCounters).as_ref() };
    count_message(counters, severity, kind, message);
    vk::FALSE
}

impl Instance {
    /// Creates the instance. With `validation`, the Khronos layer is required (an error names the
    /// package when it is missing) and every message is counted.
    pub fn new(validation: bool) -> Result<Self, VkError> {
        Self::with_extensions(validation, &[])
    }

    /// As [`Self::new`], also enabling `extra` instance extensions (e.g. the surface extensions
    /// `ash_window::enumerate_required_extensions` names for a window).
    pub fn with_extensions(validation: bool, extra: &[&CStr]) -> Result<Self, VkError> {
        // The `Entry` keeps the library loaded for as long as it lives (as long as the instance:
        // see `Instance`).
        // SAFETY: loading the system Vulkan loader runs its initialisation.
        let entry = unsafe { ash::Entry::load() }.map_err(|e| VkError::Loader(e.to_string()))?;
        let counters = Arc::new(ValidationCounters::default());

        let mut layers = Vec::new();
        let mut extensions: Vec<*const std::ffi::c_char> =
            extra.iter().map(|e| e.as_ptr()).collect();
        if validation {
            // SAFETY: a global query on the loaded entry; it fills plain structs.
            let available = unsafe { entry.enumerate_instance_layer_properties() }
                .call("vkEnumerateInstanceLayerProperties")?;
            let found = available
                .iter()
                .any(|l| l.layer_name_as_c_str().ok() == Some(VALIDATION_LAYER));
            if !found {
                return Err(VkError::ValidationLayerMissing);
            }
            layers.push(VALIDATION_LAYER.as_ptr());
            extensions.push(ext::debug_utils::NAME.as_ptr());
        }

        let app_info = vk::ApplicationInfo::default()
            .application_name(c"aerie")
            .application_version(1)
            .engine_name(c"aerie")
            .api_version(vk::API_VERSION_1_3);
        let mut messenger_info = vk::DebugUtilsMessengerCreateInfoEXT::default()
            .message_severity(
                vk::DebugUtilsMessageSeverityFlagsEXT::ERROR
                    | vk::DebugUtilsMessageSeverityFlagsEXT::WARNING
                    | vk::DebugUtilsMessageSeverityFlagsEXT::INFO,
            )
            .message_type(
                vk::DebugUtilsMessageTypeFlagsEXT::GENERAL
                    | vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION
                    | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE,
            )
            .pfn_user_callback(Some(debug_callback))
            .user_data(Arc::as_ptr(&counters) as *mut c_void);
        let mut create_info = vk::InstanceCreateInfo::default()
            .application_info(&app_info)
            .enabled_layer_names(&layers)
            .enabled_extension_names(&extensions);
        if validation {
            // Also catches messages from vkCreateInstance / vkDestroyInstance themselves.
            create_info = create_info.push_next(&mut messenger_info);
        }
        // The layer was found above and the extensions are the caller's (window-system ones) plus debug-utils, which the
        // validation layer provides. The messenger's user data (`counters`) is kept alive by `Self`.
        // SAFETY: the create-info and every name, layer and chained struct it points to live until the call returns.
        let raw = unsafe { entry.create_instance(&create_info, None) }.call("vkCreateInstance")?;

        let debug = if validation {
            let loader = ext::debug_utils::Instance::new(&entry, &raw);
            // The user data points into `counters`, which `Self` keeps until the messenger is
            // destroyed.
            // SAFETY: `raw` is live and has the debug-utils extension enabled.
            let messenger = unsafe { loader.create_debug_utils_messenger(&messenger_info, None) };
            match messenger {
                Ok(m) => Some((loader, m)),
                Err(e) => {
                    // SAFETY: the instance was just created and nothing was made from it.
                    unsafe { raw.destroy_instance(None) };
                    return Err(VkError::Call {
                        call: "vkCreateDebugUtilsMessengerEXT",
                        result: e,
                    });
                }
            }
        } else {
            None
        };
        Ok(Self {
            entry,
            raw,
            debug,
            counters,
            validation,
            destroyed: false,
        })
    }

    /// What validation has reported so far (errors, warnings, first messages).
    pub fn counters(&self) -> Arc<ValidationCounters> {
        self.counters.clone()
    }

    /// Destroys the messenger, then the instance. Every device and surface made from it must
    /// be destroyed before (the validation layer reports any left). Idempotent.
    pub fn destroy(&mut self) {
        if self.destroyed {
            return;
        }
        self.destroyed = true;
        if let Some((loader, messenger)) = self.debug.take() {
            // After this the layer no longer calls back into `counters`.
            // SAFETY: the messenger was created on this live instance and is taken, so it is destroyed once.
            unsafe { loader.destroy_debug_utils_messenger(messenger, None) };
        }
        // Its children were destroyed by their owners first (contract above).
        // SAFETY: `destroyed` was false, so the instance is live and destroyed exactly once.
        unsafe { self.raw.destroy_instance(None) };
    }
}
