//! Offscreen rendering with wgpu: triangle meshes with per-vertex colours, depth-tested, both
//! sides lit, supersampled 2×2 and box-filtered down, read back as RGBA8 (sRGB) pixels.

use super::camera::Camera;
use crate::error::Error;
use crate::gpu::GpuContext;
use bytemuck::{Pod, Zeroable};
use glam::{Mat4, Vec2, Vec3};
use wgpu::util::DeviceExt;

/// One mesh to draw: positions, smooth normals and linear RGB colours per vertex.
#[derive(Clone, Debug, Default)]
pub struct DrawMesh {
    /// Positions in m.
    pub positions: Vec<Vec3>,
    /// Linear RGB per vertex.
    pub colors: Vec<Vec3>,
    /// Triangles.
    pub triangles: Vec<[u32; 3]>,
    /// Pattern coordinates in m per vertex for the checker, or empty.
    pub uv: Vec<Vec2>,
    /// The checker's square size in m (0: no checker).
    pub checker: f32,
}

impl DrawMesh {
    /// Area-weighted vertex normals (unnormalised sums of the triangles' cross products).
    pub fn normals(&self) -> Vec<Vec3> {
        crate::mesh::vertex_normals(&self.positions, &self.triangles)
    }
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct Vertex {
    pos: [f32; 3],
    normal: [f32; 3],
    color: [f32; 3],
    /// Pattern u, v in m and the checker's square size (0: none).
    uv: [f32; 3],
}

/// Supersampling factor per axis.
const SS: u32 = 2;

/// Renders `meshes` seen by `camera` into a `width × height` RGBA8 sRGB image (row-major, top
/// row first) on a light grey background.
pub fn render(
    ctx: &GpuContext,
    meshes: &[DrawMesh],
    camera: &Camera,
    width: u32,
    height: u32,
) -> Result<Vec<u8>, Error> {
    let device = &ctx.device;
    let (w, h) = (width * SS, height * SS);
    let limit = device.limits().max_texture_dimension_2d;
    if w > limit || h > limit {
        return Err(Error::Gpu(format!(
            "a {width}×{height} preview needs {w}×{h} texels with supersampling; this adapter \
             allows {limit}: ask for at most {}×{}",
            limit / SS,
            limit / SS
        )));
    }
    let mut vertices = Vec::new();
    let mut indices = Vec::new();
    for m in meshes {
        let base = vertices.len() as u32;
        let textured = m.checker > 0.0 && m.uv.len() == m.positions.len();
        for (k, ((p, n), c)) in (m.positions.iter().zip(m.normals()).zip(&m.colors)).enumerate() {
            let uv = if textured {
                [m.uv[k].x, m.uv[k].y, m.checker]
            } else {
                [0.0; 3]
            };
            vertices.push(Vertex {
                pos: p.to_array(),
                normal: n.to_array(),
                color: c.to_array(),
                uv,
            });
        }
        indices.extend(m.triangles.iter().flat_map(|t| t.map(|i| i + base)));
    }
    let view_proj: Mat4 = camera.view_proj(width as f32 / height as f32);
    let uniform = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("preview view"),
        contents: bytemuck::bytes_of(&view_proj.to_cols_array()),
        usage: wgpu::BufferUsages::UNIFORM,
    });
    // An empty draw still needs buffers of non-zero size.
    let vbuf = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("preview vertices"),
        contents: if vertices.is_empty() {
            &[0u8; 48]
        } else {
            bytemuck::cast_slice(&vertices)
        },
        usage: wgpu::BufferUsages::VERTEX,
    });
    let ibuf = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("preview indices"),
        contents: if indices.is_empty() {
            &[0u8; 12]
        } else {
            bytemuck::cast_slice(&indices)
        },
        usage: wgpu::BufferUsages::INDEX,
    });
    let format = wgpu::TextureFormat::Rgba8UnormSrgb;
    let target = device.create_texture(&wgpu::TextureDescriptor {
        label: Some("preview target"),
        size: wgpu::Extent3d {
            width: w,
            height: h,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
        view_formats: &[],
    });
    let depth = device.create_texture(&wgpu::TextureDescriptor {
        label: Some("preview depth"),
        size: target.size(),
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::Depth32Float,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
        view_formats: &[],
    });
    let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("preview"),
        entries: &[wgpu::BindGroupLayoutEntry {
            binding: 0,
            visibility: wgpu::ShaderStages::VERTEX,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Uniform,
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        }],
    });
    let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("preview"),
        layout: &layout,
        entries: &[wgpu::BindGroupEntry {
            binding: 0,
            resource: uniform.as_entire_binding(),
        }],
    });
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("preview shade"),
        source: wgpu::ShaderSource::Wgsl(SHADER.into()),
    });
    let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some("preview"),
        bind_group_layouts: &[Some(&layout)],
        immediate_size: 0,
    });
    let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some("preview"),
        layout: Some(&pipeline_layout),
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some("vs"),
            compilation_options: Default::default(),
            buffers: &[Some(wgpu::VertexBufferLayout {
                array_stride: std::mem::size_of::<Vertex>() as u64,
                step_mode: wgpu::VertexStepMode::Vertex,
                attributes: &wgpu::vertex_attr_array![
                    0 => Float32x3, 1 => Float32x3, 2 => Float32x3, 3 => Float32x3
                ],
            })],
        },
        primitive: wgpu::PrimitiveState {
            topology: wgpu::PrimitiveTopology::TriangleList,
            // Cloth has two sides: nothing is culled.
            cull_mode: None,
            ..Default::default()
        },
        depth_stencil: Some(wgpu::DepthStencilState {
            format: wgpu::TextureFormat::Depth32Float,
            depth_write_enabled: Some(true),
            depth_compare: Some(wgpu::CompareFunction::Less),
            stencil: Default::default(),
            bias: Default::default(),
        }),
        multisample: Default::default(),
        fragment: Some(wgpu::FragmentState {
            module: &module,
            entry_point: Some("fs"),
            compilation_options: Default::default(),
            targets: &[Some(wgpu::ColorTargetState {
                format,
                blend: None,
                write_mask: wgpu::ColorWrites::ALL,
            })],
        }),
        multiview_mask: None,
        cache: None,
    });
    // Rows of a texture-to-buffer copy are padded to 256 bytes.
    let row = (4 * w).next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT);
    let staging = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("preview staging"),
        size: row as u64 * h as u64,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut encoder = device.create_command_encoder(&Default::default());
    {
        let color_view = target.create_view(&Default::default());
        let depth_view = depth.create_view(&Default::default());
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("preview"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &color_view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color {
                        r: 0.78,
                        g: 0.80,
                        b: 0.83,
                        a: 1.0,
                    }),
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &depth_view,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(1.0),
                    store: wgpu::StoreOp::Discard,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &group, &[]);
        pass.set_vertex_buffer(0, vbuf.slice(..));
        pass.set_index_buffer(ibuf.slice(..), wgpu::IndexFormat::Uint32);
        pass.draw_indexed(0..indices.len() as u32, 0, 0..1);
    }
    encoder.copy_texture_to_buffer(
        target.as_image_copy(),
        wgpu::TexelCopyBufferInfo {
            buffer: &staging,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(row),
                rows_per_image: Some(h),
            },
        },
        target.size(),
    );
    ctx.queue.submit([encoder.finish()]);
    let slice = staging.slice(..);
    let (tx, rx) = std::sync::mpsc::channel();
    slice.map_async(wgpu::MapMode::Read, move |r| {
        let _ = tx.send(r);
    });
    device
        .poll(wgpu::PollType::wait_indefinitely())
        .map_err(|e| Error::Gpu(format!("waiting for the GPU failed: {e}")))?;
    rx.recv()
        .map_err(|e| Error::Gpu(format!("readback was dropped: {e}")))?
        .map_err(|e| Error::Gpu(format!("mapping the preview failed: {e}")))?;
    let big = slice
        .get_mapped_range()
        .map_err(|e| Error::Gpu(format!("reading the preview failed: {e}")))?
        .to_vec();
    staging.unmap();
    Ok(downsample(&big, row as usize, width, height))
}

/// Averages each SS×SS block of the supersampled image (in sRGB-encoded bytes, which is close
/// enough for anti-aliasing edges).
fn downsample(big: &[u8], row: usize, width: u32, height: u32) -> Vec<u8> {
    let mut out = vec![0u8; (4 * width * height) as usize];
    for y in 0..height as usize {
        for x in 0..width as usize {
            for c in 0..4 {
                let mut sum = 0u32;
                for dy in 0..SS as usize {
                    for dx in 0..SS as usize {
                        let (bx, by) = (x * SS as usize + dx, y * SS as usize + dy);
                        sum += big[by * row + 4 * bx + c] as u32;
                    }
                }
                out[4 * (y * width as usize + x) + c] = (sum / (SS * SS)) as u8;
            }
        }
    }
    out
}

/// The preview shader.
pub const SHADER: &str = include_str!("shade.wgsl");
