//! Offscreen rendering with wgpu: triangle meshes with per-vertex colours (or a fabric image
//! over their pattern coordinates) and ambient occlusion, depth-tested, both sides lit,
//! supersampled 2×2 and box-filtered down, read back as RGBA8 (sRGB) pixels.

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
    /// Vertex normals, when they are not the mesh's own (a garment's seams shaded smooth across
    /// its panels); empty: from the triangles.
    pub smooth_normals: Vec<Vec3>,
    /// Each vertex's ambient light left unoccluded on its normal's side and on the other, 0 to
    /// 1; empty: all of it.
    pub occlusion: Vec<[f32; 2]>,
    /// Whether the fabric image covers this mesh (at `uv`).
    pub textured: bool,
    /// A closed, outward-facing surface (a body): only the side its normals point to is ever
    /// seen, so ambient occlusion shades that side alone.
    pub closed: bool,
}

impl DrawMesh {
    /// Vertex normals: `smooth_normals` when given, else area-weighted (unnormalised sums of
    /// the triangles' cross products).
    pub fn normals(&self) -> Vec<Vec3> {
        if self.smooth_normals.len() == self.positions.len() {
            return self.smooth_normals.clone();
        }
        crate::mesh::vertex_normals(&self.positions, &self.triangles)
    }
}

/// An image of the fabric: RGBA8 sRGB pixels, and the size one copy covers on the cloth.
#[derive(Clone, Debug, PartialEq)]
pub struct FabricTexture {
    /// The image.
    pub image: image::RgbaImage,
    /// Width and height of one copy, in m.
    pub size_m: [f32; 2],
}

impl FabricTexture {
    /// Reads a `[preview] texture`.
    pub fn load(setting: &crate::scene::TextureSetting) -> Result<FabricTexture, Error> {
        let image = image::open(&setting.path)
            .map_err(|e| Error::io(&setting.path, std::io::Error::other(e.to_string())))?
            .to_rgba8();
        Ok(FabricTexture {
            image,
            size_m: setting.size_m,
        })
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
    /// Unoccluded ambient light on the normal's side and the other, and 1 where the fabric
    /// image covers the vertex.
    shade: [f32; 3],
}

/// The shader's uniform: keep in sync with `View` in shade.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct View {
    view_proj: [f32; 16],
    /// 1 / the fabric image's width and height in m (0 without one).
    texture_scale: [f32; 4],
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
    render_textured(ctx, meshes, None, camera, width, height)
}

/// `render`, with `texture` over the meshes marked `textured`.
pub fn render_textured(
    ctx: &GpuContext,
    meshes: &[DrawMesh],
    texture: Option<&FabricTexture>,
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
        let has_uv = m.uv.len() == m.positions.len();
        let checker = if has_uv { m.checker.max(0.0) } else { 0.0 };
        let image = (m.textured && has_uv && texture.is_some()) as u32 as f32;
        for (k, ((p, n), c)) in (m.positions.iter().zip(m.normals()).zip(&m.colors)).enumerate() {
            let uv = m.uv.get(k).filter(|_| has_uv).copied().unwrap_or_default();
            let [front, back] = m.occlusion.get(k).copied().unwrap_or([1.0; 2]);
            vertices.push(Vertex {
                pos: p.to_array(),
                normal: n.to_array(),
                color: c.to_array(),
                uv: [uv.x, uv.y, checker],
                shade: [front, back, image],
            });
        }
        indices.extend(m.triangles.iter().flat_map(|t| t.map(|i| i + base)));
    }
    let view_proj: Mat4 = camera.view_proj(width as f32 / height as f32);
    let view = View {
        view_proj: view_proj.to_cols_array(),
        texture_scale: texture.map_or([0.0; 4], |t| {
            [1.0 / t.size_m[0], 1.0 / t.size_m[1], 0.0, 0.0]
        }),
    };
    let uniform = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("preview view"),
        contents: bytemuck::bytes_of(&view),
        usage: wgpu::BufferUsages::UNIFORM,
    });
    let (image_view, sampler) = fabric_image(ctx, texture);
    // An empty draw still needs buffers of non-zero size.
    let vbuf = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("preview vertices"),
        contents: if vertices.is_empty() {
            &[0u8; 60]
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
        entries: &[
            wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            },
            wgpu::BindGroupLayoutEntry {
                binding: 1,
                visibility: wgpu::ShaderStages::FRAGMENT,
                ty: wgpu::BindingType::Texture {
                    sample_type: wgpu::TextureSampleType::Float { filterable: true },
                    view_dimension: wgpu::TextureViewDimension::D2,
                    multisampled: false,
                },
                count: None,
            },
            wgpu::BindGroupLayoutEntry {
                binding: 2,
                visibility: wgpu::ShaderStages::FRAGMENT,
                ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
                count: None,
            },
        ],
    });
    let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("preview"),
        layout: &layout,
        entries: &[
            wgpu::BindGroupEntry {
                binding: 0,
                resource: uniform.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: wgpu::BindingResource::TextureView(&image_view),
            },
            wgpu::BindGroupEntry {
                binding: 2,
                resource: wgpu::BindingResource::Sampler(&sampler),
            },
        ],
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
                    0 => Float32x3, 1 => Float32x3, 2 => Float32x3, 3 => Float32x3,
                    4 => Float32x3
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

/// The fabric image with its mip levels (so that a fine weave seen from afar averages instead
/// of aliasing), repeated over the texture coordinates; a white texel without one.
fn fabric_image(
    ctx: &GpuContext,
    texture: Option<&FabricTexture>,
) -> (wgpu::TextureView, wgpu::Sampler) {
    let white = image::RgbaImage::from_pixel(1, 1, image::Rgba([255; 4]));
    let base = texture.map_or(&white, |t| &t.image);
    let mut levels = vec![base.clone()];
    while let Some(last) = levels.last().filter(|l| l.width() > 1 || l.height() > 1) {
        let (w, h) = ((last.width() / 2).max(1), (last.height() / 2).max(1));
        let next = image::imageops::resize(last, w, h, image::imageops::FilterType::Triangle);
        levels.push(next);
    }
    let gpu_texture = ctx.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("preview fabric image"),
        size: wgpu::Extent3d {
            width: base.width(),
            height: base.height(),
            depth_or_array_layers: 1,
        },
        mip_level_count: levels.len() as u32,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::Rgba8UnormSrgb,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    });
    for (level, img) in levels.iter().enumerate() {
        ctx.queue.write_texture(
            wgpu::TexelCopyTextureInfo {
                texture: &gpu_texture,
                mip_level: level as u32,
                origin: wgpu::Origin3d::ZERO,
                aspect: wgpu::TextureAspect::All,
            },
            img.as_raw(),
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(4 * img.width()),
                rows_per_image: Some(img.height()),
            },
            wgpu::Extent3d {
                width: img.width(),
                height: img.height(),
                depth_or_array_layers: 1,
            },
        );
    }
    let sampler = ctx.device.create_sampler(&wgpu::SamplerDescriptor {
        label: Some("preview fabric image"),
        address_mode_u: wgpu::AddressMode::Repeat,
        address_mode_v: wgpu::AddressMode::Repeat,
        mag_filter: wgpu::FilterMode::Linear,
        min_filter: wgpu::FilterMode::Linear,
        mipmap_filter: wgpu::MipmapFilterMode::Linear,
        ..Default::default()
    });
    (gpu_texture.create_view(&Default::default()), sampler)
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
