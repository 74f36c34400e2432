//! One buffer or texture per resource (wgpu cannot alias memory).

use super::*;

pub(crate) fn create_memory(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    plan: &Plan,
    instance: &Instance,
    inputs: &Upload,
    prepared: &[Prepared<'_>],
) -> Result<Vec<Option<Memory>>, WgpuError> {
    let g = &plan.graph;
    // Texture usages from how live passes access each image.
    let mut usages: Vec<wgpu::TextureUsages> =
        vec![wgpu::TextureUsages::COPY_SRC | wgpu::TextureUsages::COPY_DST; g.resources.len()];
    let mut used = vec![false; g.resources.len()];
    for prep in prepared {
        for a in &g.passes[prep.p].accesses {
            let r = g.physical(a.resource);
            used[r] = true;
            usages[r] |= match a.usage {
                Usage::Sampled => wgpu::TextureUsages::TEXTURE_BINDING,
                Usage::Color | Usage::Depth => wgpu::TextureUsages::RENDER_ATTACHMENT,
                _ => wgpu::TextureUsages::STORAGE_BINDING,
            };
        }
    }
    let mut memory = Vec::with_capacity(g.resources.len());
    for (r, res) in g.resources.iter().enumerate() {
        let imported = res.decl.lifetime() != LifetimeClass::Transient;
        if res.version_of.is_some() || !(used[r] || imported) {
            memory.push(None);
            continue;
        }
        let size = instance.sizes[r];
        let init = inputs.resources.get(&res.name);
        if let Some(w) = init
            && w.len() as u64 * 4 > size.bytes
        {
            return Err(WgpuError::Input {
                resource: res.name.clone(),
                message: format!(
                    "{} words given, the plan sizes it at {} bytes",
                    w.len(),
                    size.bytes
                ),
            });
        }
        let made = match &res.decl {
            ResourceDecl::Buffer { .. } => {
                let buffer = device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some(&res.name),
                    size: size.bytes.max(4).next_multiple_of(4),
                    usage: wgpu::BufferUsages::STORAGE
                        | wgpu::BufferUsages::INDIRECT
                        | wgpu::BufferUsages::COPY_SRC
                        | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                });
                if let Some(w) = init {
                    queue.write_buffer(&buffer, 0, bytemuck::cast_slice(w));
                }
                Memory::Buffer(buffer, size.bytes.div_ceil(4) as usize)
            }
            ResourceDecl::Image { format, .. } => {
                let extent = size.extent.unwrap_or([1, 1, 1]);
                let wformat = texture_format(*format);
                let mut usage = usages[r];
                if format.is_depth() {
                    usage -= wgpu::TextureUsages::STORAGE_BINDING;
                }
                let texture = device.create_texture(&wgpu::TextureDescriptor {
                    label: Some(&res.name),
                    size: wgpu::Extent3d {
                        width: extent[0].max(1),
                        height: extent[1].max(1),
                        depth_or_array_layers: extent[2].max(1),
                    },
                    mip_level_count: 1,
                    sample_count: 1,
                    dimension: wgpu::TextureDimension::D2,
                    format: wformat,
                    usage,
                    view_formats: &[],
                });
                let texel_bytes = format.texel_bytes() as u32;
                if let Some(w) = init {
                    let bytes: &[u8] = bytemuck::cast_slice(w);
                    let row = extent[0] * texel_bytes;
                    let rows = extent[1] * extent[2].max(1);
                    let mut full = bytes.to_vec();
                    full.resize((row * rows) as usize, 0);
                    queue.write_texture(
                        texture.as_image_copy(),
                        &full,
                        wgpu::TexelCopyBufferLayout {
                            offset: 0,
                            bytes_per_row: Some(row),
                            rows_per_image: Some(extent[1]),
                        },
                        texture.size(),
                    );
                }
                Memory::Texture {
                    texture,
                    format: wformat,
                    extent,
                    texel_bytes,
                }
            }
        };
        memory.push(Some(made));
    }
    Ok(memory)
}
