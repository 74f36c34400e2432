//! The frame's upload prologue, on the graphics queue: after every lane's
//! previous frame, it zero-fills imported and history resources on the
//! first frame (wgpu and the CPU backend start from zeros), copies the
//! frame's inputs from the staging buffer, and puts imported images in the
//! layout their first pass expects (`SyncPlan::first_layout`).

use crate::barriers::Scope;
use crate::error::{AshError, VkContext};
use crate::memory::{Res, full_range};
use crate::session::Session;
use crate::submit::image_barrier;
use ash::vk;
use strandgraph_graph::LifetimeClass;
use strandgraph_passes::upload::Upload;

/// Every earlier command (the semaphore waits use ALL_COMMANDS).
const WAIT_ALL: Scope = Scope {
    stages: vk::PipelineStageFlags2::ALL_COMMANDS,
    access: vk::AccessFlags2::NONE,
};

/// The prologue's clears and copies.
const COPY_WRITE: Scope = Scope {
    stages: vk::PipelineStageFlags2::from_raw(
        vk::PipelineStageFlags2::COPY.as_raw() | vk::PipelineStageFlags2::CLEAR.as_raw(),
    ),
    access: vk::AccessFlags2::TRANSFER_WRITE,
};

/// Whatever the frame does next.
const EVERYTHING: Scope = Scope {
    stages: vk::PipelineStageFlags2::ALL_COMMANDS,
    access: vk::AccessFlags2::from_raw(
        vk::AccessFlags2::MEMORY_READ.as_raw() | vk::AccessFlags2::MEMORY_WRITE.as_raw(),
    ),
};

/// An imported or history buffer: its staging offset and the bytes to
/// upload this frame, if any.
struct BufferUpload {
    buffer: vk::Buffer,
    size: u64,
    at: u64,
    upload: Option<u64>,
}

/// An imported or history image, its layout from the last frame, and the
/// bytes to upload this frame, if any.
struct ImageUpload {
    r: usize,
    image: vk::Image,
    range: vk::ImageSubresourceRange,
    extent: [u32; 3],
    aspect: vk::ImageAspectFlags,
    texel_bytes: u32,
    at: u64,
    upload: Option<u64>,
    old: vk::ImageLayout,
}

/// One `vkCmdPipelineBarrier2`, none when there is nothing to wait for.
fn barrier(
    d: &ash::Device,
    cmd: vk::CommandBuffer,
    images: &[vk::ImageMemoryBarrier2<'_>],
    global: &[vk::MemoryBarrier2<'_>],
) {
    if images.is_empty() && global.is_empty() {
        return;
    }
    let info = vk::DependencyInfo::default()
        .image_memory_barriers(images)
        .memory_barriers(global);
    // SAFETY: recording.
    unsafe { d.cmd_pipeline_barrier2(cmd, &info) };
}

impl Session {
    /// Records the frame's upload prologue into a fresh command buffer.
    pub(crate) fn record_prologue(
        &mut self,
        inputs: &Upload,
    ) -> Result<vk::CommandBuffer, AshError> {
        let d = &self.gpu.device;
        let first_frame = self.frames == 0;
        // SAFETY: the previous frame (and its prologue) completed: nothing
        // from this pool is pending.
        unsafe { d.reset_command_pool(self.util_pool.raw(), vk::CommandPoolResetFlags::empty()) }
            .ctx("vkResetCommandPool")?;
        let info = vk::CommandBufferAllocateInfo::default()
            .command_pool(self.util_pool.raw())
            .level(vk::CommandBufferLevel::PRIMARY)
            .command_buffer_count(1);
        // SAFETY: valid pool; the buffer is freed with the pool's next reset.
        let cmd = unsafe { d.allocate_command_buffers(&info) }.ctx("vkAllocateCommandBuffers")?[0];
        let begin = vk::CommandBufferBeginInfo::default()
            .flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT);
        // SAFETY: fresh command buffer.
        unsafe { d.begin_command_buffer(cmd, &begin) }.ctx("vkBeginCommandBuffer")?;
        let (buffers, images) = self.uploads(inputs);
        let to_dst: Vec<vk::ImageMemoryBarrier2<'_>> = images
            .iter()
            .filter(|i| first_frame || i.upload.is_some())
            .map(|i| {
                let old = if first_frame {
                    vk::ImageLayout::UNDEFINED
                } else {
                    i.old
                };
                let dst = vk::ImageLayout::TRANSFER_DST_OPTIMAL;
                image_barrier(i.image, i.range, old, dst, WAIT_ALL, COPY_WRITE)
            })
            .collect();
        // Everything the previous frame did is done (semaphore waits with
        // ALL_COMMANDS); the copies follow that.
        let start = [vk::MemoryBarrier2::default()
            .src_stage_mask(WAIT_ALL.stages)
            .dst_stage_mask(COPY_WRITE.stages)
            .dst_access_mask(COPY_WRITE.access)];
        barrier(d, cmd, &to_dst, &start);
        if first_frame {
            zero_fill(d, cmd, &buffers, &images);
        }
        for b in &buffers {
            if let Some(bytes) = b.upload.filter(|&b| b > 0) {
                let region = vk::BufferCopy {
                    src_offset: b.at,
                    dst_offset: 0,
                    size: bytes,
                };
                // SAFETY: recording; in bounds (checked in `run`).
                unsafe { d.cmd_copy_buffer(cmd, self.staging.buffer(), b.buffer, &[region]) };
            }
        }
        let to_first: Vec<_> = images
            .iter()
            .filter_map(|i| self.upload_image(cmd, i, first_frame))
            .collect();
        barrier(d, cmd, &to_first, &[]);
        // SAFETY: recording.
        unsafe { d.end_command_buffer(cmd) }.ctx("vkEndCommandBuffer")?;
        Ok(cmd)
    }

    /// The imported and history resources and what to upload into each:
    /// inputs given this frame, history ones only on the first frame.
    fn uploads(&self, inputs: &Upload) -> (Vec<BufferUpload>, Vec<ImageUpload>) {
        let g = &self.plan.graph;
        let first_frame = self.frames == 0;
        let mut buffers = Vec::new();
        let mut images = Vec::new();
        for (&r, &at) in &self.staging_at {
            let res = &g.resources[r];
            let given = inputs.resources.get(&res.name).map(|w| w.len() as u64 * 4);
            let history = res.decl.lifetime() == LifetimeClass::History;
            let upload = given.filter(|_| first_frame || !history);
            match &self.memory.res[r] {
                Some(Res::Buffer { buffer, size, .. }) => buffers.push(BufferUpload {
                    buffer: buffer.raw(),
                    size: *size,
                    at,
                    upload,
                }),
                Some(
                    res @ Res::Image {
                        image,
                        extent,
                        texel_bytes,
                        ..
                    },
                ) => images.push(ImageUpload {
                    r,
                    image: image.raw(),
                    range: full_range(res.aspect(), extent[2]),
                    extent: *extent,
                    aspect: res.aspect(),
                    texel_bytes: *texel_bytes,
                    at,
                    upload,
                    old: self
                        .layouts
                        .get(&r)
                        .copied()
                        .unwrap_or(vk::ImageLayout::UNDEFINED),
                }),
                None => {}
            }
        }
        (buffers, images)
    }

    /// Copies an image's given rows (CPU layout: rows of texels, layers
    /// after each other); the barrier into its first layout, if it needs one.
    fn upload_image(
        &self,
        cmd: vk::CommandBuffer,
        i: &ImageUpload,
        first_frame: bool,
    ) -> Option<vk::ImageMemoryBarrier2<'static>> {
        let first = self
            .sync
            .first_layout
            .get(&i.r)
            .copied()
            .unwrap_or(vk::ImageLayout::GENERAL);
        if let Some(bytes) = i.upload.filter(|&b| b > 0) {
            let region = upload_region(i, bytes);
            // SAFETY: recording; the image is in TRANSFER_DST_OPTIMAL.
            unsafe {
                self.gpu.device.cmd_copy_buffer_to_image(
                    cmd,
                    self.staging.buffer(),
                    i.image,
                    vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                    &[region],
                )
            };
        }
        let from = if first_frame || i.upload.is_some() {
            vk::ImageLayout::TRANSFER_DST_OPTIMAL
        } else {
            i.old
        };
        (from != first || from == vk::ImageLayout::TRANSFER_DST_OPTIMAL).then(|| {
            image_barrier(
                i.image,
                i.range,
                from,
                first,
                COPY_WRITE.or(WAIT_ALL),
                EVERYTHING,
            )
        })
    }
}

/// The copy of `bytes` given bytes of an image: whole rows, whole layers
/// when more than one.
fn upload_region(i: &ImageUpload, bytes: u64) -> vk::BufferImageCopy {
    let extent = i.extent;
    let row = u64::from(extent[0]) * u64::from(i.texel_bytes);
    let rows = (bytes.div_ceil(row.max(1))).min(u64::from(extent[1]) * u64::from(extent[2])) as u32;
    let layers = (rows / extent[1].max(1)).max(u32::from(rows > 0));
    let height = if layers > 1 {
        extent[1]
    } else {
        rows.min(extent[1])
    };
    vk::BufferImageCopy {
        buffer_offset: i.at,
        buffer_row_length: 0,
        buffer_image_height: 0,
        image_subresource: vk::ImageSubresourceLayers {
            aspect_mask: i.aspect,
            mip_level: 0,
            base_array_layer: 0,
            layer_count: layers.min(extent[2]),
        },
        image_offset: vk::Offset3D::default(),
        image_extent: vk::Extent3D {
            width: extent[0],
            height,
            depth: 1,
        },
    }
}

/// First frame: zeros in every imported and history resource, then a
/// barrier so the uploads land after the clears.
fn zero_fill(
    d: &ash::Device,
    cmd: vk::CommandBuffer,
    buffers: &[BufferUpload],
    images: &[ImageUpload],
) {
    for b in buffers {
        // SAFETY: recording; size is a multiple of 4.
        unsafe { d.cmd_fill_buffer(cmd, b.buffer, 0, b.size, 0) };
    }
    let dst = vk::ImageLayout::TRANSFER_DST_OPTIMAL;
    for i in images {
        // SAFETY: recording; the image is in TRANSFER_DST_OPTIMAL.
        unsafe {
            if i.aspect == vk::ImageAspectFlags::DEPTH {
                let zero = vk::ClearDepthStencilValue {
                    depth: 0.0,
                    stencil: 0,
                };
                d.cmd_clear_depth_stencil_image(cmd, i.image, dst, &zero, &[i.range]);
            } else {
                let zero = vk::ClearColorValue { uint32: [0; 4] };
                d.cmd_clear_color_image(cmd, i.image, dst, &zero, &[i.range]);
            }
        }
    }
    let after_clear = [vk::MemoryBarrier2::default()
        .src_stage_mask(COPY_WRITE.stages)
        .src_access_mask(COPY_WRITE.access)
        .dst_stage_mask(COPY_WRITE.stages)
        .dst_access_mask(COPY_WRITE.access)];
    barrier(d, cmd, &[], &after_clear);
}
