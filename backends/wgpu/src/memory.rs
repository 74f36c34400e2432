//! One buffer or texture per resource (wgpu cannot alias memory).

use super::*;

/// Creates every resource a live pass uses, and every imported or history
/// resource, zeroed.
pub(crate) fn create_memory(
    device: &wgpu::Device,
    plan: &Plan,
    instance: &Instance,
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
                Memory::Buffer(buffer, size.bytes.div_ceil(4) as usize)
            }
            ResourceDecl::Image { format, .. } => {
                let extent = size.extent.unwrap_or([1, 1, 1]);
                let wformat = texture_format(*format);
                let mut usage = usages[r];
                let samples = res.decl.samples();
                if samples > 1 {
                    // Only draws touch a multisampled image (the graph checks it).
                    usage = wgpu::TextureUsages::RENDER_ATTACHMENT;
                }
                if format.is_depth() {
                    // Uploads draw into depth images (crate::depth_upload).
                    usage -= wgpu::TextureUsages::STORAGE_BINDING;
                    usage |= wgpu::TextureUsages::RENDER_ATTACHMENT;
                }
                let texture = device.create_texture(&wgpu::TextureDescriptor {
                    label: Some(&res.name),
                    size: wgpu::Extent3d {
                        width: extent[0].max(1),
                        height: extent[1].max(1),
                        depth_or_array_layers: extent[2].max(1),
                    },
                    mip_level_count: 1,
                    sample_count: samples,
                    dimension: wgpu::TextureDimension::D2,
                    format: wformat,
                    usage,
                    view_formats: &[],
                });
                let texel_bytes = format.texel_bytes() as u32;
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

/// Writes a frame's inputs into the imported resources they name. Inputs for
/// transients are ignored, as on the CPU backend; history resources named by
/// no input keep what the previous frame wrote.
pub(crate) fn upload(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    plan: &Plan,
    instance: &Instance,
    memory: &[Option<Memory>],
    inputs: &Upload,
) -> Result<(), WgpuError> {
    let g = &plan.graph;
    for (name, words) in &inputs.resources {
        let Some(r) = g.resource_id(name) else {
            continue; // packed for another graph
        };
        if g.resources[r].decl.lifetime() == LifetimeClass::Transient {
            continue;
        }
        let input_error = |message: String| WgpuError::Input {
            resource: name.clone(),
            message,
        };
        let bytes = instance.sizes[r].bytes;
        if words.len() as u64 * 4 > bytes {
            return Err(input_error(format!(
                "{} words given, the plan sizes it at {bytes} bytes",
                words.len()
            )));
        }
        match &memory[g.physical(r)] {
            None => {}
            Some(Memory::Buffer(buffer, _)) => {
                queue.write_buffer(buffer, 0, bytemuck::cast_slice(words));
            }
            Some(Memory::Texture {
                texture,
                format: wgpu::TextureFormat::Depth32Float,
                extent,
                ..
            }) => {
                if extent[2] > 1 {
                    return Err(input_error(
                        "depth images with more than one layer cannot be uploaded".into(),
                    ));
                }
                let mut texels = words.clone();
                texels.resize((extent[0] * extent[1]) as usize, 0);
                crate::depth_upload::upload_depth(device, queue, texture, extent[0], &texels);
            }
            Some(Memory::Texture {
                texture,
                extent,
                texel_bytes,
                ..
            }) => {
                let row = extent[0] * texel_bytes;
                let rows = extent[1] * extent[2].max(1);
                let mut full: Vec<u8> = bytemuck::cast_slice(words).to_vec();
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
        }
    }
    Ok(())
}
