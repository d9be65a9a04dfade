//! Implicit Euler on the CPU: the solve's arrays and the executor that runs a substep's
//! `SolveOp`s (`plan::implicit_schedule`) through the stages' CPU twins, in the order the
//! GPU encodes them.

use super::assemble::assemble;
use super::coarse_operator::coarse_operator;
use super::contact_planes::contact_planes;
use super::force_residual::{force_residual, reduce_residual};
use super::implicit_terms::{Implicit, VbdElements, PLANE_BLOCKS};
use super::line_energy::{apply_correction, line_search_from_full_step};
use super::pcg::{pcg_direction, pcg_start, pcg_step, pcg_step_length, PcgScalars};
use super::prolong::{correction_filter, prolong};
use super::restrict::restrict;
use super::smooth::{block_jacobi, smooth, ColourRows};
use super::vbd_solve::{vbd_solve, SweepPlan};
use crate::model::layout::{
    Hinge, Membrane, Seam, SimParams, SpringRef, SubstepParams, WORKGROUP_SIZE,
};
use crate::model::multigrid::{BlockPattern, Multigrid};
use crate::model::{ClothModel, Csr};
use crate::plan::SolveOp;
use glam::{Mat3, Vec4};
use rayon::prelude::*;
use std::sync::Arc;

/// The elements the solve gathers over.
pub struct Elements {
    springs: Csr<SpringRef>,
    hinges: Option<(Vec<Hinge>, Csr<u32>)>,
    seams: Option<(Vec<Seam>, Csr<u32>)>,
    membranes: Option<(Vec<Membrane>, Csr<u32>)>,
    /// Each vertex's row when the lists run in a sweep's order (`in_order`); `None` in
    /// particle order.
    row_of: Option<Vec<u32>>,
}

impl Elements {
    /// The model's springs, hinges, seam pairs and membrane (whose springs carry no force:
    /// the solve leaves them out).
    pub fn new(model: &ClothModel) -> Elements {
        let membrane = !model.membranes.is_empty();
        Elements {
            springs: if membrane {
                Csr {
                    offsets: vec![0; model.len() + 1],
                    items: Vec::new(),
                }
            } else {
                model.spring_csr()
            },
            membranes: membrane.then(|| by_ref(&model.membranes, model.membrane_csr())),
            hinges: (!model.hinges.is_empty()).then(|| by_ref(&model.hinges, model.hinge_csr())),
            seams: (!model.seams.is_empty()).then(|| by_ref(&model.seams, model.seam_csr())),
            row_of: None,
        }
    }

    /// The same elements with each vertex's lists side by side in the order `order` (a
    /// permutation of the particles) visits the vertices. A sweep visits a colour's vertices
    /// across the whole cloth: in particle order, every vertex's springs, hinges and seams
    /// begin with a cache miss on a large mesh; in the sweep's order they are one stream. The
    /// same elements in the same order per vertex, so the same numbers.
    pub fn in_order(&self, order: &[u32]) -> Elements {
        assert!(self.row_of.is_none(), "the lists are in particle order");
        let n = self.springs.offsets.len() - 1;
        let mut row_of = vec![u32::MAX; n];
        for (r, &i) in order.iter().enumerate() {
            let slot = row_of.get_mut(i as usize);
            *slot.unwrap_or_else(|| panic!("the order lists particle {i} of {n}")) = r as u32;
        }
        assert!(
            order.len() == n && !row_of.contains(&u32::MAX),
            "the order lists every particle once"
        );
        let (springs, _) = csr_in_order(&self.springs, order);
        Elements {
            springs,
            hinges: self.hinges.as_ref().map(|l| refs_in_order(l, order)),
            seams: self.seams.as_ref().map(|l| refs_in_order(l, order)),
            membranes: self.membranes.as_ref().map(|l| refs_in_order(l, order)),
            row_of: Some(row_of),
        }
    }

    /// Borrowed as the stages take them (`VbdElements`).
    pub fn view(&self) -> VbdElements<'_> {
        VbdElements {
            row_of: self.row_of.as_deref(),
            springs: (&self.springs.offsets, &self.springs.items),
            hinges: self
                .hinges
                .as_ref()
                .map(|(h, c)| (&c.offsets[..], &c.items[..], &h[..])),
            seams: self
                .seams
                .as_ref()
                .map(|(s, c)| (&c.offsets[..], &c.items[..], &s[..])),
            membranes: self
                .membranes
                .as_ref()
                .map(|(m, c)| (&c.offsets[..], &c.items[..], &m[..])),
        }
    }
}

/// Elements as a vertex's sweep reads them: the CSR of their refs (element · 4 + role), and a
/// copy of each ref's element at the ref's position. A sweep visits a colour's vertices across
/// the whole cloth, and each vertex about twelve hinges or six membrane triangles; read through
/// the refs, every element is a cache miss on a large mesh (the 5 mm T-shirt's hinges take
/// 3.5 MB), read in ref order a vertex's elements are one contiguous run. The same elements,
/// so the same numbers.
fn by_ref<T: Copy>(elements: &[T], csr: Csr<u32>) -> (Vec<T>, Csr<u32>) {
    let copies = (csr.items.iter())
        .map(|&r| elements[(r / 4) as usize])
        .collect();
    (copies, csr)
}

/// `by_ref`'s copies and refs, each vertex's side by side in `order`.
fn refs_in_order<T: Copy>((copies, csr): &(Vec<T>, Csr<u32>), order: &[u32]) -> (Vec<T>, Csr<u32>) {
    let (refs, positions) = csr_in_order(csr, order);
    (pick(copies, &positions), refs)
}

/// A per-vertex list with each vertex's entries side by side in `order`, and each new entry's
/// position in the old list.
fn csr_in_order<T: Copy>(csr: &Csr<T>, order: &[u32]) -> (Csr<T>, Vec<u32>) {
    let (mut offsets, mut positions) = (vec![0], Vec::with_capacity(csr.items.len()));
    for &i in order {
        positions.extend(csr.offsets[i as usize]..csr.offsets[i as usize + 1]);
        offsets.push(positions.len() as u32);
    }
    let items = pick(&csr.items, &positions);
    (Csr { offsets, items }, positions)
}

/// The entries of `items` at `positions`.
fn pick<T: Copy>(items: &[T], positions: &[u32]) -> Vec<T> {
    positions.iter().map(|&k| items[k as usize]).collect()
}

/// One level's arrays of the Newton step's linear system (level 0: the fine level).
pub struct LevelArrays {
    /// Its matrix, in its pattern's order (level 0: the assembled Hessian).
    pub blocks: Vec<Mat3>,
    /// Its right-hand side (level 0: the conjugate-gradient residual r).
    pub rhs: Vec<Vec4>,
    /// Its correction (level 0: the preconditioned residual z).
    pub e: Vec<Vec4>,
    /// Its residual rhs − A·e.
    pub res: Vec<Vec4>,
    /// Its matrix again, each colour's rows side by side, for the smoothing sweeps.
    pub by_colour: ColourRows,
}

impl LevelArrays {
    /// The arrays of a level of matrix structure `pattern` whose particles `order` lists colour
    /// after colour (colour k from `colour_offsets[k]`).
    fn new(pattern: &BlockPattern, order: &[u32], colour_offsets: &[u32]) -> LevelArrays {
        let particles = pattern.rows();
        LevelArrays {
            blocks: vec![Mat3::ZERO; pattern.blocks()],
            rhs: vec![Vec4::ZERO; particles],
            e: vec![Vec4::ZERO; particles],
            res: vec![Vec4::ZERO; particles],
            by_colour: ColourRows::new(pattern, order, colour_offsets),
        }
    }

    /// Copies its matrix, just computed, into `by_colour`.
    fn matrix_changed(&mut self) {
        self.by_colour.fill(&self.blocks);
    }
}

/// The Newton step's arrays.
pub struct Newton {
    /// The hierarchy.
    pub structure: Arc<Multigrid>,
    /// The fine force f at the last assembly.
    pub force: Vec<Vec4>,
    /// Every level's linear system, the fine level first.
    pub levels: Vec<LevelArrays>,
    /// The correction c (the conjugate-gradient solution).
    pub correction: Vec<Vec4>,
    /// The search direction p.
    pub p: Vec<Vec4>,
    /// H·p.
    pub ap: Vec<Vec4>,
    /// The conjugate-gradient scalars.
    pub scalars: PcgScalars,
    /// The line search's energy partials.
    pub energy: Vec<Vec4>,
    /// The line search's slope partials.
    pub slopes: Vec<Vec4>,
    /// The step length of each Newton step of the last substep.
    pub alphas: Vec<f32>,
}

/// Vertex Block Descent: the elements, the colour order and sweeps, and the solve's arrays.
pub struct Vbd {
    elements: Arc<Elements>,
    /// The same, each vertex's lists in the sweep's order (`Elements::in_order`): a second
    /// copy of the lists (about 20 MB on the 5 mm T-shirt) for sweeps about 40% faster there.
    sweep_elements: Arc<Elements>,
    /// The vertices and colours of a sweep.
    pub sweep: SweepPlan,
    /// The substep's operations.
    pub schedule: Vec<SolveOp>,
    /// The iterate: each particle's displacement over the step (w = inverse mass).
    pub x: Vec<Vec4>,
    /// The inertial target, as a displacement.
    pub y: Vec<Vec4>,
    /// The largest Newton step of each sweep of the last substep, in m.
    pub steps: Vec<f32>,
    /// Each body's contact plane per particle (body after body).
    pub planes: Vec<Vec4>,
    /// Each particle's normal force per body at the start of the step.
    pub lambdas: Vec<Vec4>,
    /// Newton's method's arrays, with coarse levels.
    pub newton: Option<Newton>,
    /// A sweep's scratch: the colour's next displacements (`vbd_solve`).
    next: Vec<Option<(Vec4, f32)>>,
    /// The force residual's partials.
    pub residual_partials: Vec<Vec4>,
    /// The last measured force residual: largest and RMS |f|/(m·g).
    pub residual: (f32, f32),
    /// Every force residual measured in the last substep, in order, with the sweeps run
    /// before it.
    pub history: Vec<(u32, f32, f32)>,
    /// Sweeps run, in all; and as many as were last reported.
    pub iterations_run: (u64, u64),
    /// Newton steps run, in all; and as many as were last reported.
    pub newton_run: (u64, u64),
    /// Whether the schedule's last operation, the final force residual, runs: only in the last
    /// substep of a batch (the frame's), where it is read back.
    pub measure_final: bool,
    /// With `profile` on: seconds spent in each kind of operation, and how many ran.
    pub profile: Option<std::collections::BTreeMap<&'static str, (u64, f64)>>,
}

impl Vbd {
    /// The solve's arrays for `model` stepping with `params` through `schedule`.
    pub fn new(model: &ClothModel, params: &SimParams, schedule: Vec<SolveOp>) -> Vbd {
        let n = model.len();
        let coloring = model.vertex_coloring();
        let groups = n.div_ceil(WORKGROUP_SIZE as usize).max(1);
        let sweeps = schedule
            .iter()
            .filter(|op| matches!(op, SolveOp::Sweep { .. }))
            .count();
        let newton = schedule.contains(&SolveOp::Assemble).then(|| {
            let structure = model
                .multigrid
                .clone()
                .expect("a multigrid schedule has levels");
            let fine = LevelArrays::new(&structure.fine, &coloring.order, &coloring.offsets);
            let mut levels = vec![fine];
            levels.extend(
                (structure.levels.iter())
                    .map(|l| LevelArrays::new(&l.pattern, &l.order, &l.color_offsets)),
            );
            Newton {
                force: vec![Vec4::ZERO; n],
                levels,
                correction: vec![Vec4::ZERO; n],
                p: vec![Vec4::ZERO; n],
                ap: vec![Vec4::ZERO; n],
                scalars: PcgScalars::default(),
                energy: vec![Vec4::ZERO; groups],
                slopes: vec![Vec4::ZERO; groups],
                alphas: Vec::new(),
                structure,
            }
        });
        let elements = Arc::new(Elements::new(model));
        // What makes a sweep's colour a set of independent updates (`vbd_solve`); one pass.
        assert!(
            elements.view().separated_by(&coloring.color_of),
            "the vertex colouring leaves an element with two vertices of one colour"
        );
        Vbd {
            sweep_elements: Arc::new(elements.in_order(&coloring.order)),
            elements,
            sweep: SweepPlan::new(coloring.order, &coloring.offsets, n),
            schedule,
            x: vec![Vec4::ZERO; n],
            y: vec![Vec4::ZERO; n],
            steps: vec![0.0; sweeps.max(1)],
            planes: vec![Vec4::ZERO; PLANE_BLOCKS * n * (params.num_bodies as usize).max(1)],
            lambdas: vec![Vec4::ZERO; n],
            newton,
            next: Vec::new(),
            residual_partials: vec![Vec4::ZERO; groups],
            residual: (0.0, 0.0),
            history: Vec::new(),
            iterations_run: (0, 0),
            newton_run: (0, 0),
            measure_final: true,
            profile: None,
        }
    }

    /// Runs the substep's solve (between `vbd_init` and `vbd_finish`): every operation of the
    /// schedule, until the schedule ends or a tolerance check finds the solve converged.
    pub fn solve(
        &mut self,
        params: &SimParams,
        step: &SubstepParams,
        prev: &[Vec4],
        sdfs: &[&[f32]],
    ) {
        if let Some(c) = &mut self.newton {
            c.alphas.clear();
        }
        self.history.clear();
        let mut schedule = self.schedule.clone();
        if !self.measure_final && schedule.last() == Some(&SolveOp::ForceResidual) {
            schedule.pop();
        }
        self.run_ops(&schedule, params, step, prev, sdfs);
    }

    /// Runs `ops` in order on the current iterate (a whole schedule, or part of one for
    /// benchmarks and tests), until they end or a tolerance check finds the solve converged.
    pub fn run_ops(
        &mut self,
        ops: &[SolveOp],
        params: &SimParams,
        step: &SubstepParams,
        prev: &[Vec4],
        sdfs: &[&[f32]],
    ) {
        let (elements, sweep_elements) = (self.elements.clone(), self.sweep_elements.clone());
        let el = (elements.view(), sweep_elements.view());
        let mut swept = self.history.last().map_or(0, |h| h.0);
        for &op in ops {
            let started = self.profile.is_some().then(std::time::Instant::now);
            self.run_op(op, params, step, prev, sdfs, &el, &mut swept);
            if let (Some(t), Some(p)) = (started, &mut self.profile) {
                let e = p.entry(op.kind()).or_insert((0, 0.0));
                e.0 += 1;
                e.1 += t.elapsed().as_secs_f64();
            }
            if op == SolveOp::CheckConverged && self.residual.1 <= params.tolerance {
                return;
            }
        }
    }

    /// Every particle's force at the iterate, f = −∇G (inertia, air damping, the elements,
    /// contact and friction at the step's planes), each from the same iterate (a sweep's step
    /// sees the neighbours its colours before it moved); zero for a pinned particle.
    /// Particles in parallel.
    pub fn forces(
        &self,
        params: &SimParams,
        step: &SubstepParams,
        prev: &[Vec4],
        out: &mut [Vec4],
    ) {
        let el = self.elements.view();
        let s = Implicit {
            params,
            step,
            prev,
            target: &self.y,
            el: &el,
            planes: &self.planes,
            lambdas: &self.lambdas,
        };
        (out.par_iter_mut().with_min_len(super::grain::VERTEX))
            .enumerate()
            .for_each(|(i, f)| {
                *f = if prev[i].w == 0.0 {
                    Vec4::ZERO
                } else {
                    let sys = s.vertex_system(i, &self.x, None, &mut |_, _| {});
                    sys.force.extend(0.0)
                };
            });
    }

    /// One operation of the schedule.
    #[allow(clippy::too_many_arguments)]
    fn run_op(
        &mut self,
        op: SolveOp,
        params: &SimParams,
        step: &SubstepParams,
        prev: &[Vec4],
        sdfs: &[&[f32]],
        (el, sweep_el): &(VbdElements, VbdElements),
        swept: &mut u32,
    ) {
        {
            if op == SolveOp::ContactPlanes {
                let s = Implicit {
                    params,
                    step,
                    prev,
                    target: &self.y,
                    el,
                    planes: &[],
                    lambdas: &[],
                };
                contact_planes(&s, &self.x, sdfs, &mut self.planes, &mut self.lambdas);
                return;
            }
            let s = Implicit {
                params,
                step,
                prev,
                target: &self.y,
                el,
                planes: &self.planes,
                lambdas: &self.lambdas,
            };
            match op {
                SolveOp::Sweep { iteration } => {
                    let (x, steps, next) = (&mut self.x, &mut self.steps, &mut self.next);
                    let s = Implicit { el: sweep_el, ..s };
                    vbd_solve(&s, (&self.sweep, iteration), x, steps, next);
                    self.iterations_run.0 += 1;
                    *swept += 1;
                }
                SolveOp::ForceResidual => {
                    force_residual(&s, &self.x, &mut self.residual_partials);
                    self.residual = reduce_residual(&self.residual_partials);
                    self.history
                        .push((*swept, self.residual.0, self.residual.1));
                }
                SolveOp::CheckConverged => {}
                _ => {
                    if op == SolveOp::Assemble {
                        self.newton_run.0 += 1;
                    }
                    let newton = self
                        .newton
                        .as_mut()
                        .expect("Newton steps need coarse levels");
                    newton.run(op, &s, &mut self.x);
                }
            }
        }
    }
}

impl Newton {
    /// One operation of a Newton step.
    fn run(&mut self, op: SolveOp, s: &Implicit, x: &mut [Vec4]) {
        let mg = &*self.structure;
        let level = |l: u32| &mg.levels[l as usize - 1];
        match op {
            SolveOp::Assemble => {
                let l0 = &mut self.levels[0];
                assemble(
                    s,
                    x,
                    &mg.fine,
                    &mg.element_blocks,
                    &mut self.force,
                    &mut l0.blocks,
                );
                l0.matrix_changed();
            }
            SolveOp::CoarseOperator { level: l } => {
                let (finer, coarse) = self.levels.split_at_mut(l as usize);
                coarse_operator(
                    &level(l).galerkin,
                    &finer[l as usize - 1].blocks,
                    &mut coarse[0].blocks,
                );
                coarse[0].matrix_changed();
            }
            SolveOp::PcgStart => {
                let l0 = &mut self.levels[0];
                pcg_start(&self.force, &mut self.correction, &mut l0.rhs, &mut l0.e);
            }
            SolveOp::Smooth { level: l, backward } => {
                let a = &mut self.levels[l as usize];
                let m = &a.by_colour;
                let colours = if backward { m.backward() } else { m.forward() };
                smooth(m, colours, &a.rhs, &mut a.e);
            }
            SolveOp::BlockJacobi => {
                let l0 = &mut self.levels[0];
                block_jacobi(&mg.fine, &l0.blocks, &l0.rhs, &mut l0.e);
            }
            SolveOp::Residual { level: l } => {
                let a = &mut self.levels[l as usize];
                a.by_colour.residual(&a.rhs, &a.e, &mut a.res);
            }
            SolveOp::Restrict { to } => {
                let (finer, coarse) = self.levels.split_at_mut(to as usize);
                let c = &mut coarse[0];
                restrict(
                    &level(to).children,
                    &finer[to as usize - 1].res,
                    &mut c.rhs,
                    &mut c.e,
                );
            }
            SolveOp::Prolong { from } => {
                let (finer, coarse) = self.levels.split_at_mut(from as usize);
                let lv = level(from);
                prolong(
                    &lv.parents,
                    &lv.weights,
                    &coarse[0].e,
                    &mut finer[from as usize - 1].e,
                );
            }
            SolveOp::PcgDirection { first } => {
                let l0 = &self.levels[0];
                pcg_direction(first, &l0.rhs, &l0.e, &mut self.p, &mut self.scalars);
            }
            SolveOp::PcgMatVec => {
                self.levels[0].by_colour.product(&self.p, &mut self.ap);
                pcg_step_length(&self.p, &self.ap, &mut self.scalars);
            }
            SolveOp::PcgStep => {
                let l0 = &mut self.levels[0];
                let (c, r, z) = (&mut self.correction, &mut l0.rhs, &mut l0.e);
                pcg_step(&self.scalars, &self.p, &self.ap, c, r, z);
            }
            SolveOp::CorrectionFilter => correction_filter(s, x, &mut self.correction),
            // The CPU chooses the step while it sums G's changes, the shorter steps only when
            // the full one is not taken and the slopes only when a change is within its
            // rounding: the same choice, at one step length's evaluation of each element
            // instead of three and no forces at the full step when the full step is taken.
            SolveOp::LineEnergy => {
                let partials = (&mut self.energy[..], &mut self.slopes[..]);
                let (c, f) = (&self.correction, &self.force);
                let alpha = line_search_from_full_step(s, x, c, f, partials);
                self.alphas.push(alpha);
            }
            SolveOp::LineSlopes | SolveOp::LineSearch => {}
            SolveOp::ApplyCorrection => {
                let alpha = self.alphas.last().copied().unwrap_or(0.0);
                apply_correction(alpha, &self.correction, x);
            }
            other => unreachable!("{other:?} is not a Newton-step operation"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::{GridPlane, TriMesh};
    use crate::scene::{Fabric, Orthotropic};
    use glam::Vec3;

    fn fabric(membrane: Option<Orthotropic>) -> Fabric {
        Fabric {
            density: 0.2,
            stretch_stiffness: 100.0,
            bending_stiffness: Some(1e-5),
            damping_ratio: 0.05,
            preset: None,
            membrane,
            buckling: false,
        }
    }

    /// Every ref's copy in `(offsets, refs, copies)` is the element of `elements` it names,
    /// with the ref's vertex at the ref's role of `vertices`.
    fn each_ref_is_its_element<T: PartialEq + std::fmt::Debug>(
        (offsets, refs, copies): (&[u32], &[u32], &[T]),
        elements: &[T],
        vertices: impl Fn(&T) -> [u32; 4],
    ) {
        assert_eq!(copies.len(), refs.len());
        for i in 0..offsets.len() - 1 {
            for k in offsets[i] as usize..offsets[i + 1] as usize {
                let r = refs[k];
                assert_eq!(copies[k], elements[(r / 4) as usize]);
                assert_eq!(vertices(&copies[k])[(r % 4) as usize] as usize, i);
            }
        }
    }

    /// Each vertex's entries of each list of `el`, as bits (`bytemuck`), vertex after vertex.
    fn lists_by_vertex(el: &VbdElements, n: usize) -> Vec<Vec<u8>> {
        fn entries<T: bytemuck::Pod>(
            el: &VbdElements,
            (offsets, items): (&[u32], &[T]),
            i: usize,
        ) -> Vec<u8> {
            bytemuck::cast_slice(&items[el.span(offsets, i)]).to_vec()
        }
        let mut lists = Vec::new();
        for i in 0..n {
            lists.push(entries(el, el.springs, i));
            if let Some((offsets, refs, hinges)) = el.hinges {
                lists.extend([
                    entries(el, (offsets, refs), i),
                    entries(el, (offsets, hinges), i),
                ]);
            }
            if let Some((offsets, refs, seams)) = el.seams {
                lists.extend([
                    entries(el, (offsets, refs), i),
                    entries(el, (offsets, seams), i),
                ]);
            }
            if let Some((offsets, refs, membranes)) = el.membranes {
                lists.extend([
                    entries(el, (offsets, refs), i),
                    entries(el, (offsets, membranes), i),
                ]);
            }
        }
        lists
    }

    /// A 6×5 grid as springs and as a membrane (both bend).
    fn grid_models() -> [ClothModel; 2] {
        let mesh = TriMesh::grid(1.0, 1.0, 6, 5, Vec3::ZERO, GridPlane::Xy);
        let membrane = Orthotropic {
            warp: 100.0,
            weft: 50.0,
            shear: 5.0,
            bending: None,
            large_strain: None,
        };
        [None, Some(membrane)].map(|m| ClothModel::from_mesh(&mesh, &fabric(m), &[]))
    }

    #[test]
    fn lists_in_a_sweep_order_hold_each_vertex_s_elements_in_particle_order_s_order() {
        // A sweep reads the lists in its own order (`Elements::in_order`); every vertex must find
        // there the entries it has in particle order, in the same order, for the same numbers.
        // (A sewn garment's seam pairs: `tests/implicit_stages`, which sweeps both ways.)
        for model in grid_models() {
            let order = model.vertex_coloring().order;
            assert!(
                order.windows(2).any(|w| w[0] > w[1]),
                "a sweep order, not particle order"
            );
            let by_particle = Elements::new(&model);
            let by_sweep = by_particle.in_order(&order);
            let (a, b) = (by_particle.view(), by_sweep.view());
            assert!(a.row_of.is_none() && b.row_of.is_some());
            assert_eq!(
                lists_by_vertex(&a, model.len()),
                lists_by_vertex(&b, model.len())
            );
        }
    }

    #[test]
    #[should_panic(expected = "lists every particle once")]
    fn a_sweep_order_that_leaves_out_a_particle_is_refused() {
        let mesh = TriMesh::grid(1.0, 1.0, 3, 3, Vec3::ZERO, GridPlane::Xy);
        let model = ClothModel::from_mesh(&mesh, &fabric(None), &[]);
        let mut order: Vec<u32> = (0..model.len() as u32).collect();
        order[1] = 0;
        Elements::new(&model).in_order(&order);
    }

    #[test]
    fn each_ref_holds_the_element_it_names_and_the_vertex_at_its_role() {
        for model in grid_models() {
            let elements = Elements::new(&model);
            let el = elements.view();
            let hinges = el.hinges.expect("the grid bends");
            each_ref_is_its_element(hinges, &model.hinges, |h| h.v);
            if let Some(membranes) = el.membranes {
                each_ref_is_its_element(membranes, &model.membranes, |m| m.v);
            }
        }
    }
}
