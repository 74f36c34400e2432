//! Reading resources back to the CPU.

use super::*;

/// How long a readback waits for the GPU (the frame before it included):
/// a shader that never ends becomes an error, not a hang (ash's default).
pub(crate) const GPU_TIMEOUT: std::time::Duration = std::time::Duration::from_secs(60);

/// Copies `bytes` of `buffer` into a mappable buffer and reads it.
pub(crate) fn read_buffer(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    buffer: &wgpu::Buffer,
    bytes: u64,
) -> Result<Vec<u8>, WgpuError> {
    let size = bytes.max(4).next_multiple_of(4);
    let staging = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("readback"),
        size,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut encoder = device.create_command_encoder(&Default::default());
    encoder.copy_buffer_to_buffer(buffer, 0, &staging, 0, size.min(buffer.size()));
    queue.submit([encoder.finish()]);
    map_and_read(device, &staging)
}

pub(crate) fn map_and_read(
    device: &wgpu::Device,
    staging: &wgpu::Buffer,
) -> Result<Vec<u8>, WgpuError> {
    let mapped: Arc<Mutex<Option<Result<(), wgpu::BufferAsyncError>>>> = Arc::default();
    {
        let mapped = mapped.clone();
        staging.slice(..).map_async(wgpu::MapMode::Read, move |r| {
            *mapped.lock().unwrap_or_else(|e| e.into_inner()) = Some(r);
        });
    }
    let wait = wgpu::PollType::Wait {
        submission_index: None,
        timeout: Some(GPU_TIMEOUT),
    };
    match device.poll(wait) {
        Ok(_) => {}
        Err(wgpu::PollError::Timeout) => {
            return Err(WgpuError::Timeout {
                millis: GPU_TIMEOUT.as_millis(),
            });
        }
        Err(e) => return Err(WgpuError::Validation(format!("poll: {e}"))),
    }
    match mapped.lock().unwrap_or_else(|e| e.into_inner()).take() {
        Some(Ok(())) => {}
        Some(Err(e)) => return Err(WgpuError::Validation(format!("map: {e}"))),
        None => return Err(WgpuError::Validation("map did not complete".into())),
    }
    let data = staging
        .slice(..)
        .get_mapped_range()
        .map_err(|e| WgpuError::Validation(format!("map: {e:?}")))?
        .to_vec();
    staging.unmap();
    Ok(data)
}

impl Session {
    /// A copy of resource `name`'s words, laid out as the CPU backend lays
    /// them out (images: rows of texels, no padding). `None` when the
    /// resource does not exist or has no memory (used by no live pass).
    pub fn read(&self, plan: &Plan, name: &str) -> Result<Option<Vec<u32>>, WgpuError> {
        let Some(r) = plan.graph.resource_id(name) else {
            return Ok(None);
        };
        let r = plan.graph.physical(r);
        let bytes = match &self.memory[r] {
            None => return Ok(None),
            Some(Memory::Buffer(b, _)) => {
                read_buffer(&self.gpu.device, &self.gpu.queue, b, b.size())?
            }
            Some(Memory::Texture {
                texture,
                format,
                extent,
                texel_bytes,
            }) => {
                let row = extent[0] * texel_bytes;
                // wgpu copies rows at 256-byte strides (COPY_BYTES_PER_ROW_ALIGNMENT).
                let stride = row.next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT);
                let layers = extent[2].max(1);
                let staging = self.gpu.device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("readback"),
                    size: u64::from(stride) * u64::from(extent[1] * layers),
                    usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                });
                let mut encoder = self.gpu.device.create_command_encoder(&Default::default());
                encoder.copy_texture_to_buffer(
                    wgpu::TexelCopyTextureInfo {
                        texture,
                        mip_level: 0,
                        origin: wgpu::Origin3d::ZERO,
                        aspect: if format.is_depth_stencil_format() {
                            wgpu::TextureAspect::DepthOnly
                        } else {
                            wgpu::TextureAspect::All
                        },
                    },
                    wgpu::TexelCopyBufferInfo {
                        buffer: &staging,
                        layout: wgpu::TexelCopyBufferLayout {
                            offset: 0,
                            bytes_per_row: Some(stride),
                            rows_per_image: Some(extent[1]),
                        },
                    },
                    texture.size(),
                );
                self.gpu.queue.submit([encoder.finish()]);
                let padded = map_and_read(&self.gpu.device, &staging)?;
                padded
                    .chunks(stride as usize)
                    .flat_map(|r| &r[..row as usize])
                    .copied()
                    .collect()
            }
        };
        let mut words: Vec<u32> = bytes
            .chunks(4)
            .map(|c| {
                let mut w = [0u8; 4];
                w[..c.len()].copy_from_slice(c);
                u32::from_le_bytes(w)
            })
            .collect();
        if let Some(Memory::Buffer(_, len)) = &self.memory[r] {
            words.truncate(*len);
        }
        Ok(Some(words))
    }
}
