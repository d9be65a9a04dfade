//! NVIDIA Warp's mass-spring cloth benchmark, rebuilt as a drapekit model, so that
//! `drapekit bench peer` times both on the same cloth.
//!
//! Warp's benchmark (`warp/examples/benchmarks/benchmark_cloth.py` in the `warp-lang` wheel,
//! version 1.19.0): a `dim × dim` grid of particles with spacing 0.1 m in the x–z plane (y = 0,
//! gravity −9.81 m/s² along y), particle `y·dim + x` at (0.1·x, 0, 0.1·y), mass 0.1 kg each,
//! the two corners of row y = 0 pinned; structural springs to the neighbours at distance 1,
//! bend springs to those at distance 2 along x and y, and shear springs along both diagonals,
//! all with k = 1000 N/m and damping 10 N·s/m; semi-implicit Euler with 16 substeps per
//! 1/60 s frame, no air damping, no bending hinges, no collisions. The peer driver checks the
//! installed benchmark against these values before anything is timed.

use crate::model::layout::{SimParams, INTEGRATOR_IMPLICIT};
use crate::model::{ClothModel, Spring};
use crate::plan::{Effects, PassPlan};
use glam::Vec3;

/// Particle spacing in m (`radius` in the benchmark).
pub const SPACING: f64 = 0.1;
/// Stiffness of every spring in N/m (`k_stretch`, `k_shear`, `k_bend`).
pub const STIFFNESS: f32 = 1000.0;
/// Damping of every spring in N·s/m (`create_spring`'s default `damp`).
pub const DAMPING: f32 = 10.0;
/// Mass of every particle in kg.
pub const MASS: f32 = 0.1;
/// Output frames per second (`sim_fps`).
pub const FPS: f64 = 60.0;
/// Substeps per frame (`sim_substeps`).
pub const SUBSTEPS: u32 = 16;
/// Gravity in m/s², along −y.
pub const GRAVITY: f32 = -9.81;

/// Warp's benchmark cloth with `dim × dim` particles, in Warp's particle and spring order.
/// Positions and rest lengths are computed in f64 and rounded once, as numpy does before
/// Warp's float32 arrays are filled, so both systems start from the same bits.
pub fn model(dim: u32) -> ClothModel {
    let d = dim as usize;
    let index = |x: usize, y: usize| (y * d + x) as u32;
    let at = |x: usize, y: usize| [x as f64 * SPACING, 0.0, y as f64 * SPACING];
    let mut positions = Vec::with_capacity(d * d);
    let mut pinned = Vec::with_capacity(d * d);
    let mut triangles = Vec::new();
    for y in 0..d {
        for x in 0..d {
            let p = at(x, y);
            positions.push(Vec3::new(p[0] as f32, p[1] as f32, p[2] as f32));
            pinned.push(y == 0 && (x == 0 || x == d - 1));
            if x > 0 && y > 0 {
                triangles.push([index(x - 1, y - 1), index(x, y - 1), index(x, y)]);
                triangles.push([index(x - 1, y - 1), index(x, y), index(x - 1, y)]);
            }
        }
    }
    let mut springs = Vec::new();
    let mut spring = |a: (usize, usize), b: (usize, usize)| {
        let (pa, pb) = (at(a.0, a.1), at(b.0, b.1));
        let rest = (0..3).map(|k| (pa[k] - pb[k]).powi(2)).sum::<f64>().sqrt();
        springs.push(Spring {
            ends: [index(a.0, a.1), index(b.0, b.1)],
            rest_length: rest as f32,
            stiffness: STIFFNESS,
            damping: DAMPING,
        });
    };
    // The benchmark's loops, in its order: first along rows (structural, bend, both shears),
    // then along columns (structural, bend).
    for y in 0..d {
        for x in 0..d {
            if x > 0 {
                spring((x, y), (x - 1, y));
            }
            if x > 1 {
                spring((x, y), (x - 2, y));
            }
            if y > 0 && x + 1 < d {
                spring((x, y), (x + 1, y - 1));
            }
            if y > 0 && x > 0 {
                spring((x, y), (x - 1, y - 1));
            }
        }
    }
    for x in 0..d {
        for y in 0..d {
            if y > 0 {
                spring((x, y), (x, y - 1));
            }
            if y > 1 {
                spring((x, y), (x, y - 2));
            }
        }
    }
    ClothModel {
        velocities: vec![Vec3::ZERO; positions.len()],
        masses: vec![MASS; positions.len()],
        positions,
        pinned,
        triangles,
        springs,
        hinges: Vec::new(),
        multigrid: None,
        seams: Vec::new(),
        membranes: Vec::new(),
        colliders: Vec::new(),
    }
}

/// The benchmark's frame length divided into `substeps`, in f64 then rounded, as Warp passes
/// `dt / substeps` to its kernel.
pub fn substep_dt(substeps: u32) -> f32 {
    (1.0 / FPS / substeps as f64) as f32
}

/// Parameters for `integrator` (symplectic, as Warp, or implicit) at `substeps` per frame;
/// `iterations` are implicit Euler's sweeps per substep.
pub fn params(model: &ClothModel, integrator: u32, substeps: u32, iterations: u32) -> SimParams {
    SimParams {
        gravity: [0.0, GRAVITY, 0.0, 0.0],
        num_particles: model.len() as u32,
        integrator,
        dt: substep_dt(substeps),
        iterations,
        ..Default::default()
    }
}

/// Springs and the integrator: no bending, wind, body, self-collision or strain limit.
pub fn plan(model: &ClothModel, integrator: u32) -> PassPlan {
    PassPlan::new(
        model,
        Effects {
            bending: false,
            wind: false,
            body: false,
            self_collision: false,
            implicit: integrator == INTEGRATOR_IMPLICIT,
            strain_limit: false,
        },
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spring_counts_and_incidence_match_the_benchmark_loops() {
        // For dim n: structural 2·n(n−1), bend 2·n(n−2), shear 2·(n−1)².
        for n in [3usize, 4, 16] {
            let m = model(n as u32);
            let expected = 2 * n * (n - 1) + 2 * n * (n - 2) + 2 * (n - 1) * (n - 1);
            assert_eq!(m.springs.len(), expected, "dim {n}");
            assert_eq!(m.len(), n * n);
            assert_eq!(m.pinned.iter().filter(|&&p| p).count(), 2);
            assert!(m.pinned[0] && m.pinned[n - 1]);
        }
        // An interior particle of a large grid has 12 springs: 4 structural, 4 bend, 4 shear.
        let m = model(16);
        let csr = m.spring_csr();
        let i = 8 * 16 + 8;
        assert_eq!(csr.offsets[i + 1] - csr.offsets[i], 12);
        // Rest lengths: 0.1, 0.2 and 0.1·√2 m, to f32 rounding.
        for s in &m.springs {
            let l = s.rest_length as f64;
            let ok = [0.1, 0.2, 0.1 * 2f64.sqrt()]
                .iter()
                .any(|r| (l - r).abs() < 1e-7);
            assert!(ok, "rest length {l}");
        }
    }
}
