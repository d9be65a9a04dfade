//! The stages of the Newton step's linear system: the coarse levels' Galerkin operators, one
//! V-cycle operation by operation, and conjugate gradients' direction, product and step (see
//! main.rs for the bounds' reasoning).

use super::{abs_blocks, abs_vecs, abs_weights, block_diff, longest_run, mat_max, within, EPS};
use crate::common::{max_abs_diff, max_norm};
use drapekit::cpu::{self, PcgScalars};
use drapekit::gpu::implicit::layout::SolveScalars;
use drapekit::gpu::implicit::SolveArray;
use drapekit::gpu::GpuSolver;
use drapekit::model::layout::SubstepParams;
use drapekit::model::multigrid::Multigrid;
use drapekit::plan::SolveOp;
use glam::{Mat3, Vec4};
/// One level's arrays of the Newton step's linear system on the CPU.
#[derive(Clone)]
pub(crate) struct Level {
    pub(crate) blocks: Vec<Mat3>,
    pub(crate) rhs: Vec<Vec4>,
    pub(crate) e: Vec<Vec4>,
    pub(crate) res: Vec<Vec4>,
}

impl Level {
    pub(crate) fn new(rows: usize, blocks: Vec<Mat3>) -> Level {
        let zero = vec![Vec4::ZERO; rows];
        Level {
            blocks,
            rhs: zero.clone(),
            e: zero.clone(),
            res: zero,
        }
    }
}

pub(crate) fn upload_levels(g: &mut GpuSolver, lv: &[Level]) {
    for (l, a) in lv.iter().enumerate() {
        let l = l as u32;
        g.set_solve_blocks(l, &a.blocks).unwrap();
        g.set_solve_array(SolveArray::Rhs(l), &a.rhs).unwrap();
        g.set_solve_array(SolveArray::LevelCorrection(l), &a.e)
            .unwrap();
        g.set_solve_array(SolveArray::LevelResidual(l), &a.res)
            .unwrap();
    }
}

pub(crate) fn check_coarse_operators(
    g: &mut GpuSolver,
    lv: &mut [Level],
    mg: &Multigrid,
    step: SubstepParams,
) {
    for l in 1..lv.len() {
        let level = &mg.levels[l - 1];
        g.set_solve_blocks(l as u32 - 1, &lv[l - 1].blocks).unwrap();
        g.run_solve_ops(&[SolveOp::CoarseOperator { level: l as u32 }], &step)
            .unwrap();
        let (finer, coarse) = lv.split_at_mut(l);
        cpu::coarse_operator(&level.galerkin, &finer[l - 1].blocks, &mut coarse[0].blocks);
        // Each coarse block sums k weighted finer blocks in order: the difference is at most
        // k + 1 roundings of Σ|w|·|A| (the same sum of magnitudes, from the CPU twin).
        let mut magnitude = vec![Mat3::ZERO; level.pattern.blocks()];
        let abs = abs_blocks(&finer[l - 1].blocks);
        cpu::coarse_operator(&abs_weights(&level.galerkin), &abs, &mut magnitude);
        let k = longest_run(&level.galerkin) as f32;
        let bound = (k + 1.0) * EPS * block_max_of(&magnitude);
        let got = g.solve_blocks(l as u32).unwrap();
        within(
            &format!("coarse_operator {l}"),
            block_diff(&got, &lv[l].blocks),
            bound,
        );
    }
}

fn block_max_of(a: &[Mat3]) -> f32 {
    a.iter().map(mat_max).fold(0.0, f32::max)
}

/// One level operation on the GPU and on the CPU from the same arrays.
pub(crate) fn check_level_op(
    g: &mut GpuSolver,
    lv: &mut [Level],
    (mg, fine): (&Multigrid, &[Vec<u32>]),
    op: SolveOp,
    step: SubstepParams,
) {
    upload_levels(g, lv);
    g.run_solve_ops(&[op], &step).unwrap();
    let pattern = |l: usize| {
        if l == 0 {
            &mg.fine
        } else {
            &mg.levels[l - 1].pattern
        }
    };
    let (out, l, bound) = match op {
        SolveOp::Smooth { level, backward } => {
            let l = level as usize;
            let colours = colours(mg, fine, l);
            let a = &mut lv[l];
            let mut offsets = vec![0u32];
            offsets.extend(colours.iter().scan(0, |end, c| {
                *end += c.len() as u32;
                Some(*end)
            }));
            let mut rows = cpu::ColourRows::new(pattern(l), &colours.concat(), &offsets);
            rows.fill(&a.blocks);
            let sweep = if backward {
                rows.backward()
            } else {
                rows.forward()
            };
            cpu::smooth(&rows, sweep, &a.rhs, &mut a.e);
            // A row's update A_rr⁻¹(rhs_r − Σ A_rc·e_c) rounds a few times relative to the
            // largest correction (the blocks are diagonally dominant, so the sum over A_rr is at
            // most that); later colours pass earlier differences on, undamped at most.
            let bound = 8.0 * EPS * max_norm(&a.e) * colours.len() as f32;
            (SolveArray::LevelCorrection(level), l, bound)
        }
        SolveOp::Residual { level } => {
            let l = level as usize;
            let a = &mut lv[l];
            cpu::level_residual(pattern(l), &a.blocks, &a.rhs, &a.e, &mut a.res);
            // rhs − Σ A·e over a row's k blocks: k + 1 roundings of |rhs| + Σ|A|·|e|.
            let mut magnitude = vec![Vec4::ZERO; a.rhs.len()];
            let minus_e: Vec<Vec4> = a.e.iter().map(|v| -v.abs()).collect();
            let abs = abs_blocks(&a.blocks);
            cpu::level_residual(
                pattern(l),
                &abs,
                &abs_vecs(&a.rhs),
                &minus_e,
                &mut magnitude,
            );
            let k = pattern(l)
                .offsets
                .windows(2)
                .map(|w| w[1] - w[0])
                .max()
                .unwrap() as f32;
            (
                SolveArray::LevelResidual(level),
                l,
                (k + 1.0) * EPS * max_norm(&magnitude),
            )
        }
        SolveOp::Restrict { to } => {
            let t = to as usize;
            let children = &mg.levels[t - 1].children;
            let (finer, coarse) = lv.split_at_mut(t);
            let c = &mut coarse[0];
            cpu::restrict(children, &finer[t - 1].res, &mut c.rhs, &mut c.e);
            let (mut magnitude, mut zero) = (c.rhs.clone(), c.e.clone());
            let abs = abs_vecs(&finer[t - 1].res);
            cpu::restrict(&abs_weights(children), &abs, &mut magnitude, &mut zero);
            let k = longest_run(children) as f32;
            (
                SolveArray::Rhs(to),
                t,
                (k + 1.0) * EPS * max_norm(&magnitude),
            )
        }
        SolveOp::Prolong { from } => {
            let f = from as usize;
            let level = &mg.levels[f - 1];
            let (finer, coarse) = lv.split_at_mut(f);
            let mut magnitude = abs_vecs(&finer[f - 1].e);
            let w: Vec<[f32; 3]> = level.weights.iter().map(|w| w.map(f32::abs)).collect();
            cpu::prolong(&level.parents, &w, &abs_vecs(&coarse[0].e), &mut magnitude);
            cpu::prolong(
                &level.parents,
                &level.weights,
                &coarse[0].e,
                &mut finer[f - 1].e,
            );
            // e + Σ of three weighted parents: four roundings of |e| + Σ|w|·|e_parent|.
            (
                SolveArray::LevelCorrection(from - 1),
                f - 1,
                4.0 * EPS * max_norm(&magnitude),
            )
        }
        other => panic!("{other:?} is not a level operation"),
    };
    let got = g.solve_array(out).unwrap();
    let want = match out {
        SolveArray::Rhs(_) => &lv[l].rhs,
        SolveArray::LevelCorrection(_) => &lv[l].e,
        _ => &lv[l].res,
    };
    within(&format!("{op:?}"), max_abs_diff(&got, want), bound);
}

/// A level's colours, each its rows in order (the fine level's: the model's vertex colours).
fn colours(mg: &Multigrid, fine: &[Vec<u32>], l: usize) -> Vec<Vec<u32>> {
    if l == 0 {
        return fine.to_vec();
    }
    let c = &mg.levels[l - 1];
    (0..c.colors()).map(|k| c.color_rows(k).to_vec()).collect()
}

/// Conjugate gradients' vectors and scalars on the CPU.
pub(crate) struct Pcg {
    pub(crate) p: Vec<Vec4>,
    pub(crate) correction: Vec<Vec4>,
    pub(crate) scalars: PcgScalars,
}

/// Rounding bound of a dot product as the kernels reduce it (tree within 64 lanes, then the
/// workgroups in order) of vectors with these magnitudes: 3 roundings per particle's term, 6 in
/// the tree, one per workgroup after.
fn dot_bound(a: &[Vec4], b: &[Vec4]) -> f32 {
    let groups = a.len().div_ceil(64) as f32;
    (groups + 9.0) * EPS * cpu::dot(&abs_vecs(a), &abs_vecs(b))
}

pub(crate) fn check_pcg(
    g: &mut GpuSolver,
    lv: &mut [Level],
    mg: &Multigrid,
    cg: &mut Pcg,
    first: bool,
    step: SubstepParams,
) {
    let previous = cg.scalars.rz;
    let (r, z) = (lv[0].rhs.clone(), lv[0].e.clone());
    let p_before = cg.p.clone();
    cpu::pcg_direction(first, &r, &z, &mut cg.p, &mut cg.scalars);
    // The kernel writes r·z at the parity of its iteration (0 when run alone) and reads the
    // previous one at the other.
    g.set_solve_array(SolveArray::Rhs(0), &r).unwrap();
    g.set_solve_array(SolveArray::LevelCorrection(0), &z)
        .unwrap();
    g.set_solve_array(SolveArray::Direction, &p_before).unwrap();
    g.set_solve_scalars(SolveScalars {
        rz: [0.0, previous],
        ..Default::default()
    })
    .unwrap();
    g.run_solve_ops(&[SolveOp::PcgDirection { first }], &step)
        .unwrap();
    let rz = g.solve_scalars().unwrap().rz[0];
    let drz = dot_bound(&r, &z);
    within("pcg_direction r·z", (rz - cg.scalars.rz).abs(), drz);
    // p = z + β·p: two roundings of |z| + |β·p|, and β's own difference (that of r·z over the
    // previous r·z) times |p|; the first direction is z itself.
    let beta = if first { 0.0 } else { cg.scalars.rz / previous };
    let dbeta = if first {
        0.0
    } else {
        drz / previous.abs() + EPS * beta.abs()
    };
    let bound =
        2.0 * EPS * (max_norm(&z) + beta.abs() * max_norm(&p_before)) + dbeta * max_norm(&p_before);
    within(
        "pcg_direction p",
        max_abs_diff(&g.solve_array(SolveArray::Direction).unwrap(), &cg.p),
        bound,
    );

    // H·p and the step along p, from the CPU's p and r·z.
    let mut ap = vec![Vec4::ZERO; r.len()];
    cpu::pcg_matvec(&mg.fine, &lv[0].blocks, &cg.p, &mut ap, &mut cg.scalars);
    let c_before = cg.correction.clone();
    {
        let l0 = &mut lv[0];
        cpu::pcg_step(
            &cg.scalars,
            &cg.p,
            &ap,
            &mut cg.correction,
            &mut l0.rhs,
            &mut l0.e,
        );
    }
    g.set_solve_array(SolveArray::Direction, &cg.p).unwrap();
    g.set_solve_array(SolveArray::Correction, &c_before)
        .unwrap();
    g.set_solve_scalars(SolveScalars {
        rz: [cg.scalars.rz, 0.0],
        ..Default::default()
    })
    .unwrap();
    g.run_solve_ops(&[SolveOp::PcgMatVec, SolveOp::PcgStep], &step)
        .unwrap();
    // H·p: k + 1 roundings of Σ|A|·|p| per row (its magnitude from the CPU twin).
    let mut magnitude = vec![Vec4::ZERO; r.len()];
    let abs = abs_blocks(&lv[0].blocks);
    cpu::pcg_matvec(
        &mg.fine,
        &abs,
        &abs_vecs(&cg.p),
        &mut magnitude,
        &mut PcgScalars::default(),
    );
    let k = mg
        .fine
        .offsets
        .windows(2)
        .map(|w| w[1] - w[0])
        .max()
        .unwrap() as f32;
    let dap = (k + 1.0) * EPS * max_norm(&magnitude);
    within(
        "pcg_matvec H·p",
        max_abs_diff(&g.solve_array(SolveArray::Product).unwrap(), &ap),
        dap,
    );
    // α = r·z / p·H·p: p·H·p differs by its dot product's rounding and by p·ΔHp.
    let pap = cpu::dot(&cg.p, &ap);
    let dpap =
        dot_bound(&cg.p, &magnitude) + (k + 1.0) * EPS * cpu::dot(&abs_vecs(&cg.p), &magnitude);
    let alpha = cg.scalars.alpha;
    let dalpha = alpha.abs() * (dpap / pap.abs() + 2.0 * EPS);
    within(
        "pcg_step α",
        (g.solve_scalars().unwrap().alpha - alpha).abs(),
        dalpha,
    );
    // c + α·p and r − α·H·p: a rounding or two of each term, and α's and H·p's differences.
    let dc = 2.0 * EPS * (max_norm(&c_before) + alpha.abs() * max_norm(&cg.p))
        + dalpha * max_norm(&cg.p);
    within(
        "pcg_step c",
        max_abs_diff(
            &g.solve_array(SolveArray::Correction).unwrap(),
            &cg.correction,
        ),
        dc,
    );
    let dr = 2.0 * EPS * (max_norm(&r) + alpha.abs() * max_norm(&ap))
        + dalpha * max_norm(&ap)
        + alpha.abs() * dap;
    within(
        "pcg_step r",
        max_abs_diff(&g.solve_array(SolveArray::Rhs(0)).unwrap(), &lv[0].rhs),
        dr,
    );
    assert!(g
        .solve_array(SolveArray::LevelCorrection(0))
        .unwrap()
        .iter()
        .all(|v| *v == Vec4::ZERO));
    // Both go on from the CPU's.
    g.set_solve_array(SolveArray::Rhs(0), &lv[0].rhs).unwrap();
}
