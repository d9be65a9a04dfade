//! The GPU backend: one compute pipeline per planned stage, all substeps of a batch encoded
//! into one submission, readback through a MAP_READ staging buffer only when asked.
//!
//! Every array is a [`TexelArray`]. Positions and velocities ping-pong between two textures
//! (integrate reads one pair and writes the other), so each stage has one bind group per
//! parity. Force stages chain through at most two force textures: stage j writes `forces[j % 2]`
//! and reads `forces[(j + 1) % 2]`, except the first, which starts from zero.

use super::context::GpuContext;
use super::elements::{element_arrays, stage_elements};
use super::implicit::{ImplicitSolve, Shared, SolveOptions};
use super::kernels::{compose_with, ForceInput, VbdEnergies};
use super::pipelines::{build_stage, Binding, Stage};
use super::profile::Profiler;
use super::texels::TexelArray;
use crate::error::Error;
use crate::model::layout::{SimParams, SubstepParams, WORKGROUP_SIZE};
use crate::model::ClothModel;
use crate::plan::{HingeEvaluation, Pass, PassPlan};
use crate::solver::{AdapterReport, ParticleState, Solver};
use glam::Vec4;
use wgpu::util::DeviceExt;
use wgpu::TextureFormat::Rgba32Float;

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
    /// `SimParams::tolerance` as last set (the host's copy, for the residual).
    pub(super) tolerance: f32,
    pub(super) pos: [TexelArray; 2],
    pub(super) vel: [TexelArray; 2],
    pub(super) forces: Vec<TexelArray>,
    /// What `hinge_forces` writes and `integrate` gathers: four texels per hinge, in CSR order.
    pub(super) hinge_forces: Option<TexelArray>,
    /// Which of `pos`/`vel` holds the current state.
    pub(super) current: usize,
    /// Which of `forces` the last force stage wrote.
    pub(super) last_forces: usize,
    pub(super) n: usize,
    /// Each particle's hinge refs in CSR order (the order `hinge_forces` writes in), for
    /// reading its forces back.
    pub(super) hinge_refs: Vec<u32>,
    pub(super) staging: wgpu::Buffer,
    pub(super) substeps: Option<SubstepBuffer>,
    pub(super) stages: Vec<Stage>,
    pub(super) resource_labels: Vec<&'static str>,
    pub(super) hash: Option<HashBuffers>,
    /// Implicit Euler's solve, when the plan steps by it.
    pub(super) implicit: Option<ImplicitSolve>,
    /// The plan's stages in order (`vbd_solve` has no stage of its own: `implicit` runs it).
    pub(super) passes: Vec<Pass>,
    /// The `monitor` stage's per-workgroup partials (two `vec4<u32>` each).
    pub(super) health: wgpu::Buffer,
    /// GPU timestamps per stage, once `start_profile` was called.
    pub(super) profile: Option<Profiler>,
}

impl GpuSolver {
    /// How the GPU evaluates hinges unless the plan says otherwise: once per vertex, measured
    /// faster on lavapipe than once per hinge (docs/src/benchmarks/throughput.md; unmeasured on real GPUs).
    pub const HINGES: HingeEvaluation = HingeEvaluation::PerVertex;

    /// Uploads `model` and builds the pipelines of `plan` (with hinges as `HINGES` if the plan
    /// leaves it open). `max_batch` is the most substeps one `advance` call submits at once
    /// (longer calls are split into batches of that size).
    ///
    /// ```
    /// use drapekit::cpu::CpuSolver;
    /// use drapekit::gpu::{AdapterChoice, GpuContext, GpuSolver};
    /// use drapekit::scene::Scene;
    /// use drapekit::sim::{prepare, substep_params};
    /// use drapekit::solver::Solver;
    /// use std::path::Path;
    ///
    /// let dir = Path::new(env!("CARGO_MANIFEST_DIR"));
    /// let prep = prepare(&Scene::load(&dir.join("fixtures/scenes/hanging_cloth.toml"))?)?;
    /// // wgpu's software adapter (Mesa's lavapipe), present wherever the tests run.
    /// let Ok(ctx) = GpuContext::new(&AdapterChoice::Fallback) else {
    ///     return Ok(()); // no adapter on this machine
    /// };
    /// let mut gpu = GpuSolver::new(&ctx, &prep.model, prep.params, &prep.plan, 64)?;
    /// let mut cpu = CpuSolver::new(&prep.model, prep.params, &prep.plan);
    /// let steps = substep_params(&prep, 1);
    /// gpu.advance(&steps)?;
    /// cpu.advance(&steps)?;
    /// // The GPU pass and its CPU twin agree (bit for bit on lavapipe; within rounding elsewhere).
    /// let (g, c) = (gpu.state()?, cpu.state()?);
    /// let apart = g.positions.iter().zip(&c.positions).map(|(a, b)| (*a - *b).length());
    /// assert!(apart.fold(0.0f32, f32::max) < 1e-4);
    /// # Ok::<(), drapekit::Error>(())
    /// ```
    pub fn new(
        ctx: &GpuContext,
        model: &ClothModel,
        params: SimParams,
        plan: &PassPlan,
        max_batch: usize,
    ) -> Result<Self, Error> {
        let options = SolveOptions::for_adapter(ctx);
        Self::with_options(ctx, model, params, plan, max_batch, options)
    }

    /// `new`, with the implicit solve's level operations run as `options` says.
    pub fn with_options(
        ctx: &GpuContext,
        model: &ClothModel,
        params: SimParams,
        plan: &PassPlan,
        max_batch: usize,
        options: SolveOptions,
    ) -> Result<Self, Error> {
        let plan = &plan.for_backend(Self::HINGES);
        let n = model.len();
        // The kernels loop over `num_bodies` bodies and index the SDF texture by their offsets:
        // more than the model's bodies would read past its nodes.
        if plan.contains(Pass::CollideBody) && params.num_bodies as usize != model.colliders.len() {
            return Err(Error::Gpu(format!(
                "{} bodies in the parameters but {} in the model",
                params.num_bodies,
                model.colliders.len()
            )));
        }
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
        // `integrate` always reads a force texture; implicit steps need one only for wind.
        let force_textures = if plan.contains(Pass::Integrate) {
            force_stages.clamp(1, 2)
        } else {
            force_stages.min(2)
        };
        let forces = (0..force_textures)
            .map(|_| TexelArray::new(ctx, "forces", Rgba32Float, n, state_usage))
            .collect::<Result<Vec<_>, _>>()?;
        let hinge_forces = match plan.contains(Pass::HingeForces) {
            true => {
                labels.push("hinge_forces");
                let len = 4 * model.hinges.len();
                Some(TexelArray::new(
                    ctx,
                    "hinge_forces",
                    Rgba32Float,
                    len,
                    state_usage,
                )?)
            }
            false => None,
        };
        let staging = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("staging"),
            size: 2 * pos[0].padded_bytes(),
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });

        let needs_substep = [
            Pass::WindForces,
            Pass::SeamForces,
            Pass::CollideBody,
            Pass::VbdSolve,
        ]
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
        let implicit = match plan.contains(Pass::VbdSolve) {
            true => {
                let shared = Shared {
                    ctx,
                    params: &params_buf,
                    substeps: &substeps
                        .as_ref()
                        .expect("the solve has substep params")
                        .buffer,
                    pos: &pos,
                    labels: &mut labels,
                };
                Some(ImplicitSolve::new(shared, model, &params, plan, options)?)
            }
            false => None,
        };
        let energies = VbdEnergies {
            bending: !model.hinges.is_empty(),
            seams: !model.seams.is_empty(),
            body: plan.contains(Pass::CollideBody),
            membrane: !model.membranes.is_empty(),
        };
        let dispatch_for = |threads: u32| {
            let total = threads.div_ceil(WORKGROUP_SIZE).max(1);
            let max_x = ctx.device.limits().max_compute_workgroups_per_dimension;
            if total <= max_x {
                (total, 1)
            } else {
                (max_x, total.div_ceil(max_x))
            }
        };
        let (gx, gy) = dispatch_for(n as u32);
        labels.push("health_partials");
        let health = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("health_partials"),
            size: 32 * (gx * gy) as u64,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let mut stages = Vec::new();
        let mut force_index = 0;
        // The substep plan, then the per-frame monitor.
        for &pass in plan.passes.iter().chain(&[Pass::Monitor]) {
            if pass == Pass::VbdSolve {
                continue;
            }
            // integrate's bending section gathers what hinge_forces wrote.
            let energies = match pass {
                Pass::Integrate => VbdEnergies {
                    bending: hinge_forces.is_some(),
                    seams: false,
                    body: false,
                    membrane: false,
                },
                _ => energies,
            };
            // Stage-specific arrays live as long as the bind groups that hold them.
            let mut owned: Vec<TexelArray> = Vec::new();
            for kind in stage_elements(pass, energies) {
                for (label, format, bytes) in element_arrays(model, kind) {
                    labels.push(label);
                    let (layout, none) = (kind.layout(ctx.layout), wgpu::TextureUsages::empty());
                    owned.push(TexelArray::with_data_in(
                        layout, ctx, label, format, &bytes, none,
                    )?);
                }
            }
            let (force_out, force_in) = if pass.is_force() {
                let j = force_index;
                force_index += 1;
                (Some(j % 2), (j > 0).then_some((j + 1) % 2))
            } else if pass.reads_forces() {
                // vbd_init reads the last force stage's sum, if any ran.
                (None, (force_index > 0).then(|| (force_index - 1) % 2))
            } else {
                (None, None)
            };
            // The forces integrate reads: the last force stage's output (zero if none ran).
            let summed = (force_stages + 1) % 2 % forces.len().max(1);
            let vb = || &implicit.as_ref().expect("the implicit solve").buffers;
            let substep_buf = substeps.as_ref().map(|s| &s.buffer);
            let hb = || hash.as_ref().expect("self-collision buffers");
            let bindings = |p: usize| -> Vec<Binding> {
                let o = |k: usize| Binding::Read(&owned[k]);
                let out = || Binding::Write(&forces[force_out.expect("force stage")]);
                let per_hinge = || hinge_forces.as_ref().expect("hinge_forces is in the plan");
                match pass {
                    Pass::HingeForces => vec![
                        Binding::Uniform(&params_buf),
                        Binding::Read(&pos[p]),
                        o(0),
                        o(1),
                        o(2),
                        Binding::Write(per_hinge()),
                    ],
                    Pass::SpringForces => vec![
                        Binding::Uniform(&params_buf),
                        Binding::Read(&pos[p]),
                        Binding::Read(&vel[p]),
                        out(),
                        o(0),
                        o(1),
                    ],
                    Pass::MembraneForces => vec![
                        Binding::Uniform(&params_buf),
                        Binding::Read(&pos[p]),
                        Binding::Read(&vel[p]),
                        out(),
                        o(0),
                        o(1),
                        o(2),
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
                    Pass::VbdInit => vec![
                        Binding::Uniform(&params_buf),
                        Binding::Read(&pos[p]),
                        Binding::Read(&vel[p]),
                        Binding::Storage(&vb().disp, false),
                        Binding::Storage(&vb().target, false),
                        Binding::Storage(&vb().steps, false),
                        Binding::Storage(&vb().control, false),
                    ],
                    Pass::VbdSolve => unreachable!("the implicit solve has no stage"),
                    Pass::VbdFinish => vec![
                        Binding::Uniform(&params_buf),
                        Binding::Read(&pos[p]),
                        Binding::Storage(&vb().disp, true),
                        Binding::Write(&pos[1 - p]),
                        Binding::Write(&vel[1 - p]),
                    ],
                    Pass::StrainLimit => vec![
                        Binding::Uniform(&params_buf),
                        Binding::Read(&pos[p]),
                        Binding::Read(&vel[p]),
                        o(0),
                        o(1),
                        Binding::Write(&pos[1 - p]),
                        Binding::Write(&vel[1 - p]),
                    ],
                    Pass::Monitor => vec![
                        Binding::Uniform(&params_buf),
                        Binding::Read(&pos[p]),
                        Binding::Read(&vel[p]),
                        o(0),
                        o(1),
                        Binding::Storage(&health, false),
                    ],
                    Pass::Integrate => {
                        let mut list = vec![
                            Binding::Uniform(&params_buf),
                            Binding::Read(&pos[p]),
                            Binding::Read(&vel[p]),
                            Binding::Read(&forces[summed]),
                            Binding::Write(&pos[1 - p]),
                            Binding::Write(&vel[1 - p]),
                        ];
                        list.extend(match hinge_forces.is_some() {
                            true => [o(0), Binding::Read(per_hinge())],
                            false => [Binding::Gap; 2],
                        });
                        list
                    }
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
                Pass::HingeForces => dispatch_for(model.hinges.len() as u32),
                _ => dispatch_for(n as u32),
            };
            let mut stage = build_stage(
                ctx,
                pass,
                compose_with(pass, input, energies),
                [&bindings(0), &bindings(1)],
                force_in.as_ref().map(|b| &b[..]),
                force_out,
                dispatch,
            );
            if pass == Pass::StrainLimit {
                stage.repeats = params.strain_iterations;
            }
            stages.push(stage);
        }

        Ok(GpuSolver {
            ctx: ctx.clone(),
            params: params_buf,
            tolerance: params.tolerance,
            pos,
            vel,
            forces,
            hinge_forces,
            current: 0,
            last_forces: 0,
            n,
            hinge_refs: match plan.contains(Pass::HingeForces) {
                true => model.hinge_csr().items,
                false => Vec::new(),
            },
            staging,
            substeps,
            stages,
            resource_labels: labels,
            hash,
            implicit,
            passes: plan.passes.clone(),
            health,
            profile: None,
        })
    }

    /// From now on, times every stage (and every dispatch of the implicit solve) on the GPU,
    /// one substep per submission; the context must have been opened with timestamps.
    pub fn start_profile(&mut self) -> Result<(), Error> {
        self.profile = Some(Profiler::new(&self.ctx)?);
        Ok(())
    }

    /// What `start_profile` measured so far.
    pub fn profile(&self) -> Option<&Profiler> {
        self.profile.as_ref()
    }

    /// The plan's stages in order: what `advance` runs each substep.
    pub fn passes(&self) -> &[Pass] {
        &self.passes
    }

    /// The stages that have pipelines, in order (`monitor` last, which `advance` leaves to
    /// `health`).
    pub fn pipeline_passes(&self) -> Vec<Pass> {
        let mut passes = self.passes.clone();
        passes.push(Pass::Monitor);
        passes
    }

    /// Dispatches encoded per substep: one per stage, a Jacobi stage's iterations, and the
    /// implicit solve's.
    pub fn dispatches_per_substep(&self) -> usize {
        (self.passes.iter())
            .map(|&p| match p {
                Pass::VbdSolve => self.implicit.as_ref().map_or(0, |s| s.dispatches()),
                _ => (self.stages.iter())
                    .find(|s| s.pass == p)
                    .map_or(0, |s| s.repeats as usize),
            })
            .sum()
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
        // The plan's stages only: `monitor` runs once per frame, in `health`, as on the CPU.
        let passes = self.passes.clone();
        if let Some(p) = self.profile.as_mut() {
            p.add_substeps(steps.len());
        }
        self.run_passes(&passes, steps)
    }

    fn finish(&mut self) -> Result<(), Error> {
        self.ctx
            .device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| Error::Gpu(format!("waiting for the GPU failed: {e}")))?;
        Ok(())
    }

    fn health(&mut self) -> Result<crate::solver::Health, Error> {
        self.run_passes(&[Pass::Monitor], &[SubstepParams::default()])?;
        let words = self.read_u32(&self.health)?;
        let partials: Vec<_> = words
            .chunks_exact(8)
            .map(|w| crate::solver::HealthPartial {
                kinetic_energy: f32::from_bits(w[0]),
                gravity_energy: f32::from_bits(w[6]),
                elastic_energy: f32::from_bits(w[7]),
                max_speed: f32::from_bits(w[1]),
                max_strain: f32::from_bits(w[2]),
                worst: w[3],
                non_finite: w[4],
                first_non_finite: w[5],
            })
            .collect();
        Ok(crate::solver::Health::from_partials(&partials))
    }

    fn residual(&mut self) -> Result<Option<crate::solver::SolveProgress>, Error> {
        let Some(solve) = &self.implicit else {
            return Ok(None);
        };
        let words = self.read_u32(&solve.buffers.steps)?;
        let control = self.solve_control()?;
        let newton_run = self.solve_scalars()?.newton_steps;
        let (steps, count) = words.split_at(words.len() - 1);
        let steps: Vec<f32> = steps.iter().map(|&w| f32::from_bits(w)).collect();
        let solve = self.implicit.as_mut().expect("checked above");
        let sweeps = count[0].wrapping_sub(solve.sweeps_reported);
        solve.sweeps_reported = count[0];
        let newton_steps = newton_run.wrapping_sub(solve.newton_reported);
        solve.newton_reported = newton_run;
        Ok(Some(crate::solver::SolveProgress {
            relative_residual: crate::solver::relative_residual(&steps),
            force_residual: (control.residual_max, control.residual_rms),
            newton_steps: newton_steps as u64,
            iterations: sweeps as u64,
        }))
    }

    fn set_params(&mut self, params: &SimParams) {
        self.tolerance = params.tolerance;
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

    fn positions(&mut self) -> Result<Vec<Vec4>, Error> {
        Ok(self.read_back(&[&self.pos[self.current]])?.remove(0))
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
