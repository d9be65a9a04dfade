//! Skeletons and linear blend skinning: joints with local rest transforms and inverse bind
//! matrices, up to four weighted joints per vertex, and animation clips sampled at any time.
//!
//! A vertex at rest position v moves to Σⱼ wⱼ·(Gⱼ·Bⱼ⁻¹)·v, with Gⱼ joint j's global transform at
//! the time and Bⱼ⁻¹ its inverse bind matrix (glTF 2.0's skinning).

use crate::mesh::TriMesh;
use glam::{Mat4, Quat, Vec3};

/// A joint's transform relative to its parent: translation, rotation, scale.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Trs {
    /// Translation.
    pub translation: Vec3,
    /// Rotation.
    pub rotation: Quat,
    /// Scale along the joint's axes.
    pub scale: Vec3,
}

impl Trs {
    /// No change.
    pub const IDENTITY: Trs = Trs {
        translation: Vec3::ZERO,
        rotation: Quat::IDENTITY,
        scale: Vec3::ONE,
    };

    /// The 4×4 matrix T·R·S.
    pub fn matrix(&self) -> Mat4 {
        Mat4::from_scale_rotation_translation(self.scale, self.rotation, self.translation)
    }

    /// `self` moved towards `other` by `s` (0: self, 1: other): translation and scale linearly,
    /// rotation by the shorter slerp.
    pub fn lerp(&self, other: &Trs, s: f32) -> Trs {
        Trs {
            translation: self.translation.lerp(other.translation, s),
            rotation: self.rotation.slerp(other.rotation, s),
            scale: self.scale.lerp(other.scale, s),
        }
    }
}

/// Joints in an order where every parent comes before its children.
#[derive(Clone, Debug, PartialEq)]
pub struct Skeleton {
    /// Each joint's name (for messages and the glTF file).
    pub names: Vec<String>,
    /// Each joint's parent joint (`None` for a top joint).
    pub parents: Vec<Option<usize>>,
    /// Each joint's local transform in the rest (bind) pose.
    pub rest: Vec<Trs>,
    /// Each joint's inverse bind matrix: from the mesh's rest frame into the joint's.
    pub inverse_bind: Vec<Mat4>,
    /// The fixed transform between each joint and its parent joint (or the world, for a top
    /// joint): the non-joint nodes between them in a glTF file; usually the identity.
    pub base: Vec<Mat4>,
}

impl Skeleton {
    /// How many joints.
    pub fn len(&self) -> usize {
        self.names.len()
    }

    /// Whether the skeleton has no joint.
    pub fn is_empty(&self) -> bool {
        self.names.is_empty()
    }

    /// Each joint's global transform for local transforms `locals` (one per joint).
    pub fn globals(&self, locals: &[Trs]) -> Vec<Mat4> {
        let mut out: Vec<Mat4> = Vec::with_capacity(self.len());
        for (j, local) in locals.iter().enumerate() {
            let above = match self.parents[j] {
                Some(p) => out[p] * self.base[j],
                None => self.base[j],
            };
            out.push(above * local.matrix());
        }
        out
    }

    /// Each joint's skinning matrix Gⱼ·Bⱼ⁻¹ for local transforms `locals`.
    pub fn skinning(&self, locals: &[Trs]) -> Vec<Mat4> {
        (self.globals(locals).iter().zip(&self.inverse_bind))
            .map(|(g, b)| *g * *b)
            .collect()
    }

    /// Inverse bind matrices that make `locals` the bind pose (each joint's global inverted).
    pub fn bind_to(&mut self, locals: &[Trs]) {
        self.inverse_bind = self.globals(locals).iter().map(|g| g.inverse()).collect();
    }

    /// The local transforms of the bind pose, in which every skinning matrix is the identity
    /// and the mesh stands as stored (each joint's global is its inverse bind matrix inverted).
    /// A file's node transforms may hold another pose.
    pub fn bind_locals(&self) -> Vec<Trs> {
        let globals: Vec<Mat4> = self.inverse_bind.iter().map(|b| b.inverse()).collect();
        (0..self.len())
            .map(|j| {
                let above = match self.parents[j] {
                    Some(p) => globals[p] * self.base[j],
                    None => self.base[j],
                };
                let (scale, rotation, translation) =
                    (above.inverse() * globals[j]).to_scale_rotation_translation();
                Trs {
                    translation,
                    rotation: rotation.normalize(),
                    scale,
                }
            })
            .collect()
    }

    /// The index of the joint called `name`.
    pub fn joint(&self, name: &str) -> Option<usize> {
        self.names.iter().position(|n| n == name)
    }
}

/// Up to four joints that move one vertex, with weights that sum to one.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Influence {
    /// Joint indices (unused slots have weight 0).
    pub joints: [u16; 4],
    /// Weights, summing to one.
    pub weights: [f32; 4],
}

impl Influence {
    /// The four largest of `(joint, weight)` pairs, normalised to sum to one (`None` when the
    /// weights sum to nothing).
    pub fn strongest(mut pairs: Vec<(u16, f32)>) -> Option<Influence> {
        pairs.retain(|(_, w)| *w > 0.0);
        pairs.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
        pairs.truncate(4);
        let sum: f32 = pairs.iter().map(|(_, w)| w).sum();
        if sum <= 0.0 || !sum.is_finite() {
            return None;
        }
        let mut out = Influence::default();
        for (k, (j, w)) in pairs.into_iter().enumerate() {
            out.joints[k] = j;
            out.weights[k] = w / sum;
        }
        Some(out)
    }

    /// The matrix Σ wⱼ·Mⱼ.
    pub fn blend(&self, matrices: &[Mat4]) -> Mat4 {
        let mut m = Mat4::ZERO;
        for (j, w) in self.joints.iter().zip(self.weights) {
            if w != 0.0 {
                m += matrices[*j as usize] * w;
            }
        }
        m
    }
}

/// Linear blend skinning of `rest` positions by `skinning` matrices (one per joint).
pub fn skin(rest: &[Vec3], influences: &[Influence], skinning: &[Mat4]) -> Vec<Vec3> {
    rest.iter()
        .zip(influences)
        .map(|(p, inf)| (inf.blend(skinning) * p.extend(1.0)).truncate())
        .collect()
}

/// How a channel interpolates between its keys (glTF's sampler interpolation).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Interpolation {
    /// Hold each key until the next.
    Step,
    /// Linear (slerp for rotations).
    Linear,
    /// Cubic Hermite with in and out tangents stored beside each key.
    CubicSpline,
}

/// The keyed values of one channel. With cubic splines each key has three values: in-tangent,
/// value, out-tangent.
#[derive(Clone, Debug, PartialEq)]
pub enum Values {
    /// Local translations.
    Translation(Vec<Vec3>),
    /// Local rotations.
    Rotation(Vec<Quat>),
    /// Local scales.
    Scale(Vec<Vec3>),
}

/// One animated property of one joint.
#[derive(Clone, Debug, PartialEq)]
pub struct Channel {
    /// The joint it moves.
    pub joint: usize,
    /// Key times in s, increasing.
    pub times: Vec<f32>,
    /// The keyed values.
    pub values: Values,
    /// How to interpolate.
    pub interpolation: Interpolation,
}

/// A named animation: channels over the skeleton's joints. Joints without a channel keep their
/// rest transform.
#[derive(Clone, Debug, PartialEq)]
pub struct Clip {
    /// The animation's name.
    pub name: String,
    /// Its channels.
    pub channels: Vec<Channel>,
}

impl Clip {
    /// Its length in s: the last key of any channel.
    pub fn duration(&self) -> f32 {
        (self.channels.iter())
            .filter_map(|c| c.times.last().copied())
            .fold(0.0, f32::max)
    }

    /// The first key of any channel, in s (0 for an empty clip).
    pub fn start(&self) -> f32 {
        (self.channels.iter())
            .filter_map(|c| c.times.first().copied())
            .fold(f32::INFINITY, f32::min)
            .min(self.duration())
    }

    /// Every joint's local transform at time `t` (clamped to the keys).
    pub fn pose(&self, skeleton: &Skeleton, t: f32) -> Vec<Trs> {
        let mut locals = skeleton.rest.clone();
        for c in &self.channels {
            let Some(local) = locals.get_mut(c.joint) else {
                continue;
            };
            match &c.values {
                Values::Translation(v) => local.translation = sample(c, v, t, lerp3),
                Values::Scale(v) => local.scale = sample(c, v, t, lerp3),
                Values::Rotation(v) => {
                    local.rotation = sample(c, v, t, slerp).normalize();
                }
            }
        }
        locals
    }
}

fn lerp3(a: Vec3, b: Vec3, s: f32) -> Vec3 {
    a.lerp(b, s)
}

fn slerp(a: Quat, b: Quat, s: f32) -> Quat {
    a.slerp(b, s)
}

/// Values that a cubic spline can combine.
trait Key: Copy + std::ops::Mul<f32, Output = Self> + std::ops::Add<Output = Self> {}
impl Key for Vec3 {}
impl Key for Quat {}

/// Channel `c`'s value at `t` from its keyed `values`.
fn sample<T: Key>(c: &Channel, values: &[T], t: f32, mix: fn(T, T, f32) -> T) -> T {
    let cubic = c.interpolation == Interpolation::CubicSpline;
    let value = |k: usize| if cubic { values[3 * k + 1] } else { values[k] };
    let times = &c.times;
    let last = times.len() - 1;
    if t <= times[0] {
        return value(0);
    }
    if t >= times[last] {
        return value(last);
    }
    // The segment [k, k + 1] holding t.
    let k = times.partition_point(|&s| s <= t) - 1;
    let span = times[k + 1] - times[k];
    let s = if span > 0.0 {
        (t - times[k]) / span
    } else {
        0.0
    };
    match c.interpolation {
        Interpolation::Step => value(k),
        Interpolation::Linear => mix(value(k), value(k + 1), s),
        Interpolation::CubicSpline => {
            // glTF 2.0 appendix C: Hermite with tangents scaled by the segment's length.
            let (p0, m0) = (values[3 * k + 1], values[3 * k + 2] * span);
            let (p1, m1) = (values[3 * (k + 1) + 1], values[3 * (k + 1)] * span);
            let (s2, s3) = (s * s, s * s * s);
            p0 * (2.0 * s3 - 3.0 * s2 + 1.0)
                + m0 * (s3 - 2.0 * s2 + s)
                + p1 * (-2.0 * s3 + 3.0 * s2)
                + m1 * (s3 - s2)
        }
    }
}

/// A skinned body: its triangles in the rest pose, the skeleton that moves them, each vertex's
/// influences and the animations.
#[derive(Clone, Debug, PartialEq)]
pub struct SkinnedMesh {
    /// The mesh in the rest (bind) pose, in m.
    pub mesh: TriMesh,
    /// One per vertex.
    pub influences: Vec<Influence>,
    /// The joints.
    pub skeleton: Skeleton,
    /// The animations.
    pub clips: Vec<Clip>,
}

impl SkinnedMesh {
    /// The clip called `name`.
    pub fn clip(&self, name: &str) -> Option<&Clip> {
        self.clips.iter().find(|c| c.name == name)
    }

    /// The vertices posed by the joints' local transforms `locals`.
    pub fn posed(&self, locals: &[Trs]) -> Vec<Vec3> {
        skin(
            &self.mesh.positions,
            &self.influences,
            &self.skeleton.skinning(locals),
        )
    }

    /// Every vertex scaled by `scale` about the origin and then moved by `offset` (the scene's
    /// units and placement), with the skeleton changed to match, so that posing the result
    /// gives the posed original scaled and moved the same way.
    pub fn placed(mut self, scale: f32, offset: Vec3) -> SkinnedMesh {
        let to = Mat4::from_translation(offset) * Mat4::from_scale(Vec3::splat(scale));
        let from = to.inverse();
        for p in &mut self.mesh.positions {
            *p = to.transform_point3(*p);
        }
        // G' = to·G and B'⁻¹ = B⁻¹·from make G'·B'⁻¹ = to·(G·B⁻¹)·from.
        for (b, parent) in self.skeleton.base.iter_mut().zip(&self.skeleton.parents) {
            if parent.is_none() {
                *b = to * *b;
            }
        }
        for ib in &mut self.skeleton.inverse_bind {
            *ib *= from;
        }
        self
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn two_joints() -> Skeleton {
        let rest = vec![
            Trs::IDENTITY,
            Trs {
                translation: Vec3::new(1.0, 0.0, 0.0),
                ..Trs::IDENTITY
            },
        ];
        let mut s = Skeleton {
            names: vec!["root".into(), "tip".into()],
            parents: vec![None, Some(0)],
            rest: rest.clone(),
            inverse_bind: vec![Mat4::IDENTITY; 2],
            base: vec![Mat4::IDENTITY; 2],
        };
        s.bind_to(&rest);
        s
    }

    #[test]
    fn the_rest_pose_leaves_every_vertex_in_place() {
        let s = two_joints();
        let m = s.skinning(&s.rest);
        for k in m {
            // Gⱼ·Gⱼ⁻¹ in f32: rounding of a unit translation, a few ulps.
            assert!(k.abs_diff_eq(Mat4::IDENTITY, 1e-6), "{k}");
        }
    }

    #[test]
    fn cubic_spline_passes_through_its_keys() {
        let c = Channel {
            joint: 0,
            times: vec![0.0, 1.0],
            values: Values::Translation(vec![
                Vec3::ZERO,
                Vec3::ZERO,
                Vec3::X,
                Vec3::ZERO,
                Vec3::Y,
                Vec3::ZERO,
            ]),
            interpolation: Interpolation::CubicSpline,
        };
        let Values::Translation(v) = &c.values else {
            unreachable!()
        };
        assert_eq!(sample(&c, v, 0.0, lerp3), Vec3::ZERO);
        assert_eq!(sample(&c, v, 1.0, lerp3), Vec3::Y);
        // Key 0's out-tangent is X, the rest are zero: at s = ½ the Hermite basis gives ½ of
        // each value and ⅛ of the out-tangent (times the 1 s span). f32: ulps.
        let mid = sample(&c, v, 0.5, lerp3);
        assert!(
            (mid - (0.5 * Vec3::Y + 0.125 * Vec3::X)).length() < 1e-6,
            "{mid}"
        );
    }
}
