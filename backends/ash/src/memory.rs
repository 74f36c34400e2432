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
use crate::owned::Owned;
use crate::placement::{Placements, alias_requests, placements_fit, sharing_bytes};
use ash::vk;
use strandgraph_graph::alias::{AliasRequest, HeapKind};
use strandgraph_graph::schema::{ImageFormat, ResourceDecl, Usage};
use strandgraph_graph::{Instance, LifetimeClass, Plan};

pub(crate) enum Res {
    Buffer {
        buffer: Owned<vk::Buffer>,
        /// Bytes created (the plan's size rounded up to 4).
        size: u64,
        /// The plan's size in 32-bit words.
        words: usize,
    },
    Image {
        // Declared before the image: dropped (destroyed) first.
        view: Owned<vk::ImageView>,
        image: Owned<vk::Image>,
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

/// A resource created but not yet bound to memory (so without a view).
enum Unbound {
    Buffer {
        buffer: Owned<vk::Buffer>,
        size: u64,
        words: usize,
    },
    Image {
        image: Owned<vk::Image>,
        format: vk::Format,
        extent: [u32; 3],
        texel_bytes: u32,
        depth: bool,
    },
}

pub(crate) struct Memory {
    /// By physical resource id; `None` for versions and unused transients.
    /// Declared before `allocations`: resources go before their memory.
    pub res: Vec<Option<Res>>,
    allocations: Vec<Owned<vk::DeviceMemory>>,
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
) -> Result<Owned<vk::DeviceMemory>, AshError> {
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
    let memory =
        unsafe { gpu.device.allocate_memory(&info, None) }.map_err(|e| {
            match AshError::vk(what, e) {
                AshError::OutOfMemory { what, kind, .. } => AshError::OutOfMemory {
                    what,
                    kind,
                    bytes: req.size,
                },
                other => other,
            }
        })?;
    Ok(gpu.device.own(memory))
}

/// Image usages from how live passes access each image (by physical id).
fn image_usages(plan: &Plan) -> Vec<vk::ImageUsageFlags> {
    let g = &plan.graph;
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
    usage
}

/// How resources are created: shared between the queue families in use.
struct Creation<'a> {
    gpu: &'a Gpu,
    sharing: vk::SharingMode,
    families: &'a [u32],
}

impl Creation<'_> {
    fn buffer(
        &self,
        name: &str,
        bytes: u64,
    ) -> Result<(Unbound, vk::MemoryRequirements), AshError> {
        let d = &self.gpu.device;
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
            .sharing_mode(self.sharing)
            .queue_family_indices(self.families);
        // SAFETY: valid device and info.
        let buffer = d
            .own(unsafe { d.create_buffer(&info, None) }.ctx(&format!("vkCreateBuffer `{name}`"))?);
        // SAFETY: the buffer was just created.
        let req = unsafe { d.get_buffer_memory_requirements(buffer.raw()) };
        let words = bytes.div_ceil(4) as usize;
        Ok((
            Unbound::Buffer {
                buffer,
                size,
                words,
            },
            req,
        ))
    }

    fn image(
        &self,
        name: &str,
        f: ImageFormat,
        extent: [u32; 3],
        samples: u32,
        usage: vk::ImageUsageFlags,
    ) -> Result<(Unbound, vk::MemoryRequirements), AshError> {
        let d = &self.gpu.device;
        let vf = format(f);
        let mut u = usage;
        if f.is_depth() {
            u &= !vk::ImageUsageFlags::STORAGE;
        }
        check_format(self.gpu, vf, u, name)?;
        let samples = sample_count(self.gpu, vf, u, samples, name)?;
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
            .samples(samples)
            .tiling(vk::ImageTiling::OPTIMAL)
            .usage(u)
            .sharing_mode(self.sharing)
            .queue_family_indices(self.families)
            .initial_layout(vk::ImageLayout::UNDEFINED);
        // SAFETY: valid device and info.
        let image =
            d.own(unsafe { d.create_image(&info, None) }.ctx(&format!("vkCreateImage `{name}`"))?);
        // SAFETY: the image was just created.
        let req = unsafe { d.get_image_memory_requirements(image.raw()) };
        let unbound = Unbound::Image {
            image,
            format: vf,
            extent,
            texel_bytes: f.texel_bytes() as u32,
            depth: f.is_depth(),
        };
        Ok((unbound, req))
    }
}

impl Unbound {
    fn bind(
        &self,
        d: &ash::Device,
        memory: vk::DeviceMemory,
        offset: u64,
    ) -> Result<(), vk::Result> {
        // SAFETY: the resource and memory are live; offsets honour the requirements.
        unsafe {
            match self {
                Unbound::Buffer { buffer, .. } => {
                    d.bind_buffer_memory(buffer.raw(), memory, offset)
                }
                Unbound::Image { image, .. } => d.bind_image_memory(image.raw(), memory, offset),
            }
        }
    }

    /// The resource, with a view for an image (which now has memory).
    fn into_res(self, gpu: &Gpu) -> Result<Res, AshError> {
        let d = &gpu.device;
        Ok(match self {
            Unbound::Buffer {
                buffer,
                size,
                words,
            } => Res::Buffer {
                buffer,
                size,
                words,
            },
            Unbound::Image {
                image,
                format,
                extent,
                texel_bytes,
                depth,
            } => {
                let aspect = if depth {
                    vk::ImageAspectFlags::DEPTH
                } else {
                    vk::ImageAspectFlags::COLOR
                };
                let info = vk::ImageViewCreateInfo::default()
                    .image(image.raw())
                    .view_type(if extent[2] > 1 {
                        vk::ImageViewType::TYPE_2D_ARRAY
                    } else {
                        vk::ImageViewType::TYPE_2D
                    })
                    .format(format)
                    .subresource_range(full_range(aspect, extent[2]));
                // SAFETY: the image is bound to memory.
                let view =
                    d.own(unsafe { d.create_image_view(&info, None) }.ctx("vkCreateImageView")?);
                Res::Image {
                    view,
                    image,
                    format,
                    extent,
                    texel_bytes,
                    depth,
                }
            }
        })
    }
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
        let unbound = create_unbound(gpu, plan, instance, used, families)?;
        let reqs: Vec<Option<vk::MemoryRequirements>> =
            unbound.iter().map(|u| u.as_ref().map(|u| u.1)).collect();
        let mut mem = Memory {
            res: Vec::new(),
            allocations: Vec::new(),
            transient_bytes: 0,
            unaliased_bytes: 0,
            owned_bytes: 0,
            aliases: Vec::new(),
            notes: Vec::new(),
        };
        let requests = alias_requests(plan, &reqs);
        mem.unaliased_bytes = requests.iter().map(|r| r.size).sum();
        if alias {
            let placements = mem.placements(plan, instance, &reqs, &requests);
            mem.bind_heaps(gpu, plan, &unbound, &placements, &requests)?;
        }
        mem.bind_separately(gpu, plan, &unbound, alias)?;
        mem.res = unbound
            .into_iter()
            .map(|u| u.map(|(u, _)| u.into_res(gpu)).transpose())
            .collect::<Result<_, _>>()?;
        Ok(mem)
    }

    /// The plan's placements of transients, checked against the real
    /// requirements, else re-planned with them (and a note saying so).
    fn placements(
        &mut self,
        plan: &Plan,
        instance: &Instance,
        reqs: &[Option<vk::MemoryRequirements>],
        requests: &[AliasRequest],
    ) -> Placements {
        let placements: Placements = instance
            .memory
            .placements
            .iter()
            .filter(|p| reqs[p.resource].is_some())
            .map(|p| (p.resource, p.heap, p.offset))
            .collect();
        if placements_fit(&placements, requests) {
            return placements;
        }
        self.notes.push(
            "the plan's aliasing offsets do not fit the driver's memory requirements; \
             transients were re-placed by the same planner with the real sizes and alignments"
                .into(),
        );
        plan.plan_memory(requests)
            .placements
            .iter()
            .map(|p| (p.resource, p.heap, p.offset))
            .collect()
    }

    /// One allocation per heap of the placements, each transient bound at its
    /// offset; records which transients share bytes.
    fn bind_heaps(
        &mut self,
        gpu: &Gpu,
        plan: &Plan,
        unbound: &[Option<(Unbound, vk::MemoryRequirements)>],
        placements: &Placements,
        requests: &[AliasRequest],
    ) -> Result<(), AshError> {
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
                let real = unbound[r].as_ref().expect("placed resources exist").1;
                req.size = req.size.max(off + real.size);
                req.alignment = req.alignment.max(real.alignment);
                req.memory_type_bits &= real.memory_type_bits;
            }
            let local = vk::MemoryPropertyFlags::DEVICE_LOCAL;
            let memory = allocate(gpu, req, local, &format!("transient {heap:?} heap"))?;
            self.transient_bytes += req.size;
            for &(r, off) in &members {
                if let Some((u, _)) = &unbound[r] {
                    let name = &plan.graph.resources[r].name;
                    u.bind(&gpu.device, memory.raw(), off)
                        .ctx(&format!("binding memory of `{name}`"))?;
                }
            }
            self.allocations.push(memory);
            self.aliases.extend(sharing_bytes(&members, requests));
        }
        Ok(())
    }

    /// Its own allocation for every resource not in a heap: imported and
    /// history ones, and transients when not aliasing.
    fn bind_separately(
        &mut self,
        gpu: &Gpu,
        plan: &Plan,
        unbound: &[Option<(Unbound, vk::MemoryRequirements)>],
        alias: bool,
    ) -> Result<(), AshError> {
        for (r, res) in plan.graph.resources.iter().enumerate() {
            let Some((u, req)) = &unbound[r] else {
                continue;
            };
            let transient = res.decl.lifetime() == LifetimeClass::Transient;
            if transient && alias {
                continue;
            }
            let local = vk::MemoryPropertyFlags::DEVICE_LOCAL;
            let memory = allocate(gpu, *req, local, &format!("`{}`", res.name))?;
            if transient {
                self.transient_bytes += req.size;
            } else {
                self.owned_bytes += req.size;
            }
            u.bind(&gpu.device, memory.raw(), 0)
                .ctx(&format!("binding memory of `{}`", res.name))?;
            self.allocations.push(memory);
        }
        Ok(())
    }
}

/// Every resource that needs memory, created without it: live ones, and
/// every imported or history one.
fn create_unbound(
    gpu: &Gpu,
    plan: &Plan,
    instance: &Instance,
    used: &[bool],
    families: &[u32],
) -> Result<Vec<Option<(Unbound, vk::MemoryRequirements)>>, AshError> {
    let g = &plan.graph;
    let usage = image_usages(plan);
    let creation = Creation {
        gpu,
        sharing: if families.len() > 1 {
            vk::SharingMode::CONCURRENT
        } else {
            vk::SharingMode::EXCLUSIVE
        },
        families,
    };
    let mut out = Vec::with_capacity(g.resources.len());
    for (r, res) in g.resources.iter().enumerate() {
        let imported = res.decl.lifetime() != LifetimeClass::Transient;
        if res.version_of.is_some() || !(used[r] || imported) {
            out.push(None);
            continue;
        }
        let made = match &res.decl {
            ResourceDecl::Buffer { .. } => creation.buffer(&res.name, instance.sizes[r].bytes)?,
            ResourceDecl::Image {
                format: f, samples, ..
            } => {
                let extent = instance.sizes[r]
                    .extent
                    .unwrap_or([1, 1, 1])
                    .map(|x| x.max(1));
                creation.image(&res.name, *f, extent, *samples, usage[r])?
            }
        };
        out.push(Some(made));
    }
    Ok(out)
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
/// The sample count flag for `samples`, or an error naming the limit when
/// the device cannot make `f` with that many (lavapipe has 1 and 4).
fn sample_count(
    gpu: &Gpu,
    f: vk::Format,
    usage: vk::ImageUsageFlags,
    samples: u32,
    name: &str,
) -> Result<vk::SampleCountFlags, AshError> {
    let flag = vk::SampleCountFlags::from_raw(samples);
    if samples == 1 {
        return Ok(flag);
    }
    // SAFETY: plain query.
    let props = unsafe {
        gpu.instance.get_physical_device_image_format_properties(
            gpu.physical,
            f,
            vk::ImageType::TYPE_2D,
            vk::ImageTiling::OPTIMAL,
            usage,
            vk::ImageCreateFlags::empty(),
        )
    };
    match props {
        Ok(p) if p.sample_counts.contains(flag) => Ok(flag),
        _ => Err(AshError::MissingFeature {
            device: gpu.name.clone(),
            feature: format!("{samples} samples of {f:?} (VkImageFormatProperties::sampleCounts)"),
            pass: format!("(image `{name}`)"),
            why: format!("the graph declares `{name}` with {samples} samples"),
        }),
    }
}

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
