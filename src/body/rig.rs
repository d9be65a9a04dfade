//! The shipped mannequin's rig: 19 joints at anatomical landmarks of the MakeHuman base mesh in
//! its A-pose, and skin weights that drapekit computes from the mesh (nearest visible bone,
//! then smoothed over the surface).
//!
//! The landmarks were read off the mesh: each limb was sliced across its axis every 1.5 cm and
//! each joint put at the centre of the section where the limb narrows or bends (elbow, wrist,
//! knee, ankle), the shoulder 5 cm below the top of the shoulder at the upper arm's axis, the
//! hips at the top of the thigh, the spine's joints on the body's mid-plane.

use super::skin::{Influence, Skeleton, SkinnedMesh, Trs};
use crate::mesh::TriMesh;
use glam::{Mat4, Vec3};
use parry3d::query::{Ray, RayCast};
use parry3d::shape::TriMesh as ParryMesh;

/// One joint of the rig: where it sits in the mesh's rest pose (the file's coordinates, m, +y
/// up, facing +z, the model's left at +x), its parent, the end of its bone when no child
/// continues it, and the bone's typical radius (which scales the distance that assigns
/// vertices to it).
struct JointSpec {
    name: &'static str,
    parent: Option<&'static str>,
    at: [f32; 3],
    end: Option<[f32; 3]>,
    radius: f32,
}

/// The joints, parents first. Coordinates as in `fixtures/bodies/mannequin.obj` (its lowest
/// point at y = −0.817 m).
const JOINTS: [JointSpec; 19] = [
    joint("hips", None, [0.0, 0.03, 0.0], None, 0.15),
    joint("spine", Some("hips"), [0.0, 0.15, -0.01], None, 0.13),
    joint("chest", Some("spine"), [0.0, 0.33, -0.01], None, 0.13),
    joint("neck", Some("chest"), [0.0, 0.56, -0.01], None, 0.05),
    joint(
        "head",
        Some("neck"),
        [0.0, 0.65, 0.02],
        Some([0.0, 0.84, 0.03]),
        0.09,
    ),
    joint("shoulder.L", Some("chest"), [0.03, 0.51, 0.01], None, 0.05),
    joint(
        "upper_arm.L",
        Some("shoulder.L"),
        [0.175, 0.49, 0.01],
        None,
        0.045,
    ),
    joint(
        "forearm.L",
        Some("upper_arm.L"),
        [0.33, 0.335, 0.035],
        None,
        0.035,
    ),
    joint(
        "hand.L",
        Some("forearm.L"),
        [0.415, 0.25, 0.16],
        Some([0.47, 0.15, 0.3]),
        0.04,
    ),
    joint("shoulder.R", Some("chest"), [-0.03, 0.51, 0.01], None, 0.05),
    joint(
        "upper_arm.R",
        Some("shoulder.R"),
        [-0.175, 0.49, 0.01],
        None,
        0.045,
    ),
    joint(
        "forearm.R",
        Some("upper_arm.R"),
        [-0.33, 0.335, 0.035],
        None,
        0.035,
    ),
    joint(
        "hand.R",
        Some("forearm.R"),
        [-0.415, 0.25, 0.16],
        Some([-0.47, 0.15, 0.3]),
        0.04,
    ),
    joint("thigh.L", Some("hips"), [0.085, 0.0, 0.01], None, 0.08),
    joint("shin.L", Some("thigh.L"), [0.165, -0.43, 0.015], None, 0.05),
    joint(
        "foot.L",
        Some("shin.L"),
        [0.215, -0.735, 0.0],
        Some([0.23, -0.8, 0.17]),
        0.04,
    ),
    joint("thigh.R", Some("hips"), [-0.085, 0.0, 0.01], None, 0.08),
    joint(
        "shin.R",
        Some("thigh.R"),
        [-0.165, -0.43, 0.015],
        None,
        0.05,
    ),
    joint(
        "foot.R",
        Some("shin.R"),
        [-0.215, -0.735, 0.0],
        Some([-0.23, -0.8, 0.17]),
        0.04,
    ),
];

const fn joint(
    name: &'static str,
    parent: Option<&'static str>,
    at: [f32; 3],
    end: Option<[f32; 3]>,
    radius: f32,
) -> JointSpec {
    JointSpec {
        name,
        parent,
        at,
        end,
        radius,
    }
}

/// How far the shipped OBJ's lowest point lies below its origin, in m: the rig stands with its
/// feet at y = 0, as `shapes::mannequin(Vec3::ZERO)` does.
const FEET_BELOW_ORIGIN: f32 = 0.81676;

/// Smoothing passes over the surface: each moves a vertex's weights a third of the way to its
/// neighbours' mean. 12 passes over the mannequin's 1–2 cm edges spread a joint's blend over
/// roughly ±3 cm, about a limb's radius.
const SMOOTHING_PASSES: usize = 12;

fn position(at: [f32; 3]) -> Vec3 {
    Vec3::from(at) + Vec3::Y * FEET_BELOW_ORIGIN
}

/// The mannequin's skeleton, bound in the A-pose (every joint's frame parallel to the world's).
pub fn skeleton() -> Skeleton {
    let index = |name: &str| JOINTS.iter().position(|j| j.name == name);
    let mut s = Skeleton {
        names: Vec::new(),
        parents: Vec::new(),
        rest: Vec::new(),
        inverse_bind: Vec::new(),
        base: Vec::new(),
    };
    for j in &JOINTS {
        let parent = j.parent.and_then(index);
        let above = parent.map_or(Vec3::ZERO, |p| position(JOINTS[p].at));
        s.names.push(j.name.to_string());
        s.parents.push(parent);
        s.rest.push(Trs {
            translation: position(j.at) - above,
            ..Trs::IDENTITY
        });
        s.base.push(Mat4::IDENTITY);
    }
    let rest = s.rest.clone();
    s.bind_to(&rest);
    s
}

/// Each joint's bone as a segment (joint to its first child, or to its end), with its radius.
fn bones() -> Vec<(Vec3, Vec3, f32)> {
    JOINTS
        .iter()
        .map(|j| {
            let child = JOINTS.iter().find(|c| c.parent == Some(j.name));
            let end = match (j.end, child) {
                (Some(e), _) => position(e),
                (None, Some(c)) => position(c.at),
                (None, None) => position(j.at),
            };
            (position(j.at), end, j.radius)
        })
        .collect()
}

fn distance_to_segment(p: Vec3, a: Vec3, b: Vec3) -> (f32, Vec3) {
    let ab = b - a;
    let t = if ab.length_squared() > 0.0 {
        ((p - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let q = a + t * ab;
    (p.distance(q), q)
}

/// Skin weights for `mesh` (the mannequin with its feet at the origin): each vertex first goes
/// wholly to the bone nearest to it relative to the bone's radius among the bones it can see
/// through the body (a straight line to the bone's nearest point that leaves the body nowhere),
/// so that the torso's side below the armpit goes to the chest, not to the nearer upper arm;
/// then the weights are smoothed over the surface so that each joint bends the skin smoothly.
pub fn weights(mesh: &TriMesh) -> Vec<Influence> {
    let bones = bones();
    let shape = ParryMesh::new(mesh.positions.clone(), mesh.triangles.clone())
        .expect("the shipped mannequin builds a BVH (tested)");
    let normals = crate::mesh::vertex_normals(&mesh.positions, &mesh.triangles);
    let n = mesh.positions.len();
    let mut w = vec![vec![0.0f32; bones.len()]; n];
    for (i, (&p, &normal)) in mesh.positions.iter().zip(&normals).enumerate() {
        // Start just inside the skin so that the vertex's own triangles do not block the view.
        let start = p - 1e-3 * normal;
        let visible = |q: Vec3| {
            let d = q - start;
            let len = d.length();
            len < 1e-6
                || shape
                    .cast_local_ray(&Ray::new(start, d / len), len, false)
                    .is_none()
        };
        let mut ranked: Vec<(f32, usize, Vec3)> = (bones.iter().enumerate())
            .map(|(b, &(a, e, r))| {
                let (d, q) = distance_to_segment(p, a, e);
                (d / r, b, q)
            })
            .collect();
        ranked.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)));
        let best = (ranked.iter())
            .find(|(_, _, q)| visible(*q))
            .unwrap_or(&ranked[0]);
        w[i][best.1] = 1.0;
    }
    let neighbours = neighbours(mesh);
    for _ in 0..SMOOTHING_PASSES {
        let before = w.clone();
        for (i, around) in neighbours.iter().enumerate() {
            if around.is_empty() {
                continue;
            }
            for b in 0..bones.len() {
                let mean = around.iter().map(|&k| before[k][b]).sum::<f32>() / around.len() as f32;
                w[i][b] = before[i][b] + (mean - before[i][b]) / 3.0;
            }
        }
    }
    w.into_iter()
        .map(|row| {
            let pairs = (row.into_iter().enumerate())
                .map(|(b, x)| (b as u16, x))
                .collect();
            Influence::strongest(pairs).expect("smoothing keeps each vertex's total at one")
        })
        .collect()
}

/// Each vertex's neighbours along triangle edges.
fn neighbours(mesh: &TriMesh) -> Vec<Vec<usize>> {
    let mut out = vec![Vec::new(); mesh.positions.len()];
    for t in &mesh.triangles {
        for k in 0..3 {
            let (a, b) = (t[k] as usize, t[(k + 1) % 3] as usize);
            if !out[a].contains(&b) {
                out[a].push(b);
            }
            if !out[b].contains(&a) {
                out[b].push(a);
            }
        }
    }
    out
}

/// The rigged mannequin with its built-in motions, as drapekit writes it to
/// `fixtures/bodies/mannequin_rigged.glb`.
pub fn rigged_mannequin() -> SkinnedMesh {
    let mesh = super::shapes::mannequin(Vec3::ZERO);
    let skeleton = skeleton();
    let influences = weights(&mesh);
    let clips = super::motions::built_in(&skeleton);
    SkinnedMesh {
        mesh,
        influences,
        skeleton,
        clips,
    }
}
