//! Uploading depth images. WebGPU forbids buffer-to-texture copies into
//! `Depth32Float`, so an imported depth image's words are drawn into it: a
//! full-screen triangle whose fragment shader writes each pixel's depth
//! from a storage buffer (`@builtin(frag_depth)`, compare always). The same
//! words reach the image bit for bit: depth writes of in-range floats are
//! not converted.

use wgpu::util::DeviceExt;

const SHADER: &str = r"
@group(0) @binding(0) var<storage, read> words: array<u32>;

@vertex
fn vs(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let uv = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4<f32>(uv * 2.0 - 1.0, 0.0, 1.0);
}

// words[0] is the image's width; texels follow row by row.
@fragment
fn fs(@builtin(position) p: vec4<f32>) -> @builtin(frag_depth) f32 {
    let i = u32(p.y) * words[0] + u32(p.x);
    return bitcast<f32>(words[1u + i]);
}
";

/// Draws `words` (one f32 per texel, rows of `width`) into layer 0 of
/// `texture`, whose format is `Depth32Float`.
pub(crate) fn upload_depth(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    texture: &wgpu::Texture,
    width: u32,
    words: &[u32],
) {
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("depth upload"),
        source: wgpu::ShaderSource::Wgsl(SHADER.into()),
    });
    let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some("depth upload"),
        layout: None,
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some("vs"),
            compilation_options: Default::default(),
            buffers: &[],
        },
        fragment: Some(wgpu::FragmentState {
            module: &module,
            entry_point: Some("fs"),
            compilation_options: Default::default(),
            targets: &[],
        }),
        primitive: wgpu::PrimitiveState::default(),
        depth_stencil: Some(wgpu::DepthStencilState {
            format: wgpu::TextureFormat::Depth32Float,
            depth_write_enabled: Some(true),
            depth_compare: Some(wgpu::CompareFunction::Always),
            stencil: Default::default(),
            bias: Default::default(),
        }),
        multisample: Default::default(),
        multiview_mask: None,
        cache: None,
    });
    let mut contents = Vec::with_capacity(words.len() + 1);
    contents.push(width);
    contents.extend_from_slice(words);
    let buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("depth upload"),
        contents: bytemuck::cast_slice(&contents),
        usage: wgpu::BufferUsages::STORAGE,
    });
    let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("depth upload"),
        layout: &pipeline.get_bind_group_layout(0),
        entries: &[wgpu::BindGroupEntry {
            binding: 0,
            resource: buffer.as_entire_binding(),
        }],
    });
    let view = texture.create_view(&wgpu::TextureViewDescriptor {
        base_array_layer: 0,
        array_layer_count: Some(1),
        dimension: Some(wgpu::TextureViewDimension::D2),
        ..Default::default()
    });
    let mut encoder = device.create_command_encoder(&Default::default());
    {
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("depth upload"),
            color_attachments: &[],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &view,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(0.0),
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: None,
            }),
            ..Default::default()
        });
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &bind_group, &[]);
        pass.draw(0..3, 0..1);
    }
    queue.submit([encoder.finish()]);
}
