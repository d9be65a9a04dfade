//! The body's edges for cloth-edge against body-edge contacts (CPU only): a cloth edge can cut
//! through a sharp or thin body feature while both its ends stay clear of every face, which
//! point–triangle queries alone cannot see.

use crate::mesh::TriMesh;
use glam::Vec3;
use parry3d::bounding_volume::Aabb;
use parry3d::partitioning::{Bvh, BvhBuildStrategy};
use parry3d::query::details::closest_points_segment_segment_with_locations_nD;
use std::collections::HashMap;

/// Every edge of a closed body mesh, with an outward normal, in a BVH.
pub struct BodyEdges {
    ends: Vec<[Vec3; 2]>,
    /// The normalised sum of the two adjacent faces' unit normals.
    normals: Vec<Vec3>,
    bvh: Bvh,
}

/// The closest approach of a cloth edge to a body edge.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EdgeContact {
    /// Where along the cloth edge, 0 at its first end and 1 at its second.
    pub s: f32,
    /// The nearest point on the body edge.
    pub point: Vec3,
    /// Unit direction that moves the cloth edge out of contact.
    pub normal: Vec3,
    /// Distance from the body edge along `normal`, negative when the cloth edge lies inside.
    pub distance: f32,
}

impl BodyEdges {
    /// The unique edges of a closed, outward-oriented mesh.
    pub fn new(mesh: &TriMesh) -> Self {
        let mut sums: HashMap<(u32, u32), Vec3> = HashMap::new();
        for t in &mesh.triangles {
            let p = t.map(|i| mesh.positions[i as usize]);
            let n = (p[1] - p[0]).cross(p[2] - p[0]).normalize_or_zero();
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                *sums.entry((a.min(b), a.max(b))).or_insert(Vec3::ZERO) += n;
            }
        }
        let mut keys: Vec<(u32, u32)> = sums.keys().copied().collect();
        keys.sort_unstable();
        let ends: Vec<[Vec3; 2]> = keys
            .iter()
            .map(|&(a, b)| [mesh.positions[a as usize], mesh.positions[b as usize]])
            .collect();
        let normals = keys.iter().map(|k| sums[k].normalize_or_zero()).collect();
        let boxes: Vec<Aabb> = ends
            .iter()
            .map(|[a, b]| Aabb::new(a.min(*b), a.max(*b)))
            .collect();
        BodyEdges {
            bvh: Bvh::from_leaves(BvhBuildStrategy::default(), &boxes),
            ends,
            normals,
        }
    }

    /// Bytes the edges hold on the heap: their ends, normals and BVH.
    pub fn heap_bytes(&self) -> usize {
        self.ends.capacity() * std::mem::size_of::<[Vec3; 2]>()
            + self.normals.capacity() * std::mem::size_of::<Vec3>()
            + self.bvh.total_memory_size()
    }

    /// Number of edges.
    pub fn len(&self) -> usize {
        self.ends.len()
    }

    /// Whether the mesh had no edges.
    pub fn is_empty(&self) -> bool {
        self.ends.is_empty()
    }

    /// The deepest contact of the cloth edge `a`→`b` (body frame) with a body edge closer than
    /// `reach`, if any. `inside` tells whether a point is inside the body: a cloth edge that
    /// has passed through an edge is pushed back out along the edge's normal.
    pub fn deepest(
        &self,
        a: Vec3,
        b: Vec3,
        reach: f32,
        inside: impl Fn(Vec3) -> bool,
    ) -> Option<EdgeContact> {
        let region = Aabb::new(a.min(b) - Vec3::splat(reach), a.max(b) + Vec3::splat(reach));
        let mut best: Option<EdgeContact> = None;
        for leaf in self.bvh.intersect_aabb(&region) {
            let [c, d] = self.ends[leaf as usize];
            let (on_cloth, on_body) =
                closest_points_segment_segment_with_locations_nD((&a, &b), (&c, &d));
            let [_, s] = on_cloth.barycentric_coordinates();
            let [_, t] = on_body.barycentric_coordinates();
            let (p, q) = (a.lerp(b, s), c.lerp(d, t));
            let gap = p - q;
            let length = gap.length();
            if length >= reach {
                continue;
            }
            let edge_normal = self.normals[leaf as usize];
            let (normal, distance) = if inside(p) {
                (edge_normal, -length)
            } else if length > 1e-9 {
                (gap / length, length)
            } else {
                (edge_normal, 0.0)
            };
            if best.is_none_or(|c| distance < c.distance) {
                best = Some(EdgeContact {
                    s,
                    point: q,
                    normal,
                    distance,
                });
            }
        }
        best
    }
}
