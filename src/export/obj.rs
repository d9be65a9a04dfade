//! Wavefront OBJ text of a cloth frame (smooth normals, pattern coordinates, one group per
//! panel) and of the body at a pose.

use crate::mesh::vertex_normals;
use glam::{Vec2, Vec3};
use rayon::prelude::*;
use std::fmt::Write as _;

/// A named set of triangles written under one `g` record.
#[derive(Clone, Debug, PartialEq)]
pub struct Group {
    /// The group's name (whitespace would end it early in OBJ, so it is replaced by `_`).
    pub name: String,
    /// Indices into the mesh's triangles.
    pub triangles: Vec<u32>,
}

/// Groups from each triangle's panel: one group per panel that has triangles, in panel order.
pub fn panel_groups(names: &[String], triangle_panel: &[u32]) -> Vec<Group> {
    let mut groups: Vec<Group> = (names.iter())
        .map(|n| Group {
            name: n.split_whitespace().collect::<Vec<_>>().join("_"),
            triangles: Vec::new(),
        })
        .collect();
    for (t, &p) in triangle_panel.iter().enumerate() {
        if let Some(g) = groups.get_mut(p as usize) {
            g.triangles.push(t as u32);
        }
    }
    groups.retain(|g| !g.triangles.is_empty());
    groups
}

/// Unit area-weighted vertex normals; a vertex of no (or only degenerate) triangles gets +z,
/// since OBJ and glTF readers expect unit normals.
pub fn unit_normals(positions: &[Vec3], triangles: &[[u32; 3]]) -> Vec<Vec3> {
    (vertex_normals(positions, triangles).into_iter())
        .map(|n| n.normalize_or(Vec3::Z))
        .collect()
}

/// A cloth frame: `v` in m, `vt` pattern coordinates in m (when given), `vn` smooth normals,
/// and the faces `f a/a/a` (or `f a//a` without `vt`) under their groups. Vertex order is the
/// particle order, so a point cache of the same run lines up with it.
pub fn cloth_obj(
    positions: &[Vec3],
    triangles: &[[u32; 3]],
    uv: Option<&[Vec2]>,
    groups: &[Group],
) -> String {
    let mut s = String::with_capacity(positions.len() * 80 + triangles.len() * 32);
    s.push_str("# drapekit frame, units: m");
    s.push_str(if uv.is_some() {
        "; vt: pattern coordinates in m\n"
    } else {
        "\n"
    });
    vertices(&mut s, positions, triangles);
    lines(&mut s, uv.unwrap_or_default(), |s, t| {
        let _ = writeln!(s, "vt {} {}", t.x, t.y);
    });
    for g in groups {
        let _ = writeln!(s, "g {}", g.name);
        lines(&mut s, &g.triangles, |s, &t| {
            let [a, b, c] = triangles[t as usize].map(|i| i + 1);
            let _ = match uv {
                Some(_) => writeln!(s, "f {a}/{a}/{a} {b}/{b}/{b} {c}/{c}/{c}"),
                None => writeln!(s, "f {a}//{a} {b}//{b} {c}//{c}"),
            };
        });
    }
    s
}

/// The body in world coordinates (m) at one pose, with smooth normals, as group `body`.
pub fn body_obj(positions: &[Vec3], triangles: &[[u32; 3]]) -> String {
    let mut s = String::with_capacity(positions.len() * 80 + triangles.len() * 32);
    s.push_str("# drapekit body, world coordinates, units: m\n");
    vertices(&mut s, positions, triangles);
    s.push_str("g body\n");
    lines(&mut s, triangles, |s, t| {
        let [a, b, c] = t.map(|i| i + 1);
        let _ = writeln!(s, "f {a}//{a} {b}//{b} {c}//{c}");
    });
    s
}

/// `v` and `vn` records. Rust's `{}` of an f32 is its shortest exact form: a reader gets the
/// very same f32 back.
fn vertices(s: &mut String, positions: &[Vec3], triangles: &[[u32; 3]]) {
    lines(s, positions, |s, p| {
        let _ = writeln!(s, "v {} {} {}", p.x, p.y, p.z);
    });
    lines(s, &unit_normals(positions, triangles), |s, n| {
        let _ = writeln!(s, "vn {} {} {}", n.x, n.y, n.z);
    });
}

/// Appends `line` of every item to `s`, in order. Chunks are formatted on the pool: a 5 mm
/// shirt's frame is 7 MB of text, written every few frames of the run.
fn lines<T: Sync>(s: &mut String, items: &[T], line: impl Fn(&mut String, &T) + Sync) {
    let chunks: Vec<String> = (items.par_chunks(4096))
        .map(|chunk| {
            let mut text = String::with_capacity(chunk.len() * 40);
            chunk.iter().for_each(|x| line(&mut text, x));
            text
        })
        .collect();
    chunks.iter().for_each(|c| s.push_str(c));
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn groups_follow_panels_and_faces_carry_normals() {
        // Two triangles in the z = 0 plane, one per panel; the second panel's name has a space.
        let p = [Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::ONE];
        let tris = [[0, 1, 2], [1, 3, 2]];
        let names = ["front".to_string(), "back panel".to_string(), "none".into()];
        let groups = panel_groups(&names, &[0, 1]);
        assert_eq!(groups.len(), 2, "a panel without triangles gets no group");
        let uv = [Vec2::ZERO; 4];
        let text = cloth_obj(&p, &tris, Some(&uv), &groups);
        assert!(text.contains("g front\nf 1/1/1 2/2/2 3/3/3\ng back_panel\nf 2/2/2 4/4/4 3/3/3\n"));
        assert_eq!(text.matches("\nvn ").count(), 4);
        // Vertex 0 lies only in the first triangle, which faces +z.
        assert!(text.contains("vn 0 0 1\n"), "{text}");
        let plain = cloth_obj(&p, &tris, None, &[]);
        assert!(!plain.contains("vt") && !plain.contains("\nf "));
    }
}
