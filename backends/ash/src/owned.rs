//! Vulkan objects that destroy themselves.
//!
//! Every object the backend creates is owned by a value whose `Drop` calls
//! the matching `vkDestroy*`/`vkFree*`, so an early `?` anywhere frees what
//! was made so far and no function cleans up by hand. Destruction order
//! follows from ownership:
//! - device children ([`Owned`]) hold an `Arc` of the [`Device`], so the
//!   device outlives them all; the device waits idle before it goes;
//! - the [`Device`] holds the debug [`Messenger`] and an `Arc` of the
//!   [`Instance`], and the messenger holds one too: device, then messenger,
//!   then instance, as the specification requires;
//! - objects that may still be in use by the GPU are dropped only after the
//!   session has waited for the device to go idle (`Drop for Session`).
//!
//! Command buffers and descriptor sets are not owned one by one: they go
//! with their pool.

use crate::device::Messages;
use ash::{ext, vk};
use std::ops::Deref;
use std::sync::Arc;

/// A `VkInstance`, destroyed when the last owner (the device, the
/// messenger, the session's `Gpu`) drops.
pub(crate) struct Instance {
    raw: ash::Instance,
    /// Keeps the loader's function pointers valid while the instance lives.
    pub entry: ash::Entry,
}

impl Instance {
    pub fn new(entry: ash::Entry, raw: ash::Instance) -> Arc<Self> {
        Arc::new(Self { raw, entry })
    }
}

impl Deref for Instance {
    type Target = ash::Instance;
    fn deref(&self) -> &ash::Instance {
        &self.raw
    }
}

impl Drop for Instance {
    fn drop(&mut self) {
        // SAFETY: every object created from the instance holds an `Arc` of
        // it, so none is alive any more.
        unsafe { self.raw.destroy_instance(None) };
    }
}

/// The validation layer's debug-utils messenger. It owns the message list
/// its callback writes into (the callback's user data points into it), so
/// the list lives exactly as long as the messenger can call back.
pub(crate) struct Messenger {
    loader: ext::debug_utils::Instance,
    raw: vk::DebugUtilsMessengerEXT,
    _messages: Messages,
    _instance: Arc<Instance>,
}

impl Messenger {
    pub fn new(
        instance: &Arc<Instance>,
        loader: ext::debug_utils::Instance,
        raw: vk::DebugUtilsMessengerEXT,
        messages: Messages,
    ) -> Self {
        Self {
            loader,
            raw,
            _messages: messages,
            _instance: instance.clone(),
        }
    }
}

impl Drop for Messenger {
    fn drop(&mut self) {
        // SAFETY: created from the instance this struct keeps alive.
        unsafe { self.loader.destroy_debug_utils_messenger(self.raw, None) };
    }
}

/// The logical device. Dropped after every [`Owned`] child (each holds an
/// `Arc` of it), it waits for the GPU to go idle, then destroys the device;
/// its fields then drop the messenger and the instance, in that order.
pub(crate) struct Device {
    raw: ash::Device,
    _messenger: Option<Messenger>,
    _instance: Arc<Instance>,
}

impl Device {
    pub fn new(
        instance: &Arc<Instance>,
        raw: ash::Device,
        messenger: Option<Messenger>,
    ) -> Arc<Self> {
        Arc::new(Self {
            raw,
            _messenger: messenger,
            _instance: instance.clone(),
        })
    }
}

impl Device {
    /// Takes ownership of `raw`, just created from this device.
    pub fn own<H: Destroy>(self: &Arc<Self>, raw: H) -> Owned<H> {
        Owned {
            raw,
            device: self.clone(),
        }
    }
}

impl Deref for Device {
    type Target = ash::Device;
    fn deref(&self) -> &ash::Device {
        &self.raw
    }
}

impl Drop for Device {
    fn drop(&mut self) {
        // SAFETY: no child object is alive (they hold `Arc`s of this); the
        // wait makes sure no submitted work is either.
        unsafe {
            let _ = self.raw.device_wait_idle();
            self.raw.destroy_device(None);
        }
    }
}

/// A handle destroyed (or freed) by one device call.
pub(crate) trait Destroy: Copy {
    /// # Safety
    /// `self` was created from `device` and is no longer used by the GPU.
    unsafe fn destroy(self, device: &ash::Device);
}

macro_rules! destroy_with {
    ($($ty:ty => $call:ident),* $(,)?) => {$(
        impl Destroy for $ty {
            unsafe fn destroy(self, device: &ash::Device) {
                // SAFETY: per the trait's contract.
                unsafe { device.$call(self, None) }
            }
        }
    )*};
}

destroy_with! {
    vk::Buffer => destroy_buffer,
    vk::Image => destroy_image,
    vk::ImageView => destroy_image_view,
    vk::DeviceMemory => free_memory,
    vk::ShaderModule => destroy_shader_module,
    vk::DescriptorSetLayout => destroy_descriptor_set_layout,
    vk::DescriptorPool => destroy_descriptor_pool,
    vk::PipelineLayout => destroy_pipeline_layout,
    vk::Pipeline => destroy_pipeline,
    vk::CommandPool => destroy_command_pool,
    vk::Semaphore => destroy_semaphore,
    vk::Fence => destroy_fence,
    vk::QueryPool => destroy_query_pool,
}

/// A device child that destroys itself when dropped.
pub(crate) struct Owned<H: Destroy> {
    raw: H,
    device: Arc<Device>,
}

impl<H: Destroy> Owned<H> {
    /// The handle, for recording and descriptor writes; valid while `self` lives.
    pub fn raw(&self) -> H {
        self.raw
    }
}

impl<H: Destroy> Drop for Owned<H> {
    fn drop(&mut self) {
        // SAFETY: created from this device; owners drop in-flight objects
        // only after the session waited for the device to go idle.
        unsafe { self.raw.destroy(&self.device) };
    }
}

#[cfg(test)]
mod tests {
    use crate::{AshBackend, Validation};
    use std::path::Path;
    use strandgraph_assets::Scene;
    use strandgraph_graph::compile_file;
    use strandgraph_passes::Registry;
    use strandgraph_passes::upload::upload;

    /// Destroying a session that ran frames and a readback leaves nothing
    /// behind and destroys in a valid order: the validation layer reports
    /// objects still alive at `vkDestroyDevice` (and use after destroy)
    /// into the message list, which the messenger keeps until the very end.
    /// The showcase's visibility graph has images, raster passes, aliased
    /// transients, indirect dispatches and async compute.
    #[test]
    fn dropping_a_session_is_clean_under_validation() {
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
        let scene = Scene::load(&root.join("scenes/showcase.ron")).unwrap();
        let plan = compile_file(
            &root.join("scenes/graphs/kulikov_visibility.ron"),
            &Registry,
            scene.counts().models as u32,
        )
        .unwrap();
        let up = upload(&scene, 48, 27);
        let instance = plan.instantiate(&up.quantities).unwrap();
        let backend = AshBackend {
            validation: Validation::Sync,
            ..AshBackend::default()
        };
        let mut session = backend
            .open(&plan, &instance)
            .unwrap_or_else(|e| panic!("{e}"));
        for _ in 0..2 {
            session.run(&up).unwrap_or_else(|e| panic!("{e}"));
        }
        assert!(session.read("debug_layers").unwrap().is_some());
        let messages = session.gpu.messages().expect("validating");
        drop(session);
        let said = messages.lock().unwrap().clone();
        assert!(said.is_empty(), "{said:#?}");
        // Only the test's clone is left: the messenger (and so the device and
        // instance that hold it) is gone.
        assert_eq!(std::sync::Arc::strong_count(&messages), 1);
    }
}
