//! The GPU backend: one compute pipeline per planned stage, all substeps of a batch encoded
//! into one submission, readback through a MAP_READ staging buffer only when asked.
//!
//! Every array is a [`TexelArray`]. Positions and velocities ping-pong between two textures
//! (integrate reads one pair and writes the other), so each stage has one bind group per
//! parity. Force stages chain through at most two force textures: stage j writes `forces[j % 2]`
//! and reads `forces[(j + 1) % 2]`, except the first, which starts from zero.

use super::context::GpuContext;
use super::kernels::ForceInput;
use super::pipelines::{build_stage, Binding, Stage};
use super::texels::TexelArray;
use crate::error::Error;
use crate::model::layout::{SimParams, SubstepParams, WORKGROUP_SIZE};
use crate::model::ClothModel;
use crate::plan::{Pass, PassPlan};
use crate::solver::{AdapterReport, ParticleState, Solver};
use glam::Vec4;
use wgpu::util::DeviceExt;
use wgpu::TextureFormat::{R32Float, R32Uint, Rgba32Float, Rgba32Uint};

/// The self-collision spatial hash on the GPU.
pub(super) struct HashBuffers {
    pub(super) counts: wgpu::Buffer,
    pub(super) starts: wgpu::Buffer,
    pub(super) cursor: wgpu::Buffer,
    pub(super) sorted: wgpu::Buffer,
}

/// The per-substep uniform array: `capacity` entries at `stride` bytes.
pub(super) struct SubstepBuffer {
    pub(super) buffer: wgpu::Buffer,
    pub(super) stride: u64,
    pub(super) capacity: usize,
}

/// The wgpu backend. Creates textures, buffers and pipelines only for the stages in its plan.
pub struct GpuSolver {
    pub(super) ctx: GpuContext,
    pub(super) params: wgpu::Buffer,
    pub(super) pos: [TexelArray; 2],
    pub(super) vel: [TexelArray; 2],
    pub(super) forces: Vec<TexelArray>,
    /// Which of `pos`/`vel` holds the current state.
    pub(super) current: usize,
    /// Which of `forces` the last force stage wrote.
    pub(super) last_forces: usize,
    pub(super) n: usize,
    pub(super) staging: wgpu::Buffer,
    pub(super) substeps: Option<SubstepBuffer>,
    pub(super) stages: Vec<Stage>,
    pub(super) resource_labels: Vec<&'static str>,
    pub(super) hash: Option<HashBuffers>,
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
