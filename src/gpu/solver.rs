//! The GPU backend: one compute pipeline per planned stage, all substeps of a batch encoded
//! into one submission, readback through a MAP_READ staging buffer only when asked.
//!
//! Every array is a [`TexelArray`]. Positions and velocities ping-pong between two textures
//! (integrate reads one pair and writes the other), so each stage has one bind group per
//! parity. Force stages chain through at most two force textures: stage j writes `forces[j % 2]`
//! and reads `forces[(j + 1) % 2]`, except the first, which starts from zero.

use super::context::GpuContext;
use super::kernels::{compose, ForceInput};
use super::layout::{SimParams, SubstepParams, WORKGROUP_SIZE};
use super::texels::TexelArray;
use crate::error::Error;
use crate::model::ClothModel;
use crate::plan::{Pass, PassPlan};
use crate::solver::{AdapterReport, ParticleState, Solver};
use glam::Vec4;
use std::num::NonZeroU64;
use wgpu::util::DeviceExt;
use wgpu::TextureFormat::{R32Float, R32Uint, Rgba32Float, Rgba32Uint};

/// One binding of a stage; the layout entry and the bind group entry come from the same value.
#[derive(Clone, Copy)]
enum Binding<'a> {
    Uniform(&'a wgpu::Buffer),
    /// One `SubstepParams` at a dynamic offset.
    SubstepUniform(&'a wgpu::Buffer),
    /// Read with textureLoad.
    Read(&'a TexelArray),
    /// Written with textureStore.
    Write(&'a TexelArray),
    /// A storage buffer (u32 arrays and atomics of the spatial hash).
    Storage(&'a wgpu::Buffer, bool),
}

struct Stage {
    pass: Pass,
    pipeline: wgpu::ComputePipeline,
    /// Indexed by which state texture pair is current.
    bind_groups: [wgpu::BindGroup; 2],
    /// Group 1: the force texture of the previous force stage.
    force_in: Option<wgpu::BindGroup>,
    /// The force texture this stage writes.
    force_out: Option<usize>,
    uses_substep: bool,
    /// Workgroups in x and y.
    dispatch: (u32, u32),
}

/// Counts, starts and sorted particle indices of the spatial hash, as read back.
pub type HashTables = (Vec<u32>, Vec<u32>, Vec<u32>);

/// The self-collision spatial hash on the GPU.
struct HashBuffers {
    counts: wgpu::Buffer,
    starts: wgpu::Buffer,
    cursor: wgpu::Buffer,
    sorted: wgpu::Buffer,
}

/// The per-substep uniform array: `capacity` entries at `stride` bytes.
struct SubstepBuffer {
    buffer: wgpu::Buffer,
    stride: u64,
    capacity: usize,
}

/// The wgpu backend. Creates textures, buffers and pipelines only for the stages in its plan.
pub struct GpuSolver {
    ctx: GpuContext,
    params: wgpu::Buffer,
    pos: [TexelArray; 2],
    vel: [TexelArray; 2],
    forces: Vec<TexelArray>,
    /// Which of `pos`/`vel` holds the current state.
    current: usize,
    /// Which of `forces` the last force stage wrote.
    last_forces: usize,
    n: usize,
    staging: wgpu::Buffer,
    substeps: Option<SubstepBuffer>,
    stages: Vec<Stage>,
    resource_labels: Vec<&'static str>,
    hash: Option<HashBuffers>,
}

impl GpuSolver {
    /// Uploads `model` and builds the pipelines of `plan`. `max_batch` is the most substeps one
    /// `advance` call submits at once (longer calls are split into batches of that size).
    pub fn new(
        ctx: &GpuContext,
        model: &ClothModel,
        params: SimParams,
        plan: &PassPlan,
        max_batch: usize,
    ) -> Result<Self, Error> {
        let n = model.len();
        let state_usage = wgpu::TextureUsages::STORAGE_BINDING | wgpu::TextureUsages::COPY_SRC;
        let mut labels = vec!["params", "positions", "velocities", "forces", "staging"];
        let params_buf = ctx
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("params"),
                contents: bytemuck::bytes_of(&params),
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            });
        let state = |label: &str, data: &[Vec4]| -> Result<[TexelArray; 2], Error> {
            let bytes = bytemuck::cast_slice(data);
            Ok([
                TexelArray::with_data(ctx, label, Rgba32Float, bytes, state_usage)?,
                TexelArray::with_data(ctx, label, Rgba32Float, bytes, state_usage)?,
            ])
        };
        let pos = state("positions", &model.packed_positions())?;
        let vel = state("velocities", &model.packed_velocities())?;
        let force_stages = plan.passes.iter().filter(|p| p.is_force()).count();
        let forces = (0..force_stages.clamp(1, 2))
            .map(|_| TexelArray::new(ctx, "forces", Rgba32Float, n, state_usage))
            .collect::<Result<Vec<_>, _>>()?;
        let staging = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("staging"),
            size: 2 * pos[0].padded_bytes(),
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });

        let needs_substep = [Pass::WindForces, Pass::SeamForces, Pass::CollideBody]
            .into_iter()
            .any(|p| plan.contains(p));
        let substeps = needs_substep.then(|| {
            labels.push("substep_params");
            let align = ctx.device.limits().min_uniform_buffer_offset_alignment as u64;
            let stride = (std::mem::size_of::<SubstepParams>() as u64).next_multiple_of(align);
            let capacity = max_batch.max(1);
            SubstepBuffer {
                buffer: ctx.device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("substep_params"),
                    size: stride * capacity as u64,
                    usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                }),
                stride,
                capacity,
            }
        });

        let hash = plan.contains(Pass::SelfCollide).then(|| {
            let buckets = params.hash_buckets as u64;
            let mut buffer = |label: &'static str, words: u64| {
                labels.push(label);
                ctx.device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some(label),
                    size: 4 * words.max(4),
                    usage: wgpu::BufferUsages::STORAGE
                        | wgpu::BufferUsages::COPY_SRC
                        | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                })
            };
            HashBuffers {
                counts: buffer("hash_counts", buckets),
                starts: buffer("hash_starts", buckets + 1),
                cursor: buffer("hash_cursor", buckets),
                sorted: buffer("hash_sorted", n as u64),
            }
        });
        let dispatch_for = |threads: u32| {
            let total = threads.div_ceil(WORKGROUP_SIZE).max(1);
            let max_x = ctx.device.limits().max_compute_workgroups_per_dimension;
            if total <= max_x {
                (total, 1)
            } else {
                (max_x, total.div_ceil(max_x))
            }
        };
        let mut stages = Vec::new();
        let mut force_index = 0;
        for &pass in &plan.passes {
            // Stage-specific arrays live as long as the bind groups that hold them.
            let mut owned: Vec<TexelArray> = Vec::new();
            let mut add = |label: &'static str, format, bytes: &[u8]| -> Result<(), Error> {
                labels.push(label);
                let none = wgpu::TextureUsages::empty();
                owned.push(TexelArray::with_data(ctx, label, format, bytes, none)?);
                Ok(())
            };
            match pass {
                Pass::SpringForces => {
                    let csr = model.spring_csr();
                    add(
                        "spring_offsets",
                        R32Uint,
                        bytemuck::cast_slice(&csr.offsets),
                    )?;
                    add("springs", Rgba32Uint, bytemuck::cast_slice(&csr.items))?;
                }
                Pass::BendingForces => {
                    let csr = model.hinge_csr();
                    add("hinge_offsets", R32Uint, bytemuck::cast_slice(&csr.offsets))?;
                    add("hinge_refs", R32Uint, bytemuck::cast_slice(&csr.items))?;
                    add("hinges", Rgba32Uint, bytemuck::cast_slice(&model.hinges))?;
                }
                Pass::WindForces => {
                    let csr = model.triangle_csr();
                    add(
                        "triangle_offsets",
                        R32Uint,
                        bytemuck::cast_slice(&csr.offsets),
                    )?;
                    add("triangle_refs", R32Uint, bytemuck::cast_slice(&csr.items))?;
                    let tris = model.packed_triangles();
                    add("triangles", Rgba32Uint, bytemuck::cast_slice(&tris))?;
                }
                Pass::SeamForces => {
                    let csr = model.seam_csr();
                    add("seam_offsets", R32Uint, bytemuck::cast_slice(&csr.offsets))?;
                    add("seam_refs", R32Uint, bytemuck::cast_slice(&csr.items))?;
                    add("seams", Rgba32Uint, bytemuck::cast_slice(&model.seams))?;
                }
                Pass::SelfCollide => {
                    let csr = model.spring_csr();
                    add(
                        "self_neighbour_offsets",
                        R32Uint,
                        bytemuck::cast_slice(&csr.offsets),
                    )?;
                    add(
                        "self_neighbours",
                        Rgba32Uint,
                        bytemuck::cast_slice(&csr.items),
                    )?;
                }
                Pass::HashClear | Pass::HashCount | Pass::HashScan | Pass::HashFill => {}
                Pass::CollideBody => {
                    let c = model.collider.as_ref().expect("collide_body needs a body");
                    add("sdf", R32Float, bytemuck::cast_slice(&c.sdf.values))?;
                }
                Pass::Integrate => {}
            }
            let (force_out, force_in) = if pass.is_force() {
                let j = force_index;
                force_index += 1;
                (Some(j % 2), (j > 0).then_some((j + 1) % 2))
            } else {
                (None, None)
            };
            // The forces integrate reads: the last force stage's output (zero if none ran).
            let summed = (force_stages + 1) % 2 % forces.len();
            let substep_buf = substeps.as_ref().map(|s| &s.buffer);
            let hb = || hash.as_ref().expect("self-collision buffers");
            let bindings = |p: usize| -> Vec<Binding> {
                let o = |k: usize| Binding::Read(&owned[k]);
                let out = || Binding::Write(&forces[force_out.expect("force stage")]);
                match pass {
                    Pass::SpringForces => vec![
                        Binding::Uniform(&params_buf),
                        Binding::Read(&pos[p]),
                        Binding::Read(&vel[p]),
                        out(),
                        o(0),
                        o(1),
                    ],
                    Pass::BendingForces => vec![
                        Binding::Uniform(&params_buf),
                        Binding::Read(&pos[p]),
                        out(),
                        o(0),
                        o(1),
                        o(2),
                    ],
                    Pass::WindForces => vec![
                        Binding::Uniform(&params_buf),
                        Binding::SubstepUniform(substep_buf.expect("wind needs substep params")),
                        Binding::Read(&pos[p]),
                        Binding::Read(&vel[p]),
                        out(),
                        o(0),
                        o(1),
                        o(2),
                    ],
                    Pass::SeamForces => vec![
                        Binding::Uniform(&params_buf),
                        Binding::SubstepUniform(substep_buf.expect("seams need substep params")),
                        Binding::Read(&pos[p]),
                        Binding::Read(&vel[p]),
                        out(),
                        o(0),
                        o(1),
                        o(2),
                    ],
                    Pass::CollideBody => vec![
                        Binding::Uniform(&params_buf),
                        Binding::SubstepUniform(
                            substep_buf.expect("collision needs substep params"),
                        ),
                        Binding::Read(&pos[p]),
                        Binding::Read(&vel[p]),
                        o(0),
                        Binding::Write(&pos[1 - p]),
                        Binding::Write(&vel[1 - p]),
                    ],
                    Pass::HashClear => vec![
                        Binding::Uniform(&params_buf),
                        Binding::Storage(&hb().counts, false),
                    ],
                    Pass::HashCount => vec![
                        Binding::Uniform(&params_buf),
                        Binding::Read(&pos[p]),
                        Binding::Storage(&hb().counts, false),
                    ],
                    Pass::HashScan => vec![
                        Binding::Uniform(&params_buf),
                        Binding::Storage(&hb().counts, true),
                        Binding::Storage(&hb().starts, false),
                        Binding::Storage(&hb().cursor, false),
                    ],
                    Pass::HashFill => vec![
                        Binding::Uniform(&params_buf),
                        Binding::Read(&pos[p]),
                        Binding::Storage(&hb().cursor, false),
                        Binding::Storage(&hb().sorted, false),
                    ],
                    Pass::SelfCollide => vec![
                        Binding::Uniform(&params_buf),
                        Binding::Read(&pos[p]),
                        Binding::Read(&vel[p]),
                        Binding::Storage(&hb().starts, true),
                        Binding::Storage(&hb().sorted, true),
                        o(0),
                        o(1),
                        Binding::Write(&pos[1 - p]),
                        Binding::Write(&vel[1 - p]),
                    ],
                    Pass::Integrate => vec![
                        Binding::Uniform(&params_buf),
                        Binding::Read(&pos[p]),
                        Binding::Read(&vel[p]),
                        Binding::Read(&forces[summed]),
                        Binding::Write(&pos[1 - p]),
                        Binding::Write(&vel[1 - p]),
                    ],
                }
            };
            let input = if force_in.is_some() {
                ForceInput::Texture
            } else {
                ForceInput::Zero
            };
            let force_in = force_in.map(|k| [Binding::Read(&forces[k])]);
            let dispatch = match pass {
                Pass::HashClear => dispatch_for(params.hash_buckets),
                Pass::HashScan => (1, 1),
                _ => dispatch_for(n as u32),
            };
            stages.push(build_stage(
                ctx,
                pass,
                input,
                [&bindings(0), &bindings(1)],
                force_in.as_ref().map(|b| &b[..]),
                force_out,
                dispatch,
            ));
        }

        Ok(GpuSolver {
            ctx: ctx.clone(),
            params: params_buf,
            pos,
            vel,
            forces,
            current: 0,
            last_forces: 0,
            n,
            staging,
            substeps,
            stages,
            resource_labels: labels,
            hash,
        })
    }

    /// The stages that have a pipeline, in order.
    pub fn pipeline_passes(&self) -> Vec<Pass> {
        self.stages.iter().map(|s| s.pass).collect()
    }

    /// Labels of every buffer and texture this solver created.
    pub fn resource_labels(&self) -> &[&'static str] {
        &self.resource_labels
    }

    /// Runs the given stages (each must be in the plan) once per entry of `steps`, in one
    /// submission. `advance` runs the whole plan; parity tests run single stages.
    pub fn run_passes(&mut self, passes: &[Pass], steps: &[SubstepParams]) -> Result<(), Error> {
        let capacity = self.substeps.as_ref().map_or(usize::MAX, |s| s.capacity);
        for batch in steps.chunks(capacity.min(steps.len().max(1))) {
            if let Some(sb) = &self.substeps {
                let mut bytes = vec![0u8; sb.stride as usize * batch.len()];
                for (k, step) in batch.iter().enumerate() {
                    let at = k * sb.stride as usize;
                    bytes[at..at + std::mem::size_of::<SubstepParams>()]
                        .copy_from_slice(bytemuck::bytes_of(step));
                }
                self.ctx.queue.write_buffer(&sb.buffer, 0, &bytes);
            }
            let mut encoder = self.ctx.device.create_command_encoder(&Default::default());
            {
                let mut cpass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some("substeps"),
                    timestamp_writes: None,
                });
                for k in 0..batch.len() {
                    for &pass in passes {
                        let stage =
                            self.stages.iter().find(|s| s.pass == pass).ok_or_else(|| {
                                Error::Gpu(format!("{} is not in the plan", pass.name()))
                            })?;
                        cpass.set_pipeline(&stage.pipeline);
                        let offset = match (&self.substeps, stage.uses_substep) {
                            (Some(sb), true) => vec![(k as u64 * sb.stride) as u32],
                            _ => vec![],
                        };
                        cpass.set_bind_group(0, &stage.bind_groups[self.current], &offset);
                        if let Some(force_in) = &stage.force_in {
                            cpass.set_bind_group(1, force_in, &[]);
                        }
                        cpass.dispatch_workgroups(stage.dispatch.0, stage.dispatch.1, 1);
                        if let Some(out) = stage.force_out {
                            self.last_forces = out;
                        }
                        if pass.writes_state() {
                            self.current = 1 - self.current;
                        }
                    }
                }
            }
            self.ctx.queue.submit([encoder.finish()]);
        }
        Ok(())
    }

    /// Reads back the spatial hash: counts, starts and sorted particle indices (for parity
    /// tests of the self-collision stages).
    pub fn hash_tables(&self) -> Result<HashTables, Error> {
        let h = self
            .hash
            .as_ref()
            .ok_or_else(|| Error::Gpu("self-collision is not in the plan".into()))?;
        Ok((
            self.read_u32(&h.counts)?,
            self.read_u32(&h.starts)?,
            self.read_u32(&h.sorted)?,
        ))
    }

    /// Uploads bucket starts and sorted indices (so `self_collide` can be compared alone).
    pub fn set_hash(&mut self, starts: &[u32], sorted: &[u32]) {
        if let Some(h) = &self.hash {
            self.ctx
                .queue
                .write_buffer(&h.starts, 0, bytemuck::cast_slice(starts));
            self.ctx
                .queue
                .write_buffer(&h.sorted, 0, bytemuck::cast_slice(sorted));
        }
    }

    fn read_u32(&self, buffer: &wgpu::Buffer) -> Result<Vec<u32>, Error> {
        let size = buffer.size();
        let staging = self.ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("hash staging"),
            size,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut encoder = self.ctx.device.create_command_encoder(&Default::default());
        encoder.copy_buffer_to_buffer(buffer, 0, &staging, 0, size);
        self.ctx.queue.submit([encoder.finish()]);
        let slice = staging.slice(..);
        self.map_read(slice, |bytes| bytemuck::cast_slice(bytes).to_vec())
    }

    /// Maps a MAP_READ slice once the submitted work is done and hands its bytes to `read`.
    fn map_read<T>(
        &self,
        slice: wgpu::BufferSlice,
        read: impl FnOnce(&[u8]) -> T,
    ) -> Result<T, Error> {
        let (tx, rx) = std::sync::mpsc::channel();
        slice.map_async(wgpu::MapMode::Read, move |r| {
            let _ = tx.send(r);
        });
        self.ctx
            .device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| Error::Gpu(format!("waiting for the GPU failed: {e}")))?;
        rx.recv()
            .map_err(|e| Error::Gpu(format!("readback was dropped: {e}")))?
            .map_err(|e| Error::Gpu(format!("mapping the staging buffer failed: {e}")))?;
        let out = read(
            &slice
                .get_mapped_range()
                .map_err(|e| Error::Gpu(format!("reading the staging buffer failed: {e}")))?,
        );
        slice.buffer().unmap();
        Ok(out)
    }

    /// Reads back the forces the last force stage wrote (for per-stage parity tests).
    pub fn forces(&mut self) -> Result<Vec<Vec4>, Error> {
        Ok(self.read_back(&[&self.forces[self.last_forces]])?.remove(0))
    }

    fn read_back(&self, arrays: &[&TexelArray]) -> Result<Vec<Vec<Vec4>>, Error> {
        let mut encoder = self.ctx.device.create_command_encoder(&Default::default());
        let mut at = 0;
        for a in arrays {
            a.copy_to_buffer(&mut encoder, &self.staging, at);
            at += a.padded_bytes();
        }
        self.ctx.queue.submit([encoder.finish()]);
        self.map_read(self.staging.slice(..at), |bytes| {
            let all: &[Vec4] = bytemuck::cast_slice(bytes);
            let mut start = 0;
            arrays
                .iter()
                .map(|a| {
                    let texels = a.padded_bytes() as usize / 16;
                    let data = all[start..start + self.n].to_vec();
                    start += texels;
                    data
                })
                .collect()
        })
    }
}

fn layout_entry(binding: u32, b: &Binding) -> wgpu::BindGroupLayoutEntry {
    let substep_size = NonZeroU64::new(std::mem::size_of::<SubstepParams>() as u64);
    let ty = match b {
        Binding::Uniform(_) | Binding::SubstepUniform(_) => {
            let dynamic = matches!(b, Binding::SubstepUniform(_));
            wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Uniform,
                has_dynamic_offset: dynamic,
                min_binding_size: if dynamic { substep_size } else { None },
            }
        }
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

fn group_entry<'a>(binding: u32, b: &Binding<'a>) -> wgpu::BindGroupEntry<'a> {
    let resource = match *b {
        Binding::Uniform(buffer) => buffer.as_entire_binding(),
        // The dynamic binding covers one entry; the offset selects which.
        Binding::SubstepUniform(buffer) => wgpu::BindingResource::Buffer(wgpu::BufferBinding {
            buffer,
            offset: 0,
            size: NonZeroU64::new(std::mem::size_of::<SubstepParams>() as u64),
        }),
        Binding::Read(t) | Binding::Write(t) => wgpu::BindingResource::TextureView(&t.view),
        Binding::Storage(buffer, _) => buffer.as_entire_binding(),
    };
    wgpu::BindGroupEntry { binding, resource }
}

/// A layout and one bind group per binding list (all lists have the same shape).
fn bind_groups<const K: usize>(
    device: &wgpu::Device,
    label: &str,
    lists: [&[Binding]; K],
) -> (wgpu::BindGroupLayout, [wgpu::BindGroup; K]) {
    let entries: Vec<_> = (lists[0].iter().enumerate())
        .map(|(i, b)| layout_entry(i as u32, b))
        .collect();
    let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some(label),
        entries: &entries,
    });
    let groups = lists.map(|list| {
        let entries: Vec<_> = (list.iter().enumerate())
            .map(|(i, b)| group_entry(i as u32, b))
            .collect();
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(label),
            layout: &layout,
            entries: &entries,
        })
    });
    (layout, groups)
}

fn build_stage(
    ctx: &GpuContext,
    pass: Pass,
    input: ForceInput,
    state_bindings: [&[Binding]; 2],
    force_in: Option<&[Binding]>,
    force_out: Option<usize>,
    dispatch: (u32, u32),
) -> Stage {
    let device = &ctx.device;
    let (layout0, groups) = bind_groups(device, pass.name(), state_bindings);
    let force_in = force_in.map(|b| bind_groups(device, "force_in", [b]));
    let mut layouts = vec![Some(&layout0)];
    if let Some((layout1, _)) = &force_in {
        layouts.push(Some(layout1));
    }
    let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some(pass.name()),
        bind_group_layouts: &layouts,
        immediate_size: 0,
    });
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(pass.name()),
        source: wgpu::ShaderSource::Wgsl(compose(pass, input).into()),
    });
    let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some(pass.name()),
        layout: Some(&layout),
        module: &module,
        entry_point: Some("main"),
        compilation_options: Default::default(),
        cache: None,
    });
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
    }
}

impl Solver for GpuSolver {
    fn backend_name(&self) -> &'static str {
        "gpu"
    }

    fn adapter(&self) -> Option<AdapterReport> {
        Some(self.ctx.report())
    }

    fn advance(&mut self, steps: &[SubstepParams]) -> Result<(), Error> {
        let passes = self.pipeline_passes();
        self.run_passes(&passes, steps)
    }

    fn finish(&mut self) -> Result<(), Error> {
        self.ctx
            .device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| Error::Gpu(format!("waiting for the GPU failed: {e}")))?;
        Ok(())
    }

    fn set_params(&mut self, params: &SimParams) {
        self.ctx
            .queue
            .write_buffer(&self.params, 0, bytemuck::bytes_of(params));
    }

    /// Replaces positions and velocities and clears forces.
    fn set_state(&mut self, state: &ParticleState) {
        let q = &self.ctx.queue;
        self.pos[self.current].write(q, bytemuck::cast_slice(&state.positions));
        self.vel[self.current].write(q, bytemuck::cast_slice(&state.velocities));
        for f in &self.forces {
            f.write(q, &[]);
        }
    }

    fn state(&mut self) -> Result<ParticleState, Error> {
        let (p, v) = (&self.pos[self.current], &self.vel[self.current]);
        let mut out = self.read_back(&[p, v])?;
        let velocities = out.pop().unwrap_or_default();
        let positions = out.pop().unwrap_or_default();
        Ok(ParticleState {
            positions,
            velocities,
        })
    }
}
