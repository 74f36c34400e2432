//! Errors: every failure is a value naming what failed (the pass, the
//! feature, the Vulkan call), never a panic or a hang.

use ash::vk;

#[derive(Debug, thiserror::Error)]
pub enum AshError {
    #[error("Vulkan loader: {0} (install libvulkan1 and a driver, e.g. mesa-vulkan-drivers)")]
    Loader(String),
    #[error(
        "validation was requested but the layer `{0}` is not installed (apt-get install vulkan-validationlayers)"
    )]
    LayerMissing(String),
    #[error("no Vulkan 1.3 device{0}")]
    NoDevice(String),
    #[error("device `{device}` lacks {feature}, which pass `{pass}` needs ({why})")]
    MissingFeature {
        device: String,
        feature: String,
        pass: String,
        why: String,
    },
    #[error("{what}: {result}")]
    Vulkan { what: String, result: vk::Result },
    #[error("{what}: the device was lost (VK_ERROR_DEVICE_LOST)")]
    DeviceLost { what: String },
    #[error("{what}: out of {kind} memory ({bytes} bytes requested)")]
    OutOfMemory {
        what: String,
        kind: &'static str,
        bytes: u64,
    },
    #[error("{what}: no completion within {millis} ms")]
    Timeout { what: String, millis: u128 },
    #[error("Vulkan validation reported {} message(s) during {what}:\n{}", messages.len(), messages.join("\n"))]
    Validation { what: String, messages: Vec<String> },
    #[error("pass `{pass}`: kind `{kind}` has no definition")]
    NoDefinition { pass: String, kind: String },
    #[error(transparent)]
    MissingBinding(#[from] strandgraph_passes::bind::MissingBinding),
    #[error(transparent)]
    Param(#[from] strandgraph_passes::ParamError),
    #[error("shader: {0}")]
    Shader(String),
    #[error("input `{resource}`: {message}")]
    Input { resource: String, message: String },
    #[error("pass `{pass}`: {message}")]
    Pass { pass: String, message: String },
    #[error("no resource `{0}`")]
    NoResource(String),
}

impl AshError {
    /// Wraps a failed Vulkan call, singling out device loss and memory exhaustion.
    pub(crate) fn vk(what: impl Into<String>, result: vk::Result) -> Self {
        let what = what.into();
        match result {
            vk::Result::ERROR_DEVICE_LOST => AshError::DeviceLost { what },
            vk::Result::ERROR_OUT_OF_DEVICE_MEMORY => AshError::OutOfMemory {
                what,
                kind: "device",
                bytes: 0,
            },
            vk::Result::ERROR_OUT_OF_HOST_MEMORY => AshError::OutOfMemory {
                what,
                kind: "host",
                bytes: 0,
            },
            vk::Result::TIMEOUT => AshError::Timeout { what, millis: 0 },
            result => AshError::Vulkan { what, result },
        }
    }
}

/// `result.map_err(|e| AshError::vk(what, e))`.
pub(crate) trait VkContext<T> {
    fn ctx(self, what: &str) -> Result<T, AshError>;
}

impl<T> VkContext<T> for Result<T, vk::Result> {
    fn ctx(self, what: &str) -> Result<T, AshError> {
        self.map_err(|e| AshError::vk(what, e))
    }
}
