//! Bounding-volume hierarchies over a body's triangles, with axis-aligned boxes, oriented
//! boxes or bounding spheres (all parry3d shapes), answering "nearest surface point and
//! inside or outside" for the CPU collision strategies.

use super::closest_point_on_triangle;
use crate::mesh::TriMesh;
use glam::{DVec3, Vec3};
use parry3d::bounding_volume::{Aabb, BoundingSphere};
use parry3d::math::Pose;
use parry3d::query::PointQuery;
use parry3d::shape::Cuboid;

/// Which bounding volume the hierarchy uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VolumeKind {
    /// Axis-aligned boxes.
    Aabb,
    /// Oriented boxes along the principal axes of their triangles' vertices.
    Obb,
    /// Bounding spheres.
    Sphere,
}

enum Volume {
    Aabb(Aabb),
    Obb(Pose, Cuboid),
    Sphere(BoundingSphere),
}

impl Volume {
    fn fit(kind: VolumeKind, points: &[Vec3]) -> Volume {
        match kind {
            VolumeKind::Aabb => Volume::Aabb(Aabb::from_points(points.iter().copied())),
            VolumeKind::Obb => {
                let (pose, cuboid) = parry3d::utils::obb(points);
                Volume::Obb(pose, cuboid)
            }
            VolumeKind::Sphere => Volume::Sphere(
                parry3d::bounding_volume::details::point_cloud_bounding_sphere(points),
            ),
        }
    }

    /// A lower bound on the distance from `p` to anything inside the volume (0 inside). For an
    /// oriented box this is the separating-axis test along its three face axes.
    fn distance(&self, p: Vec3) -> f32 {
        match self {
            Volume::Aabb(b) => b.distance_to_local_point(p, true),
            Volume::Obb(pose, c) => c.distance_to_point(pose, p, true),
            Volume::Sphere(s) => (p.distance(s.center()) - s.radius()).max(0.0),
        }
    }
}

struct Node {
    volume: Volume,
    /// Leaf: triangles `order[first..first + count]`; inner: children at `first`, `first + 1`
    /// is not assumed, so both are stored.
    first: u32,
    count: u32,
    children: Option<[u32; 2]>,
}

/// Triangles per leaf.
const LEAF_SIZE: usize = 4;

/// A BVH over a closed, outward-oriented mesh, with angle-weighted pseudo-normals for the sign.
pub struct BodyBvh {
    nodes: Vec<Node>,
    order: Vec<u32>,
    mesh: TriMesh,
    /// Each triangle's axis-aligned box (lower and upper corner).
    boxes: Vec<[Vec3; 2]>,
    face_normals: Vec<DVec3>,
    vertex_normals: Vec<DVec3>,
    edge_normals: std::collections::HashMap<[u32; 2], DVec3>,
}

impl BodyBvh {
    /// Builds the hierarchy top-down, splitting at the median centroid along the longest axis.
    pub fn new(mesh: &TriMesh, kind: VolumeKind) -> Self {
        let mut order: Vec<u32> = (0..mesh.triangles.len() as u32).collect();
        let mut nodes = Vec::new();
        build(mesh, kind, &mut order, 0, &mut nodes);
        let (face_normals, vertex_normals, edge_normals) = pseudo_normals(mesh);
        let boxes = (mesh.triangles.iter())
            .map(|t| {
                let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
                [a.min(b).min(c), a.max(b).max(c)]
            })
            .collect();
        BodyBvh {
            nodes,
            order,
            boxes,
            mesh: mesh.clone(),
            face_normals,
            vertex_normals,
            edge_normals,
        }
    }

    /// Bytes the hierarchy holds on the heap: its nodes, triangle order, copy of the mesh and
    /// pseudo-normals (hash map entries counted at their key and value size).
    pub fn heap_bytes(&self) -> usize {
        use std::mem::size_of;
        self.nodes.capacity() * size_of::<Node>()
            + self.order.capacity() * size_of::<u32>()
            + self.boxes.capacity() * size_of::<[Vec3; 2]>()
            + self.mesh.positions.capacity() * size_of::<Vec3>()
            + self.mesh.triangles.capacity() * size_of::<[u32; 3]>()
            + (self.face_normals.capacity() + self.vertex_normals.capacity()) * size_of::<DVec3>()
            + self.edge_normals.capacity() * size_of::<([u32; 2], DVec3)>()
    }

    /// Signed distance (negative inside) and nearest surface point, by branch and bound.
    pub fn query(&self, p: Vec3) -> (f32, Vec3) {
        let pd = p.as_dvec3();
        let mut best = (f64::INFINITY, DVec3::ZERO, 0u32);
        // Nodes to visit with the lower bound their parent computed, so that no volume is
        // measured twice. A median split of ≥ 4 triangles per leaf stays under 64 levels.
        let mut stack = [(0u32, 0.0f32); 64];
        let mut len = 1;
        while len > 0 {
            len -= 1;
            let (n, bound) = stack[len];
            if bound as f64 > best.0 {
                continue;
            }
            let node = &self.nodes[n as usize];
            match node.children {
                Some([a, b]) => {
                    let da = self.nodes[a as usize].volume.distance(p);
                    let db = self.nodes[b as usize].volume.distance(p);
                    // Visit the nearer child first (pushed last) so that pruning bites early.
                    let (near, far) = if da < db {
                        ((a, da), (b, db))
                    } else {
                        ((b, db), (a, da))
                    };
                    stack[len] = far;
                    stack[len + 1] = near;
                    len += 2;
                }
                None => {
                    for &t in &self.order[node.first as usize..(node.first + node.count) as usize] {
                        // The triangle's box bounds its distance from below: skip the exact
                        // closest point (in f64) when the box is already farther than the best.
                        let [lo, hi] = self.boxes[t as usize];
                        let gap = (lo - p).max(p - hi).max(Vec3::ZERO).length();
                        if gap as f64 > best.0 {
                            continue;
                        }
                        let [a, b, c] = self.corners(t);
                        let q = closest_point_on_triangle(pd, a, b, c);
                        let d = pd.distance(q);
                        if d < best.0 {
                            best = (d, q, t);
                        }
                    }
                }
            }
        }
        let (d, q, t) = best;
        let inside = (pd - q).dot(self.pseudo_normal(t, q)) < 0.0;
        let d = d as f32;
        (if inside { -d } else { d }, q.as_vec3())
    }

    fn corners(&self, t: u32) -> [DVec3; 3] {
        self.mesh.triangles[t as usize].map(|i| self.mesh.positions[i as usize].as_dvec3())
    }

    /// The pseudo-normal of the feature of triangle `t` that `q` lies on (Bærentzen & Aanæs):
    /// the face normal inside it, the sum of the two face normals on an edge, the
    /// angle-weighted vertex normal at a corner.
    fn pseudo_normal(&self, t: u32, q: DVec3) -> DVec3 {
        let tri = self.mesh.triangles[t as usize];
        let [a, b, c] = self.corners(t);
        let area2 = (b - a).cross(c - a).length();
        // Barycentric weights of q; a weight near 0 puts q on the opposite edge.
        let w = [
            (b - q).cross(c - q).length() / area2,
            (c - q).cross(a - q).length() / area2,
            (a - q).cross(b - q).length() / area2,
        ];
        let eps = 1e-9;
        let zero: Vec<usize> = (0..3).filter(|&k| w[k] < eps).collect();
        match zero.len() {
            0 => self.face_normals[t as usize],
            1 => {
                let k = zero[0];
                let (u, v) = (tri[(k + 1) % 3], tri[(k + 2) % 3]);
                self.edge_normals[&[u.min(v), u.max(v)]]
            }
            _ => {
                let k = (0..3).find(|k| !zero.contains(k)).unwrap_or(0);
                self.vertex_normals[tri[k] as usize]
            }
        }
    }
}

fn build(
    mesh: &TriMesh,
    kind: VolumeKind,
    order: &mut [u32],
    first: u32,
    nodes: &mut Vec<Node>,
) -> u32 {
    let points: Vec<Vec3> = order
        .iter()
        .flat_map(|&t| mesh.triangles[t as usize].map(|i| mesh.positions[i as usize]))
        .collect();
    let id = nodes.len() as u32;
    nodes.push(Node {
        volume: Volume::fit(kind, &points),
        first,
        count: order.len() as u32,
        children: None,
    });
    if order.len() <= LEAF_SIZE {
        return id;
    }
    let centroid = |t: u32| {
        mesh.triangles[t as usize]
            .iter()
            .map(|&i| mesh.positions[i as usize])
            .sum::<Vec3>()
            / 3.0
    };
    let (lo, hi) = order.iter().fold((Vec3::MAX, Vec3::MIN), |(lo, hi), &t| {
        (lo.min(centroid(t)), hi.max(centroid(t)))
    });
    let axis = (hi - lo).max_position();
    order.sort_by(|&x, &y| centroid(x)[axis].total_cmp(&centroid(y)[axis]));
    let mid = order.len() / 2;
    let (left, right) = order.split_at_mut(mid);
    let l = build(mesh, kind, left, first, nodes);
    let r = build(mesh, kind, right, first + mid as u32, nodes);
    nodes[id as usize].children = Some([l, r]);
    id
}

type PseudoNormals = (
    Vec<DVec3>,
    Vec<DVec3>,
    std::collections::HashMap<[u32; 2], DVec3>,
);

fn pseudo_normals(mesh: &TriMesh) -> PseudoNormals {
    let mut faces = Vec::with_capacity(mesh.triangles.len());
    let mut vertices = vec![DVec3::ZERO; mesh.positions.len()];
    let mut edges = std::collections::HashMap::new();
    for t in &mesh.triangles {
        let p = t.map(|i| mesh.positions[i as usize].as_dvec3());
        let n = (p[1] - p[0]).cross(p[2] - p[0]).normalize_or_zero();
        faces.push(n);
        for k in 0..3 {
            let (u, v) = (p[(k + 1) % 3] - p[k], p[(k + 2) % 3] - p[k]);
            vertices[t[k] as usize] += u.angle_between(v) * n;
            let (a, b) = (t[k], t[(k + 1) % 3]);
            *edges.entry([a.min(b), a.max(b)]).or_insert(DVec3::ZERO) += n;
        }
    }
    (faces, vertices, edges)
}
