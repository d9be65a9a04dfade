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

pub use access::SolveArray;
pub use kernels::{Include, Res, SolveKernel};

use super::context::GpuContext;
use super::elements::{element_arrays, Elements};
use super::kernels::VbdEnergies;
use super::pipelines::{compute_pipeline, numbered_bind_groups, Binding};
use super::texels::TexelArray;
use crate::error::Error;
use crate::model::layout::{SimParams, WORKGROUP_SIZE};
use crate::model::ClothModel;
use crate::plan::{implicit_schedule, PassPlan, SolveOp, SolveShape};
use dispatch::{Builder, Dispatch, Tables};
use hierarchy::LevelInfo;
use layout::{OpParams, SolveControl, SolveScalars};
use std::collections::HashMap;
use wgpu::TextureFormat::R32Uint;

/// How the GPU runs the solve's level operations.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SolveOptions {
    /// Level operations (smoothing, residuals, restriction, prolongation) over at most this
    /// many rows run back to back in one single-workgroup dispatch (`coarse_cycle`) instead of
    /// one dispatch per colour or operation.
    pub small_rows: u32,
}

impl SolveOptions {
    /// On a hardware GPU, levels of up to 1,024 particles run in one workgroup (a few rows per
    /// invocation per colour). On a software adapter, where a dispatch costs about 56 µs and a
    /// workgroup runs on one CPU thread anyway, every level does: the whole V-cycle is one
    /// dispatch.
    pub fn for_adapter(ctx: &GpuContext) -> SolveOptions {
        SolveOptions {
            small_rows: if ctx.is_software() { u32::MAX } else { 1024 },
        }
    }
}

/// The solve's buffers (see `Res` for what each holds).
pub(super) struct SolveBuffers {
    pub(super) disp: wgpu::Buffer,
    pub(super) target: wgpu::Buffer,
    pub(super) steps: wgpu::Buffer,
    pub(super) control: wgpu::Buffer,
    planes: wgpu::Buffer,
    lambdas: wgpu::Buffer,
    hier: wgpu::Buffer,
    blocks: wgpu::Buffer,
    force: wgpu::Buffer,
    correction: wgpu::Buffer,
    p: wgpu::Buffer,
    ap: wgpu::Buffer,
    rhs: wgpu::Buffer,
    e: wgpu::Buffer,
    res: wgpu::Buffer,
    partials: wgpu::Buffer,
    scalars: wgpu::Buffer,
    op_params: wgpu::Buffer,
    op_list: wgpu::Buffer,
}

/// A built kernel: its pipeline and a bind group per state parity (which `pos` texture holds
/// xₙ).
struct KernelPipeline {
    pipeline: wgpu::ComputePipeline,
    groups: [wgpu::BindGroup; 2],
}

/// Implicit Euler's solve: buffers, pipelines and the substep's dispatches.
pub struct ImplicitSolve {
    pub(super) buffers: SolveBuffers,
    /// The element and SDF textures the kernels bind (kept alive with their bind groups).
    _textures: Vec<TexelArray>,
    /// Every level's blocks as texels (kept alive with the bind groups that hold them).
    _block_texels: [TexelArray; 2],
    pipelines: HashMap<SolveKernel, KernelPipeline>,
    /// The substep's operations and their dispatches.
    schedule: Vec<SolveOp>,
    dispatches: Vec<Dispatch>,
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
        let packed = hierarchy::pack(model);
        let max_groups_x = device.limits().max_compute_workgroups_per_dimension;
        let groups = move |threads: u32| dispatch_for(threads, max_groups_x);
        let mut tables = Tables::default();
        let mut builder = Builder {
            levels: &packed.levels,
            small_rows: options.small_rows,
            groups: &groups,
            tables: &mut tables,
            cg: 0,
        };
        let dispatches = builder.expand(&schedule);
        // Every operation alone too, for `run_solve_ops`.
        for op in &schedule {
            builder.expand(std::slice::from_ref(op));
        }
        let kernels: Vec<SolveKernel> = SolveKernel::ALL
            .into_iter()
            .filter(|k| dispatches.iter().any(|d| d.kernel == *k))
            .collect();
        let energies = VbdEnergies {
            bending: !model.hinges.is_empty(),
            seams: !model.seams.is_empty(),
            body: false,
        };
        check_storage_limit(ctx, &kernels, energies)?;

        let sweeps = schedule
            .iter()
            .filter(|op| matches!(op, SolveOp::Sweep { .. }))
            .count();
        let newton = schedule.contains(&SolveOp::Assemble);
        let bodies = (params.num_bodies as usize).max(1);
        let groups_n = {
            let (gx, gy) = groups(n);
            (gx * gy) as usize
        };
        let capacity = (
            tables.params.len() + SPARE_ENTRIES,
            tables.op_list.len() + SPARE_ENTRIES,
        );
        let align = device.limits().min_uniform_buffer_offset_alignment as u64;
        let op_stride = (std::mem::size_of::<OpParams>() as u64).next_multiple_of(align);
        let max_binding = device.limits().max_storage_buffer_binding_size;
        let labels = shared.labels;
        let mut storage = |label: &'static str, bytes: usize| -> Result<wgpu::Buffer, Error> {
            if bytes as u64 > max_binding {
                return Err(Error::Gpu(format!(
                    "implicit Euler's {label} needs {bytes} bytes, but this adapter binds at most \
                     {max_binding} bytes of a storage buffer; use a coarser mesh or --backend cpu"
                )));
            }
            labels.push(label);
            Ok(device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: (bytes as u64).max(16),
                usage: wgpu::BufferUsages::STORAGE
                    | wgpu::BufferUsages::COPY_SRC
                    | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }))
        };
        let vec4 = 16;
        let per = |rows: usize| if newton { rows } else { 0 };
        let buffers = SolveBuffers {
            disp: storage("vbd_x", vec4 * n as usize)?,
            target: storage("vbd_y", vec4 * n as usize)?,
            steps: storage("vbd_steps", 4 * (sweeps.max(1) + 1))?,
            control: storage("solve_control", std::mem::size_of::<SolveControl>())?,
            planes: storage("contact_planes", vec4 * bodies * n as usize)?,
            lambdas: storage("contact_lambdas", vec4 * n as usize)?,
            hier: storage("hierarchy", 4 * packed.words.len())?,
            blocks: storage("blocks", 48 * per(packed.blocks as usize))?,
            force: storage("newton_force", vec4 * per(n as usize))?,
            correction: storage("newton_correction", vec4 * per(n as usize))?,
            p: storage("pcg_p", vec4 * per(n as usize))?,
            ap: storage("pcg_ap", vec4 * per(n as usize))?,
            rhs: storage("level_rhs", vec4 * per(packed.rows as usize))?,
            e: storage("level_e", vec4 * per(packed.rows as usize))?,
            res: storage("level_res", vec4 * per(packed.rows as usize))?,
            partials: storage("solve_partials", vec4 * groups_n)?,
            scalars: storage("solve_scalars", std::mem::size_of::<SolveScalars>())?,
            op_list: storage("coarse_cycle_ops", 16 * capacity.1)?,
            op_params: {
                labels.push("solve_ops");
                device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("solve_ops"),
                    size: op_stride * capacity.0 as u64,
                    usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                })
            },
        };
        ctx.queue
            .write_buffer(&buffers.hier, 0, bytemuck::cast_slice(&packed.words));

        labels.push("block_texels");
        let block_texels = TexelArray::new(
            ctx,
            "block_texels",
            wgpu::TextureFormat::Rgba32Float,
            3 * per(packed.blocks as usize),
            wgpu::TextureUsages::STORAGE_BINDING,
        )?;
        labels.push("block_columns");
        let none = wgpu::TextureUsages::empty();
        let columns: &[u32] = if newton { &packed.columns } else { &[] };
        let bytes = bytemuck::cast_slice(columns);
        let block_columns = TexelArray::with_data(ctx, "block_columns", R32Uint, bytes, none)?;
        // The element arrays, and every body's SDF for contact_planes.
        let mut textures = Vec::new();
        let mut kinds = vec![Elements::Springs];
        kinds.extend(energies.bending.then_some(Elements::Hinges));
        kinds.extend(energies.seams.then_some(Elements::Seams));
        kinds.extend(
            kernels
                .contains(&SolveKernel::ContactPlanes)
                .then_some(Elements::Sdf),
        );
        for kind in kinds {
            for (label, format, bytes) in element_arrays(model, kind) {
                labels.push(label);
                let none = wgpu::TextureUsages::empty();
                textures.push((
                    label,
                    TexelArray::with_data(ctx, label, format, &bytes, none)?,
                ));
            }
        }
        let texture = |label: &str| {
            let found = textures.iter().find(|(l, _)| *l == label);
            &found.expect("the kernel's textures were made").1
        };
        let resources = Resources {
            buffers: &buffers,
            params: shared.params,
            substeps: shared.substeps,
            pos: shared.pos,
            texture: &texture,
            block_texels: &block_texels,
            block_columns: &block_columns,
        };
        let pipelines = kernels
            .iter()
            .map(|&k| Ok((k, resources.pipeline(device, k, energies)?)))
            .collect::<Result<HashMap<_, _>, Error>>()?;

        let mut solve = ImplicitSolve {
            buffers,
            _textures: textures.into_iter().map(|(_, t)| t).collect(),
            _block_texels: [block_texels, block_columns],
            pipelines,
            schedule,
            dispatches,
            tables,
            capacity,
            op_stride,
            levels: packed.levels,
            small_rows: options.small_rows,
            max_groups_x,
            n,
            sweeps_reported: 0,
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
    /// `substep_offset`.
    pub(super) fn encode(&self, cpass: &mut wgpu::ComputePass, parity: usize, substep_offset: u32) {
        self.encode_dispatches(cpass, &self.dispatches, parity, substep_offset);
    }

    fn encode_dispatches(
        &self,
        cpass: &mut wgpu::ComputePass,
        dispatches: &[Dispatch],
        parity: usize,
        substep_offset: u32,
    ) {
        for d in dispatches {
            let k = &self.pipelines[&d.kernel];
            cpass.set_pipeline(&k.pipeline);
            let op_offset = (d.op as u64 * self.op_stride) as u32;
            cpass.set_bind_group(0, &k.groups[parity], &[substep_offset, op_offset]);
            cpass.dispatch_workgroups(d.groups.0, d.groups.1, 1);
        }
    }

    /// Encodes and submits the copy of a level's blocks to their texels (after the host wrote
    /// the blocks).
    pub(super) fn publish(&mut self, ctx: &GpuContext, level: u32) -> Result<(), Error> {
        let max_x = self.max_groups_x;
        let groups = move |threads: u32| dispatch_for(threads, max_x);
        let mut builder = Builder {
            levels: &self.levels,
            small_rows: self.small_rows,
            groups: &groups,
            tables: &mut self.tables,
            cg: 0,
        };
        let mut dispatches = Vec::new();
        builder.publish(&mut dispatches, level);
        self.check_dispatches(ctx, &dispatches)?;
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        {
            let mut cpass = encoder.begin_compute_pass(&Default::default());
            self.encode_dispatches(&mut cpass, &dispatches, 0, 0);
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
        let max_x = self.max_groups_x;
        let groups = move |threads: u32| dispatch_for(threads, max_x);
        let mut builder = Builder {
            levels: &self.levels,
            small_rows: self.small_rows,
            groups: &groups,
            tables: &mut self.tables,
            cg: 0,
        };
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

/// Workgroups (x, y) for `threads` invocations: 2D past the adapter's per-dimension limit.
fn dispatch_for(threads: u32, max_x: u32) -> (u32, u32) {
    let total = threads.div_ceil(WORKGROUP_SIZE).max(1);
    if total <= max_x {
        (total, 1)
    } else {
        (max_x, total.div_ceil(max_x))
    }
}

/// The storage buffers one stage may bind on `ctx`'s device must cover the kernels'.
fn check_storage_limit(
    ctx: &GpuContext,
    kernels: &[SolveKernel],
    energies: VbdEnergies,
) -> Result<(), Error> {
    let limit = ctx.device.limits().max_storage_buffers_per_shader_stage;
    for &k in kernels {
        let used = k
            .binds(energies)
            .iter()
            .filter(|(r, _)| r.is_storage())
            .count() as u32;
        if used > limit {
            return Err(Error::Gpu(format!(
                "implicit Euler's {} kernel binds {used} storage buffers, but this device allows \
                 {limit} per stage; use --backend cpu",
                k.file()
            )));
        }
    }
    Ok(())
}

/// Everything a solve kernel may bind.
struct Resources<'a> {
    buffers: &'a SolveBuffers,
    params: &'a wgpu::Buffer,
    substeps: &'a wgpu::Buffer,
    pos: &'a [TexelArray; 2],
    texture: &'a dyn Fn(&str) -> &'a TexelArray,
    block_texels: &'a TexelArray,
    block_columns: &'a TexelArray,
}

impl<'a> Resources<'a> {
    fn binding(&self, res: Res, writable: bool, parity: usize) -> Binding<'a> {
        let b = self.buffers;
        let storage = |buffer| Binding::Storage(buffer, !writable);
        let t = |label| Binding::Read((self.texture)(label));
        match res {
            Res::Params => Binding::Uniform(self.params),
            Res::Step => Binding::SubstepUniform(self.substeps),
            Res::Op => Binding::Dynamic(&b.op_params, std::mem::size_of::<OpParams>() as u64),
            Res::Pos => Binding::Read(&self.pos[parity]),
            Res::SpringOffsets => t("spring_offsets"),
            Res::Springs => t("springs"),
            Res::HingeOffsets => t("hinge_offsets"),
            Res::HingeRefs => t("hinge_refs"),
            Res::Hinges => t("hinges"),
            Res::SeamOffsets => t("seam_offsets"),
            Res::SeamRefs => t("seam_refs"),
            Res::Seams => t("seams"),
            Res::Sdf => t("sdf"),
            Res::Control => storage(&b.control),
            Res::Disp => storage(&b.disp),
            Res::Target => storage(&b.target),
            Res::Planes => storage(&b.planes),
            Res::Lambdas => storage(&b.lambdas),
            Res::Hier => storage(&b.hier),
            Res::Blocks => storage(&b.blocks),
            Res::Force => storage(&b.force),
            Res::Correction => storage(&b.correction),
            Res::P => storage(&b.p),
            Res::Ap => storage(&b.ap),
            Res::Rhs => storage(&b.rhs),
            Res::E => storage(&b.e),
            Res::Residual => storage(&b.res),
            Res::Partials => storage(&b.partials),
            Res::Scalars => storage(&b.scalars),
            Res::Steps => storage(&b.steps),
            Res::OpList => storage(&b.op_list),
            Res::BlockTexels if writable => Binding::Write(self.block_texels),
            Res::BlockTexels => Binding::Read(self.block_texels),
            Res::BlockColumns => Binding::Read(self.block_columns),
        }
    }

    fn pipeline(
        &self,
        device: &wgpu::Device,
        kernel: SolveKernel,
        energies: VbdEnergies,
    ) -> Result<KernelPipeline, Error> {
        let binds = kernel.binds(energies);
        let list = |parity: usize| -> Vec<(u32, Binding)> {
            (binds.iter())
                .map(|&(r, w)| (r.binding(), self.binding(r, w, parity)))
                .collect()
        };
        let (l0, l1) = (list(0), list(1));
        let label = kernel.file();
        let (layout, groups) = numbered_bind_groups(device, label, [&l0[..], &l1[..]]);
        let source = kernel.compose(energies).source;
        let pipeline = compute_pipeline(device, label, source, kernel.entry(), &[&layout]);
        Ok(KernelPipeline { pipeline, groups })
    }
}
