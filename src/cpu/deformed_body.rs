//! CPU twin of `kernels/deformed_body.wgsl`: a deforming body's signed distance, normal and
//! surface velocity at a world point, by inverse skinning into its rest pose.
//!
//! Each collision part whose rest-pose box holds the point mapped back by that part's rigid pose
//! is a candidate. From there the rest point y is refined as the fixed point of y = A⁻¹(x − b),
//! where A and b blend the parts' rotations and translations with the skin weights at y (those
//! of y's nearest rest triangle at its closest point): y is then where linear blend skinning
//! takes the rest surface to x. Near a joint the plain iteration can oscillate about the fixed
//! point and shrink slowly (by 0.85 per step at a shoulder mid-walk, leaving it 4 mm off after
//! 12 steps); a step that turns back on the last one is halved, which lands near the middle.
//! The rest SDF at y gives φ; A⁻ᵀ∇φ the normal. A candidate whose y does not skin back to
//! within the thickness of x is dropped (the fixed point did not settle); of the rest, the
//! smallest φ wins (the point is inside if any part says so and no other part refutes that
//! depth: `deformed_sample`).

use super::collide_body::{body_velocity_at, sample_body_sdf, to_body_frame};
use crate::body::deformed_sdf::WEIGHT_WORDS;
use crate::body::sdf::SDF_FAR;
use crate::model::layout::{BodyParams, BodyPose};
use glam::{Mat3, Vec3, Vec4};

/// Most fixed-point refinements of the rest point before it is checked. Near a shoulder with
/// the arm lowered 35°, 3 left cloth 1 cm inside the torso unsettled (no part claimed it) in
/// `tshirt_walk`; 12 settle it to within 0.5 mm of the exact distance there.
pub const REFINEMENTS: u32 = 12;

/// A refinement that moves the rest point less than this, in m, has settled: f32 rounding of
/// coordinates near 1 m is 1e-7 m, a hundredth of this.
pub const SETTLED_STEP: f32 = 1e-5;

fn v3(a: [f32; 4]) -> Vec3 {
    Vec3::new(a[0], a[1], a[2])
}

/// A deforming body's contact at a world point: φ, the world normal and the surface velocity
/// field around it, v(p) = `linear` + `angular` × (p − `center`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DeformedSample {
    /// Signed distance in m (`SDF_FAR`: no part is near).
    pub phi: f32,
    /// Unit outward normal (world).
    pub normal: Vec3,
    /// Where `linear` holds.
    pub center: Vec3,
    /// Surface velocity at `center`, m/s.
    pub linear: Vec3,
    /// Blended angular velocity, rad/s.
    pub angular: Vec3,
}

impl DeformedSample {
    const FAR: DeformedSample = DeformedSample {
        phi: SDF_FAR,
        normal: Vec3::ZERO,
        center: Vec3::ZERO,
        linear: Vec3::ZERO,
        angular: Vec3::ZERO,
    };

    /// The surface velocity at `p`.
    pub fn velocity_at(&self, p: Vec3) -> Vec3 {
        self.linear + self.angular.cross(p - self.center)
    }
}

/// The body's words: its SDF nodes and then those of `body::deformed_sdf`, read as the kernel
/// reads its one texture.
struct Words<'a>(&'a [f32]);

impl Words<'_> {
    fn f(&self, i: u32) -> f32 {
        self.0[i as usize]
    }

    fn u(&self, i: u32) -> u32 {
        self.f(i).to_bits()
    }

    fn vec3(&self, i: u32) -> Vec3 {
        Vec3::new(self.f(i), self.f(i + 1), self.f(i + 2))
    }
}

/// The parts blended at one rest point: A = Σ cₖRₖ, b = Σ cₖtₖ, and the blended velocity
/// field's terms at world point x.
struct Blend {
    a: Mat3,
    b: Vec3,
    linear: Vec3,
    angular: Vec3,
}

/// Offsets of the blocks after the SDF (words, from the body's first).
struct Layout {
    nodes: u32,
    vertices: u32,
    triangles: u32,
    weights: u32,
    boxes: u32,
}

fn layout(body: &BodyParams, w: &Words) -> Layout {
    let d = body.sdf_dims;
    let nodes = d[0] * d[1] * d[2];
    let header = 2 * nodes;
    let (vertex_count, triangle_count) = (w.u(header), w.u(header + 1));
    let vertices = header + 2;
    let triangles = vertices + 3 * vertex_count;
    let weights = triangles + 3 * triangle_count;
    Layout {
        nodes,
        vertices,
        triangles,
        weights,
        boxes: weights + WEIGHT_WORDS as u32 * vertex_count,
    }
}

/// Barycentric coordinates (of a, b, c) of the point of triangle (a, b, c) closest to p
/// (Ericson, Real-Time Collision Detection 5.1.5, in f32 as the kernel computes it).
pub fn closest_barycentric(p: Vec3, a: Vec3, b: Vec3, c: Vec3) -> Vec3 {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return Vec3::X;
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return Vec3::Y;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return Vec3::new(1.0 - v, v, 0.0);
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return Vec3::Z;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return Vec3::new(1.0 - w, 0.0, w);
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return Vec3::new(0.0, 1.0 - w, w);
    }
    let denom = 1.0 / (va + vb + vc);
    let (v, w) = (vb * denom, vc * denom);
    Vec3::new(1.0 - v - w, v, w)
}

/// A⁻¹ through the adjugate (as the kernel, which has no matrix inverse); `None` when singular.
fn inverse(a: Mat3) -> Option<Mat3> {
    let (c0, c1, c2) = (a.x_axis, a.y_axis, a.z_axis);
    let (r0, r1, r2) = (c1.cross(c2), c2.cross(c0), c0.cross(c1));
    let det = c0.dot(r0);
    // Rows of the adjugate are the cross products of the columns.
    (det.abs() > 1e-12).then(|| Mat3::from_cols(r0, r1, r2).transpose() / det)
}

/// One part's answer at x: the sample from its rest point y and, where the part has x outside,
/// how far x is from where the rest surface point nearest y skins to. That point lies on the
/// deformed surface (up to the SDF's interpolation and the weights' blend), so x's true distance
/// to the surface is at most about this (`SDF_FAR`: not computed, or it cannot be skinned).
struct Candidate {
    sample: DeformedSample,
    surface_distance: f32,
}

/// One body's words read for one query: the parts' poses and where each block lies.
struct Query<'a> {
    body: &'a BodyParams,
    parts: &'a [BodyPose],
    words: Words<'a>,
    layout: Layout,
}

impl Query<'_> {
    /// The skin weights at rest point `y` (those at the closest point of the triangle nearest to
    /// y's grid node), blended over the parts' poses; `None` outside the grid.
    fn blend_at(&self, y: Vec3, x: Vec3) -> Option<Blend> {
        let (body, w, l) = (self.body, &self.words, &self.layout);
        let d = body.sdf_dims;
        let g = (y - v3(body.sdf_origin)) / body.sdf_origin[3];
        let last = Vec3::new(d[0] as f32, d[1] as f32, d[2] as f32) - Vec3::ONE;
        if g.cmplt(Vec3::ZERO).any() || g.cmpgt(last).any() {
            return None;
        }
        let c = (g + Vec3::splat(0.5)).floor().min(last).as_uvec3();
        let node = c.x + d[0] * (c.y + d[1] * c.z);
        let t = w.u(l.nodes + node);
        let corner = |k: u32| w.u(l.triangles + 3 * t + k);
        let (ia, ib, ic) = (corner(0), corner(1), corner(2));
        let (a, b, cc) = (
            w.vec3(l.vertices + 3 * ia),
            w.vec3(l.vertices + 3 * ib),
            w.vec3(l.vertices + 3 * ic),
        );
        let bary = closest_barycentric(y, a, b, cc);
        let mut out = Blend {
            a: Mat3::ZERO,
            b: Vec3::ZERO,
            linear: Vec3::ZERO,
            angular: Vec3::ZERO,
        };
        for (k, vertex) in [ia, ib, ic].into_iter().enumerate() {
            let base = l.weights + WEIGHT_WORDS as u32 * vertex;
            let packed = w.u(base);
            for slot in 0..4u32 {
                let weight = bary[k] * w.f(base + 1 + slot);
                if weight == 0.0 {
                    continue;
                }
                let pose = &self.parts[((packed >> (8 * slot)) & 0xff) as usize];
                out.a += Mat3::from_cols(v3(pose.x), v3(pose.y), v3(pose.z)) * weight;
                out.b += v3(pose.translation) * weight;
                let offset = x - v3(pose.translation);
                out.linear += body_velocity_at(pose, offset) * weight;
                out.angular += v3(pose.angular_velocity) * weight;
            }
        }
        Some(out)
    }

    /// The rest point that part `k` maps x back to (its pose's inverse, then the skinning fixed
    /// point), `None` where x is outside the part's box or the refinement cannot start.
    fn rest_point(&self, k: usize, x: Vec3) -> Option<Vec3> {
        let (w, l) = (&self.words, &self.layout);
        let (mut y, _) = to_body_frame(&self.parts[k], x);
        let lo = w.vec3(l.boxes + 6 * k as u32);
        let hi = w.vec3(l.boxes + 6 * k as u32 + 3);
        if y.cmplt(lo).any() || y.cmpgt(hi).any() {
            return None;
        }
        let mut settled = None;
        let mut last = Vec3::ZERO;
        for _ in 0..REFINEMENTS {
            let Some(blend) = self.blend_at(y, x) else {
                break;
            };
            let Some(inv) = inverse(blend.a) else { break };
            let mut step = inv * (x - blend.b) - y;
            // A step that turns back on the last one is overshooting an oscillation (near a
            // joint the weights change fast along the step): half of it lands near the middle.
            if step.dot(last) < 0.0 {
                step *= 0.5;
            }
            y += step;
            last = step;
            settled = Some(y);
            if step.length() < SETTLED_STEP {
                break;
            }
        }
        settled
    }

    /// Part `k`'s answer at x, `None` where it has none (no settled rest point, or one that does
    /// not skin back to within the thickness of x).
    fn candidate(&self, k: usize, x: Vec3) -> Option<Candidate> {
        let body = self.body;
        let y = self.rest_point(k, x)?;
        let blend = self.blend_at(y, x)?;
        // Where the rest point skins to now; a candidate that has not settled within the
        // thickness does not describe the surface near x.
        if (blend.a * y + blend.b - x).length() > body.thickness {
            return None;
        }
        let s = sample_body_sdf(body, self.words.0, y);
        let n = inverse(blend.a)?.transpose() * s.truncate();
        let len = n.length();
        if len <= 1e-12 {
            return None;
        }
        let surface_distance = if s.w >= 0.0 {
            self.skinned_surface_distance(y, s, x)
        } else {
            SDF_FAR
        };
        let sample = DeformedSample {
            phi: s.w,
            normal: n / len,
            center: x,
            linear: blend.linear,
            angular: blend.angular,
        };
        Some(Candidate {
            sample,
            surface_distance,
        })
    }

    /// How far x is from where the rest surface point nearest y (y − φ∇φ̂, from the SDF's
    /// sample `s` at y) skins to (`SDF_FAR` where it cannot be skinned).
    fn skinned_surface_distance(&self, y: Vec3, s: Vec4, x: Vec3) -> f32 {
        let g = s.truncate().length();
        let to_surface = if g > 0.0 {
            s.truncate() / g
        } else {
            Vec3::ZERO
        };
        let on_rest = y - s.w * to_surface;
        match self.blend_at(on_rest, x) {
            Some(b) => (b.a * on_rest + b.b - x).length(),
            None => SDF_FAR,
        }
    }
}

/// The body's contact at world point `x`. `parts` are the body's own parts' poses (its slice of
/// `SubstepParams::parts`), `words` its rest SDF's nodes followed by the words of
/// `body::deformed_sdf`.
///
/// Of the parts' answers, the smallest φ wins (x is inside if any part says so), except an
/// inside claim that another part refutes. Linear blend skinning folds where a joint bends far
/// (a knee flexed mid-stride): there a rest point 3.9 cm inside the leg skins to a point that
/// the deformed mesh has 3.6 mm outside. A depth d claims that no surface lies within d of x;
/// a part that has x outside and skinned a surface point to within d − thickness of x shows the
/// claim false. The margin is the thickness because the distances compared are approximate
/// (trilinear φ, blended weights) to a millimetre or so, and a claim no deeper than the layer
/// only moves cloth within it. The deepest inside claim wins if it stands, else the shallowest
/// if it does (a third claim between them is not tried: refutation drops the deepest first, and
/// the shallowest moves cloth least), else the nearest outside answer.
pub fn deformed_sample(
    body: &BodyParams,
    parts: &[BodyPose],
    words: &[f32],
    x: Vec3,
) -> DeformedSample {
    let words = Words(words);
    let query = Query {
        body,
        parts,
        layout: layout(body, &words),
        words,
    };
    let (mut deepest, mut shallowest) = (None, None);
    let mut outside = DeformedSample::FAR;
    let mut nearest_skinned_surface = SDF_FAR;
    for k in 0..(body.parts as usize).min(parts.len()) {
        let Some(c) = query.candidate(k, x) else {
            continue;
        };
        let phi = c.sample.phi;
        if phi < 0.0 {
            if deepest.is_none_or(|d: DeformedSample| phi < d.phi) {
                deepest = Some(c.sample);
            }
            if shallowest.is_none_or(|d: DeformedSample| phi > d.phi) {
                shallowest = Some(c.sample);
            }
        } else {
            nearest_skinned_surface = nearest_skinned_surface.min(c.surface_distance);
            if phi < outside.phi {
                outside = c.sample;
            }
        }
    }
    let stands = |s: &DeformedSample| -s.phi <= nearest_skinned_surface + body.thickness;
    (deepest.filter(stands))
        .or(shallowest.filter(stands))
        .unwrap_or(outside)
}
