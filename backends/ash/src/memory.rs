//! Resources and their memory: transients in one `VkDeviceMemory` per heap of
//! the plan's memory plan, at its offsets (`graph/src/alias.rs`, the same
//! layout `backends/cpu/src/memory.rs` gives its arena); imported and history
//! resources in their own allocations.
//!
//! The plan placed transients with default sizes and alignments; the driver's
//! `vkGet*MemoryRequirements` may ask for more. When the plan's offsets do
//! not fit the real requirements (misaligned, or two resources alive at once
//! then overlap), the placement is re-planned with the real requirements by
//! the same planner (`plan_memory`, which takes them as inputs for this), and
//! the frame notes say so.
//!
//! Sharing: with two queue families every resource is
//! `VK_SHARING_MODE_CONCURRENT`. Exclusive ownership would need a release and
//! an acquire barrier for every cross-queue dependency, and aliased
//! transients would need ownership re-established whenever their bytes change
//! hands; on NVIDIA buffers lose nothing by concurrent sharing and the few
//! images here are small next to the buffers.

use crate::device::Gpu;
use crate::error::{AshError, VkContext};
use ash::vk;
use strandgraph_graph::alias::{AliasRequest, HeapKind, plan_memory};
use strandgraph_graph::schema::{ImageFormat, ResourceDecl, Usage};
use strandgraph_graph::{Instance, LifetimeClass, Plan};

pub(crate) enum Res {
    Buffer {
        buffer: vk::Buffer,
        /// Bytes created (the plan's size rounded up to 4).
        size: u64,
        /// The plan's size in 32-bit words.
        words: usize,
    },
    Image {
        image: vk::Image,
        view: vk::ImageView,
        format: vk::Format,
        extent: [u32; 3],
        texel_bytes: u32,
        depth: bool,
    },
}

impl Res {
    pub fn aspect(&self) -> vk::ImageAspectFlags {
        match self {
            Res::Image { depth: true, .. } => vk::ImageAspectFlags::DEPTH,
            _ => vk::ImageAspectFlags::COLOR,
        }
    }
}

pub(crate) struct Memory {
    /// By physical resource id; `None` for versions and unused transients.
    pub res: Vec<Option<Res>>,
    allocations: Vec<vk::DeviceMemory>,
    /// Transient bytes allocated (with the aliasing in use).
    pub transient_bytes: u64,
    /// What the transients would take in separate allocations.
    pub unaliased_bytes: u64,
    /// Imported and history bytes.
    pub owned_bytes: u64,
    /// `(earlier, later)` transients sharing bytes.
    pub aliases: Vec<(usize, usize)>,
    pub notes: Vec<String>,
}

pub(crate) fn format(f: ImageFormat) -> vk::Format {
    use vk::Format as F;
    match f {
        ImageFormat::R8Unorm => F::R8_UNORM,
        ImageFormat::Rgba8Unorm => F::R8G8B8A8_UNORM,
        ImageFormat::Rgba8Srgb => F::R8G8B8A8_SRGB,
        ImageFormat::R16Float => F::R16_SFLOAT,
        ImageFormat::Rg16Float => F::R16G16_SFLOAT,
        ImageFormat::Rgba16Float => F::R16G16B16A16_SFLOAT,
        ImageFormat::R32Float => F::R32_SFLOAT,
        ImageFormat::R32Uint => F::R32_UINT,
        ImageFormat::Rg32Uint => F::R32G32_UINT,
        ImageFormat::Rgba32Float => F::R32G32B32A32_SFLOAT,
        ImageFormat::D32Float => F::D32_SFLOAT,
    }
}

/// A device allocation of `req`, failing with the byte count.
pub(crate) fn allocate(
    gpu: &Gpu,
    req: vk::MemoryRequirements,
    wanted: vk::MemoryPropertyFlags,
    what: &str,
) -> Result<vk::DeviceMemory, AshError> {
    let ty = gpu
        .memory_type(req.memory_type_bits, wanted)
        .or_else(|| {
            // Host-visible memory that is not device-local is fine for staging
            // on a discrete GPU; device-local memory may lack host visibility.
            (!wanted.contains(vk::MemoryPropertyFlags::HOST_VISIBLE))
                .then(|| gpu.memory_type(req.memory_type_bits, vk::MemoryPropertyFlags::empty()))
                .flatten()
        })
        .ok_or_else(|| AshError::Pass {
            pass: what.to_string(),
            message: format!(
                "no memory type with {wanted:?} among bits {:#x}",
                req.memory_type_bits
            ),
        })?;
    let info = vk::MemoryAllocateInfo::default()
        .allocation_size(req.size.max(4))
        .memory_type_index(ty);
    // SAFETY: valid device and info.
    unsafe { gpu.device.allocate_memory(&info, None) }.map_err(|e| match AshError::vk(what, e) {
        AshError::OutOfMemory { what, kind, .. } => AshError::OutOfMemory {
            what,
            kind,
            bytes: req.size,
        },
        other => other,
    })
}

impl Memory {
    pub fn create(
        gpu: &Gpu,
        plan: &Plan,
        instance: &Instance,
        used: &[bool],
        families: &[u32],
        alias: bool,
    ) -> Result<Memory, AshError> {
        let g = &plan.graph;
        let mut mem = Memory {
            res: (0..g.resources.len()).map(|_| None).collect(),
            allocations: Vec::new(),
            transient_bytes: 0,
            unaliased_bytes: 0,
            owned_bytes: 0,
            aliases: Vec::new(),
            notes: Vec::new(),
        };
        let result = mem.fill(gpu, plan, instance, used, families, alias);
        if let Err(e) = result {
            mem.destroy(&gpu.device);
            return Err(e);
        }
        Ok(mem)
    }

    fn fill(
        &mut self,
        gpu: &Gpu,
        plan: &Plan,
        instance: &Instance,
        used: &[bool],
        families: &[u32],
        alias: bool,
    ) -> Result<(), AshError> {
        let g = &plan.graph;
        let d = &gpu.device;
        let sharing = if families.len() > 1 {
            vk::SharingMode::CONCURRENT
        } else {
            vk::SharingMode::EXCLUSIVE
        };
        // Image usages from how live passes access each image.
        let mut usage = vec![
            vk::ImageUsageFlags::TRANSFER_SRC | vk::ImageUsageFlags::TRANSFER_DST;
            g.resources.len()
        ];
        for &p in &plan.order {
            for a in &g.passes[p].accesses {
                usage[g.physical(a.resource)] |= match a.usage {
                    Usage::Sampled => vk::ImageUsageFlags::SAMPLED,
                    Usage::Color => vk::ImageUsageFlags::COLOR_ATTACHMENT,
                    Usage::Depth => vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT,
                    _ => vk::ImageUsageFlags::STORAGE,
                };
            }
        }
        let mut reqs: Vec<Option<vk::MemoryRequirements>> = vec![None; g.resources.len()];
        for (r, res) in g.resources.iter().enumerate() {
            let imported = res.decl.lifetime() != LifetimeClass::Transient;
            if res.version_of.is_some() || !(used[r] || imported) {
                continue;
            }
            let bytes = instance.sizes[r].bytes;
            let made = match &res.decl {
                ResourceDecl::Buffer { .. } => {
                    let size = bytes.max(4).next_multiple_of(4);
                    let info = vk::BufferCreateInfo::default()
                        .size(size)
                        .usage(
                            vk::BufferUsageFlags::STORAGE_BUFFER
                                | vk::BufferUsageFlags::UNIFORM_BUFFER
                                | vk::BufferUsageFlags::INDIRECT_BUFFER
                                | vk::BufferUsageFlags::TRANSFER_SRC
                                | vk::BufferUsageFlags::TRANSFER_DST,
                        )
                        .sharing_mode(sharing)
                        .queue_family_indices(families);
                    // SAFETY: valid device and info.
                    let buffer = unsafe { d.create_buffer(&info, None) }
                        .ctx(&format!("vkCreateBuffer `{}`", res.name))?;
                    // SAFETY: the buffer was just created.
                    reqs[r] = Some(unsafe { d.get_buffer_memory_requirements(buffer) });
                    Res::Buffer {
                        buffer,
                        size,
                        words: bytes.div_ceil(4) as usize,
                    }
                }
                ResourceDecl::Image { format: f, .. } => {
                    let extent = instance.sizes[r]
                        .extent
                        .unwrap_or([1, 1, 1])
                        .map(|x| x.max(1));
                    let vf = format(*f);
                    let mut u = usage[r];
                    if f.is_depth() {
                        u &= !vk::ImageUsageFlags::STORAGE;
                    }
                    check_format(gpu, vf, u, &res.name)?;
                    let info = vk::ImageCreateInfo::default()
                        .image_type(vk::ImageType::TYPE_2D)
                        .format(vf)
                        .extent(vk::Extent3D {
                            width: extent[0],
                            height: extent[1],
                            depth: 1,
                        })
                        .mip_levels(1)
                        .array_layers(extent[2])
                        .samples(vk::SampleCountFlags::TYPE_1)
                        .tiling(vk::ImageTiling::OPTIMAL)
                        .usage(u)
                        .sharing_mode(sharing)
                        .queue_family_indices(families)
                        .initial_layout(vk::ImageLayout::UNDEFINED);
                    // SAFETY: valid device and info.
                    let image = unsafe { d.create_image(&info, None) }
                        .ctx(&format!("vkCreateImage `{}`", res.name))?;
                    // SAFETY: the image was just created.
                    reqs[r] = Some(unsafe { d.get_image_memory_requirements(image) });
                    Res::Image {
                        image,
                        view: vk::ImageView::null(),
                        format: vf,
                        extent,
                        texel_bytes: f.texel_bytes() as u32,
                        depth: f.is_depth(),
                    }
                }
            };
            self.res[r] = Some(made);
        }

        // Transients: the plan's placements, checked against the real requirements.
        let mut placements: Vec<(usize, HeapKind, u64)> = instance
            .memory
            .placements
            .iter()
            .filter(|p| reqs[p.resource].is_some())
            .map(|p| (p.resource, p.heap, p.offset))
            .collect();
        let requests: Vec<AliasRequest> = plan
            .lifetimes
            .iter()
            .filter_map(|l| {
                let req = reqs[l.resource]?;
                let heap = if g.resources[l.resource].decl.is_image() {
                    HeapKind::Images
                } else {
                    HeapKind::Buffers
                };
                Some(AliasRequest {
                    resource: l.resource,
                    heap,
                    size: req.size,
                    alignment: req.alignment.max(heap.default_alignment()),
                    first: l.first,
                    end: l.end,
                })
            })
            .collect();
        let request = |r: usize| requests.iter().find(|q| q.resource == r);
        let fits = placements.iter().all(|&(r, heap, off)| {
            let Some(a) = request(r) else { return false };
            off % a.alignment == 0
                && placements.iter().all(|&(o, oheap, ooff)| {
                    let Some(b) = request(o) else { return false };
                    o == r
                        || oheap != heap
                        || !(a.first <= b.end && b.first <= a.end)
                        || off + a.size <= ooff
                        || ooff + b.size <= off
                })
        });
        if alias && !fits {
            let replanned = plan_memory(&requests);
            placements = replanned
                .placements
                .iter()
                .map(|p| (p.resource, p.heap, p.offset))
                .collect();
            self.notes.push(
                "the plan's aliasing offsets do not fit the driver's memory requirements; \
                 transients were re-placed by the same planner with the real sizes and alignments"
                    .into(),
            );
        }
        self.unaliased_bytes = requests.iter().map(|r| r.size).sum();

        let bind = |r: usize, memory: vk::DeviceMemory, offset: u64| -> Result<(), AshError> {
            let name = &g.resources[r].name;
            // SAFETY: the resource and memory are live; offsets honour the requirements.
            unsafe {
                match &self.res[r] {
                    Some(Res::Buffer { buffer, .. }) => {
                        d.bind_buffer_memory(*buffer, memory, offset)
                    }
                    Some(Res::Image { image, .. }) => d.bind_image_memory(*image, memory, offset),
                    None => Ok(()),
                }
            }
            .ctx(&format!("binding memory of `{name}`"))
        };
        let local = vk::MemoryPropertyFlags::DEVICE_LOCAL;
        if alias {
            for heap in [HeapKind::Buffers, HeapKind::Images] {
                let members: Vec<(usize, u64)> = placements
                    .iter()
                    .filter(|p| p.1 == heap)
                    .map(|p| (p.0, p.2))
                    .collect();
                if members.is_empty() {
                    continue;
                }
                let mut req = vk::MemoryRequirements {
                    size: 0,
                    alignment: 1,
                    memory_type_bits: u32::MAX,
                };
                for &(r, off) in &members {
                    let real = reqs[r].expect("placed resources exist");
                    req.size = req.size.max(off + real.size);
                    req.alignment = req.alignment.max(real.alignment);
                    req.memory_type_bits &= real.memory_type_bits;
                }
                let memory = allocate(gpu, req, local, &format!("transient {heap:?} heap"))?;
                self.allocations.push(memory);
                self.transient_bytes += req.size;
                for &(r, off) in &members {
                    bind(r, memory, off)?;
                }
                // Pairs that share bytes, earlier lifetime first.
                for (i, &(a, ao)) in members.iter().enumerate() {
                    for &(b, bo) in &members[i + 1..] {
                        let (ra, rb) = (request(a), request(b));
                        let (Some(ra), Some(rb)) = (ra, rb) else {
                            continue;
                        };
                        if ao < bo + rb.size && bo < ao + ra.size {
                            if ra.end < rb.first {
                                self.aliases.push((a, b));
                            } else if rb.end < ra.first {
                                self.aliases.push((b, a));
                            }
                        }
                    }
                }
            }
        }
        for (r, res) in g.resources.iter().enumerate() {
            let Some(req) = reqs[r] else { continue };
            let transient = res.decl.lifetime() == LifetimeClass::Transient;
            if transient && alias {
                continue;
            }
            let memory = allocate(gpu, req, local, &format!("`{}`", res.name))?;
            self.allocations.push(memory);
            if transient {
                self.transient_bytes += req.size;
            } else {
                self.owned_bytes += req.size;
            }
            bind(r, memory, 0)?;
        }
        // Views, now that images have memory.
        for res in self.res.iter_mut().flatten() {
            if let Res::Image {
                image,
                view,
                format,
                extent,
                depth,
                ..
            } = res
            {
                let aspect = if *depth {
                    vk::ImageAspectFlags::DEPTH
                } else {
                    vk::ImageAspectFlags::COLOR
                };
                let info = vk::ImageViewCreateInfo::default()
                    .image(*image)
                    .view_type(if extent[2] > 1 {
                        vk::ImageViewType::TYPE_2D_ARRAY
                    } else {
                        vk::ImageViewType::TYPE_2D
                    })
                    .format(*format)
                    .subresource_range(full_range(aspect, extent[2]));
                // SAFETY: the image is bound to memory.
                *view = unsafe { d.create_image_view(&info, None) }.ctx("vkCreateImageView")?;
            }
        }
        Ok(())
    }

    pub fn destroy(&mut self, d: &ash::Device) {
        // SAFETY: the device is idle (the session waits before dropping).
        unsafe {
            for res in self.res.iter_mut().filter_map(Option::take) {
                match res {
                    Res::Buffer { buffer, .. } => d.destroy_buffer(buffer, None),
                    Res::Image { image, view, .. } => {
                        if view != vk::ImageView::null() {
                            d.destroy_image_view(view, None);
                        }
                        d.destroy_image(image, None);
                    }
                }
            }
            for m in self.allocations.drain(..) {
                d.free_memory(m, None);
            }
        }
    }
}

pub(crate) fn full_range(aspect: vk::ImageAspectFlags, layers: u32) -> vk::ImageSubresourceRange {
    vk::ImageSubresourceRange {
        aspect_mask: aspect,
        base_mip_level: 0,
        level_count: 1,
        base_array_layer: 0,
        layer_count: layers.max(1),
    }
}

/// Refuses an image whose format cannot be used as the passes use it.
fn check_format(
    gpu: &Gpu,
    f: vk::Format,
    usage: vk::ImageUsageFlags,
    name: &str,
) -> Result<(), AshError> {
    // SAFETY: plain query.
    let props = unsafe {
        gpu.instance
            .get_physical_device_format_properties(gpu.physical, f)
    };
    let have = props.optimal_tiling_features;
    for (u, feature) in [
        (
            vk::ImageUsageFlags::STORAGE,
            vk::FormatFeatureFlags::STORAGE_IMAGE,
        ),
        (
            vk::ImageUsageFlags::SAMPLED,
            vk::FormatFeatureFlags::SAMPLED_IMAGE,
        ),
        (
            vk::ImageUsageFlags::COLOR_ATTACHMENT,
            vk::FormatFeatureFlags::COLOR_ATTACHMENT,
        ),
        (
            vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT,
            vk::FormatFeatureFlags::DEPTH_STENCIL_ATTACHMENT,
        ),
    ] {
        if usage.contains(u) && !have.contains(feature) {
            return Err(AshError::MissingFeature {
                device: gpu.name.clone(),
                feature: format!("{feature:?} for {f:?}"),
                pass: format!("(image `{name}`)"),
                why: format!("the passes use `{name}` as {u:?}"),
            });
        }
    }
    Ok(())
}

/// A host-visible, coherent buffer, mapped.
pub(crate) struct HostBuffer {
    pub buffer: vk::Buffer,
    memory: vk::DeviceMemory,
    pub ptr: *mut u8,
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
        let buffer = unsafe { d.create_buffer(&info, None) }.ctx(what)?;
        // SAFETY: the buffer was just created.
        let req = unsafe { d.get_buffer_memory_requirements(buffer) };
        let memory = match allocate(
            gpu,
            req,
            vk::MemoryPropertyFlags::HOST_VISIBLE | vk::MemoryPropertyFlags::HOST_COHERENT,
            what,
        ) {
            Ok(m) => m,
            Err(e) => {
                // SAFETY: unused buffer.
                unsafe { d.destroy_buffer(buffer, None) };
                return Err(e);
            }
        };
        let mapped = (|| {
            // SAFETY: fresh memory, bound once and mapped once.
            unsafe {
                d.bind_buffer_memory(buffer, memory, 0).ctx(what)?;
                d.map_memory(memory, 0, vk::WHOLE_SIZE, vk::MemoryMapFlags::empty())
                    .ctx(what)
            }
        })();
        match mapped {
            Ok(ptr) => Ok(Self {
                buffer,
                memory,
                ptr: ptr.cast(),
                size,
            }),
            Err(e) => {
                // SAFETY: unused objects.
                unsafe {
                    d.destroy_buffer(buffer, None);
                    d.free_memory(memory, None);
                }
                Err(e)
            }
        }
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

    pub fn destroy(&mut self, d: &ash::Device) {
        // SAFETY: the device is idle for this buffer.
        unsafe {
            d.destroy_buffer(self.buffer, None);
            d.free_memory(self.memory, None);
        }
    }
}
