//! The GPU backend: one compute pipeline per planned stage, all substeps of a batch encoded
//! into one submission, readback through a MAP_READ staging buffer only when asked.

use super::context::GpuContext;
use super::kernels::compose;
use super::layout::{SimParams, SubstepParams, WORKGROUP_SIZE};
use crate::error::Error;
use crate::model::ClothModel;
use crate::plan::{Pass, PassPlan};
use crate::solver::{AdapterReport, ParticleState, Solver};
use glam::Vec4;
use std::num::NonZeroU64;
use wgpu::util::DeviceExt;

/// How a stage uses a buffer; the layout entry and the bind group entry come from the same list.
#[derive(Clone, Copy)]
enum Access {
    Uniform,
    /// One `SubstepParams` at a dynamic offset.
    SubstepUniform,
    Read,
    ReadWrite,
}

struct Stage {
    pass: Pass,
    pipeline: wgpu::ComputePipeline,
    bind_group: wgpu::BindGroup,
    uses_substep: bool,
}

/// The per-substep uniform array: `capacity` entries at `stride` bytes.
struct SubstepBuffer {
    buffer: wgpu::Buffer,
    stride: u64,
    capacity: usize,
}

/// The wgpu backend. Creates buffers and pipelines only for the stages in its plan.
pub struct GpuSolver {
    ctx: GpuContext,
    n: u32,
    pos: wgpu::Buffer,
    vel: wgpu::Buffer,
    force: wgpu::Buffer,
    staging: wgpu::Buffer,
    substeps: Option<SubstepBuffer>,
    stages: Vec<Stage>,
    buffer_labels: Vec<&'static str>,
    groups: (u32, u32),
}

fn storage_init(
    ctx: &GpuContext,
    label: &'static str,
    bytes: &[u8],
    extra: wgpu::BufferUsages,
) -> wgpu::Buffer {
    // A binding may not be empty; a 16-byte minimum keeps zero-length lists legal.
    let mut data = bytes.to_vec();
    data.resize(data.len().max(16), 0);
    ctx.device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents: &data,
            usage: wgpu::BufferUsages::STORAGE | extra,
        })
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
        let n = model.len() as u32;
        let copy = wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST;
        let mut labels = vec!["params", "positions", "velocities", "forces", "staging"];
        let params_buf = ctx
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("params"),
                contents: bytemuck::bytes_of(&params),
                usage: wgpu::BufferUsages::UNIFORM,
            });
        let pos = storage_init(
            ctx,
            "positions",
            bytemuck::cast_slice(&model.packed_positions()),
            copy,
        );
        let vel = storage_init(
            ctx,
            "velocities",
            bytemuck::cast_slice(&model.packed_velocities()),
            copy,
        );
        let force = storage_init(ctx, "forces", &vec![0u8; 16 * n as usize], copy);
        let state_bytes = 16 * n as u64;
        let staging = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("staging"),
            size: (2 * state_bytes).max(16),
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });

        let needs_substep = plan.contains(Pass::WindForces);
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

        let mut stages = Vec::new();
        for &pass in &plan.passes {
            // Stage-specific buffers live only as long as the bind group that holds them.
            let mut owned: Vec<wgpu::Buffer> = Vec::new();
            let mut add = |label: &'static str, bytes: &[u8]| {
                labels.push(label);
                owned.push(storage_init(ctx, label, bytes, wgpu::BufferUsages::empty()));
                owned.len() - 1
            };
            let extra: Vec<usize> = match pass {
                Pass::SpringForces => {
                    let csr = model.spring_csr();
                    vec![
                        add("spring_offsets", bytemuck::cast_slice(&csr.offsets)),
                        add("springs", bytemuck::cast_slice(&csr.items)),
                    ]
                }
                Pass::BendingForces => {
                    let csr = model.hinge_csr();
                    vec![
                        add("hinge_offsets", bytemuck::cast_slice(&csr.offsets)),
                        add("hinge_refs", bytemuck::cast_slice(&csr.items)),
                        add("hinges", bytemuck::cast_slice(&model.hinges)),
                    ]
                }
                Pass::WindForces => {
                    let csr = model.triangle_csr();
                    vec![
                        add("triangle_offsets", bytemuck::cast_slice(&csr.offsets)),
                        add("triangle_refs", bytemuck::cast_slice(&csr.items)),
                        add("triangles", bytemuck::cast_slice(&model.packed_triangles())),
                    ]
                }
                Pass::Integrate => vec![],
            };
            let o = |k: usize| &owned[extra[k]];
            let substep_buf = substeps.as_ref().map(|s| &s.buffer);
            let bindings: Vec<(Access, &wgpu::Buffer)> = match pass {
                Pass::SpringForces => vec![
                    (Access::Uniform, &params_buf),
                    (Access::Read, &pos),
                    (Access::Read, &vel),
                    (Access::ReadWrite, &force),
                    (Access::Read, o(0)),
                    (Access::Read, o(1)),
                ],
                Pass::BendingForces => vec![
                    (Access::Uniform, &params_buf),
                    (Access::Read, &pos),
                    (Access::ReadWrite, &force),
                    (Access::Read, o(0)),
                    (Access::Read, o(1)),
                    (Access::Read, o(2)),
                ],
                Pass::WindForces => vec![
                    (Access::Uniform, &params_buf),
                    (
                        Access::SubstepUniform,
                        substep_buf.expect("wind needs substep params"),
                    ),
                    (Access::Read, &pos),
                    (Access::Read, &vel),
                    (Access::ReadWrite, &force),
                    (Access::Read, o(0)),
                    (Access::Read, o(1)),
                    (Access::Read, o(2)),
                ],
                Pass::Integrate => vec![
                    (Access::Uniform, &params_buf),
                    (Access::ReadWrite, &pos),
                    (Access::ReadWrite, &vel),
                    (Access::ReadWrite, &force),
                ],
            };
            stages.push(build_stage(ctx, pass, &bindings));
        }

        let total_groups = n.div_ceil(WORKGROUP_SIZE).max(1);
        let max_x = ctx.device.limits().max_compute_workgroups_per_dimension;
        let groups = if total_groups <= max_x {
            (total_groups, 1)
        } else {
            (max_x, total_groups.div_ceil(max_x))
        };
        Ok(GpuSolver {
            ctx: ctx.clone(),
            n,
            pos,
            vel,
            force,
            staging,
            substeps,
            stages,
            buffer_labels: labels,
            groups,
        })
    }

    /// The stages that have a pipeline, in order.
    pub fn pipeline_passes(&self) -> Vec<Pass> {
        self.stages.iter().map(|s| s.pass).collect()
    }

    /// Labels of every buffer this solver created.
    pub fn buffer_labels(&self) -> &[&'static str] {
        &self.buffer_labels
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
                        cpass.set_bind_group(0, &stage.bind_group, &offset);
                        cpass.dispatch_workgroups(self.groups.0, self.groups.1, 1);
                    }
                }
            }
            self.ctx.queue.submit([encoder.finish()]);
        }
        Ok(())
    }

    /// Uploads positions and velocities and clears forces.
    pub fn set_state(&mut self, state: &ParticleState) {
        let q = &self.ctx.queue;
        q.write_buffer(&self.pos, 0, bytemuck::cast_slice(&state.positions));
        q.write_buffer(&self.vel, 0, bytemuck::cast_slice(&state.velocities));
        q.write_buffer(&self.force, 0, &vec![0u8; 16 * self.n as usize]);
    }

    /// Reads the force accumulator back (for per-stage parity tests).
    pub fn forces(&mut self) -> Result<Vec<Vec4>, Error> {
        Ok(self.read_back(&[&self.force])?.remove(0))
    }

    fn read_back(&self, buffers: &[&wgpu::Buffer]) -> Result<Vec<Vec<Vec4>>, Error> {
        let bytes = 16 * self.n as u64;
        let mut encoder = self.ctx.device.create_command_encoder(&Default::default());
        for (k, b) in buffers.iter().enumerate() {
            encoder.copy_buffer_to_buffer(b, 0, &self.staging, k as u64 * bytes, bytes);
        }
        self.ctx.queue.submit([encoder.finish()]);
        let total = bytes * buffers.len() as u64;
        let slice = self.staging.slice(..total);
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
        let out = {
            let view = slice
                .get_mapped_range()
                .map_err(|e| Error::Gpu(format!("reading the staging buffer failed: {e}")))?;
            let all: &[Vec4] = bytemuck::cast_slice(&view);
            all.chunks(self.n as usize).map(|c| c.to_vec()).collect()
        };
        self.staging.unmap();
        Ok(out)
    }
}

fn build_stage(ctx: &GpuContext, pass: Pass, bindings: &[(Access, &wgpu::Buffer)]) -> Stage {
    let device = &ctx.device;
    let substep_size = NonZeroU64::new(std::mem::size_of::<SubstepParams>() as u64);
    let layout_entries: Vec<wgpu::BindGroupLayoutEntry> = bindings
        .iter()
        .enumerate()
        .map(|(i, (access, _))| {
            let ty = match access {
                Access::Uniform => wgpu::BufferBindingType::Uniform,
                Access::SubstepUniform => wgpu::BufferBindingType::Uniform,
                Access::Read => wgpu::BufferBindingType::Storage { read_only: true },
                Access::ReadWrite => wgpu::BufferBindingType::Storage { read_only: false },
            };
            let dynamic = matches!(access, Access::SubstepUniform);
            wgpu::BindGroupLayoutEntry {
                binding: i as u32,
                visibility: wgpu::ShaderStages::COMPUTE,
                ty: wgpu::BindingType::Buffer {
                    ty,
                    has_dynamic_offset: dynamic,
                    min_binding_size: if dynamic { substep_size } else { None },
                },
                count: None,
            }
        })
        .collect();
    let bgl = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some(pass.name()),
        entries: &layout_entries,
    });
    let entries: Vec<wgpu::BindGroupEntry> = bindings
        .iter()
        .enumerate()
        .map(|(i, (access, buffer))| wgpu::BindGroupEntry {
            binding: i as u32,
            resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                buffer,
                offset: 0,
                // The dynamic binding covers one entry; the offset selects which.
                size: if matches!(access, Access::SubstepUniform) {
                    substep_size
                } else {
                    None
                },
            }),
        })
        .collect();
    let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some(pass.name()),
        layout: &bgl,
        entries: &entries,
    });
    let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some(pass.name()),
        bind_group_layouts: &[Some(&bgl)],
        immediate_size: 0,
    });
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(pass.name()),
        source: wgpu::ShaderSource::Wgsl(compose(pass).into()),
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
        bind_group,
        uses_substep: bindings
            .iter()
            .any(|(a, _)| matches!(a, Access::SubstepUniform)),
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

    fn state(&mut self) -> Result<ParticleState, Error> {
        let mut out = self.read_back(&[&self.pos, &self.vel])?;
        let velocities = out.pop().unwrap_or_default();
        let positions = out.pop().unwrap_or_default();
        Ok(ParticleState {
            positions,
            velocities,
        })
    }
}
