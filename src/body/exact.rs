//! Exact point queries against a body's triangles through parry3d's BVH: the ground truth for
//! the SDF and for penetration measurements.

use crate::mesh::TriMesh;
use glam::Vec3;
use parry3d::query::PointQuery;
use parry3d::shape::{TriMesh as ParryMesh, TriMeshFlags};

/// A body mesh prepared for exact nearest-point and inside/outside queries. The sign comes
/// from parry's angle-weighted pseudo-normals (Bærentzen & Aanæs), which are robust on closed,
/// consistently oriented meshes.
pub struct ExactBody {
    shape: ParryMesh,
}

impl ExactBody {
    /// Builds the BVH and pseudo-normals of a closed, outward-oriented mesh.
    pub fn new(mesh: &TriMesh) -> Result<Self, String> {
        let shape = ParryMesh::with_flags(
            mesh.positions.clone(),
            mesh.triangles.clone(),
            TriMeshFlags::ORIENTED,
        )
        .map_err(|e| format!("{e:?}"))?;
        Ok(ExactBody { shape })
    }

    /// Bytes parry's mesh holds on the heap: vertices, indices, pseudo-normals (one per vertex
    /// and three per triangle) and its BVH.
    pub fn heap_bytes(&self) -> usize {
        let (v, t) = (self.shape.vertices().len(), self.shape.indices().len());
        let vector = std::mem::size_of::<Vec3>();
        v * vector + t * 3 * 4 + (v + 3 * t) * vector + self.shape.bvh().total_memory_size()
    }

    /// `query`, with the index of the triangle that holds the nearest point.
    pub fn query_triangle(&self, p: Vec3) -> (f32, Vec3, u32) {
        use parry3d::query::PointQueryWithLocation;
        let (proj, (triangle, _)) = self.shape.project_local_point_and_get_location(p, false);
        let d = p.distance(proj.point);
        (if proj.is_inside { -d } else { d }, proj.point, triangle)
    }

    /// Signed distance to the surface (negative inside) and the nearest surface point.
    pub fn query(&self, p: Vec3) -> (f32, Vec3) {
        let proj = self.shape.project_local_point(p, false);
        let d = p.distance(proj.point);
        (if proj.is_inside { -d } else { d }, proj.point)
    }
}
