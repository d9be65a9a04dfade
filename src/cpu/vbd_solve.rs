//! CPU twin of `kernels/vbd_solve.wgsl`: a Vertex Block Descent sweep (Chen, Macklin et al.,
//! SIGGRAPH 2024), colour after colour (the kernel runs one colour a dispatch).
//!
//! Backward Euler is the minimisation of the incremental potential G (`implicit_terms`). Each
//! vertex takes one Newton step on G with every other vertex held fixed: with f the vertex's
//! force (−gradient) and H its 3×3 Hessian block, D += H⁻¹f. Vertices of one colour share no
//! element, so they update at once (one dispatch) without reading each other.

use super::colour_run::{colour_after_colour, colour_of_each, Cells};
use super::implicit_terms::Implicit;
use glam::{Mat3, Vec3, Vec4};
use std::ops::Range;
use std::sync::atomic::{AtomicU32, Ordering};

/// The vertex's Newton step H⁻¹f, unless it would end inside a body's contact layer (along
/// the step's contact plane with normal n̂, body by body in scene order): then the step that
/// lands on the layer, a·n̂ with a the distance to it, plus the best step in the layer's
/// tangent plane given that, (SHS)⁻¹S(f − a·H·n̂) with S = I − n̂n̂ᵀ (on n̂ the solve uses H's
/// mean diagonal, so that the 3×3 system stays invertible while its answer has no n̂ part).
/// A step that only stopped at the layer kept the tangential part meant for a free vertex, and
/// a vertex on a body pulled sideways by springs that also press it in never balanced; a step
/// into the layer with the penalty's stiffness left it 30 µm deep, its springs' neighbours
/// 0.06 N off balance, a hundred times a 2 cm particle's weight.
pub fn newton_step(s: &Implicit, i: usize, d: Vec3, f: Vec3, hess: Mat3) -> Vec3 {
    let mut delta = solve3(hess, f);
    for b in 0..s.params.num_bodies as usize {
        let plane = s.plane(b, i);
        let n = plane.truncate();
        let phi = plane.w + n.dot(d);
        let thickness = s.params.bodies[b].thickness;
        if phi + n.dot(delta) < thickness {
            let a = thickness - phi;
            let t = Mat3::IDENTITY - outer(n, n);
            let mean = (hess.x_axis.x + hess.y_axis.y + hess.z_axis.z) / 3.0;
            let system = t * hess * t + mean * outer(n, n);
            delta = t * solve3(system, t * (f - a * (hess * n))) + a * n;
        }
    }
    delta
}

fn outer(a: Vec3, b: Vec3) -> Mat3 {
    Mat3::from_cols(a * b.x, a * b.y, a * b.z)
}

/// H⁻¹f through the adjugate (as the kernel, which has no matrix inverse); zero when H is
/// singular, which a positive mass rules out.
pub fn solve3(hess: Mat3, f: Vec3) -> Vec3 {
    let (c0, c1, c2) = (hess.x_axis, hess.y_axis, hess.z_axis);
    let r0 = c1.cross(c2);
    let r1 = c2.cross(c0);
    let r2 = c0.cross(c1);
    let det = c0.dot(r0);
    if det.abs() < 1e-30 {
        return Vec3::ZERO;
    }
    // Rows of the adjugate are the cross products of the columns.
    Vec3::new(r0.dot(f), r1.dot(f), r2.dot(f)) / det
}

/// What a sweep visits, fixed for a solver and checked once: the vertices in colour order, and
/// the sweep's phases (each colour twice: its steps, then their writes).
pub struct SweepPlan {
    order: Vec<u32>,
    phases: Vec<Range<usize>>,
    vertices: usize,
}

impl SweepPlan {
    /// The plan of sweeping the `n` vertices that `order` lists colour after colour, colour k
    /// from `colour_offsets[k]`.
    ///
    /// Panics if `order` lists a vertex twice (two rows would write one vertex at once) or one
    /// past `n` (`colour_of_each`), or if the offsets run past `order`.
    pub fn new(order: Vec<u32>, colour_offsets: &[u32], n: usize) -> SweepPlan {
        assert!(
            colour_offsets
                .last()
                .is_none_or(|&end| end as usize <= order.len()),
            "the colour offsets run past the order"
        );
        colour_of_each(&order, colour_offsets, n);
        let phases: Vec<Range<usize>> = (colour_offsets.windows(2))
            .flat_map(|w| {
                let rows = w[0] as usize..w[1] as usize;
                [rows.clone(), rows]
            })
            .collect();
        SweepPlan {
            order,
            phases,
            vertices: n,
        }
    }
}

/// One sweep of `plan` (colour after colour): every free vertex takes its Newton step, in
/// place, and the sweep's `iteration` records the largest step length in `steps` (m).
///
/// A vertex's system reads only itself and vertices of other colours, so a colour's steps are
/// computed in parallel from the same `x` into `next` (scratch, one entry per row of the
/// plan: the vertex's next displacement and step length, `None` when pinned; kept between
/// calls so that a sweep allocates little) and then written, each colour one parallel phase of
/// the sweep (`colour_after_colour`) and its writes the next: the same numbers as one vertex
/// after another, on any number of threads (the largest of them too).
///
/// That every vertex reads only vertices of other colours is the colouring's promise
/// (`VbdElements::separated_by`, checked when the solver is built); the phases keep the sweep
/// free of data races whatever the colouring, as the plan names no vertex twice.
pub fn vbd_solve(
    s: &Implicit,
    (plan, iteration): (&SweepPlan, u32),
    x: &mut [Vec4],
    steps: &mut [f32],
    next: &mut Vec<Option<(Vec4, f32)>>,
) {
    assert_eq!(x.len(), plan.vertices, "the plan is for another mesh");
    let order = &plan.order[..];
    next.resize(order.len(), None);
    let (x, next) = (Cells::new(x), Cells::new(next));
    let longest = AtomicU32::new(0);
    colour_after_colour(&plan.phases, |phase, rows| {
        if phase % 2 == 0 {
            // SAFETY: nothing writes `x` during a colour's steps (its writes are the next
            // phase), and each entry of `next` belongs to one row.
            let x_now = unsafe { x.as_slice() };
            for r in rows {
                unsafe { next.set(r, vertex_step(s, order[r] as usize, x_now)) };
            }
        } else {
            let mut most = 0.0f32;
            for r in rows {
                // SAFETY: row r's vertex is written by this row alone (the plan names no
                // vertex twice), and no colour's steps run while the writes do.
                if let Some((moved, len)) = unsafe { next.get(r) } {
                    unsafe { x.set(order[r] as usize, moved) };
                    most = most.max(len);
                }
            }
            // Lengths are not negative, so their bits order as the numbers do.
            longest.fetch_max(most.to_bits(), Ordering::Relaxed);
        }
    });
    let iteration = iteration as usize;
    steps[iteration] = steps[iteration].max(f32::from_bits(longest.into_inner()));
}

/// Vertex `i`'s next displacement and step length (`None` when pinned).
fn vertex_step(s: &Implicit, i: usize, x: &[Vec4]) -> Option<(Vec4, f32)> {
    let w = s.prev[i].w;
    if w == 0.0 {
        return None;
    }
    let sys = s.vertex_system(i, x, None, &mut |_, _| {});
    let d = x[i].truncate();
    let delta = newton_step(s, i, d, sys.force, sys.hessian);
    Some(((d + delta).extend(w), delta.length()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_plan_has_each_colour_twice() {
        let plan = SweepPlan::new(vec![0, 2, 1], &[0, 2, 3], 3);
        assert_eq!(plan.phases, vec![0..2, 0..2, 2..3, 2..3]);
    }

    #[test]
    #[should_panic(expected = "lists vertex 0 twice")]
    fn a_plan_refuses_a_vertex_twice() {
        SweepPlan::new(vec![0, 2, 0], &[0, 2, 3], 3);
    }

    #[test]
    #[should_panic(expected = "lists vertex 3 of 3")]
    fn a_plan_refuses_a_vertex_past_the_mesh() {
        SweepPlan::new(vec![0, 3, 1], &[0, 2, 3], 3);
    }

    #[test]
    #[should_panic(expected = "run past the order")]
    fn a_plan_refuses_rows_past_the_order() {
        SweepPlan::new(vec![0, 2, 1], &[0, 2, 4], 3);
    }
}
