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
use drapekit::model::multigrid::{BlockPattern, Multigrid};
use drapekit::plan::SolveOp;
use glam::{Mat3, Vec3, Vec4};
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
            let mut colours = colours(mg, fine, l);
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
            let before = a.e.clone();
            cpu::smooth(&rows, sweep, &a.rhs, &mut a.e);
            if backward {
                colours.reverse();
            }
            let bounds = smoothing_bounds(pattern(l), &a.blocks, &colours, &a.rhs, &before, &a.e);
            let got = g.solve_array(SolveArray::LevelCorrection(level)).unwrap();
            within_rows(&format!("{op:?}"), &got, &a.e, &bounds);
            // A wrong kernel is off by a sizeable part of the correction; the bounds, carried
            // from row to row, must stay well below that to catch it (measured: at most 2.4e-2
            // of the largest correction, at light seam vertices with a weak diagonal; most rows
            // far less).
            let largest = bounds.iter().map(|b| b.max_element()).fold(0.0, f32::max);
            assert!(
                largest <= 0.1 * max_norm(&a.e),
                "{op:?}: the bounds carry too far"
            );
            return;
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

/// Per row, how far the GPU's and the CPU's Gauss–Seidel sweep over `colours` (in sweep
/// order) can end apart, from the arrays themselves (no assumption on the matrix): a row's
/// update x = A_II⁻¹·s with s = r_I − Σ_J A_IJ·e_J rounds in s (3k + 1 terms over its k blocks:
/// (3k + 1)·ε of |r_I| + Σ|A_IJ|·|e_J|, carried through |A_II⁻¹|) and in the adjugate solve
/// (cofactors 2 roundings, their dot products with s and with a column 3 more, the division
/// 2.5 ULP as WGSL allows: 5ε of |adj|·|s| and of |x|·|c₀|·|adj₀|, over |det|, plus 5ε of |x|);
/// each backend within that of the exact update of its own inputs (the GPU within twice it,
/// its rounding mode being open), so three times it, plus
/// |A_II⁻¹|·Σ|A_IJ|·d_J for rows J that this sweep updated before (their difference d_J;
/// rows not yet updated are the same uploaded values).
fn smoothing_bounds(
    pattern: &BlockPattern,
    blocks: &[Mat3],
    colours: &[Vec<u32>],
    rhs: &[Vec4],
    before: &[Vec4],
    after: &[Vec4],
) -> Vec<Vec3> {
    let mut d = vec![Vec3::ZERO; rhs.len()];
    let mut updated = vec![false; rhs.len()];
    for colour in colours {
        let mut next = Vec::with_capacity(colour.len());
        for &r in colour {
            let r = r as usize;
            let (start, end) = (pattern.offsets[r] as usize, pattern.offsets[r + 1] as usize);
            let mut magnitude = rhs[r].truncate().abs();
            let mut carried = Vec3::ZERO;
            let others = pattern.columns[start + 1..end]
                .iter()
                .zip(&blocks[start + 1..end]);
            for (&c, &block) in others {
                let c = c as usize;
                let (e, dc) = match updated[c] {
                    true => (after[c].truncate().abs() + d[c], d[c]),
                    false => (before[c].truncate().abs(), Vec3::ZERO),
                };
                magnitude += abs_block(block) * e;
                carried += abs_block(block) * dc;
            }
            let terms = (3 * (end - start - 1) + 1) as f32;
            let diagonal = blocks[start];
            let (c0, c1, c2) = (diagonal.x_axis, diagonal.y_axis, diagonal.z_axis);
            // As `solve3` computes it: both sides return zero below 1e-30; near that, one side
            // may return zero and the other the update.
            let det = c0.dot(c1.cross(c2));
            if det.abs() < 2e-30 {
                next.push((r, after[r].truncate().abs()));
                continue;
            }
            let inverse = abs_block(diagonal.inverse());
            let x = after[r].truncate().abs();
            let (c0, c1, c2) = (c0.abs(), c1.abs(), c2.abs());
            let adjugate_rows =
                Mat3::from_cols(abs_cross(c1, c2), abs_cross(c2, c0), abs_cross(c0, c1))
                    .transpose();
            let det_magnitude = c0.dot(abs_cross(c1, c2));
            let s = magnitude;
            let solve =
                5.0 * EPS * (adjugate_rows * s + x * det_magnitude) / det.abs() + 5.0 * EPS * x;
            let rounding = inverse * (terms * EPS * magnitude) + solve;
            // The CPU rounds to nearest (ε); WGSL leaves the rounding mode open, so the GPU may
            // take either neighbouring float (2ε): 3ε in all per rounding counted.
            next.push((r, 3.0 * rounding + inverse * carried));
        }
        for (r, bound) in next {
            d[r] = bound;
            updated[r] = true;
        }
    }
    d
}

/// |a|·|b|'s cross product: each component's two products by magnitude, summed.
fn abs_cross(a: Vec3, b: Vec3) -> Vec3 {
    Vec3::new(
        a.y * b.z + a.z * b.y,
        a.z * b.x + a.x * b.z,
        a.x * b.y + a.y * b.x,
    )
}

fn abs_block(m: Mat3) -> Mat3 {
    Mat3::from_cols(m.x_axis.abs(), m.y_axis.abs(), m.z_axis.abs())
}

/// Every row of `got` within its bound of `want`, component by component.
fn within_rows(what: &str, got: &[Vec4], want: &[Vec4], bounds: &[Vec3]) {
    let mut worst = (0.0f32, 0.0f32, 0.0f32);
    for ((g, w), b) in got.iter().zip(want).zip(bounds) {
        let diff = (g.truncate() - w.truncate()).abs();
        for k in 0..3 {
            let ratio = if diff[k] == 0.0 { 0.0 } else { diff[k] / b[k] };
            if ratio > worst.0 || ratio.is_nan() {
                worst = (ratio, diff[k], b[k]);
            }
        }
    }
    let largest = bounds.iter().map(|b| b.max_element()).fold(0.0, f32::max);
    eprintln!(
        "  {what}: worst row {:.2e} of its bound {:.2e} ({:.2}x; largest row bound {largest:.2e})",
        worst.1, worst.2, worst.0
    );
    assert!(
        worst.0 <= 1.0,
        "{what}: a row differs by {}, bound {}",
        worst.1,
        worst.2
    );
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
