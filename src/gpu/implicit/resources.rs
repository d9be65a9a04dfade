//! The solve's buffers and textures, and the pipelines and bind groups of its kernels over
//! them.

use super::hierarchy::Packed;
use super::kernels::{Include, Res, SolveKernel};
use super::layout::{OpParams, SolveControl, SolveScalars};
use crate::error::Error;
use crate::gpu::array_layout::{bind_as_buffers, ArrayLayout};
use crate::gpu::context::GpuContext;
use crate::gpu::elements::{element_arrays, Elements};
use crate::gpu::kernels::VbdEnergies;
use crate::gpu::pipelines::{compute_pipeline, numbered_bind_groups, Binding};
use crate::gpu::texels::TexelArray;
use std::collections::HashMap;
use wgpu::TextureFormat::{R32Uint, Rgba32Float};

/// The solve's buffers (see `Res` for what each holds).
pub(in crate::gpu) struct SolveBuffers {
    pub(in crate::gpu) disp: wgpu::Buffer,
    pub(in crate::gpu) target: wgpu::Buffer,
    pub(in crate::gpu) steps: wgpu::Buffer,
    pub(in crate::gpu) control: wgpu::Buffer,
    pub(super) planes: wgpu::Buffer,
    pub(super) lambdas: wgpu::Buffer,
    pub(super) hier: wgpu::Buffer,
    pub(super) blocks: wgpu::Buffer,
    pub(super) force: wgpu::Buffer,
    pub(super) correction: wgpu::Buffer,
    pub(super) p: wgpu::Buffer,
    pub(super) ap: wgpu::Buffer,
    pub(super) rhs: wgpu::Buffer,
    pub(super) e: wgpu::Buffer,
    pub(super) res: wgpu::Buffer,
    pub(super) partials: wgpu::Buffer,
    pub(super) scalars: wgpu::Buffer,
    pub(super) op_params: wgpu::Buffer,
    pub(super) op_list: wgpu::Buffer,
}

/// How large the solve's arrays are.
pub(super) struct Sizes {
    /// Particles.
    pub(super) n: usize,
    /// Bodies (at least one: the planes' buffer is never empty).
    pub(super) bodies: usize,
    /// Sweeps per substep.
    pub(super) sweeps: usize,
    /// Whether the schedule takes Newton steps (its linear-system arrays exist).
    pub(super) newton: bool,
    /// Workgroups of a dispatch over the particles (their reductions' partials).
    pub(super) groups: usize,
    /// Entries of the `OpParams` table and of the op lists.
    pub(super) capacity: (usize, usize),
    /// Bytes between `OpParams` entries.
    pub(super) op_stride: u64,
}

impl SolveBuffers {
    pub(super) fn new(
        ctx: &GpuContext,
        labels: &mut Vec<&'static str>,
        sizes: &Sizes,
        packed: &Packed,
    ) -> Result<SolveBuffers, Error> {
        let device = &ctx.device;
        let max_binding = device.limits().max_storage_buffer_binding_size;
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
        let (vec4, n) = (16, sizes.n);
        // The linear system's arrays exist only where the schedule takes Newton steps.
        let newton = |len: usize| if sizes.newton { len } else { 0 };
        let rows = newton(packed.rows as usize);
        let buffers = SolveBuffers {
            disp: storage("vbd_x", vec4 * n)?,
            target: storage("vbd_y", vec4 * n)?,
            steps: storage("vbd_steps", 4 * (sizes.sweeps.max(1) + 1))?,
            control: storage("solve_control", std::mem::size_of::<SolveControl>())?,
            // Planes, then surface velocities (cpu::PLANE_BLOCKS).
            planes: storage("contact_planes", 2 * vec4 * sizes.bodies * n)?,
            lambdas: storage("contact_lambdas", vec4 * n)?,
            hier: storage("hierarchy", 4 * packed.words.len())?,
            blocks: storage("blocks", 48 * newton(packed.blocks as usize))?,
            force: storage("newton_force", vec4 * newton(n))?,
            correction: storage("newton_correction", vec4 * newton(n))?,
            p: storage("pcg_p", vec4 * newton(n))?,
            ap: storage("pcg_ap", vec4 * newton(n))?,
            rhs: storage("level_rhs", vec4 * rows)?,
            e: storage("level_e", vec4 * rows)?,
            res: storage("level_res", vec4 * rows)?,
            // Two sets: the line search reads line_energy's and line_slopes' side by side.
            partials: storage("solve_partials", 2 * vec4 * sizes.groups)?,
            scalars: storage("solve_scalars", std::mem::size_of::<SolveScalars>())?,
            op_list: storage("coarse_cycle_ops", 16 * sizes.capacity.1)?,
            op_params: {
                labels.push("solve_ops");
                device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("solve_ops"),
                    size: sizes.op_stride * sizes.capacity.0 as u64,
                    usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                })
            },
        };
        let words = bytemuck::cast_slice(&packed.words);
        ctx.queue.write_buffer(&buffers.hier, 0, words);
        Ok(buffers)
    }
}

/// The textures the solve's kernels read.
pub(super) struct SolveTextures {
    /// The element arrays and the bodies' SDF nodes, by label.
    elements: Vec<(&'static str, TexelArray)>,
    /// Every level's blocks, three texels each (written by `publish_blocks`).
    block_texels: TexelArray,
    /// Every level's block columns.
    block_columns: TexelArray,
}

impl SolveTextures {
    /// The textures of `model`'s elements (and its bodies' SDFs when `contact`) and of the
    /// hierarchy's blocks.
    pub(super) fn new(
        ctx: &GpuContext,
        labels: &mut Vec<&'static str>,
        model: &crate::model::ClothModel,
        packed: &Packed,
        (newton, contact): (bool, bool),
    ) -> Result<SolveTextures, Error> {
        let none = wgpu::TextureUsages::empty();
        let blocks = if newton { packed.blocks as usize } else { 0 };
        labels.extend(["block_texels", "block_columns"]);
        let block_texels = TexelArray::new(
            ctx,
            "block_texels",
            Rgba32Float,
            3 * blocks,
            wgpu::TextureUsages::STORAGE_BINDING,
        )?;
        let columns = bytemuck::cast_slice(&packed.columns[..blocks]);
        let block_columns = TexelArray::with_data(ctx, "block_columns", R32Uint, columns, none)?;
        // A membrane's springs carry no force: the solve gathers an empty spring list, as the
        // CPU's `Elements::new` does.
        let membrane = !model.membranes.is_empty();
        let springs = match membrane {
            true => Elements::NoSprings,
            false => Elements::Springs,
        };
        let mut kinds = vec![springs];
        kinds.extend((!model.hinges.is_empty()).then_some(Elements::Hinges));
        kinds.extend((!model.seams.is_empty()).then_some(Elements::Seams));
        kinds.extend(membrane.then_some(Elements::Membranes));
        kinds.extend(contact.then_some(Elements::Sdf));
        let mut elements = Vec::new();
        for kind in kinds {
            for (label, format, bytes) in element_arrays(model, kind) {
                labels.push(label);
                let layout = kind.layout(ctx.layout);
                let texture = TexelArray::with_data_in(layout, ctx, label, format, &bytes, none)?;
                elements.push((label, texture));
            }
        }
        Ok(SolveTextures {
            elements,
            block_texels,
            block_columns,
        })
    }

    fn element(&self, label: &str) -> &TexelArray {
        let found = self.elements.iter().find(|(l, _)| *l == label);
        &found.expect("the kernels' element arrays were made").1
    }
}

/// A built kernel: its pipeline and a bind group per state parity (which `pos` texture holds
/// xₙ).
pub(super) struct KernelPipeline {
    pub(super) pipeline: wgpu::ComputePipeline,
    pub(super) groups: [wgpu::BindGroup; 2],
}

/// Everything a solve kernel may bind.
pub(super) struct Resources<'a> {
    pub(super) buffers: &'a SolveBuffers,
    pub(super) textures: &'a SolveTextures,
    pub(super) params: &'a wgpu::Buffer,
    pub(super) substeps: &'a wgpu::Buffer,
    pub(super) pos: &'a [TexelArray; 2],
    /// Where the arrays live, which also sets the multigrid kernels' loads in flight.
    pub(super) layout: ArrayLayout,
    /// `SolveOptions::cached_rows`.
    pub(super) cached_rows: u32,
}

impl<'a> Resources<'a> {
    fn binding(&self, res: Res, writable: bool, parity: usize) -> Binding<'a> {
        let (b, t) = (self.buffers, self.textures);
        let storage = |buffer| Binding::Storage(buffer, !writable);
        let element = |label| Binding::Read(t.element(label));
        match res {
            Res::Params => Binding::Uniform(self.params),
            Res::Step => Binding::SubstepUniform(self.substeps),
            Res::Op => Binding::Dynamic(&b.op_params, std::mem::size_of::<OpParams>() as u64),
            Res::Pos => Binding::Read(&self.pos[parity]),
            Res::SpringOffsets => element("spring_offsets"),
            Res::Springs => element("springs"),
            Res::HingeOffsets => element("hinge_offsets"),
            Res::HingeRefs => element("hinge_refs"),
            Res::Hinges => element("hinges"),
            Res::SeamOffsets => element("seam_offsets"),
            Res::SeamRefs => element("seam_refs"),
            Res::Seams => element("seams"),
            Res::MembraneOffsets => element("membrane_offsets"),
            Res::MembraneRefs => element("membrane_refs"),
            Res::Membranes => element("membranes"),
            Res::Sdf => element("sdf"),
            Res::BlockTexels if writable => Binding::Write(&t.block_texels),
            Res::BlockTexels => Binding::Read(&t.block_texels),
            Res::BlockColumns => Binding::Read(&t.block_columns),
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
        }
    }

    /// Each kernel's pipeline and bind groups.
    pub(super) fn pipelines(
        &self,
        device: &wgpu::Device,
        kernels: &[SolveKernel],
        energies: VbdEnergies,
    ) -> HashMap<SolveKernel, KernelPipeline> {
        (kernels.iter())
            .map(|&k| (k, self.pipeline(device, k, energies)))
            .collect()
    }

    fn pipeline(
        &self,
        device: &wgpu::Device,
        kernel: SolveKernel,
        energies: VbdEnergies,
    ) -> KernelPipeline {
        let binds = kernel.binds(energies);
        let list = |parity: usize| -> Vec<(u32, Binding)> {
            (binds.iter())
                .map(|&(r, w)| (r.binding(), self.binding(r, w, parity)))
                .collect()
        };
        let (l0, l1) = (list(0), list(1));
        let label = kernel.file();
        let (layout, groups) = numbered_bind_groups(device, label, [&l0[..], &l1[..]]);
        let source = bind_as_buffers(kernel.compose(energies).source, &[(0, &l0)]);
        let constants = self.constants(kernel);
        let entry = kernel.entry();
        let pipeline = compute_pipeline(device, label, source, entry, &[&layout], &constants);
        KernelPipeline { pipeline, groups }
    }

    /// The pipeline-overridable constants of `kernel` (multigrid.wgsl's).
    fn constants(&self, kernel: SolveKernel) -> Vec<(&'static str, f64)> {
        let mut constants = Vec::new();
        if kernel.includes().contains(&Include::Multigrid) {
            constants.push(("BLOCKS_IN_FLIGHT", self.layout.blocks_in_flight() as f64));
        }
        if kernel == SolveKernel::CoarseCycle {
            constants.push(("CACHE_ROWS", self.cached_rows as f64));
        }
        constants
    }
}

/// The storage buffers one stage may bind on `ctx`'s device must cover the kernels'.
pub(super) fn check_storage_limit(
    ctx: &GpuContext,
    kernels: &[SolveKernel],
    energies: VbdEnergies,
) -> Result<(), Error> {
    let limit = ctx.device.limits().max_storage_buffers_per_shader_stage;
    for &k in kernels {
        let binds = k.binds(energies);
        let used = binds.iter().filter(|(r, _)| r.is_storage()).count() as u32;
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
