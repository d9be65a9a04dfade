//! Collision bodies: closed triangle meshes in their own frame (metres), loaded from OBJ or
//! generated (sphere, box, capsule), with a baked signed distance field and rigid motion.

pub mod bvh;
pub mod cache;
pub mod deform;
pub mod deformed_sdf;
pub mod edges;
pub mod exact;
pub mod fit;
pub mod gltf_read;
pub mod gltf_write;
pub mod motion;
pub mod motions;
pub mod rig;
pub mod sdf;
pub mod shapes;
pub mod simplify;
pub mod size;
pub mod skin;

use crate::error::InputError;
use crate::mesh::TriMesh;
use glam::{DVec3, Vec3};
use std::collections::HashMap;
use std::path::Path;

/// Linear RGB of a body in previews and exported files (the previews' `BODY`).
pub const BODY_COLOR: [f32; 3] = [0.62, 0.60, 0.58];

/// How the CPU path finds contacts with the body (the GPU path always uses the SDF).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Strategy {
    /// The same grid and trilinear interpolation as the GPU.
    Sdf,
    /// parry3d's BVH point projection against the exact triangles.
    Exact,
    /// Every particle against every triangle (small tests only).
    Brute,
    /// Our BVH with axis-aligned boxes.
    BvhAabb,
    /// Our BVH with oriented boxes (separating-axis distance bounds).
    BvhObb,
    /// Our BVH with bounding spheres.
    BvhSphere,
}

impl Strategy {
    /// Every strategy with its scene name.
    pub const ALL: [(Strategy, &'static str); 6] = [
        (Strategy::Sdf, "sdf"),
        (Strategy::Exact, "exact"),
        (Strategy::Brute, "brute"),
        (Strategy::BvhAabb, "bvh-aabb"),
        (Strategy::BvhObb, "bvh-obb"),
        (Strategy::BvhSphere, "bvh-sphere"),
    ];

    /// The bounding volume of a BVH strategy.
    pub fn volume(self) -> Option<bvh::VolumeKind> {
        match self {
            Strategy::BvhAabb => Some(bvh::VolumeKind::Aabb),
            Strategy::BvhObb => Some(bvh::VolumeKind::Obb),
            Strategy::BvhSphere => Some(bvh::VolumeKind::Sphere),
            _ => None,
        }
    }

    /// The scene name.
    pub fn name(self) -> &'static str {
        Self::ALL
            .iter()
            .find(|(s, _)| *s == self)
            .map_or("?", |(_, n)| n)
    }
}

/// Everything the collision stage needs: the body, its SDF, its exact BVH, its motion and the
/// CPU strategy.
pub struct Collider {
    /// The body in its own frame.
    pub body: Body,
    /// Its baked distance field. A deforming body's holds its rest pose's nodes followed by
    /// the words its collision reads after them (`deformed_sdf`), as the kernels' SDF texture.
    pub sdf: sdf::Sdf,
    /// Its exact point queries.
    pub exact: exact::ExactBody,
    /// How it moves.
    pub motion: motion::Motion,
    /// How the CPU path finds contacts.
    pub strategy: Strategy,
    /// The hierarchy of a BVH strategy.
    pub bvh: Option<bvh::BodyBvh>,
    /// The body's edges, when the CPU path also tests cloth edges against them.
    pub edges: Option<edges::BodyEdges>,
    /// How the SDF was obtained.
    pub bake: sdf::BakeReport,
    /// A deforming body's motion and the words its collision reads after the SDF (`None`: the
    /// body is rigid; its SDF is then of the rest pose).
    pub deformed: Option<DeformedBody>,
}

/// What a deforming body adds to its collider.
#[derive(Clone, Debug, PartialEq)]
pub struct DeformedBody {
    /// Its motion.
    pub deformation: deform::Deformation,
    /// How many collision parts it has.
    pub parts: usize,
}

impl Collider {
    /// Whether the body moves or deforms at some time.
    pub fn moves(&self) -> bool {
        self.deformed.is_some() || self.motion.moves()
    }

    /// The body's vertices in the world at time `t`: posed rigidly, or deformed.
    pub fn world_positions(&self, t: f32) -> Vec<Vec3> {
        match &self.deformed {
            Some(d) => d.deformation.positions_at(t),
            None => {
                let pose = self.motion.at(t);
                (self.body.mesh.positions.iter())
                    .map(|p| pose.rotation * *p + pose.translation)
                    .collect()
            }
        }
    }

    /// Signed distance (negative inside) and nearest surface point by the CPU strategy (the SDF
    /// strategy has no nearest point; use `sdf.sample`).
    pub fn query(&self, p: Vec3) -> (f32, Vec3) {
        match (self.strategy, &self.bvh) {
            (_, Some(bvh)) => bvh.query(p),
            (Strategy::Brute, _) => brute_query(&self.body.mesh, p),
            _ => self.exact.query(p),
        }
    }
}

/// Colliders compare by identity: two models share a body only if they share the `Arc`.
impl PartialEq for Collider {
    fn eq(&self, other: &Self) -> bool {
        std::ptr::eq(self, other)
    }
}

impl std::fmt::Debug for Collider {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Collider")
            .field("vertices", &self.body.mesh.positions.len())
            .field("sdf_dims", &self.sdf.dims)
            .field("strategy", &self.strategy)
            .finish()
    }
}

/// What `check_closed` had to repair.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Repairs {
    /// Faces whose winding was flipped to agree with their neighbours.
    pub flipped_faces: usize,
    /// Whether the mesh, or one of its closed pieces, was inside out (negative volume) and was
    /// flipped.
    pub turned_outside_out: bool,
}

/// Checks that `mesh` is closed and two-manifold (every edge shared by exactly two faces) and
/// orients it consistently with outward normals, flipping faces where needed. Returns what was
/// repaired, or why it cannot be repaired.
pub fn close_and_orient(mesh: &mut TriMesh) -> Result<Repairs, String> {
    let mut faces_of: HashMap<[u32; 2], Vec<usize>> = HashMap::new();
    for (f, t) in mesh.triangles.iter().enumerate() {
        if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
            return Err(format!("face {} repeats a vertex", f + 1));
        }
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            faces_of.entry([a.min(b), a.max(b)]).or_default().push(f);
        }
    }
    let mut open = 0;
    for (edge, faces) in &faces_of {
        match faces.len() {
            2 => {}
            1 => open += 1,
            n => {
                return Err(format!(
                    "edge between vertices {} and {} is shared by {n} faces (non-manifold)",
                    edge[0] + 1,
                    edge[1] + 1
                ))
            }
        }
    }
    if open > 0 {
        return Err(format!(
            "the mesh is open: {open} edges belong to only one face"
        ));
    }
    // Propagate one orientation across shared edges (breadth first, per connected piece).
    let n = mesh.triangles.len();
    let mut seen = vec![false; n];
    let mut piece_faces: Vec<Vec<usize>> = Vec::new();
    let mut repairs = Repairs::default();
    let directed = |t: &[u32; 3], a: u32, b: u32| (0..3).any(|k| t[k] == a && t[(k + 1) % 3] == b);
    for start in 0..n {
        if seen[start] {
            continue;
        }
        seen[start] = true;
        piece_faces.push(vec![start]);
        let piece = piece_faces.last_mut().expect("just pushed");
        let mut queue = std::collections::VecDeque::from([start]);
        while let Some(f) = queue.pop_front() {
            let t = mesh.triangles[f];
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                for &g in &faces_of[&[a.min(b), a.max(b)]] {
                    if g == f || seen[g] {
                        continue;
                    }
                    // A consistent neighbour traverses the shared edge the other way.
                    if directed(&mesh.triangles[g], a, b) {
                        mesh.triangles[g].swap(1, 2);
                        repairs.flipped_faces += 1;
                    }
                    seen[g] = true;
                    piece.push(g);
                    queue.push_back(g);
                }
            }
        }
    }
    // Each closed piece faces out on its own: one piece inside out (a separate object of the
    // file, say) would otherwise survive a check of the whole mesh's volume.
    for faces in &piece_faces {
        let volume: f64 = faces.iter().map(|&f| triangle_volume(mesh, f)).sum();
        if volume < 0.0 {
            for &f in faces {
                mesh.triangles[f].swap(1, 2);
            }
            repairs.turned_outside_out = true;
        }
    }
    Ok(repairs)
}

/// The signed volume of the tetrahedron from the origin to face `f`, in m³.
fn triangle_volume(mesh: &TriMesh, f: usize) -> f64 {
    let [a, b, c] = mesh.triangles[f].map(|i| mesh.positions[i as usize].as_dvec3());
    a.dot(b.cross(c)) / 6.0
}

/// Signed volume (positive for outward-facing closed meshes), in m³.
pub fn signed_volume(mesh: &TriMesh) -> f64 {
    (0..mesh.triangles.len())
        .map(|f| triangle_volume(mesh, f))
        .sum()
}

/// A collision body in its own frame.
#[derive(Clone, Debug)]
pub struct Body {
    /// Closed, outward-oriented triangles in metres.
    pub mesh: TriMesh,
    /// What was repaired on load (empty for generated shapes).
    pub repairs: Repairs,
}

impl Body {
    /// Loads an OBJ body scaled by `scale` (m per file unit) and shifted by `offset`, welds
    /// vertices that share a position (UV seams, several objects), and checks that it is closed
    /// and consistently oriented (repairing orientation where possible).
    pub fn load(
        path: &Path,
        scale: f32,
        offset: glam::Vec3,
        key: &str,
    ) -> Result<Body, InputError> {
        let mut mesh = TriMesh::load_obj(path, scale, key)?;
        mesh.weld_coincident();
        for p in &mut mesh.positions {
            *p += offset;
        }
        Self::from_mesh(mesh).map_err(|problem| {
            InputError::new(
                path,
                key,
                format!("cannot be used as a collision body: {problem}"),
                "close the mesh (every edge shared by exactly two faces) in a mesh editor, or use \
                 the shipped mannequin",
            )
        })
    }

    /// Checks and orients a mesh.
    pub fn from_mesh(mut mesh: TriMesh) -> Result<Body, String> {
        let repairs = close_and_orient(&mut mesh)?;
        Ok(Body { mesh, repairs })
    }

    /// A stable content hash of the mesh (FNV-1a over its vertex and index bytes), for caches.
    pub fn hash(&self) -> u64 {
        let mut h: u64 = 0xcbf2_9ce4_8422_2325;
        let mut eat = |bytes: &[u8]| {
            for &b in bytes {
                h ^= b as u64;
                h = h.wrapping_mul(0x0100_0000_01b3);
            }
        };
        eat(bytemuck::cast_slice(&self.mesh.positions));
        eat(bytemuck::cast_slice(&self.mesh.triangles));
        h
    }
}

/// The closest point of triangle (a, b, c) to p (Ericson, Real-Time Collision Detection 5.1.5).
pub fn closest_point_on_triangle(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> DVec3 {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return a + ab * (d1 / (d1 - d3));
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return a + ac * (d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let denom = 1.0 / (va + vb + vc);
    a + ab * (vb * denom) + ac * (vc * denom)
}

/// Generalised winding number of a closed mesh around p: 1 inside, 0 outside (sum of the
/// triangles' signed solid angles, Van Oosterom & Strackee 1983).
pub fn winding_number(mesh: &TriMesh, p: Vec3) -> f64 {
    let mut total = 0.0;
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|i| (mesh.positions[i as usize] - p).as_dvec3());
        let (la, lb, lc) = (a.length(), b.length(), c.length());
        let det = a.dot(b.cross(c));
        let div = la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb;
        total += 2.0 * det.atan2(div);
    }
    total / (4.0 * std::f64::consts::PI)
}

/// Every triangle tested: signed distance (negative inside, by winding number) and the nearest
/// surface point. O(triangles) per query; for small tests and as a reference.
pub fn brute_query(mesh: &TriMesh, p: Vec3) -> (f32, Vec3) {
    // In f64: the reference must not add its own rounding to the comparison.
    let pd = p.as_dvec3();
    let mut best = (f64::INFINITY, pd);
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|i| mesh.positions[i as usize].as_dvec3());
        let q = closest_point_on_triangle(pd, a, b, c);
        let d = pd.distance(q);
        if d < best.0 {
            best = (d, q);
        }
    }
    let inside = winding_number(mesh, p) > 0.5;
    let d = best.0 as f32;
    (if inside { -d } else { d }, best.1.as_vec3())
}
