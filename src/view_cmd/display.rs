//! Shows a graph's main image in egui: copies it out of the session (so the
//! graph's resources keep only the usages its passes declare), then one
//! full-screen triangle (`display.wgsl`) tone-maps it into an
//! `Rgba8Unorm` texture of display-encoded values registered with egui's
//! renderer (egui samples textures as gamma-encoded).

use strandgraph::images::Display;
use strandgraph::tonemap::Tonemap;
use strandgraph_graph::schema::ImageFormat;
use strandgraph_wgpu::Gpu;
use wgpu::util::DeviceExt;

const SHADER: &str = include_str!("display.wgsl");
const TARGET_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;

/// The display texture of one slot and what writes it.
pub struct DisplayTarget {
    pub size: (u32, u32),
    /// The graph's output, copied.
    copy: wgpu::Texture,
    format: ImageFormat,
    target: wgpu::TextureView,
    uniform: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
    pipeline: wgpu::RenderPipeline,
    pub texture: egui::TextureId,
}

impl DisplayTarget {
    pub fn new(
        gpu: &Gpu,
        renderer: &mut egui_wgpu::Renderer,
        size: (u32, u32),
        format: ImageFormat,
    ) -> DisplayTarget {
        let device = &gpu.device;
        let texture = |label, format, usage| {
            device.create_texture(&wgpu::TextureDescriptor {
                label: Some(label),
                size: wgpu::Extent3d {
                    width: size.0,
                    height: size.1,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage,
                view_formats: &[],
            })
        };
        let copy_format = match format {
            ImageFormat::Rgba8Unorm => wgpu::TextureFormat::Rgba8Unorm,
            _ => wgpu::TextureFormat::Rgba16Float,
        };
        let copy = texture(
            "viewer: graph output",
            copy_format,
            wgpu::TextureUsages::COPY_DST | wgpu::TextureUsages::TEXTURE_BINDING,
        );
        let target = texture(
            "viewer: display",
            TARGET_FORMAT,
            wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
        )
        .create_view(&Default::default());
        let uniform = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("viewer: display transform"),
            contents: &[0u8; 16],
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        });
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("display.wgsl"),
            source: wgpu::ShaderSource::Wgsl(SHADER.into()),
        });
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("viewer: display transform"),
            layout: None,
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs_main"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("fs_main"),
                compilation_options: Default::default(),
                targets: &[Some(TARGET_FORMAT.into())],
            }),
            primitive: Default::default(),
            depth_stencil: None,
            multisample: Default::default(),
            multiview_mask: None,
            cache: None,
        });
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("viewer: display transform"),
            layout: &pipeline.get_bind_group_layout(0),
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: uniform.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::TextureView(
                        &copy.create_view(&Default::default()),
                    ),
                },
            ],
        });
        let texture = renderer.register_native_texture(device, &target, wgpu::FilterMode::Linear);
        DisplayTarget {
            size,
            copy,
            format,
            target,
            uniform,
            bind_group,
            pipeline,
            texture,
        }
    }

    /// Copies `image` (the graph's output) and tone-maps it with `look`.
    pub fn draw(&self, gpu: &Gpu, image: &wgpu::Texture, look: Display) {
        let mode = match (self.format, look.tonemap) {
            (ImageFormat::Rgba8Unorm, _) => 3u32,
            (_, Tonemap::Aces) => 0,
            (_, Tonemap::Agx) => 1,
            (_, Tonemap::None) => 2,
        };
        let mut block = [0u8; 16];
        block[..4].copy_from_slice(&mode.to_le_bytes());
        block[4..8].copy_from_slice(&look.exposure.to_le_bytes());
        gpu.queue.write_buffer(&self.uniform, 0, &block);
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        encoder.copy_texture_to_texture(
            image.as_image_copy(),
            self.copy.as_image_copy(),
            self.copy.size(),
        );
        {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("viewer: display transform"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &self.target,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                ..Default::default()
            });
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, &self.bind_group, &[]);
            pass.draw(0..3, 0..1);
        }
        gpu.queue.submit([encoder.finish()]);
    }
}
