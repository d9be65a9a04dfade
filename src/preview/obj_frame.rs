//! Reading back the frames `drapekit run` wrote: `frame_NNNN.obj` with positions in particle
//! order, pattern coordinates (`vt`, one per vertex) and one group per panel.

use super::previewer::bad;
use crate::error::Error;
use glam::{Vec2, Vec3};
use std::path::{Path, PathBuf};

/// One frame's cloth.
#[derive(Clone, Debug, Default)]
pub struct FrameMesh {
    /// The frame number.
    pub number: u32,
    /// Positions in file order (the particle order).
    pub positions: Vec<Vec3>,
    /// Triangles (polygons as fans).
    pub triangles: Vec<[u32; 3]>,
    /// Each triangle's group (panel) in order of first appearance; 0 without `g` records.
    pub groups: Vec<u32>,
    /// The groups' names (the panels'), indexed by `groups`' values.
    pub group_names: Vec<String>,
    /// Pattern coordinates in m, one per vertex, or empty when the file has none.
    pub uv: Vec<Vec2>,
}

/// The frames `frame_NNNN.obj` in a run folder, in order.
pub fn frames(run: &Path) -> Result<Vec<(u32, PathBuf)>, Error> {
    let entries = std::fs::read_dir(run).map_err(|e| Error::io(run, e))?;
    let mut out: Vec<(u32, PathBuf)> = entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter_map(|p| {
            let name = p.file_name()?.to_str()?;
            let n = name
                .strip_prefix("frame_")?
                .strip_suffix(".obj")?
                .parse()
                .ok()?;
            Some((n, p))
        })
        .collect();
    out.sort();
    Ok(out)
}

/// The farthest a frame's vertex may lie from the origin, in m (on any axis).
const MAX_COORDINATE_M: f32 = 1e6;

/// Reads the `v`, `vt`, `g` and `f` records of an OBJ file. `vt` are kept only when there is
/// one per vertex, as drapekit writes them (`f a/a/a`).
pub fn read_obj(path: &Path) -> Result<FrameMesh, Error> {
    // A frame the run listed but that cannot be read is a damaged run folder: bad input.
    let text = std::fs::read_to_string(path).map_err(|e| {
        bad(
            path,
            format!("cannot read the frame ({e})"),
            "rerun drapekit run to rewrite the frame",
        )
    })?;
    let broken = |n: usize| {
        bad(
            path,
            format!(
                "line {}: not an OBJ vertex (three finite numbers) or face",
                n + 1
            ),
            "rerun drapekit run to rewrite the frame",
        )
    };
    let mut m = FrameMesh::default();
    let mut group_names: Vec<String> = Vec::new();
    let mut group = 0u32;
    for (n, line) in text.lines().enumerate() {
        let mut words = line.split_whitespace();
        match words.next() {
            Some("v") => {
                let xyz: Vec<f32> = words.take(3).filter_map(|w| w.parse().ok()).collect();
                // A run never writes a non-finite vertex (it stops first): NaN is damage.
                if xyz.len() != 3 || xyz.iter().any(|x| !x.is_finite()) {
                    return Err(broken(n));
                }
                // Framing squares coordinates: near f32's limit they overflow and the picture
                // comes out blank. A thousand kilometres is far past any scene's cloth.
                if xyz.iter().any(|x| x.abs() > MAX_COORDINATE_M) {
                    return Err(bad(
                        path,
                        format!(
                            "line {}: a vertex lies beyond {MAX_COORDINATE_M:e} m of the \
                             origin, which no garment does",
                            n + 1
                        ),
                        "rerun drapekit run to rewrite the frame",
                    ));
                }
                m.positions.push(Vec3::from_slice(&xyz));
            }
            Some("vt") => {
                let uv: Vec<f32> = words.take(2).filter_map(|w| w.parse().ok()).collect();
                if uv.len() != 2 {
                    return Err(broken(n));
                }
                m.uv.push(Vec2::from_slice(&uv));
            }
            Some("g") => {
                let name = words.collect::<Vec<_>>().join(" ");
                group = match group_names.iter().position(|g| *g == name) {
                    Some(k) => k as u32,
                    None => {
                        group_names.push(name);
                        group_names.len() as u32 - 1
                    }
                };
            }
            Some("f") => {
                let mut ids = Vec::new();
                for w in words {
                    let i: i64 = (w.split('/').next())
                        .and_then(|s| s.parse().ok())
                        .ok_or_else(|| broken(n))?;
                    // 1-based, or negative: counted back from the last vertex.
                    let i = if i < 0 {
                        m.positions.len() as i64 + i
                    } else {
                        i - 1
                    };
                    if i < 0 || i >= m.positions.len() as i64 {
                        return Err(broken(n));
                    }
                    ids.push(i as u32);
                }
                for k in 1..ids.len().saturating_sub(1) {
                    m.triangles.push([ids[0], ids[k], ids[k + 1]]);
                    m.groups.push(group);
                }
            }
            _ => {}
        }
    }
    m.group_names = group_names;
    if m.triangles.is_empty() {
        // Every frame a run writes has the cloth's faces: an empty or cut file is damage.
        return Err(bad(
            path,
            "holds no faces (an empty or cut-off frame)",
            "rerun drapekit run to rewrite the frame",
        ));
    }
    if m.uv.len() != m.positions.len() {
        m.uv.clear();
    }
    Ok(m)
}

#[cfg(test)]
mod tests {
    use super::read_obj;

    #[test]
    fn a_frame_with_a_vertex_that_is_not_a_finite_number_is_damaged() {
        let dir = std::env::temp_dir().join(format!("drapekit-obj-frame-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let gone = read_obj(&dir.join("frame_gone.obj")).expect_err("a missing frame was read");
        assert!(gone.to_string().contains("cannot read the frame"), "{gone}");
        assert_eq!(gone.exit_code(), 2, "a damaged run folder is bad input");
        let empty = dir.join("frame_empty.obj");
        std::fs::write(&empty, "").unwrap();
        let e = read_obj(&empty).expect_err("an empty frame was read");
        assert!(e.to_string().contains("holds no faces"), "{e}");
        for (name, x) in [
            ("nan", "nan"),
            ("inf", "inf"),
            ("far", "-3e38"),
            ("ok", "0.5"),
        ] {
            let path = dir.join(format!("frame_{name}.obj"));
            let text = format!("v 0 0 0\nv {x} 0 0\nv 0 1 0\nf 1 2 3\n");
            std::fs::write(&path, text).unwrap();
            match (name, read_obj(&path)) {
                ("ok", r) => assert_eq!(r.unwrap().positions.len(), 3),
                ("far", r) => {
                    let e = r.expect_err("a vertex 3e38 m away was read").to_string();
                    assert!(e.contains("line 2: a vertex lies beyond"), "{e}");
                }
                (_, r) => {
                    let e = r.expect_err("a non-finite vertex was read").to_string();
                    assert!(e.contains("line 2: not an OBJ vertex"), "{e}");
                }
            }
        }
        let _ = std::fs::remove_dir_all(&dir);
    }
}
