//! Vertex caches: a body's vertex positions at a sequence of frames, from a PC2 point cache or
//! a numbered sequence of OBJ files with the body's topology, played at the cache's own frame
//! rate and interpolated linearly between frames.
//!
//! A cache lists the vertices in the order of the OBJ file's `v` records, so bodies with a
//! cache are read with their raw vertex order (`read_obj_raw`), not through the importer that
//! splits vertices by texture coordinate.

use crate::error::InputError;
use crate::mesh::TriMesh;
use glam::Vec3;
use std::path::{Path, PathBuf};

/// A PC2 file's first 12 bytes (as drapekit's exports write them).
const PC2_SIGNATURE: &[u8; 12] = b"POINTCACHE2\0";

/// Positions of every vertex at each frame.
#[derive(Clone, Debug, PartialEq)]
pub struct VertexCache {
    /// Each frame's time from the cache's first frame, in s, increasing.
    pub times: Vec<f32>,
    /// Each frame's positions, in the body's raw vertex order, in m.
    pub frames: Vec<Vec<Vec3>>,
}

impl VertexCache {
    /// Its length in s.
    pub fn duration(&self) -> f32 {
        self.times.last().copied().unwrap_or(0.0)
    }

    /// The positions at `t` s from the first frame (held before the first and after the last).
    pub fn at(&self, t: f32) -> Vec<Vec3> {
        let last = self.times.len() - 1;
        if t <= self.times[0] || last == 0 {
            return self.frames[0].clone();
        }
        if t >= self.times[last] {
            return self.frames[last].clone();
        }
        let k = self.times.partition_point(|&s| s <= t) - 1;
        let s = (t - self.times[k]) / (self.times[k + 1] - self.times[k]);
        (self.frames[k].iter().zip(&self.frames[k + 1]))
            .map(|(a, b)| a.lerp(*b, s))
            .collect()
    }

    /// Every frame scaled by `scale` and moved by `offset`.
    pub fn placed(mut self, scale: f32, offset: Vec3) -> VertexCache {
        for p in self.frames.iter_mut().flatten() {
            *p = *p * scale + offset;
        }
        self
    }
}

fn bad(path: &Path, key: &str, problem: impl Into<String>, fix: impl Into<String>) -> InputError {
    InputError::new(path, key, problem, fix)
}

/// Reads a cache: a `.pc2` file, or an OBJ sequence named with a run of `#` for the frame
/// number (`walk_####.obj`), played at `fps` frames per second. `vertices` is the body's raw
/// vertex count, which every frame must match.
pub fn read_cache(
    path: &Path,
    fps: f32,
    vertices: usize,
    key: &str,
) -> Result<VertexCache, InputError> {
    let name = path
        .file_name()
        .map_or(String::new(), |n| n.to_string_lossy().into());
    let (times, frames) = if name.contains('#') {
        read_obj_sequence(path, fps, key)?
    } else {
        read_pc2(path, fps, key)?
    };
    if frames.len() < 2 {
        return Err(bad(
            path,
            key,
            format!("holds {} frame; a motion needs at least two", frames.len()),
            "export the whole animation range",
        ));
    }
    if let Some((k, f)) = frames.iter().enumerate().find(|(_, f)| f.len() != vertices) {
        return Err(bad(
            path,
            key,
            format!(
                "frame {k} has {} vertices but the body mesh has {vertices}",
                f.len()
            ),
            "export the cache from the same mesh as the body (same vertices, same order), \
             with no modifier that adds or removes vertices",
        ));
    }
    if let Some(k) = frames.iter().position(|f| f.iter().any(|p| !p.is_finite())) {
        return Err(bad(
            path,
            key,
            format!("frame {k} has a non-finite coordinate"),
            "export the cache again",
        ));
    }
    Ok(VertexCache { times, frames })
}

type Frames = (Vec<f32>, Vec<Vec<Vec3>>);

/// A PC2 file: 32-byte header, then each sample's points as little-endian f32.
fn read_pc2(path: &Path, fps: f32, key: &str) -> Result<Frames, InputError> {
    let bytes = std::fs::read(path).map_err(|e| {
        bad(
            path,
            key,
            format!("cannot read the cache: {e}"),
            "check the path (it is relative to the scene file)",
        )
    })?;
    let word = |at: usize| {
        bytes
            .get(at..at + 4)
            .map(|w| <[u8; 4]>::try_from(w).unwrap())
    };
    if bytes.len() < 32 || &bytes[..12] != PC2_SIGNATURE {
        return Err(bad(
            path,
            key,
            "is not a PC2 point cache (no POINTCACHE2 header)",
            "give a .pc2 file, or an OBJ sequence as name_####.obj",
        ));
    }
    let points = i32::from_le_bytes(word(16).unwrap());
    let rate = f32::from_le_bytes(word(24).unwrap());
    let samples = i32::from_le_bytes(word(28).unwrap());
    let (Ok(points), Ok(samples)) = (usize::try_from(points), usize::try_from(samples)) else {
        return Err(bad(
            path,
            key,
            "has a negative point or sample count",
            "export the cache again",
        ));
    };
    let expected = points
        .checked_mul(samples)
        .and_then(|n| n.checked_mul(12))
        .and_then(|n| n.checked_add(32));
    if expected != Some(bytes.len()) {
        return Err(bad(
            path,
            key,
            format!(
                "declares {samples} samples of {points} points but holds {} bytes of them",
                bytes.len() - 32
            ),
            "export the cache again (the file is truncated or padded)",
        ));
    }
    if !(rate.is_finite() && rate > 0.0) {
        return Err(bad(
            path,
            key,
            format!("has a sample rate of {rate} frames"),
            "export the cache again with a positive sample rate",
        ));
    }
    let floats: Vec<f32> = bytes[32..]
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes(c.try_into().unwrap()))
        .collect();
    let frames = (floats.chunks_exact(3 * points.max(1)))
        .take(samples)
        .map(|s| {
            s.chunks_exact(3)
                .map(|c| Vec3::new(c[0], c[1], c[2]))
                .collect()
        })
        .collect::<Vec<Vec<Vec3>>>();
    let frames = if points == 0 {
        vec![Vec::new(); samples]
    } else {
        frames
    };
    let times = (0..samples).map(|k| k as f32 * rate / fps).collect();
    Ok((times, frames))
}

/// The files of an OBJ sequence: `pattern`'s file name with its run of `#` replaced by a frame
/// number (any number of digits), sorted by number.
fn sequence_files(pattern: &Path, key: &str) -> Result<Vec<(u64, PathBuf)>, InputError> {
    let name = pattern
        .file_name()
        .map_or(String::new(), |n| n.to_string_lossy().into());
    let first = name.find('#').unwrap_or(0);
    let last = name.rfind('#').unwrap_or(0);
    let (prefix, suffix) = (&name[..first], &name[last + 1..]);
    let folder = pattern.parent().filter(|p| !p.as_os_str().is_empty());
    let folder = folder.unwrap_or(Path::new("."));
    let entries = std::fs::read_dir(folder).map_err(|e| {
        bad(
            pattern,
            key,
            format!("cannot list {}: {e}", folder.display()),
            "check the folder of the OBJ sequence (relative to the scene file)",
        )
    })?;
    let mut files: Vec<(u64, PathBuf)> = entries
        .filter_map(|e| e.ok())
        .filter_map(|e| {
            let n = e.file_name().to_string_lossy().to_string();
            let digits = n.strip_prefix(prefix)?.strip_suffix(suffix)?;
            let ok = !digits.is_empty() && digits.bytes().all(|b| b.is_ascii_digit());
            ok.then(|| digits.parse().ok().map(|k| (k, e.path())))?
        })
        .collect();
    files.sort();
    if files.is_empty() {
        return Err(bad(
            pattern,
            key,
            format!(
                "no file in {} matches {prefix}<number>{suffix}",
                folder.display()
            ),
            "give the sequence's name with # for the frame number, e.g. walk_####.obj",
        ));
    }
    Ok(files)
}

/// An OBJ sequence: each file's `v` records, at `fps` frames per second of its numbers.
fn read_obj_sequence(pattern: &Path, fps: f32, key: &str) -> Result<Frames, InputError> {
    let files = sequence_files(pattern, key)?;
    let first = files[0].0;
    let mut times = Vec::new();
    let mut frames = Vec::new();
    for (number, file) in files {
        let text = std::fs::read_to_string(&file).map_err(|e| {
            bad(
                &file,
                key,
                format!("cannot read the frame: {e}"),
                "check that every file of the sequence is a readable text OBJ",
            )
        })?;
        let (points, _) = parse_obj_raw(&text, &file, key, false)?;
        times.push((number - first) as f32 / fps);
        frames.push(points);
    }
    Ok((times, frames))
}

/// Reads an OBJ body keeping its `v` records in order (what a vertex cache indexes), with its
/// faces fan-triangulated, scaled by `scale` (m per file unit).
pub fn read_obj_raw(path: &Path, scale: f32, key: &str) -> Result<TriMesh, InputError> {
    let text = std::fs::read_to_string(path).map_err(|e| {
        bad(
            path,
            key,
            format!("cannot read the mesh: {e}"),
            "check that the path exists (it is relative to the scene file) and is a text OBJ",
        )
    })?;
    let (positions, triangles) = parse_obj_raw(&text, path, key, true)?;
    if triangles.is_empty() {
        return Err(bad(
            path,
            key,
            "the mesh has no faces",
            "export the body as a triangle or polygon mesh with `f` records",
        ));
    }
    Ok(TriMesh {
        positions: positions.into_iter().map(|p| p * scale).collect(),
        triangles,
    })
}

/// The `v` records (and, with `faces`, the `f` records as triangles) of OBJ text.
fn parse_obj_raw(
    text: &str,
    path: &Path,
    key: &str,
    faces: bool,
) -> Result<(Vec<Vec3>, Vec<[u32; 3]>), InputError> {
    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    for (line_no, line) in text.lines().enumerate() {
        let mut words = line.split_whitespace();
        let at_line = |problem: String| {
            let mut e = bad(path, key, problem, "repair the OBJ file");
            e.line = Some(line_no + 1);
            e
        };
        match words.next() {
            Some("v") => {
                let c: Vec<f32> = words.take(3).filter_map(|w| w.parse().ok()).collect();
                if c.len() != 3 {
                    return Err(at_line("a `v` record needs three numbers".into()));
                }
                if c.iter().any(|x| !x.is_finite()) {
                    return Err(at_line(format!(
                        "vertex {} has a coordinate that is not a finite number ({c:?})",
                        positions.len() + 1
                    )));
                }
                positions.push(Vec3::new(c[0], c[1], c[2]));
            }
            Some("f") if faces => {
                let mut corners = Vec::new();
                for w in words {
                    let index: i64 = w
                        .split('/')
                        .next()
                        .and_then(|i| i.parse().ok())
                        .ok_or_else(|| {
                            at_line(format!("face corner {w:?} does not start with a number"))
                        })?;
                    // Negative indices count back from the last vertex so far.
                    let i = if index < 0 {
                        positions.len() as i64 + index
                    } else {
                        index - 1
                    };
                    if i < 0 || i >= positions.len() as i64 {
                        return Err(at_line(format!("face corner {w} names no vertex")));
                    }
                    corners.push(i as u32);
                }
                for k in 1..corners.len().saturating_sub(1) {
                    triangles.push([corners[0], corners[k], corners[k + 1]]);
                }
            }
            _ => {}
        }
    }
    Ok((positions, triangles))
}
