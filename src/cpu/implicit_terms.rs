//! Implicit Euler's incremental potential at one vertex: its force (−gradient), its Hessian
//! blocks and the change of its energy along a correction. Every implicit stage (`vbd_solve`,
//! `assemble`, `line_energy`, `line_slopes`, `force_residual`) evaluates these; `kernels/implicit_terms.wgsl`
//! is their GPU twin.
//!
//! Backward Euler is x_{n+1} = argmin G(x) with
//! G(x) = ½‖x − y‖²_M / h² + ½(c·m/h)‖x − xₙ‖² + E(x) + friction.
//! The iterate is kept as the displacement D = x − xₙ of each vertex over the step, not as a
//! world position: a 5 mm edge at 1.3 m keeps 8 fewer bits in world coordinates (ulp 1.2e-7 m)
//! than as a difference of displacements (ulp ~1e-10 m over a millimetre), and a spring's
//! force k·1.2e-7 m is already several times a 5 mm particle's weight. Edge vectors, and a
//! hinge's vertices relative to its first, are (xₙᵢ − xₙⱼ) + (Dᵢ − Dⱼ): the first difference
//! is exact in f32 for nearby points.
//!
//! The terms (each a potential in D within a step, so that a line search can compare
//! energies):
//! - inertia ½(m/h²)|D − Y|², Y = h·vₙ + h²·(g + f_wind/m); air damping ½(c·m/h)|D|²;
//! - springs ½k(|d| − L)², or buckling in compression (`stretch_law`), Hessian made positive
//!   semi-definite (a compressed spring's transverse term dropped), and damping ½(c/h)(n̂ₙ·(Dᵢ − Dⱼ))² along the spring's
//!   direction at the start of the step n̂ₙ;
//! - hinges w₀·ψ(θ), ψ = −2cos(θ/2) − sin(θ₀/2)·θ, whose gradient is the Bridson hinge force
//!   w₀(sin(θ/2) − sin(θ₀/2))·u with the hinge's rest weight w₀ (`Hinge::rest_weight`);
//!   Gauss–Newton Hessian ½cos(θ/2)·w₀·uᵢuⱼᵀ;
//! - seam pairs ½k|gap|² (zero rest) or ½k(|gap| − r)² beyond a shrinking rest gap r, and
//!   damping ½(c/h)|opening|²; the partner's ends take −(1 − w) and −w shares;
//! - contact with each body through a plane fixed for the step (`contact_planes`):
//!   φ ≈ c + n̂·D, penalty ½k_c(thickness − φ)² where φ < thickness, k_c = `CONTACT_RATIO`
//!   times the vertex's constant stiffness (`contact_stiffness`);
//! - friction as a lagged potential μλ·f₀(|u_T|) with the normal force λ estimated at the
//!   start of the step (`contact_planes`), u_T the slip relative to the body in the plane and
//!   f₀(s) = s²/(2ε) below ε = ε_v·h, s − ε/2 above: Coulomb friction, static (proportional to
//!   the slip) below the slip speed ε_v.

mod energy_change;

pub use energy_change::hinge_psi;

use super::hinge_forces::HingeFrame;
use super::membrane::MembraneStep;
use super::seam_forces::rest_gap;
use super::stretch_law::StretchLaw;
use crate::model::layout::{Hinge, Membrane, Seam, SimParams, SpringRef, SubstepParams};
use crate::model::multigrid::ElementBlocks;
use glam::{Mat3, Vec3, Vec3A, Vec4};

/// Contact is this many times stiffer than the vertex's own stiffness (`contact_stiffness`),
/// whatever the fabric and step.
pub const CONTACT_RATIO: f32 = 100.0;

/// A vertex within this fraction of the thickness outside a body's contact layer touches the
/// body: resting vertices sit at the layer's edge, where a sweep's step or `collide_body`
/// leaves them, give or take the SDF's rounding. Touching vertices get friction's normal force
/// at the start of a step (`contact_planes`), and their normal is left out of the Newton
/// step's linear system and of the force residual.
pub const CONTACT_SLACK_FRACTION: f32 = 0.01;

/// Blocks of `num_bodies × n` entries in `Implicit::planes`: every body's plane at every
/// vertex, then every body's surface velocity there (`Implicit::surface_velocity`).
pub const PLANE_BLOCKS: usize = 2;

/// The elements a vertex gathers over, as CSR lists (the same arrays the force stages use).
pub struct VbdElements<'a> {
    /// Where each vertex's entries are in the lists below: `None` when the lists run in
    /// particle order (vertex i's entries are `offsets[i]..offsets[i + 1]`), `Some(row_of)`
    /// when they run in a sweep's order (vertex i's are those of the sweep's row `row_of[i]`).
    pub row_of: Option<&'a [u32]>,
    /// Spring offsets per particle and incident springs.
    pub springs: (&'a [u32], &'a [SpringRef]),
    /// Hinge offsets, hinge refs (index · 4 + role) and each ref's hinge (at the ref's
    /// position, so that a vertex's hinges lie side by side), when bending is on.
    pub hinges: Option<(&'a [u32], &'a [u32], &'a [Hinge])>,
    /// Seam offsets, seam refs (index · 4 + role) and each ref's seam pair (at the ref's
    /// position), when the cloth is sewn.
    pub seams: Option<(&'a [u32], &'a [u32], &'a [Seam])>,
    /// Membrane offsets, refs (triangle · 4 + role) and each ref's triangle (at the ref's
    /// position), when the fabric is a membrane.
    pub membranes: Option<(&'a [u32], &'a [u32], &'a [Membrane])>,
}

impl VbdElements<'_> {
    /// Whether no element joins two vertices of one colour (`colour` of each vertex): what a
    /// Vertex Block Descent sweep needs to update a colour's vertices at once, each reading
    /// only vertices of other colours.
    pub fn separated_by(&self, colour: &[u32]) -> bool {
        let mut apart = true;
        for i in 0..colour.len() {
            let mut meets = |j: u32| apart &= j as usize == i || colour[j as usize] != colour[i];
            let (offsets, springs) = self.springs;
            springs[self.span(offsets, i)]
                .iter()
                .for_each(|s| meets(s.other));
            if let Some((offsets, _, hinges)) = self.hinges {
                for hinge in &hinges[self.span(offsets, i)] {
                    hinge.v.iter().for_each(|&j| meets(j));
                }
            }
            if let Some((offsets, _, seams)) = self.seams {
                for s in &seams[self.span(offsets, i)] {
                    s.v[..3].iter().for_each(|&j| meets(j));
                }
            }
            if let Some((offsets, _, membranes)) = self.membranes {
                for m in &membranes[self.span(offsets, i)] {
                    m.v[..3].iter().for_each(|&j| meets(j));
                }
            }
        }
        apart
    }

    /// The entries of vertex `i` in one of the per-vertex lists, whose offsets are `offsets`.
    #[inline]
    pub fn span(&self, offsets: &[u32], i: usize) -> std::ops::Range<usize> {
        let row = self.row_of.map_or(i, |row_of| row_of[i] as usize);
        offsets[row] as usize..offsets[row + 1] as usize
    }
}

/// What every implicit stage reads: the step, the state at its start, the elements and the
/// contact planes.
pub struct Implicit<'a> {
    /// Run-constant parameters.
    pub params: &'a SimParams,
    /// This substep's values (bodies at their poses at its end).
    pub step: &'a SubstepParams,
    /// xₙ, w = inverse mass (0: pinned).
    pub prev: &'a [Vec4],
    /// The inertial target Y as a displacement from xₙ.
    pub target: &'a [Vec4],
    /// The elements.
    pub el: &'a VbdElements<'a>,
    /// Each body's contact plane at each vertex, body after body (`num_bodies × n`): normal
    /// (xyz) and c (w), φ ≈ c + n̂·D; then each body's surface velocity at each vertex (xyz,
    /// m/s), as many again (`PLANE_BLOCKS`).
    pub planes: &'a [Vec4],
    /// Each vertex's normal force per body at the start of the step (friction's λ), in N.
    pub lambdas: &'a [Vec4],
}

/// A vertex's force and Hessian diagonal block.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VertexSystem {
    /// f = −∇ᵢG, in N.
    pub force: Vec3,
    /// ∂²G/∂Dᵢ², in N/m.
    pub hessian: Mat3,
}

pub(crate) fn outer(a: Vec3, b: Vec3) -> Mat3 {
    Mat3::from_cols(a * b.x, a * b.y, a * b.z)
}

/// Hessian of a spring's energy in d, made positive semi-definite: `axial`·n̂n̂ᵀ +
/// k·max(0, 1 − L/|d|)·(I − n̂n̂ᵀ), with `axial` the law's axial stiffness (k when linear). The
/// transverse term is negative for a compressed spring; it is dropped.
fn spring_hessian(axial: f32, k: f32, rest: f32, d: Vec3, len: f32) -> Mat3 {
    let n = d / len;
    let nn = outer(n, n);
    let transverse = (1.0 - rest / len).max(0.0);
    axial * nn + (k * transverse) * (Mat3::IDENTITY - nn)
}

/// A spring's stretch |e| − L for e = start + change, as (|start| − L) plus the change's
/// share (2·start·change + |change|²)/(|e| + |start|): |e| in f32 moves in steps of its ulp (1e-9 m
/// at 2 cm), k times which is 2% of a 5 mm particle's weight, and the solve cannot balance a
/// force that jumps; the split form is smooth in the change down to its own rounding.
pub(crate) fn stretch(start: Vec3, start_len: f32, change: Vec3, len: f32, rest: f32) -> f32 {
    let grow = 2.0 * start.dot(change) + change.length_squared();
    let sum = len + start_len;
    (start_len - rest) + if sum > 0.0 { grow / sum } else { 0.0 }
}

fn v3(v: Vec4) -> Vec3 {
    v.truncate()
}

impl Implicit<'_> {
    fn n(&self) -> usize {
        self.params.num_particles as usize
    }

    /// Vertex `i`'s plane for body `b`.
    pub fn plane(&self, b: usize, i: usize) -> Vec4 {
        self.planes[b * self.n() + i]
    }

    // Deforming bodies: friction against the skin's velocity.
    /// The velocity of body `b`'s surface at vertex `i`'s start of step, m/s (xyz), stored by
    /// `contact_planes` after the planes (`PLANE_BLOCKS`): a deforming body's skin
    /// moves unlike its root, so the velocity comes from the same query as the plane.
    pub fn surface_velocity(&self, b: usize, i: usize) -> Vec3 {
        v3(self.planes[(self.params.num_bodies as usize + b) * self.n() + i])
    }

    /// A seam pair's gap (partner point minus seam vertex) and opening (its change over the
    /// step) at displacements `d`.
    fn seam_gap(&self, s: &Seam, d: &[Vec4]) -> (Vec3, Vec3) {
        let w = s.weight;
        let [a, b0, b1] = [s.v[0], s.v[1], s.v[2]].map(|v| v3(self.prev[v as usize]));
        let opening = seam_combination(s, d);
        let start = (1.0 - w) * (b0 - a) + w * (b1 - a);
        (start + opening, opening)
    }

    /// A seam pair's spring force on its seam vertex and that force's Hessian (a zero rest gap
    /// pulls like a zero-length spring; a positive one only beyond it), plus damping.
    fn seam_system(&self, s: &Seam, d: &[Vec4]) -> (Vec3, Mat3) {
        let h = self.params.dt;
        let (gap, opening) = self.seam_gap(s, d);
        let rest = rest_gap(s, self.params, self.step.time);
        let mut fa = s.damping / h * opening;
        let mut ha = Mat3::from_diagonal(Vec3::splat(s.damping / h));
        if rest <= 0.0 {
            fa += s.stiffness * gap;
            ha += Mat3::from_diagonal(Vec3::splat(s.stiffness));
        } else {
            let len = gap.length();
            if len > rest {
                fa += s.stiffness * (len - rest) / len * gap;
                ha += spring_hessian(s.stiffness, s.stiffness, rest, gap, len);
            }
        }
        (fa, ha)
    }

    /// The frame of hinge `hinge` at displacements `d`.
    #[inline(always)]
    fn hinge_frame(&self, hinge: &Hinge, d: &[Vec4]) -> Option<HingeFrame> {
        let corners = self.hinge_corners(hinge, |v| v3(d[v]));
        HingeFrame::at(corners, hinge.stiffness)
    }

    /// The hinge's four vertices relative to its first, at displacements `disp(v)`: the
    /// start's differences xₙᵥ − xₙₒ (exact in f32 for nearby points) plus the displacements'
    /// differences, as the springs' edge vectors are formed. World positions xₙ + D would each
    /// round to 6e-8 m at 1.3 m, 1e-5 of a 5 mm edge: the angle would move in steps of about
    /// 1e-5 rad, and the bending force with it, by more than the force residual a converged
    /// 5 mm step leaves (Newton's steps stalled at 2% of the weight).
    #[inline(always)]
    fn hinge_corners(&self, hinge: &Hinge, disp: impl Fn(usize) -> Vec3) -> [Vec3A; 4] {
        let o = hinge.v[0] as usize;
        let (start, moved) = (v3(self.prev[o]), disp(o));
        hinge.v.map(|v| {
            let v = v as usize;
            Vec3A::from((v3(self.prev[v]) - start) + (disp(v) - moved))
        })
    }

    /// The vertex's constant stiffness, the mean diagonal of what does not depend on the
    /// state: inertia m/h², air damping, each spring's (k + c/h)/3 and each seam pair's
    /// share²·(k + c/h). Contact is `CONTACT_RATIO` times this.
    pub fn contact_stiffness(&self, i: usize) -> f32 {
        let h = self.params.dt;
        let mass = 1.0 / self.prev[i].w;
        let mut sum = mass / (h * h) + self.params.air_damping * mass / h;
        let (offsets, springs) = self.el.springs;
        for s in &springs[self.el.span(offsets, i)] {
            sum += (s.stiffness + s.damping / h) / 3.0;
        }
        if let Some((offsets, refs, seams)) = self.el.seams {
            let range = self.el.span(offsets, i);
            for (&r, s) in refs[range.clone()].iter().zip(&seams[range]) {
                let share = seam_share(s, r % 4);
                sum += share * share * (s.stiffness + s.damping / h);
            }
        }
        if let Some((offsets, refs, membranes)) = self.el.membranes {
            let range = self.el.span(offsets, i);
            for (&r, m) in refs[range.clone()].iter().zip(&membranes[range]) {
                sum += MembraneStep::constant_stiffness(m, (r % 4) as usize, h);
            }
        }
        CONTACT_RATIO * sum
    }

    /// Body `b`'s slip of vertex `i` over the step relative to the body surface, in the plane
    /// with normal `n`: the displacement less the body's own over the step.
    fn slip(&self, b: usize, i: usize, d: Vec3, n: Vec3) -> Vec3 {
        let u = d - self.params.dt * self.surface_velocity(b, i);
        u - u.dot(n) * n
    }

    /// Vertex `i`'s force and Hessian diagonal block at displacements `d` (a pinned vertex's
    /// are zero). With `blocks` (whose numbering needs the lists in particle order), each
    /// off-diagonal block of the vertex's Hessian row goes to `sink` (block index, value);
    /// blocks towards pinned vertices are left out.
    pub fn vertex_system(
        &self,
        i: usize,
        d: &[Vec4],
        blocks: Option<&ElementBlocks>,
        sink: &mut impl FnMut(u32, Mat3),
    ) -> VertexSystem {
        assert!(
            blocks.is_none() || self.el.row_of.is_none(),
            "element blocks are numbered in particle order"
        );
        let p = self.params;
        let h = p.dt;
        let inv_mass = self.prev[i].w;
        if inv_mass == 0.0 {
            return VertexSystem {
                force: Vec3::ZERO,
                hessian: Mat3::ZERO,
            };
        }
        let free = |j: usize| self.prev[j].w != 0.0;
        let mass = 1.0 / inv_mass;
        let di = v3(d[i]);
        let inertia = mass / (h * h);
        let air = p.air_damping * mass / h;
        let mut f = -inertia * (di - v3(self.target[i])) - air * di;
        let mut hess = Mat3::from_diagonal(Vec3::splat(inertia + air));

        let (offsets, springs) = self.el.springs;
        for k in self.el.span(offsets, i) {
            let s = springs[k];
            let j = s.other as usize;
            let start = v3(self.prev[i]) - v3(self.prev[j]);
            let change = di - v3(d[j]);
            let e = start + change;
            let len = e.length();
            let start_len = start.length();
            let mut block = Mat3::ZERO;
            if len > 1e-12 {
                let (k, rest) = (s.stiffness, s.rest_length);
                let stretch = stretch(start, start_len, change, len, rest);
                let law = StretchLaw::spring(p, rest);
                f -= law.tension(k, stretch) / len * e;
                let axial = law.axial(k, stretch);
                block += spring_hessian(axial, k, rest, e, len);
            }
            if start_len > 1e-12 {
                let n = start / start_len;
                f -= s.damping / h * n.dot(change) * n;
                block += (s.damping / h) * outer(n, n);
            }
            hess += block;
            if let Some(b) = blocks.filter(|_| free(j)) {
                sink(b.springs[k], -block);
            }
        }

        if let Some((offsets, refs, hinges)) = self.el.hinges {
            for k in self.el.span(offsets, i) {
                let r = refs[k];
                let hinge = &hinges[k];
                let Some(t) = self.hinge_frame(hinge, d) else {
                    continue;
                };
                let role = r % 4;
                let u = t.direction(role);
                f += hinge.rest_weight * (t.sin_half - hinge.rest_sin_half) * u;
                let cos_half = (1.0 - t.sin_half * t.sin_half).max(0.0).sqrt();
                let c = 0.5 * cos_half * hinge.rest_weight;
                hess += c * outer(u, u);
                if let Some(b) = blocks {
                    for other in (0..4).filter(|&o| o != role) {
                        if free(hinge.v[other as usize] as usize) {
                            let block = c * outer(u, t.direction(other));
                            sink(b.hinges[k][other as usize], block);
                        }
                    }
                }
            }
        }

        if let Some((offsets, refs, membranes)) = self.el.membranes {
            for k in self.el.span(offsets, i) {
                let r = refs[k];
                let m = &membranes[k];
                let role = (r % 4) as usize;
                let (fm, mb) = MembraneStep::at(m, self.prev, d).system(p, m, role, h);
                f += fm;
                hess += mb[role];
                if let Some(b) = blocks {
                    for other in (0..3).filter(|&o| o != role) {
                        if free(m.v[other] as usize) {
                            sink(b.membranes[k][other], mb[other]);
                        }
                    }
                }
            }
        }

        if let Some((offsets, refs, seams)) = self.el.seams {
            for k in self.el.span(offsets, i) {
                let r = refs[k];
                let s = &seams[k];
                let (fa, ha) = self.seam_system(s, d);
                let share = seam_share(s, r % 4);
                f += share * fa;
                hess += (share * share) * ha;
                if let Some(b) = blocks {
                    for other in (0..3).filter(|&o| o != r % 4) {
                        let (j, share_j) = (s.v[other as usize], seam_share(s, other));
                        if free(j as usize) && share_j != 0.0 {
                            sink(b.seams[k][other as usize], (share * share_j) * ha);
                        }
                    }
                }
            }
        }

        if p.num_bodies > 0 {
            let k_c = self.contact_stiffness(i);
            for b in 0..p.num_bodies as usize {
                let body = &p.bodies[b];
                let plane = self.plane(b, i);
                let n = v3(plane);
                let phi = plane.w + n.dot(di);
                if phi < body.thickness {
                    f += k_c * (body.thickness - phi) * n;
                    hess += k_c * outer(n, n);
                }
                let lambda = self.lambdas[i][b];
                if lambda > 0.0 && body.friction > 0.0 {
                    let u = self.slip(b, i, di, n);
                    let scale =
                        body.friction * lambda / u.length().max(body.friction_slip_speed * h);
                    f -= scale * u;
                    hess += scale * (Mat3::IDENTITY - outer(n, n));
                }
            }
        }
        VertexSystem {
            force: f,
            hessian: hess,
        }
    }

    /// Whether vertex `i` at displacement `d` touches body `b` (within `CONTACT_SLACK_FRACTION`
    /// of its contact layer, or inside it).
    pub fn touching(&self, b: usize, i: usize, d: Vec3) -> bool {
        let plane = self.plane(b, i);
        let thickness = self.params.bodies[b].thickness;
        plane.w + v3(plane).dot(d) < thickness * (1.0 + CONTACT_SLACK_FRACTION)
    }

    /// The projection that removes the normals of the bodies vertex `i` touches at
    /// displacements `d`, Gram–Schmidt over the bodies in order; the
    /// identity without contact. The Newton step's linear system is solved in these filtered
    /// coordinates (Baraff and Witkin 1998's filtered conjugate gradients): the contact normal
    /// stays with the sweeps' local solve, and the penalty's stiffness (100 times everything
    /// else) never enters the f32 conjugate gradients, where it drowned the soft directions.
    pub fn contact_filter(&self, i: usize, d: &[Vec4]) -> Mat3 {
        let mut s = Mat3::IDENTITY;
        if self.prev[i].w == 0.0 {
            return s;
        }
        let di = v3(d[i]);
        for b in 0..self.params.num_bodies as usize {
            let n = v3(self.plane(b, i));
            if self.touching(b, i, di) {
                let m = s * n;
                let len = m.length();
                if len > 1e-3 {
                    let u = m / len;
                    s -= outer(u, u);
                }
            }
        }
        s
    }

    /// |fᵢ| / (mᵢ·g) at vertex `i` with the normals of the bodies it touches left out (the
    /// body's reaction there balances them, whatever the penalty's depth); 0 for a pinned
    /// vertex. `g` is gravity's magnitude.
    pub fn force_residual(&self, i: usize, d: &[Vec4], g: f32) -> f32 {
        if self.prev[i].w == 0.0 {
            return 0.0;
        }
        let f = self.vertex_system(i, d, None, &mut |_, _| {}).force;
        (self.contact_filter(i, d) * f).length() * self.prev[i].w / g
    }
}

/// (1 − w)·v[b0] + w·v[b1] − v[a] of a seam pair over per-vertex values `v`.
fn seam_combination(s: &Seam, v: &[Vec4]) -> Vec3 {
    let [a, b0, b1] = [s.v[0], s.v[1], s.v[2]].map(|i| v3(v[i as usize]));
    (1.0 - s.weight) * b0 + s.weight * b1 - a
}

/// The share of a seam pair's force that its vertex of `role` takes: 1 for the seam vertex,
/// −(1 − w) and −w for the partner segment's ends.
pub fn seam_share(s: &Seam, role: u32) -> f32 {
    match role {
        0 => 1.0,
        1 => -(1.0 - s.weight),
        _ => -s.weight,
    }
}
