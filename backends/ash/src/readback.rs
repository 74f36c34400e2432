//! Reading resources back: a copy on the graphics queue into a host-visible
//! buffer, after every lane's last frame (semaphore waits), fenced with a
//! timeout.

use crate::barriers::Scope;
use crate::error::{AshError, VkContext};
use crate::host::HostBuffer;
use crate::memory::{Res, full_range};
use crate::session::Session;
use crate::submit::image_barrier;
use ash::vk;

impl Session {
    /// A copy of resource `name`'s words, laid out as the CPU backend lays
    /// them out (images: rows of texels, layers after each other). `None`
    /// when there is no such resource or it has no memory (used by no live
    /// pass). With aliasing,
    /// a transient holds whatever last used its bytes.
    pub fn read(&self, name: &str) -> Result<Option<Vec<u32>>, AshError> {
        let g = &self.plan.graph;
        let Some(r) = g.resource_id(name) else {
            return Ok(None);
        };
        let r = g.physical(r);
        if self.memory.res[r].is_none() {
            return Ok(None);
        }
        self.read_words(r).map(Some)
    }

    pub(crate) fn read_words(&self, r: usize) -> Result<Vec<u32>, AshError> {
        let (bytes, words) = match &self.memory.res[r] {
            Some(Res::Buffer { size, words, .. }) => (*size, *words),
            Some(Res::Image {
                extent,
                texel_bytes,
                ..
            }) => {
                let b = u64::from(extent[0])
                    * u64::from(extent[1])
                    * u64::from(extent[2])
                    * u64::from(*texel_bytes);
                (b, b.div_ceil(4) as usize)
            }
            None => return Ok(Vec::new()),
        };
        let host = HostBuffer::new(
            &self.gpu,
            bytes,
            vk::BufferUsageFlags::TRANSFER_DST,
            "readback",
        )?;
        self.copy_into(r, &host, bytes)?;
        let raw = host.read(bytes as usize);
        let mut w: Vec<u32> = raw
            .chunks(4)
            .map(|c| {
                let mut x = [0u8; 4];
                x[..c.len()].copy_from_slice(c);
                u32::from_le_bytes(x)
            })
            .collect();
        w.truncate(words);
        Ok(w)
    }

    /// Copies resource `r` into `host` on the graphics queue and waits.
    fn copy_into(&self, r: usize, host: &HostBuffer, bytes: u64) -> Result<(), AshError> {
        let d = &self.gpu.device;
        let info = vk::CommandBufferAllocateInfo::default()
            .command_pool(self.util_pool.raw())
            .level(vk::CommandBufferLevel::PRIMARY)
            .command_buffer_count(1);
        // SAFETY: valid pool, used only from this thread.
        let cmd = unsafe { d.allocate_command_buffers(&info) }.ctx("vkAllocateCommandBuffers")?[0];
        let mut cmd = OneShot {
            d,
            pool: self.util_pool.raw(),
            cmd,
            pending: false,
        };
        let begin = vk::CommandBufferBeginInfo::default()
            .flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT);
        // SAFETY: fresh command buffer.
        unsafe { d.begin_command_buffer(cmd.cmd, &begin) }.ctx("vkBeginCommandBuffer")?;
        match &self.memory.res[r] {
            Some(Res::Buffer { buffer, .. }) => {
                let region = vk::BufferCopy {
                    src_offset: 0,
                    dst_offset: 0,
                    size: bytes,
                };
                // SAFETY: recording; handles live.
                unsafe { d.cmd_copy_buffer(cmd.cmd, buffer.raw(), host.buffer(), &[region]) };
            }
            Some(res @ Res::Image { .. }) => self.record_image_copy(cmd.cmd, r, res, host),
            None => {}
        }
        // The host reads what the copy wrote.
        let host_read = [vk::MemoryBarrier2::default()
            .src_stage_mask(vk::PipelineStageFlags2::COPY)
            .src_access_mask(vk::AccessFlags2::TRANSFER_WRITE)
            .dst_stage_mask(vk::PipelineStageFlags2::HOST)
            .dst_access_mask(vk::AccessFlags2::HOST_READ)];
        // SAFETY: recording.
        unsafe {
            let info = vk::DependencyInfo::default().memory_barriers(&host_read);
            d.cmd_pipeline_barrier2(cmd.cmd, &info);
            d.end_command_buffer(cmd.cmd).ctx("vkEndCommandBuffer")?;
        }
        let waited = self.submit_and_wait(cmd.cmd);
        // Still pending after a timeout: leave it to the pool (reset after
        // the next frame's wait).
        cmd.pending = matches!(waited, Err(AshError::Timeout { .. }));
        waited?;
        drop(cmd);
        self.gpu.check("a readback")
    }

    /// Records the copy of image `r` (in its layout between frames) into
    /// `host`, and its way back to that layout.
    fn record_image_copy(&self, cmd: vk::CommandBuffer, r: usize, res: &Res, host: &HostBuffer) {
        let Res::Image { image, extent, .. } = res else {
            return;
        };
        let d = &self.gpu.device;
        let after_waits = Scope {
            stages: vk::PipelineStageFlags2::ALL_COMMANDS,
            access: vk::AccessFlags2::NONE,
        };
        let copy_read = Scope {
            stages: vk::PipelineStageFlags2::COPY,
            access: vk::AccessFlags2::TRANSFER_READ,
        };
        let layout = self
            .layouts
            .get(&r)
            .copied()
            .unwrap_or(vk::ImageLayout::UNDEFINED);
        let range = full_range(res.aspect(), extent[2]);
        let src = vk::ImageLayout::TRANSFER_SRC_OPTIMAL;
        let to_src = [image_barrier(
            image.raw(),
            range,
            layout,
            src,
            after_waits,
            copy_read,
        )];
        let region = vk::BufferImageCopy {
            buffer_offset: 0,
            buffer_row_length: 0,
            buffer_image_height: 0,
            image_subresource: vk::ImageSubresourceLayers {
                aspect_mask: res.aspect(),
                mip_level: 0,
                base_array_layer: 0,
                layer_count: extent[2].max(1),
            },
            image_offset: vk::Offset3D::default(),
            image_extent: vk::Extent3D {
                width: extent[0],
                height: extent[1],
                depth: 1,
            },
        };
        // Back to the layout the next frame's prologue expects.
        let back = if layout == vk::ImageLayout::UNDEFINED {
            vk::ImageLayout::GENERAL
        } else {
            layout
        };
        let to_back = [image_barrier(
            image.raw(),
            range,
            src,
            back,
            copy_read,
            after_waits,
        )];
        // SAFETY: recording; handles live.
        unsafe {
            let info = vk::DependencyInfo::default().image_memory_barriers(&to_src);
            d.cmd_pipeline_barrier2(cmd, &info);
            d.cmd_copy_image_to_buffer(cmd, image.raw(), src, host.buffer(), &[region]);
            let info = vk::DependencyInfo::default().image_memory_barriers(&to_back);
            d.cmd_pipeline_barrier2(cmd, &info);
        }
    }

    /// Submits `cmd` after every lane's last frame and the last upload, and
    /// waits for it on the host with the session's timeout.
    fn submit_and_wait(&self, cmd: vk::CommandBuffer) -> Result<(), AshError> {
        let d = &self.gpu.device;
        let mut waits = self.after_last_frame();
        if self.frames > 0 {
            waits.push(Self::at(self.upload_semaphore.raw(), self.frames));
        }
        let cmds = [vk::CommandBufferSubmitInfo::default().command_buffer(cmd)];
        let submit = vk::SubmitInfo2::default()
            .wait_semaphore_infos(&waits)
            .command_buffer_infos(&cmds);
        let fence = self.fence.raw();
        // SAFETY: recorded; the fence is unsignalled after the reset.
        unsafe {
            d.reset_fences(&[fence]).ctx("vkResetFences")?;
            d.queue_submit2(self.gpu.queues[0].queue, &[submit], fence)
                .ctx("vkQueueSubmit2 (readback)")?;
        }
        let timeout = u64::try_from(self.timeout.as_nanos()).unwrap_or(u64::MAX);
        // SAFETY: live fence.
        match unsafe { d.wait_for_fences(&[fence], true, timeout) } {
            Ok(()) => Ok(()),
            Err(vk::Result::TIMEOUT) => Err(AshError::Timeout {
                what: "waiting for a readback".into(),
                millis: self.timeout.as_millis(),
            }),
            Err(e) => Err(AshError::vk("waiting for a readback", e)),
        }
    }
}

/// A command buffer of the utility pool, freed when dropped unless the GPU
/// may still run it (then the pool's next reset frees it).
struct OneShot<'a> {
    d: &'a ash::Device,
    pool: vk::CommandPool,
    cmd: vk::CommandBuffer,
    pending: bool,
}

impl Drop for OneShot<'_> {
    fn drop(&mut self) {
        if !self.pending {
            // SAFETY: completed, or never submitted.
            unsafe { self.d.free_command_buffers(self.pool, &[self.cmd]) };
        }
    }
}
