//! Implicit Euler's solve on the GPU: a substep's whole `plan::implicit_schedule` (sweeps,
//! Newton steps with multigrid-preconditioned conjugate gradients, line searches, force
//! residuals) encoded into the frame's one submission. At setup the schedule is expanded into
//! its dispatches (`dispatch`), the hierarchy packed (`hierarchy`) and one pipeline built per
//! kernel it uses (`kernels`); per substep the dispatches are encoded with the substep's
//! uniform offset. Decisions (conjugate gradients' α and β, the line search's step, the
//! tolerance check) stay on the device: nothing is read back inside a frame.

mod access;
mod dispatch;
mod hierarchy;
pub mod kernels;
pub mod layout;
mod resources;

pub use access::SolveArray;
pub use kernels::{Include, Res, SolveKernel};

use super::context::GpuContext;
use super::kernels::VbdEnergies;
use super::profile::Profiler;
use super::texels::TexelArray;
use crate::error::Error;
use crate::model::layout::SimParams;
use crate::model::ClothModel;
use crate::plan::{implicit_schedule, PassPlan, SolveOp, SolveShape};
use dispatch::{Builder, Dispatch, Tables};
use hierarchy::LevelInfo;
use layout::OpParams;
use resources::{check_storage_limit, KernelPipeline, Resources, Sizes, SolveTextures};
use std::collections::HashMap;

pub(super) use resources::SolveBuffers;

/// How the GPU runs the solve's level operations.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SolveOptions {
    /// Level operations (smoothing, residuals, restriction, prolongation) over at most this
    /// many rows run back to back in one single-workgroup dispatch (`coarse_cycle`) instead of
    /// one dispatch per colour or operation.
    pub small_rows: u32,
    /// `coarse_cycle` smooths levels of at most this many rows in workgroup memory (0: none;
    /// at most what the device's workgroup memory holds, 12 bytes a row).
    pub cached_rows: u32,
}

impl SolveOptions {
    /// On a hardware GPU, levels of up to 1,024 particles run in one workgroup (a few rows per
    /// invocation per colour). On a software adapter, where a dispatch costs about 56 µs and a
    /// workgroup runs on one CPU thread anyway, every level does: the whole V-cycle is one
    /// dispatch. A hardware GPU smooths each of those levels in workgroup memory (12 KiB for
    /// 1,024 rows, within every adapter's 16 KiB), where a software adapter's workgroup
    /// memory is ordinary memory and gains nothing.
    pub fn for_adapter(ctx: &GpuContext) -> SolveOptions {
        match ctx.is_software() {
            true => SolveOptions {
                small_rows: u32::MAX,
                cached_rows: 0,
            },
            false => SolveOptions {
                small_rows: 1024,
                cached_rows: 1024,
            },
        }
    }
}

/// Implicit Euler's solve: buffers, pipelines and the substep's dispatches.
pub struct ImplicitSolve {
    pub(super) buffers: SolveBuffers,
    /// The textures the kernels bind (kept alive with their bind groups).
    _textures: SolveTextures,
    pipelines: HashMap<SolveKernel, KernelPipeline>,
    /// The substep's operations and their dispatches.
    schedule: Vec<SolveOp>,
    dispatches: Vec<Dispatch>,
    /// How many of `dispatches`, at the end, measure the final force residual.
    final_residual: usize,
    tables: Tables,
    /// Entries the `OpParams` and op-list buffers hold.
    capacity: (usize, usize),
    op_stride: u64,
    levels: Vec<LevelInfo>,
    small_rows: u32,
    max_groups_x: u32,
    /// Particles.
    n: u32,
    /// The count of sweeps run when last reported (it wraps at 2³²).
    pub(super) sweeps_reported: u32,
    /// The count of Newton steps run when last reported (it wraps at 2³²).
    pub(super) newton_reported: u32,
}

/// Extra entries the `OpParams` and op-list buffers keep for operations run alone (tests).
const SPARE_ENTRIES: usize = 256;

/// What `ImplicitSolve::new` needs of the solver it belongs to.
pub(super) struct Shared<'a> {
    pub(super) ctx: &'a GpuContext,
    pub(super) params: &'a wgpu::Buffer,
    pub(super) substeps: &'a wgpu::Buffer,
    pub(super) pos: &'a [TexelArray; 2],
    pub(super) labels: &'a mut Vec<&'static str>,
}

impl ImplicitSolve {
    /// The solve of `model` stepping with `params` through `plan`'s schedule.
    pub(super) fn new(
        shared: Shared,
        model: &ClothModel,
        params: &SimParams,
        plan: &PassPlan,
        options: SolveOptions,
    ) -> Result<ImplicitSolve, Error> {
        let ctx = shared.ctx;
        let device = &ctx.device;
        let n = model.len() as u32;
        let schedule = implicit_schedule(SolveShape::for_run(model, params, plan));
        refuse_cpu_only(&schedule)?;
        let packed = hierarchy::pack(model);
        let max_groups_x = device.limits().max_compute_workgroups_per_dimension;
        let mut tables = Tables::default();
        let mut builder = Builder {
            levels: &packed.levels,
            small_rows: options.small_rows,
            max_groups_x,
            tables: &mut tables,
            cg: 0,
        };
        let dispatches = builder.expand(&schedule);
        // Every operation alone too, for `run_solve_ops`.
        for op in &schedule {
            builder.expand(std::slice::from_ref(op));
        }
        // The final force residual's dispatches, which only a batch's last substep runs.
        let final_residual = match schedule.last() {
            Some(&SolveOp::ForceResidual) => builder.expand(&[SolveOp::ForceResidual]).len(),
            _ => 0,
        };
        let kernels: Vec<SolveKernel> = (SolveKernel::ALL.into_iter())
            .filter(|k| dispatches.iter().any(|d| d.kernel == *k))
            .collect();
        let energies = VbdEnergies {
            bending: !model.hinges.is_empty(),
            seams: !model.seams.is_empty(),
            body: false,
            membrane: !model.membranes.is_empty(),
        };
        check_storage_limit(ctx, &kernels, energies)?;

        let align = device.limits().min_uniform_buffer_offset_alignment as u64;
        let (gx, gy) = dispatch::dispatch_for(n, max_groups_x);
        let sizes = Sizes {
            n: n as usize,
            bodies: (params.num_bodies as usize).max(1),
            sweeps: (schedule.iter())
                .filter(|op| matches!(op, SolveOp::Sweep { .. }))
                .count(),
            newton: schedule.contains(&SolveOp::Assemble),
            groups: (gx * gy) as usize,
            capacity: (
                tables.params.len() + SPARE_ENTRIES,
                tables.op_list.len() + SPARE_ENTRIES,
            ),
            op_stride: (std::mem::size_of::<OpParams>() as u64).next_multiple_of(align),
        };
        let buffers = SolveBuffers::new(ctx, shared.labels, &sizes, &packed)?;
        let contact = kernels.contains(&SolveKernel::ContactPlanes);
        let kinds = (sizes.newton, contact);
        let textures = SolveTextures::new(ctx, shared.labels, model, &packed, kinds)?;
        let resources = Resources {
            buffers: &buffers,
            textures: &textures,
            params: shared.params,
            substeps: shared.substeps,
            pos: shared.pos,
            layout: ctx.layout,
            // Three floats a row, and three spare (the array's size when nothing is cached).
            cached_rows: (options.cached_rows)
                .min((device.limits().max_compute_workgroup_storage_size / 12).saturating_sub(1)),
        };
        let pipelines = resources.pipelines(device, &kernels, energies);
        let mut solve = ImplicitSolve {
            buffers,
            _textures: textures,
            pipelines,
            schedule,
            dispatches,
            final_residual,
            tables,
            capacity: sizes.capacity,
            op_stride: sizes.op_stride,
            levels: packed.levels,
            small_rows: options.small_rows,
            max_groups_x,
            n,
            sweeps_reported: 0,
            newton_reported: 0,
        };
        solve.upload_tables(ctx);
        Ok(solve)
    }

    /// Writes the `OpParams` entries and op lists to their buffers.
    fn upload_tables(&mut self, ctx: &GpuContext) {
        let stride = self.op_stride as usize;
        let mut bytes = vec![0u8; stride * self.tables.params.len()];
        for (k, p) in self.tables.params.iter().enumerate() {
            bytes[k * stride..k * stride + std::mem::size_of::<OpParams>()]
                .copy_from_slice(bytemuck::bytes_of(p));
        }
        ctx.queue.write_buffer(&self.buffers.op_params, 0, &bytes);
        if !self.tables.op_list.is_empty() {
            let list = bytemuck::cast_slice(&self.tables.op_list);
            ctx.queue.write_buffer(&self.buffers.op_list, 0, list);
        }
    }

    /// The substep's operations.
    pub fn schedule(&self) -> &[SolveOp] {
        &self.schedule
    }

    /// Dispatches the solve encodes per substep.
    pub fn dispatches(&self) -> usize {
        self.dispatches.len()
    }

    /// Encodes the substep's whole solve: xₙ in `pos[parity]`, the substep's uniform at
    /// `substep_offset`. The final force residual runs only where it is `measured` (a batch's
    /// last substep, whose residual is read back), as on the CPU.
    pub(super) fn encode(
        &self,
        cpass: &mut wgpu::ComputePass,
        parity: usize,
        substep_offset: u32,
        measured: bool,
        profile: Option<&mut Profiler>,
    ) {
        let end = match measured {
            true => self.dispatches.len(),
            false => self.dispatches.len() - self.final_residual,
        };
        let dispatches = &self.dispatches[..end];
        self.encode_dispatches(cpass, dispatches, parity, substep_offset, profile);
    }

    fn encode_dispatches(
        &self,
        cpass: &mut wgpu::ComputePass,
        dispatches: &[Dispatch],
        parity: usize,
        substep_offset: u32,
        mut profile: Option<&mut Profiler>,
    ) {
        for d in dispatches {
            let k = &self.pipelines[&d.kernel];
            cpass.set_pipeline(&k.pipeline);
            let op_offset = (d.op as u64 * self.op_stride) as u32;
            cpass.set_bind_group(0, &k.groups[parity], &[substep_offset, op_offset]);
            cpass.dispatch_workgroups(d.groups.0, d.groups.1, 1);
            if let Some(p) = profile.as_deref_mut() {
                p.mark(cpass, 1, || self.profile_label(d));
            }
        }
    }

    /// A dispatch's profile label: the kernel, and its level where a level has its own.
    fn profile_label(&self, d: &Dispatch) -> String {
        use SolveKernel as K;
        let level = self.tables.params[d.op as usize].level;
        let name = match d.kernel {
            K::PcgDot => "pcg_dot",
            k => k.file(),
        };
        match d.kernel {
            K::Smooth | K::LevelResidual | K::Restrict | K::Prolong | K::CoarseOperator => {
                format!("solve/{name} L{level}")
            }
            _ => format!("solve/{name}"),
        }
    }

    /// A builder of dispatches into the solver's tables.
    fn builder(&mut self) -> Builder<'_> {
        Builder {
            levels: &self.levels,
            small_rows: self.small_rows,
            max_groups_x: self.max_groups_x,
            tables: &mut self.tables,
            cg: 0,
        }
    }

    /// Encodes and submits the copy of a level's blocks to their texels (after the host wrote
    /// the blocks).
    pub(super) fn publish(&mut self, ctx: &GpuContext, level: u32) -> Result<(), Error> {
        let mut builder = self.builder();
        let mut dispatches = Vec::new();
        builder.publish(&mut dispatches, level);
        self.check_dispatches(ctx, &dispatches)?;
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        {
            let mut cpass = encoder.begin_compute_pass(&Default::default());
            self.encode_dispatches(&mut cpass, &dispatches, 0, 0, None);
        }
        ctx.queue.submit([encoder.finish()]);
        Ok(())
    }

    /// The dispatches of `ops` run alone, their new `OpParams` entries uploaded.
    fn dispatches_for(
        &mut self,
        ctx: &GpuContext,
        ops: &[SolveOp],
    ) -> Result<Vec<Dispatch>, Error> {
        refuse_cpu_only(ops)?;
        let mut builder = self.builder();
        let dispatches = builder.expand(ops);
        self.check_dispatches(ctx, &dispatches)?;
        Ok(dispatches)
    }

    /// Whether the solver can run `dispatches` (its tables hold their entries, which are
    /// uploaded, and it built their kernels).
    fn check_dispatches(&mut self, ctx: &GpuContext, dispatches: &[Dispatch]) -> Result<(), Error> {
        let (params, lists) = self.capacity;
        if self.tables.params.len() > params || self.tables.op_list.len() > lists {
            return Err(Error::Gpu("too many operations run alone".into()));
        }
        if let Some(d) = (dispatches.iter()).find(|d| !self.pipelines.contains_key(&d.kernel)) {
            return Err(Error::Gpu(format!(
                "{} is not in this solver's schedule",
                d.kernel.file()
            )));
        }
        self.upload_tables(ctx);
        Ok(())
    }
}

/// An error for operations that only the CPU runs (block-Jacobi preconditioning, which
/// `bench convergence` compares the V-cycle with).
fn refuse_cpu_only(ops: &[SolveOp]) -> Result<(), Error> {
    match ops.contains(&SolveOp::BlockJacobi) {
        true => Err(Error::Gpu(
            "block-Jacobi preconditioning runs on the CPU backend only".into(),
        )),
        false => Ok(()),
    }
}
