//! One-dimensional arrays of one texel per element, stored as 2D textures `TEXELS_PER_ROW`
//! texels wide or as storage buffers of the same bytes (the context's `ArrayLayout`). Kernels
//! read them with `textureLoad(t, texel(i), 0)`; see array_layout.rs for the buffer form.

use super::array_layout::ArrayLayout;
use super::context::GpuContext;
use crate::error::Error;
use crate::model::layout::TEXELS_PER_ROW;

/// `len` elements of one texel each, in rows of `TEXELS_PER_ROW`.
pub struct TexelArray {
    /// The texture or buffer.
    pub storage: TexelStorage,
    /// Texel format: Rgba32Float, R32Float, Rgba32Uint or R32Uint.
    pub format: wgpu::TextureFormat,
    rows: u32,
}

/// Where a texel array's bytes live.
pub enum TexelStorage {
    /// A texture and its only view.
    Texture(wgpu::Texture, wgpu::TextureView),
    /// A storage buffer holding the texture's rows one after another.
    Buffer(wgpu::Buffer),
}

impl TexelArray {
    /// A zero-filled array of `len` texels in the context's layout. Fails when `len` needs more
    /// rows than the adapter's largest 2D texture.
    pub fn new(
        ctx: &GpuContext,
        label: &str,
        format: wgpu::TextureFormat,
        len: usize,
        usage: wgpu::TextureUsages,
    ) -> Result<Self, Error> {
        Self::new_in(ctx.layout, ctx, label, format, len, usage)
    }

    /// A zero-filled array of `len` texels in `layout`.
    pub fn new_in(
        layout: ArrayLayout,
        ctx: &GpuContext,
        label: &str,
        format: wgpu::TextureFormat,
        len: usize,
        usage: wgpu::TextureUsages,
    ) -> Result<Self, Error> {
        let rows = (len.div_ceil(TEXELS_PER_ROW as usize)).max(1);
        let max_rows = ctx.device.limits().max_texture_dimension_2d as usize;
        if rows > max_rows {
            return Err(Error::Gpu(format!(
                "{label}: {len} elements need {rows} rows of {TEXELS_PER_ROW} texels, but this \
                 adapter's textures have at most {max_rows}; use a coarser mesh"
            )));
        }
        let storage = match layout {
            ArrayLayout::Textures => texture_storage(ctx, label, format, rows as u32, usage),
            ArrayLayout::Buffers => {
                TexelStorage::Buffer(ctx.device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some(label),
                    size: TEXELS_PER_ROW as u64 * rows as u64 * texel_bytes(format) as u64,
                    usage: wgpu::BufferUsages::STORAGE
                        | wgpu::BufferUsages::COPY_DST
                        | wgpu::BufferUsages::COPY_SRC,
                    mapped_at_creation: false,
                }))
            }
        };
        Ok(TexelArray {
            storage,
            format,
            rows: rows as u32,
        })
    }

    /// An array holding `bytes` in the context's layout; their length must be a whole number of
    /// texels.
    pub fn with_data(
        ctx: &GpuContext,
        label: &str,
        format: wgpu::TextureFormat,
        bytes: &[u8],
        usage: wgpu::TextureUsages,
    ) -> Result<Self, Error> {
        Self::with_data_in(ctx.layout, ctx, label, format, bytes, usage)
    }

    /// An array holding `bytes` in `layout`.
    pub fn with_data_in(
        layout: ArrayLayout,
        ctx: &GpuContext,
        label: &str,
        format: wgpu::TextureFormat,
        bytes: &[u8],
        usage: wgpu::TextureUsages,
    ) -> Result<Self, Error> {
        let texel = texel_bytes(format);
        assert_eq!(
            bytes.len() % texel,
            0,
            "{label}: not a whole number of texels"
        );
        let array = Self::new_in(layout, ctx, label, format, bytes.len() / texel, usage)?;
        array.write(&ctx.queue, bytes);
        Ok(array)
    }

    /// Bytes in one row of texels (a multiple of 256, as copies require).
    pub fn row_bytes(&self) -> u32 {
        TEXELS_PER_ROW * texel_bytes(self.format) as u32
    }

    /// Bytes of the whole texture, padding included.
    pub fn padded_bytes(&self) -> u64 {
        self.row_bytes() as u64 * self.rows as u64
    }

    fn extent(&self) -> wgpu::Extent3d {
        wgpu::Extent3d {
            width: TEXELS_PER_ROW,
            height: self.rows,
            depth_or_array_layers: 1,
        }
    }

    fn layout(&self, offset: u64) -> wgpu::TexelCopyBufferLayout {
        wgpu::TexelCopyBufferLayout {
            offset,
            bytes_per_row: Some(self.row_bytes()),
            rows_per_image: Some(self.rows),
        }
    }

    /// Overwrites the array from its start with `bytes`; the rest becomes zero.
    pub fn write(&self, queue: &wgpu::Queue, bytes: &[u8]) {
        let mut padded = bytes.to_vec();
        padded.resize(self.padded_bytes() as usize, 0);
        match &self.storage {
            TexelStorage::Texture(texture, _) => queue.write_texture(
                texture.as_image_copy(),
                &padded,
                self.layout(0),
                self.extent(),
            ),
            TexelStorage::Buffer(buffer) => queue.write_buffer(buffer, 0, &padded),
        }
    }

    /// Whether the array is a storage buffer.
    pub fn is_buffer(&self) -> bool {
        matches!(self.storage, TexelStorage::Buffer(_))
    }

    /// Records a copy of the whole texture into `buffer` at `offset`.
    pub fn copy_to_buffer(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        buffer: &wgpu::Buffer,
        offset: u64,
    ) {
        match &self.storage {
            TexelStorage::Texture(texture, _) => encoder.copy_texture_to_buffer(
                texture.as_image_copy(),
                wgpu::TexelCopyBufferInfo {
                    buffer,
                    layout: self.layout(offset),
                },
                self.extent(),
            ),
            TexelStorage::Buffer(source) => {
                encoder.copy_buffer_to_buffer(source, 0, buffer, offset, self.padded_bytes())
            }
        }
    }

    /// How a kernel reads this array: `texture_2d<f32>` or `texture_2d<u32>`.
    pub fn sample_type(&self) -> wgpu::TextureSampleType {
        match self.format {
            wgpu::TextureFormat::Rgba32Float | wgpu::TextureFormat::R32Float => {
                wgpu::TextureSampleType::Float { filterable: false }
            }
            _ => wgpu::TextureSampleType::Uint,
        }
    }
}

/// A texture of `rows` rows of `TEXELS_PER_ROW` texels.
fn texture_storage(
    ctx: &GpuContext,
    label: &str,
    format: wgpu::TextureFormat,
    rows: u32,
    usage: wgpu::TextureUsages,
) -> TexelStorage {
    let texture = ctx.device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d {
            width: TEXELS_PER_ROW,
            height: rows,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: usage | wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    });
    let view = texture.create_view(&Default::default());
    TexelStorage::Texture(texture, view)
}

fn texel_bytes(format: wgpu::TextureFormat) -> usize {
    format
        .block_copy_size(None)
        .expect("texel arrays use single-aspect formats") as usize
}
