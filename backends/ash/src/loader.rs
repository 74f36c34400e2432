//! The Vulkan loader and driver, loaded once per process.
//!
//! On NVIDIA's driver (580, H100) a process that creates and destroys some
//! thirty Vulkan instances, which `strandgraph bench` does (a session per
//! table cell, wgpu's and ash's alike), gets "vkCreateInstance: Unable to
//! find a Vulkan driver" from then on: the loader unloads the driver with
//! the last instance and loads it again with the next, and the driver does
//! not survive that many reloads. So the loader is loaded once, and
//! [`keep_driver_loaded`] holds one instance for the life of the process;
//! every later instance, ours or wgpu's (the same `libvulkan.so.1`), finds
//! the driver already loaded.

use crate::error::{AshError, VkContext};
use ash::vk;
use std::sync::OnceLock;

/// The system Vulkan loader, loaded on first use and never unloaded.
pub(crate) fn entry() -> Result<ash::Entry, AshError> {
    static ENTRY: OnceLock<Result<ash::Entry, String>> = OnceLock::new();
    ENTRY
        // SAFETY: loading the system Vulkan loader; failure is an error value.
        .get_or_init(|| unsafe { ash::Entry::load() }.map_err(|e| e.to_string()))
        .clone()
        .map_err(AshError::Loader)
}

/// Creates one Vulkan instance that is never destroyed, so that the driver
/// stays loaded while sessions come and go (see the module docs). Call it
/// before opening many sessions; it is idempotent and cheap after the first
/// call.
pub fn keep_driver_loaded() -> Result<(), AshError> {
    static KEEP: OnceLock<Result<(), String>> = OnceLock::new();
    KEEP.get_or_init(|| {
        let entry = entry().map_err(|e| e.to_string())?;
        let app = vk::ApplicationInfo::default().api_version(vk::API_VERSION_1_3);
        let info = vk::InstanceCreateInfo::default().application_info(&app);
        // SAFETY: a plain instance without layers or extensions. It is
        // deliberately leaked: destroying it would unload the driver.
        unsafe { entry.create_instance(&info, None) }
            .ctx("vkCreateInstance (keeping the driver loaded)")
            .map(std::mem::forget)
            .map_err(|e| e.to_string())
    })
    .clone()
    .map_err(AshError::Loader)
}
