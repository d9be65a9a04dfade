//! Stage pipelines: bind group layouts, bind groups and compute pipelines, built from one
//! list of bindings per stage so that layout and group cannot disagree.

use super::array_layout::bind_as_buffers;
use super::context::GpuContext;
use super::texels::{TexelArray, TexelStorage};
use crate::model::layout::SubstepParams;
use crate::plan::Pass;
use std::num::NonZeroU64;

/// One binding of a stage; the layout entry and the bind group entry come from the same value.
#[derive(Clone, Copy)]
pub(super) enum Binding<'a> {
    Uniform(&'a wgpu::Buffer),
    /// One `SubstepParams` at a dynamic offset.
    SubstepUniform(&'a wgpu::Buffer),
    /// One entry of this many bytes at a dynamic offset.
    Dynamic(&'a wgpu::Buffer, u64),
    /// An unused binding number (an optional kernel section that was left out).
    Gap,
    /// Read with textureLoad (or by index, when the array is a buffer).
    Read(&'a TexelArray),
    /// Written with textureStore (or by index, when the array is a buffer).
    Write(&'a TexelArray),
    /// A storage buffer (u32 arrays and atomics of the spatial hash).
    Storage(&'a wgpu::Buffer, bool),
}

pub(super) struct Stage {
    pub(super) pass: Pass,
    pub(super) pipeline: wgpu::ComputePipeline,
    /// Indexed by which state texture pair is current.
    pub(super) bind_groups: [wgpu::BindGroup; 2],
    /// Group 1: the force texture of the previous force stage.
    pub(super) force_in: Option<wgpu::BindGroup>,
    /// The force texture this stage writes.
    pub(super) force_out: Option<usize>,
    pub(super) uses_substep: bool,
    /// Dispatches per substep of a ping-pong stage (`strain_limit`'s Jacobi iterations); 1
    /// otherwise.
    pub(super) repeats: u32,
    /// Workgroups in x and y.
    pub(super) dispatch: (u32, u32),
}

/// Bytes of one entry of a dynamic uniform array.
fn dynamic_size(b: &Binding) -> u64 {
    match b {
        Binding::Dynamic(_, size) => *size,
        _ => std::mem::size_of::<SubstepParams>() as u64,
    }
}

/// The layout entry of one binding.
fn layout_entry(binding: u32, b: &Binding) -> wgpu::BindGroupLayoutEntry {
    let ty = match b {
        Binding::Uniform(_) => wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        Binding::SubstepUniform(_) | Binding::Dynamic(..) => wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: true,
            min_binding_size: NonZeroU64::new(dynamic_size(b)),
        },
        Binding::Gap => unreachable!("gaps have no layout entry"),
        Binding::Read(t) | Binding::Write(t) if t.is_buffer() => wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage {
                read_only: matches!(b, Binding::Read(_)),
            },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        Binding::Read(t) => wgpu::BindingType::Texture {
            sample_type: t.sample_type(),
            view_dimension: wgpu::TextureViewDimension::D2,
            multisampled: false,
        },
        Binding::Write(t) => wgpu::BindingType::StorageTexture {
            access: wgpu::StorageTextureAccess::WriteOnly,
            format: t.format,
            view_dimension: wgpu::TextureViewDimension::D2,
        },
        Binding::Storage(_, read_only) => wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage {
                read_only: *read_only,
            },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
    };
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty,
        count: None,
    }
}

/// The bind group entry of one binding.
fn group_entry<'a>(binding: u32, b: &Binding<'a>) -> wgpu::BindGroupEntry<'a> {
    let resource = match *b {
        Binding::Uniform(buffer) => buffer.as_entire_binding(),
        // The dynamic binding covers one entry; the offset selects which.
        Binding::SubstepUniform(buffer) | Binding::Dynamic(buffer, _) => {
            wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                buffer,
                offset: 0,
                size: NonZeroU64::new(dynamic_size(b)),
            })
        }
        Binding::Gap => unreachable!("gaps have no bind group entry"),
        Binding::Read(t) | Binding::Write(t) => match &t.storage {
            TexelStorage::Texture(_, view) => wgpu::BindingResource::TextureView(view),
            TexelStorage::Buffer(buffer) => buffer.as_entire_binding(),
        },
        Binding::Storage(buffer, _) => buffer.as_entire_binding(),
    };
    wgpu::BindGroupEntry { binding, resource }
}

/// `list`'s bindings numbered by their position in it.
fn numbered<'a>(list: &[Binding<'a>]) -> Vec<(u32, Binding<'a>)> {
    (list.iter().enumerate())
        .map(|(i, b)| (i as u32, *b))
        .collect()
}

/// A layout and one bind group per binding list (all lists have the same shape); each list's
/// bindings are numbered by their position in it.
fn bind_groups<const K: usize>(
    device: &wgpu::Device,
    label: &str,
    lists: [&[Binding]; K],
) -> (wgpu::BindGroupLayout, [wgpu::BindGroup; K]) {
    let lists = lists.map(numbered);
    numbered_bind_groups(device, label, lists.each_ref().map(|l| &l[..]))
}

/// `bind_groups` with each binding's number given beside it.
pub(super) fn numbered_bind_groups<const K: usize>(
    device: &wgpu::Device,
    label: &str,
    lists: [&[(u32, Binding)]; K],
) -> (wgpu::BindGroupLayout, [wgpu::BindGroup; K]) {
    let entries: Vec<_> = (lists[0].iter())
        .filter(|(_, b)| !matches!(b, Binding::Gap))
        .map(|(i, b)| layout_entry(*i, b))
        .collect();
    let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some(label),
        entries: &entries,
    });
    let groups = lists.map(|list| {
        let entries: Vec<_> = (list.iter())
            .filter(|(_, b)| !matches!(b, Binding::Gap))
            .map(|(i, b)| group_entry(*i, b))
            .collect();
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(label),
            layout: &layout,
            entries: &entries,
        })
    });
    (layout, groups)
}

/// One stage's pipeline (from its composed WGSL `source`) and bind groups (one per state
/// parity).
pub(super) fn build_stage(
    ctx: &GpuContext,
    pass: Pass,
    source: String,
    state_bindings: [&[Binding]; 2],
    force_in: Option<&[Binding]>,
    force_out: Option<usize>,
    dispatch: (u32, u32),
) -> Stage {
    let device = &ctx.device;
    let (layout0, groups) = bind_groups(device, pass.name(), state_bindings);
    let force_in_bindings = force_in;
    let force_in = force_in.map(|b| bind_groups(device, "force_in", [b]));
    let mut layouts = vec![&layout0];
    if let Some((layout1, _)) = &force_in {
        layouts.push(layout1);
    }
    let group0 = numbered(state_bindings[0]);
    let group1 = force_in_bindings.map(numbered).unwrap_or_default();
    let source = bind_as_buffers(source, &[(0, &group0), (1, &group1)]);
    let pipeline = compute_pipeline(device, pass.name(), source, "main", &layouts, &[]);
    Stage {
        pass,
        pipeline,
        bind_groups: groups,
        force_in: force_in.map(|(_, [g])| g),
        force_out,
        dispatch,
        uses_substep: state_bindings[0]
            .iter()
            .any(|b| matches!(b, Binding::SubstepUniform(_))),
        repeats: 1,
    }
}

/// The compute pipeline of entry point `entry` of the WGSL `source`, over bind groups of
/// `layouts` (group 0 first), with its pipeline-overridable `constants` (name, value).
pub(super) fn compute_pipeline(
    device: &wgpu::Device,
    label: &str,
    source: String,
    entry: &str,
    layouts: &[&wgpu::BindGroupLayout],
    constants: &[(&str, f64)],
) -> wgpu::ComputePipeline {
    let layouts: Vec<_> = layouts.iter().map(|l| Some(*l)).collect();
    let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some(label),
        bind_group_layouts: &layouts,
        immediate_size: 0,
    });
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(label),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    });
    device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some(label),
        layout: Some(&layout),
        module: &module,
        entry_point: Some(entry),
        compilation_options: wgpu::PipelineCompilationOptions {
            constants,
            ..Default::default()
        },
        cache: None,
    })
}
