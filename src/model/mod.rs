//! The cloth model: particles, springs, hinges and triangles, in SI units, plus the CSR
//! incidence lists that let each particle gather its forces without atomics, and the
//! parameter structs both backends share (`layout`, mirrored by `kernels/common.wgsl`).

pub mod bending;
pub mod budget;
mod build;
mod collider;
mod coloring;
mod deforming;
pub mod layout;
pub mod levels;
pub mod membrane;
pub mod multigrid;

pub use build::BuiltCloth;
pub use collider::build_body;
pub use coloring::Coloring;
pub use deforming::{build_deforming, MANNEQUIN_GLB_PATH};

use crate::mesh::TriMesh;
use crate::scene::Fabric;
use glam::{Vec3, Vec4};
use layout::{Hinge, Membrane, Seam, SpringRef, INTEGRATOR_EXPLICIT};

/// A stretch spring between two particles.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Spring {
    /// The two particles.
    pub ends: [u32; 2],
    /// Rest length in m.
    pub rest_length: f32,
    /// Stiffness in N/m.
    pub stiffness: f32,
    /// Damping along the spring in N·s/m.
    pub damping: f32,
}

/// Particles and the elements that act on them.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ClothModel {
    /// Initial positions in m.
    pub positions: Vec<Vec3>,
    /// Initial velocities in m/s.
    pub velocities: Vec<Vec3>,
    /// Particle masses in kg (pinned particles keep theirs, for reporting).
    pub masses: Vec<f32>,
    /// Pinned particles do not move.
    pub pinned: Vec<bool>,
    /// Triangles (for wind and output).
    pub triangles: Vec<[u32; 3]>,
    /// Stretch springs on mesh edges.
    pub springs: Vec<Spring>,
    /// Bending hinges on interior edges.
    pub hinges: Vec<Hinge>,
    /// Seam pairs (empty unless the cloth comes from a sewing pattern).
    pub seams: Vec<Seam>,
    /// Membrane triangles when the fabric is an orthotropic membrane (its springs then carry
    /// no force: they stay as the mesh's edges, for colouring, strain and the limiter).
    pub membranes: Vec<Membrane>,
    /// The collision bodies, in scene order.
    pub colliders: Vec<std::sync::Arc<crate::body::Collider>>,
    /// The coarse levels of implicit Euler's multigrid solve (`None`: plain Vertex Block
    /// Descent).
    pub multigrid: Option<std::sync::Arc<multigrid::Multigrid>>,
}

/// A compressed-sparse-row incidence list: `items[offsets[i]..offsets[i + 1]]` belong to particle i.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Csr<T> {
    /// `n + 1` offsets into `items`.
    pub offsets: Vec<u32>,
    /// The entries of all particles, particle by particle.
    pub items: Vec<T>,
}

impl<T: Copy> Csr<T> {
    /// Builds a CSR list from `(particle, item)` pairs; items keep their input order per particle.
    pub fn from_pairs(n: usize, pairs: &[(u32, T)]) -> Self {
        let mut offsets = vec![0u32; n + 1];
        for &(p, _) in pairs {
            offsets[p as usize + 1] += 1;
        }
        for i in 0..n {
            offsets[i + 1] += offsets[i];
        }
        // A counting sort: each particle's items land in input order, which fixes the sum
        // order (what a stable sort by particle gives, in one pass).
        // Particle p's items fill offsets[p]..offsets[p + 1] exactly, and these ranges tile
        // the list, so every slot of the placeholder fill is overwritten.
        let mut next = offsets.clone();
        let mut items = pairs
            .first()
            .map_or(Vec::new(), |&(_, x)| vec![x; pairs.len()]);
        for &(p, item) in pairs {
            items[next[p as usize] as usize] = item;
            next[p as usize] += 1;
        }
        Csr { offsets, items }
    }
}

/// sin(θ/2) of the signed dihedral angle of a hinge, as in `hinge_forces.wgsl`.
pub fn hinge_sin_half(x3: Vec3, x4: Vec3, x1: Vec3, x2: Vec3) -> f32 {
    let e = x4 - x3;
    let n1 = (x1 - x3).cross(x1 - x4).normalize_or_zero();
    let n2 = (x2 - x4).cross(x2 - x3).normalize_or_zero();
    // |n̂1 − n̂2| = 2 sin(θ/2), without the cancellation of √(½(1 − cos θ)) at small θ.
    let s = (0.5 * (n1 - n2).length()).min(1.0);
    if n1.cross(n2).dot(e) < 0.0 {
        -s
    } else {
        s
    }
}

/// k·|E|²/(|N1| + |N2|) of a hinge with shared edge x3→x4 and opposite vertices x1, x2 (as
/// `hinge_forces` weighs it), in N·m; 0 for a degenerate hinge.
pub fn hinge_weight(stiffness: f32, x3: Vec3, x4: Vec3, x1: Vec3, x2: Vec3) -> f32 {
    let n1 = (x1 - x3).cross(x1 - x4).length();
    let n2 = (x2 - x4).cross(x2 - x3).length();
    if n1 + n2 <= 0.0 {
        return 0.0;
    }
    stiffness * (x4 - x3).length_squared() / (n1 + n2)
}

impl ClothModel {
    /// Builds particles, springs and hinges from a mesh and a fabric. Springs sit on every mesh
    /// edge with k = Y·ΣA_T/L², summed over the one or two triangles on the edge (Van Gelder
    /// 1998), so the sheet's stiffness does not change with resolution. On a regular grid a
    /// uniform stretch along an axis then stores 1.25× the isotropic membrane's energy.
    ///
    /// ```
    /// use drapekit::mesh::{GridPlane, TriMesh};
    /// use drapekit::model::ClothModel;
    /// use drapekit::scene::Fabric;
    /// use glam::Vec3;
    ///
    /// // A 1 m × 1 m sheet of 11 × 11 particles, 0.2 kg/m², held by its first corner.
    /// let mesh = TriMesh::grid(1.0, 1.0, 11, 11, Vec3::ZERO, GridPlane::Xy);
    /// let fabric = Fabric {
    ///     density: 0.2,
    ///     stretch_stiffness: 500.0,
    ///     bending_stiffness: Some(1e-5),
    ///     damping_ratio: 0.05,
    ///     preset: None,
    ///     membrane: None,
    ///     buckling: false,
    /// };
    /// let model = ClothModel::from_mesh(&mesh, &fabric, &[0]);
    /// assert_eq!(model.len(), 121);
    /// // Each particle carries a third of its triangles' mass: 0.2 kg in all.
    /// let mass: f32 = model.masses.iter().sum();
    /// assert!((mass - 0.2).abs() < 1e-5);
    /// assert!(model.pinned[0] && !model.pinned[1]);
    /// // One spring per edge: 2 × 10 × 11 along the rows and columns, plus 100 diagonals.
    /// assert_eq!(model.springs.len(), 320);
    /// ```
    pub fn from_mesh(mesh: &TriMesh, fabric: &Fabric, pinned_ids: &[u32]) -> Self {
        let n = mesh.positions.len();
        let masses: Vec<f32> = mesh
            .vertex_areas()
            .iter()
            .map(|a| a * fabric.density)
            .collect();
        let mut pinned = vec![false; n];
        for &i in pinned_ids {
            pinned[i as usize] = true;
        }
        let mut springs = Vec::new();
        let mut hinges = Vec::new();
        for (edge, edge_area) in mesh.edges_with_areas() {
            let [a, b] = edge.v;
            let (pa, pb) = (mesh.positions[a as usize], mesh.positions[b as usize]);
            let rest_length = pa.distance(pb);
            if rest_length <= 0.0 {
                continue;
            }
            let stiffness = match fabric.membrane {
                Some(_) => 0.0,
                None => fabric.stretch_stiffness * edge_area / (rest_length * rest_length),
            };
            let (ma, mb) = (masses[a as usize], masses[b as usize]);
            let reduced_mass = ma * mb / (ma + mb);
            let damping = 2.0 * fabric.damping_ratio * (stiffness * reduced_mass).sqrt();
            springs.push(Spring {
                ends: [a, b],
                rest_length,
                stiffness,
                damping,
            });
            if let (Some(kb), [Some(o1), Some(o2)]) = (fabric.bending_stiffness, edge.opposite) {
                let p = |i: u32| mesh.positions[i as usize];
                // A flat (zero-area) triangle has no normal, so no dihedral angle: no hinge.
                let flat = |o: u32| (p(b) - p(a)).cross(p(o) - p(a)).length_squared() == 0.0;
                if flat(o1) || flat(o2) {
                    continue;
                }
                hinges.push(Hinge {
                    v: [a, b, o1, o2],
                    stiffness: kb,
                    rest_sin_half: hinge_sin_half(p(a), p(b), p(o1), p(o2)),
                    rest_weight: hinge_weight(kb, p(a), p(b), p(o1), p(o2)),
                    _pad1: 0,
                });
            }
        }
        let membranes = match &fabric.membrane {
            Some(m) => membrane::build_membranes(
                &mesh.positions,
                &masses,
                &mesh.triangles,
                &membrane::world_grain(mesh.triangles.len(), 0.0, Vec3::Z),
                m,
                fabric.damping_ratio,
            ),
            None => Vec::new(),
        };
        ClothModel {
            positions: mesh.positions.clone(),
            velocities: vec![Vec3::ZERO; n],
            masses,
            pinned,
            triangles: mesh.triangles.clone(),
            springs,
            hinges,
            seams: Vec::new(),
            membranes,
            colliders: Vec::new(),
            multigrid: None,
        }
    }

    /// Elements in the largest array a backend holds per model: the particles, or an incidence
    /// list (two entries per spring, four per hinge, three per triangle and per seam pair).
    pub fn largest_array(&self) -> usize {
        (self.len())
            .max(2 * self.springs.len())
            .max(4 * self.hinges.len())
            .max(3 * self.triangles.len())
            .max(3 * self.seams.len())
    }

    /// Number of particles.
    pub fn len(&self) -> usize {
        self.positions.len()
    }

    /// Whether the model has no particles.
    pub fn is_empty(&self) -> bool {
        self.positions.is_empty()
    }

    /// GPU-ready positions: xyz in m, w = inverse mass (0 when pinned).
    pub fn packed_positions(&self) -> Vec<Vec4> {
        (0..self.len())
            .map(|i| {
                let inv_mass = if self.pinned[i] || self.masses[i] <= 0.0 {
                    0.0
                } else {
                    1.0 / self.masses[i]
                };
                self.positions[i].extend(inv_mass)
            })
            .collect()
    }

    /// GPU-ready velocities: xyz in m/s, w = 0.
    pub fn packed_velocities(&self) -> Vec<Vec4> {
        self.velocities.iter().map(|v| v.extend(0.0)).collect()
    }

    /// Springs seen from each end, in spring order per particle.
    pub fn spring_csr(&self) -> Csr<SpringRef> {
        let mut pairs = Vec::with_capacity(2 * self.springs.len());
        for s in &self.springs {
            for (me, other) in [(s.ends[0], s.ends[1]), (s.ends[1], s.ends[0])] {
                let entry = SpringRef {
                    other,
                    rest_length: s.rest_length,
                    stiffness: s.stiffness,
                    damping: s.damping,
                };
                pairs.push((me, entry));
            }
        }
        Csr::from_pairs(self.len(), &pairs)
    }

    /// Hinge references `hinge * 4 + role` per particle.
    pub fn hinge_csr(&self) -> Csr<u32> {
        let mut pairs = Vec::with_capacity(4 * self.hinges.len());
        for (h, hinge) in self.hinges.iter().enumerate() {
            for (role, &v) in hinge.v.iter().enumerate() {
                pairs.push((v, (h * 4 + role) as u32));
            }
        }
        Csr::from_pairs(self.len(), &pairs)
    }

    /// Membrane refs per particle: triangle index · 4 + role (0, 1, 2: its vertices).
    pub fn membrane_csr(&self) -> Csr<u32> {
        let mut pairs = Vec::with_capacity(3 * self.membranes.len());
        for (t, m) in self.membranes.iter().enumerate() {
            for role in 0..3 {
                pairs.push((m.v[role], (t * 4 + role) as u32));
            }
        }
        Csr::from_pairs(self.len(), &pairs)
    }

    /// Lays the membrane's warp along `grain` (one direction per triangle of `triangles`),
    /// rebuilding it for `fabric` and, where the fabric bends by direction, setting each hinge's
    /// bending by its edge's angle to the grain (nothing without a membrane). `seam_sides`:
    /// each hinge across a seam (its index) and the edge of the other panel sewn to its own.
    pub fn set_grain(
        &mut self,
        grain: &[Vec3],
        fabric: &crate::scene::Fabric,
        seam_sides: &[(usize, [u32; 2])],
    ) {
        if let Some(m) = &fabric.membrane {
            self.membranes = membrane::build_membranes(
                &self.positions,
                &self.masses,
                &self.triangles,
                grain,
                m,
                fabric.damping_ratio,
            );
            if let Some(strips) = m.bending {
                bending::set_by_direction(self, grain, strips, seam_sides);
            }
        }
    }

    /// Seam refs per particle: pair index · 4 + role (0: seam vertex, 1, 2: partner segment
    /// ends). A partner end with zero weight gets no ref: its share of the force is zero.
    pub fn seam_csr(&self) -> Csr<u32> {
        let mut pairs = Vec::with_capacity(3 * self.seams.len());
        for (k, s) in self.seams.iter().enumerate() {
            let shares = [1.0, 1.0 - s.weight, s.weight];
            for (role, share) in shares.into_iter().enumerate() {
                if share != 0.0 {
                    pairs.push((s.v[role], (k * 4 + role) as u32));
                }
            }
        }
        Csr::from_pairs(self.len(), &pairs)
    }

    /// Triangle indices per particle.
    pub fn triangle_csr(&self) -> Csr<u32> {
        let mut pairs = Vec::with_capacity(3 * self.triangles.len());
        for (t, tri) in self.triangles.iter().enumerate() {
            for &v in tri {
                pairs.push((v, t as u32));
            }
        }
        Csr::from_pairs(self.len(), &pairs)
    }

    /// Triangles padded to `vec4<u32>` for the GPU.
    pub fn packed_triangles(&self) -> Vec<[u32; 4]> {
        self.triangles
            .iter()
            .map(|t| [t[0], t[1], t[2], 0])
            .collect()
    }

    /// An estimate of the largest stable substep, in s, for the given integrator.
    ///
    /// The highest angular frequency is bounded per particle by Gershgorin's theorem,
    /// ω² ≤ 2·Σk/m (springs plus the hinges' linearised stiffness), and the fastest damping rate
    /// by γ ≤ 2·Σc/m + air damping. Semi-implicit Euler is stable for ω·dt < 2 and γ·dt < 2.
    /// Explicit Euler on a damped oscillator needs ω·dt < 2ζ with ζ = γ/(2ω), i.e.
    /// dt < γ/ω²; with no damping at all it has no stable step and `None` is returned.
    pub fn stable_dt(&self, integrator: u32, air_damping: f32) -> Option<f32> {
        self.stable_step(integrator, air_damping, [1.0; 2])
            .map(|(dt, _)| dt)
    }

    /// `stable_dt` and what sets it: `"stretch"` (springs or membrane), `"seam"` or `"bending"`
    /// (the largest term of the fastest particle's Gershgorin sum), or `"damping"` (the damping
    /// rate bound). A membrane that stiffens in tension is taken at its stiffest, its warp and
    /// weft stiffness times `membrane_tangent` (`scene::Fabric::tangent_ratio`; 1 when linear).
    pub fn stable_step(
        &self,
        integrator: u32,
        air_damping: f32,
        membrane_tangent: [f32; 2],
    ) -> Option<(f32, &'static str)> {
        let n = self.len();
        let mut k_sum = vec![0.0f32; n];
        let mut c_sum = vec![0.0f32; n];
        // Each particle's sum split by source, to name the term that binds.
        let mut parts = vec![[0.0f32; 3]; n];
        for s in &self.springs {
            for e in s.ends {
                k_sum[e as usize] += s.stiffness;
                parts[e as usize][0] += s.stiffness;
                c_sum[e as usize] += s.damping;
            }
        }
        // A seam pair is a zero-length spring between the vertex and the weighted partner
        // point: its stiffness matrix k·g·gᵀ with g = (1, −(1−w), −w) has row sums 2k·g_i.
        for s in &self.seams {
            let shares = [1.0, 1.0 - s.weight, s.weight];
            for (&v, share) in s.v.iter().zip(shares) {
                k_sum[v as usize] += share * s.stiffness;
                parts[v as usize][1] += share * s.stiffness;
                c_sum[v as usize] += share * s.damping;
            }
        }
        for h in &self.hinges {
            let p = |i: u32| self.positions[i as usize];
            let [x3, x4, x1, x2] = h.v.map(p);
            let e = x4 - x3;
            let n1 = (x1 - x3).cross(x1 - x4).length();
            let n2 = (x2 - x4).cross(x2 - x3).length();
            if n1 <= 0.0 || n2 <= 0.0 {
                continue;
            }
            let weight = e.length_squared() / (n1 + n2);
            // |∂θ/∂x|² is at most |E|²/|N|² for the opposite vertices; d sin(θ/2)/dθ ≤ 1/2.
            let grad_sq = e.length_squared() / (n1.min(n2) * n1.min(n2));
            let k_hinge = 0.5 * h.stiffness * weight * grad_sq;
            for v in h.v {
                k_sum[v as usize] += k_hinge;
                parts[v as usize][2] += k_hinge;
            }
        }
        // A membrane triangle's Hessian at rest (|w_u| = |w_v| = 1, w_u ⟂ w_v: the stretch
        // conditions' transverse terms vanish) has blocks k_u·a_r·a_s·ŵ_uŵ_uᵀ + k_v·b_r·b_s·ŵ_vŵ_vᵀ
        // + k_s·g_r·g_sᵀ with |g_r|² = a_r² + b_r² (`cpu::membrane`); the sum of its block
        // norms along vertex r's row bounds the row, of which the springs' 2k convention takes
        // half. Its damping is τ times the same.
        for m in &self.membranes {
            let (a, b) = m.coefficients();
            let [ku, kv, ks, tau] = m.stiffness;
            let g = |r: usize| (a[r] * a[r] + b[r] * b[r]).sqrt();
            // The damping acts with the small-strain stiffness (`cpu::membrane`).
            let row = |r: usize, [ku, kv]: [f32; 2]| -> f32 {
                (0..3)
                    .map(|s| ku * (a[r] * a[s]).abs() + kv * (b[r] * b[s]).abs() + ks * g(r) * g(s))
                    .sum()
            };
            let stiffest = [ku * membrane_tangent[0], kv * membrane_tangent[1]];
            for r in 0..3 {
                let v = m.v[r] as usize;
                let stiffness = 0.5 * row(r, stiffest);
                k_sum[v] += stiffness;
                parts[v][0] += stiffness;
                c_sum[v] += 0.5 * tau * row(r, [ku, kv]);
            }
        }
        let mut omega_sq_max = 0.0f32;
        let mut fastest = 0usize;
        let mut gamma_max = air_damping;
        let mut zeta_min = f32::INFINITY;
        for i in 0..n {
            if self.pinned[i] || self.masses[i] <= 0.0 {
                continue;
            }
            let omega_sq = 2.0 * k_sum[i] / self.masses[i];
            let gamma = 2.0 * c_sum[i] / self.masses[i] + air_damping;
            if omega_sq > omega_sq_max {
                omega_sq_max = omega_sq;
                fastest = i;
            }
            gamma_max = gamma_max.max(gamma);
            if omega_sq > 0.0 {
                // ζ = γ / (2ω) of this particle's fastest mode.
                zeta_min = zeta_min.min(gamma / (2.0 * omega_sq.sqrt()));
            }
        }
        let damping_bound = if gamma_max > 0.0 {
            2.0 / gamma_max
        } else {
            f32::INFINITY
        };
        let p = parts[fastest];
        let stiffest = if p[1] >= p[0] && p[1] >= p[2] {
            "seam"
        } else if p[2] > p[0] {
            "bending"
        } else {
            "stretch"
        };
        let pick = |stiffness_bound: f32| {
            if damping_bound < stiffness_bound {
                (damping_bound, "damping")
            } else {
                (stiffness_bound, stiffest)
            }
        };
        if integrator == INTEGRATOR_EXPLICIT {
            if omega_sq_max == 0.0 {
                return Some((damping_bound, "damping"));
            }
            if zeta_min <= 0.0 {
                return None;
            }
            let omega = omega_sq_max.sqrt();
            Some(pick(2.0 * zeta_min / omega))
        } else if omega_sq_max == 0.0 {
            Some((damping_bound, "damping"))
        } else {
            Some(pick(2.0 / omega_sq_max.sqrt()))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn csr_keeps_order_per_particle() {
        let csr = Csr::from_pairs(3, &[(2, 'a'), (0, 'b'), (2, 'c'), (0, 'd')]);
        assert_eq!(csr.offsets, vec![0, 2, 2, 4]);
        assert_eq!(csr.items, vec!['b', 'd', 'a', 'c']);
    }

    #[test]
    fn grid_spring_stiffness_matches_van_gelder() {
        // 11×11 particles, h = 0.1 m, Y = 100 N/m. Under a uniform x-strain ε = 1 a spring with
        // x-extent dx stretches by dx²/L. Horizontal springs: 9 interior rows × 10 with k = Y and
        // 2 boundary rows × 10 with k = Y/2 → ½·Y·h²·100 = 50 J. Diagonals: 100 with k = Y/2 and
        // stretch h/√2 → 100·Y·h²/8 = 12.5 J. Vertical springs store nothing. Total 62.5 J,
        // 1.25× the membrane's ½·Y·ε²·A = 50 J.
        let mesh = TriMesh::grid(1.0, 1.0, 11, 11, Vec3::ZERO, crate::mesh::GridPlane::Xy);
        let fabric = Fabric {
            density: 0.2,
            stretch_stiffness: 100.0,
            bending_stiffness: None,
            damping_ratio: 0.0,
            preset: None,
            membrane: None,
            buckling: false,
        };
        let model = ClothModel::from_mesh(&mesh, &fabric, &[]);
        let energy: f64 = model
            .springs
            .iter()
            .map(|s| {
                let d = model.positions[s.ends[1] as usize] - model.positions[s.ends[0] as usize];
                let stretch = (d.x * d.x / s.rest_length) as f64;
                0.5 * s.stiffness as f64 * stretch * stretch
            })
            .sum();
        // f32 grid coordinates and areas carry ~1e-6 relative error each; 1e-4 covers 320 terms.
        assert!((energy - 62.5).abs() < 62.5 * 1e-4, "{energy}");
    }
}
