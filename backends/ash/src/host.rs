//! Host-visible buffers: the upload staging, the parameter blocks and
//! readback targets.

use crate::device::Gpu;
use crate::error::{AshError, VkContext};
use crate::memory::allocate;
use crate::owned::Owned;
use ash::vk;

/// A host-visible, coherent buffer, mapped for its whole life (freeing the
/// memory unmaps it).
pub(crate) struct HostBuffer {
    // Declared before the memory: the buffer is destroyed first.
    buffer: Owned<vk::Buffer>,
    _memory: Owned<vk::DeviceMemory>,
    ptr: *mut u8,
    pub size: u64,
}

impl HostBuffer {
    pub fn new(
        gpu: &Gpu,
        size: u64,
        usage: vk::BufferUsageFlags,
        what: &str,
    ) -> Result<Self, AshError> {
        let d = &gpu.device;
        let size = size.max(16).next_multiple_of(4);
        let info = vk::BufferCreateInfo::default().size(size).usage(usage);
        // SAFETY: valid device and info.
        let buffer = d.own(unsafe { d.create_buffer(&info, None) }.ctx(what)?);
        // SAFETY: the buffer was just created.
        let req = unsafe { d.get_buffer_memory_requirements(buffer.raw()) };
        let host = vk::MemoryPropertyFlags::HOST_VISIBLE | vk::MemoryPropertyFlags::HOST_COHERENT;
        let memory = allocate(gpu, req, host, what)?;
        // SAFETY: fresh memory, bound once and mapped once.
        let ptr = unsafe {
            d.bind_buffer_memory(buffer.raw(), memory.raw(), 0)
                .ctx(what)?;
            d.map_memory(memory.raw(), 0, vk::WHOLE_SIZE, vk::MemoryMapFlags::empty())
                .ctx(what)?
        };
        Ok(Self {
            buffer,
            _memory: memory,
            ptr: ptr.cast(),
            size,
        })
    }

    pub fn buffer(&self) -> vk::Buffer {
        self.buffer.raw()
    }

    /// Writes `words` at byte `offset`.
    pub fn write(&self, offset: u64, words: &[u32]) {
        let bytes: &[u8] = bytemuck::cast_slice(words);
        assert!(
            offset + bytes.len() as u64 <= self.size,
            "host buffer overflow"
        );
        // SAFETY: in bounds (checked above) of a coherent mapping this struct owns.
        unsafe {
            std::ptr::copy_nonoverlapping(
                bytes.as_ptr(),
                self.ptr.add(offset as usize),
                bytes.len(),
            )
        };
    }

    pub fn read(&self, len: usize) -> Vec<u8> {
        let len = len.min(self.size as usize);
        let mut out = vec![0u8; len];
        // SAFETY: in bounds of a coherent mapping this struct owns.
        unsafe { std::ptr::copy_nonoverlapping(self.ptr, out.as_mut_ptr(), len) };
        out
    }
}
