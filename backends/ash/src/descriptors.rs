//! Descriptor sets and parameter blocks: every set of every pass comes from
//! one pool, and every parameter block lives in one host-visible buffer,
//! at offsets aligned for uniform buffers. Binding 0 of each set is its
//! block; bindings 1.. are the pass's bound resources in order.

use crate::barriers::SyncPlan;
use crate::device::Gpu;
use crate::error::{AshError, VkContext};
use crate::host::HostBuffer;
use crate::memory::Res;
use crate::owned::Owned;
use crate::pipelines::{Built, Context, Work};
use ash::vk;
use std::collections::BTreeMap;

/// One descriptor set to allocate and fill: the pass (index into the built
/// passes), its parameter block and the bound resources for bindings 1..
/// in order.
pub(crate) struct SetPlan {
    pub built: usize,
    pub params: Vec<u32>,
    pub bound: Vec<usize>,
}

/// The pool every set comes from and the buffer of parameter blocks; the
/// sets are freed with the pool.
pub(crate) struct Sets {
    _pool: Owned<vk::DescriptorPool>,
    _uniforms: HostBuffer,
}

/// Bytes of a parameter block (at least 16: an empty block still binds).
fn block_bytes(params: &[u32]) -> u64 {
    (params.len() as u64 * 4).max(16)
}

/// Allocates and writes every planned set, and hands each to its pass's
/// work (dispatches in order, or the raster pass's one set).
pub(crate) fn fill_sets(
    cx: &Context<'_>,
    sync: &SyncPlan,
    built: &mut [Built],
    sets: &[SetPlan],
) -> Result<Sets, AshError> {
    let (uniforms, offsets) = parameter_blocks(cx.gpu, sets)?;
    let pool = pool_for(cx.gpu, built, sets)?;
    let layouts: Vec<vk::DescriptorSetLayout> = sets
        .iter()
        .map(|s| built[s.built].set_layout.raw())
        .collect();
    let info = vk::DescriptorSetAllocateInfo::default()
        .descriptor_pool(pool.raw())
        .set_layouts(&layouts);
    // SAFETY: the pool was sized for these sets.
    let allocated =
        unsafe { cx.gpu.device.allocate_descriptor_sets(&info) }.ctx("vkAllocateDescriptorSets")?;
    let mut next_dispatch: BTreeMap<usize, usize> = BTreeMap::new();
    for ((s, &set), &off) in sets.iter().zip(&allocated).zip(&offsets) {
        let block = vk::DescriptorBufferInfo {
            buffer: uniforms.buffer(),
            offset: off,
            range: block_bytes(&s.params),
        };
        let b = &mut built[s.built];
        write_set(cx, sync, b, s, set, block)?;
        match &mut b.work {
            Work::Compute { dispatches, .. } => {
                let i = next_dispatch.entry(s.built).or_default();
                dispatches[*i].0 = set;
                *i += 1;
            }
            Work::Raster { set: slot, .. } => *slot = set,
        }
    }
    Ok(Sets {
        _pool: pool,
        _uniforms: uniforms,
    })
}

/// Every set's parameter block in one host-visible buffer, and their offsets.
fn parameter_blocks(gpu: &Gpu, sets: &[SetPlan]) -> Result<(HostBuffer, Vec<u64>), AshError> {
    let align = gpu.props.limits.min_uniform_buffer_offset_alignment.max(16);
    let mut offsets = Vec::new();
    let mut cursor = 0u64;
    for s in sets {
        offsets.push(cursor);
        cursor += block_bytes(&s.params).next_multiple_of(align);
    }
    let uniforms = HostBuffer::new(
        gpu,
        cursor,
        vk::BufferUsageFlags::UNIFORM_BUFFER,
        "parameter blocks",
    )?;
    for (s, &off) in sets.iter().zip(&offsets) {
        uniforms.write(off, &s.params);
    }
    Ok((uniforms, offsets))
}

/// One pool with room for every set's descriptors.
fn pool_for(
    gpu: &Gpu,
    built: &[Built],
    sets: &[SetPlan],
) -> Result<Owned<vk::DescriptorPool>, AshError> {
    let mut counts: BTreeMap<i32, u32> = BTreeMap::new();
    for s in sets {
        for (_, ty) in &built[s.built].descriptors {
            *counts.entry(ty.as_raw()).or_default() += 1;
        }
    }
    let sizes: Vec<vk::DescriptorPoolSize> = counts
        .iter()
        .map(|(&ty, &n)| vk::DescriptorPoolSize {
            ty: vk::DescriptorType::from_raw(ty),
            descriptor_count: n,
        })
        .collect();
    let info = vk::DescriptorPoolCreateInfo::default()
        .max_sets(sets.len().max(1) as u32)
        .pool_sizes(&sizes);
    let d = &gpu.device;
    // SAFETY: valid device and info.
    Ok(d.own(unsafe { d.create_descriptor_pool(&info, None) }.ctx("vkCreateDescriptorPool")?))
}

/// One descriptor of a set: a buffer or an image.
enum Descriptor {
    Buffer(vk::DescriptorBufferInfo),
    Image(vk::DescriptorImageInfo),
}

/// Writes set `set` of pass `b`: binding 0 the parameter `block`, the
/// others the planned resources, sampled images in the layout the pass
/// finds them in.
fn write_set(
    cx: &Context<'_>,
    sync: &SyncPlan,
    b: &Built,
    s: &SetPlan,
    set: vk::DescriptorSet,
    block: vk::DescriptorBufferInfo,
) -> Result<(), AshError> {
    let g = &cx.plan.graph;
    let mut planned: Vec<(u32, vk::DescriptorType, [Descriptor; 1])> = Vec::new();
    for &(binding, ty) in &b.descriptors {
        if binding == 0 {
            planned.push((0, ty, [Descriptor::Buffer(block)]));
            continue;
        }
        let Some(&r) = s.bound.get(binding as usize - 1) else {
            return Err(cx.pass_error(
                b.p,
                format!("the shader uses binding {binding}, beyond the pass's bindings"),
            ));
        };
        let descriptor = match (&cx.memory.res[r], ty) {
            (
                Some(Res::Buffer { buffer, size, .. }),
                vk::DescriptorType::STORAGE_BUFFER | vk::DescriptorType::UNIFORM_BUFFER,
            ) => {
                let limit = u64::from(cx.gpu.props.limits.max_storage_buffer_range);
                if ty == vk::DescriptorType::STORAGE_BUFFER && *size > limit {
                    return Err(AshError::MissingFeature {
                        device: cx.gpu.name.clone(),
                        feature: format!(
                            "a storage buffer range of {} MiB (maxStorageBufferRange is {} MiB)",
                            size >> 20,
                            limit >> 20
                        ),
                        pass: cx.plan.pass_name(b.p).to_string(),
                        why: format!("it binds `{}` whole", g.resources[r].name),
                    });
                }
                Descriptor::Buffer(vk::DescriptorBufferInfo {
                    buffer: buffer.raw(),
                    offset: 0,
                    range: vk::WHOLE_SIZE,
                })
            }
            (
                Some(Res::Image { view, .. }),
                vk::DescriptorType::SAMPLED_IMAGE | vk::DescriptorType::STORAGE_IMAGE,
            ) => {
                let layout = if ty == vk::DescriptorType::STORAGE_IMAGE {
                    vk::ImageLayout::GENERAL
                } else {
                    sync.layout_in
                        .get(&(b.p, r))
                        .copied()
                        .unwrap_or(vk::ImageLayout::GENERAL)
                };
                Descriptor::Image(vk::DescriptorImageInfo {
                    sampler: vk::Sampler::null(),
                    image_view: view.raw(),
                    image_layout: layout,
                })
            }
            _ => {
                let name = &g.resources[r].name;
                return Err(cx.pass_error(
                    b.p,
                    format!("binding {binding} ({ty:?}) cannot take `{name}`"),
                ));
            }
        };
        planned.push((binding, ty, [descriptor]));
    }
    // The infos are split by kind so each write points at a one-element slice.
    let buffers: Vec<[vk::DescriptorBufferInfo; 1]> = planned
        .iter()
        .map(|(_, _, [d])| match d {
            Descriptor::Buffer(i) => [*i],
            Descriptor::Image(_) => [vk::DescriptorBufferInfo::default()],
        })
        .collect();
    let images: Vec<[vk::DescriptorImageInfo; 1]> = planned
        .iter()
        .map(|(_, _, [d])| match d {
            Descriptor::Image(i) => [*i],
            Descriptor::Buffer(_) => [vk::DescriptorImageInfo::default()],
        })
        .collect();
    let writes: Vec<vk::WriteDescriptorSet<'_>> = planned
        .iter()
        .enumerate()
        .map(|(i, (binding, ty, [d]))| {
            let w = vk::WriteDescriptorSet::default()
                .dst_set(set)
                .dst_binding(*binding)
                .descriptor_type(*ty);
            match d {
                Descriptor::Buffer(_) => w.buffer_info(&buffers[i]),
                Descriptor::Image(_) => w.image_info(&images[i]),
            }
        })
        .collect();
    // SAFETY: every info outlives the call; the set is not in use.
    unsafe { cx.gpu.device.update_descriptor_sets(&writes, &[]) };
    Ok(())
}
