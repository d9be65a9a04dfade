//! Welding a sewn garment for export and display: each seam's vertex pairs become one vertex,
//! so that the panels form one connected mesh (DCC tools' Subdivision and Solidify keep it
//! closed, and shading runs smooth across seams). The simulation keeps the panels apart, joined
//! by seam forces; this is only what the files and pictures show.

use super::garment::Garment;
use glam::{Vec2, Vec3};

/// Welded vertices: which particles each one joins, and the triangles over them.
#[derive(Clone, Debug, PartialEq)]
pub struct Weld {
    /// Each welded vertex's particles, the first one its representative (pattern coordinates).
    pub members: Vec<Vec<u32>>,
    /// Each particle's welded vertex.
    pub vertex_of: Vec<u32>,
    /// The garment's triangles over welded vertices, in the garment's triangle order.
    pub triangles: Vec<[u32; 3]>,
}

/// A seam pair's partner point lies within this fraction of a segment of one of its ends when
/// the two edges are sampled alike (they are: both take the same segment count), up to the
/// difference between chord and arc fractions on a curved edge.
const NEAR_END: f32 = 0.25;

impl Weld {
    /// Joins every seam vertex with the vertex its partner point sits at, across all stitches
    /// (a corner where several seams meet becomes one vertex). A pair whose partner lies mid-
    /// segment (edges sampled unalike) is left unwelded.
    pub fn of_garment(garment: &Garment) -> Weld {
        let n = garment.uv.len();
        let mut parent: Vec<u32> = (0..n as u32).collect();
        fn root(parent: &mut [u32], mut i: u32) -> u32 {
            while parent[i as usize] != i {
                let up = parent[parent[i as usize] as usize];
                parent[i as usize] = up;
                i = up;
            }
            i
        }
        for s in &garment.seam_pairs {
            let partner = match s.w {
                w if w <= NEAR_END => s.b[0],
                w if w >= 1.0 - NEAR_END => s.b[1],
                _ => continue,
            };
            let (a, b) = (root(&mut parent, s.a), root(&mut parent, partner));
            // The smaller index is the root, so that a vertex's representative is its first
            // particle and the result does not depend on the pairs' order.
            let (lo, hi) = (a.min(b), a.max(b));
            parent[hi as usize] = lo;
        }
        let mut vertex_of = vec![u32::MAX; n];
        let mut members: Vec<Vec<u32>> = Vec::new();
        for i in 0..n as u32 {
            let r = root(&mut parent, i);
            if vertex_of[r as usize] == u32::MAX {
                vertex_of[r as usize] = members.len() as u32;
                members.push(Vec::new());
            }
            let v = vertex_of[r as usize];
            vertex_of[i as usize] = v;
            members[v as usize].push(i);
        }
        let triangles = (garment.mesh.triangles.iter())
            .map(|t| t.map(|i| vertex_of[i as usize]))
            .collect();
        Weld {
            members,
            vertex_of,
            triangles,
        }
    }

    /// Welded vertices.
    pub fn len(&self) -> usize {
        self.members.len()
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.members.is_empty()
    }

    /// A frame's welded positions: each vertex at the mean of its particles.
    pub fn positions(&self, particles: &[Vec3]) -> Vec<Vec3> {
        (self.members.iter())
            .map(|m| m.iter().map(|&i| particles[i as usize]).sum::<Vec3>() / m.len() as f32)
            .collect()
    }

    /// Each welded vertex's pattern coordinates: its representative's. Across a seam the two
    /// panels' coordinates differ, so one row of triangles on the other panel takes the
    /// texture from the representative's panel.
    pub fn uv(&self, uv: &[Vec2]) -> Vec<Vec2> {
        self.members.iter().map(|m| uv[m[0] as usize]).collect()
    }

    /// The most any particle lies from its welded vertex in a frame, in m: how far welding moves
    /// the garment.
    pub fn largest_shift(&self, particles: &[Vec3]) -> f32 {
        let welded = self.positions(particles);
        (particles.iter().zip(&self.vertex_of))
            .map(|(p, &v)| p.distance(welded[v as usize]))
            .fold(0.0, f32::max)
    }
}
