//! The disk space a run will write, estimated from the prepared model before the first frame,
//! against the free space of the output folder's disk: a run that cannot finish its files is
//! refused before it starts, with the frame count and `every` that fit.

use crate::error::InputError;
use crate::scene::Scene;
use crate::sim::Prepared;
use std::path::Path;

/// Bytes of one number in an OBJ record: Rust prints an f32 in its shortest exact form, at most
/// 9 significant digits, a sign, a point and a space (`-0.123456789 `), 13 for coordinates
/// under 10 m; longer forms (tiny or huge numbers) are rare in a cloth frame.
const OBJ_NUMBER: u64 = 13;

/// Bytes of a rendered preview PNG per pixel: 0.2 to 0.5 were measured on the shipped scenes
/// (a flat background compresses well); 1 leaves room for busier images.
const PNG_BYTES_PER_PIXEL: u64 = 1;

/// What a run will write, estimated.
#[derive(Clone, Debug, PartialEq)]
pub struct OutputEstimate {
    /// Frames written (frame 0, those on the `every` schedule, and the last).
    pub frames: u64,
    /// Bytes of one written frame (its OBJ files, its share of the caches and previews).
    pub bytes_per_frame: u64,
    /// Bytes written once (rest shape, static bodies, last previews, a checkpoint's copy).
    pub bytes_once: u64,
}

impl OutputEstimate {
    /// All the bytes the run writes.
    pub fn bytes(&self) -> u64 {
        (self.frames.saturating_mul(self.bytes_per_frame)).saturating_add(self.bytes_once)
    }
}

/// Digits of the largest 1-based index below `n`.
fn digits(n: u64) -> u64 {
    n.max(1).ilog10() as u64 + 1
}

/// An OBJ of `vertices` and `triangles` (with `vt` records when `uv`): `v` and `vn` records of
/// three numbers, `vt` of two, and faces of three `a/a/a` (or `a//a`) triples.
fn obj_bytes(vertices: u64, triangles: u64, uv: bool) -> u64 {
    let index = digits(vertices);
    let vertex = 2 * (3 + 3 * OBJ_NUMBER) + if uv { 3 + 2 * OBJ_NUMBER } else { 0 };
    let face = 2 + 3 * (3 * index + 3);
    vertices * vertex + triangles * face
}

/// The frames a run of `frames` frames writes after frame `from`: frame 0 (when it starts
/// there), every `every`-th, and the last.
fn written_frames(from: u32, frames: u32, every: u32) -> u64 {
    let every = every.max(1);
    let first = (from == 0) as u64;
    let on_schedule = (frames / every).saturating_sub(from / every) as u64;
    let last = (frames > from && !frames.is_multiple_of(every)) as u64;
    first + on_schedule + last
}

/// The files `prep`'s run writes into its output folder, from frame `from` (a resumed run
/// writes only what is left).
pub fn estimate(scene: &Scene, prep: &Prepared, from: u32) -> OutputEstimate {
    let out = &scene.output;
    let n = prep.model.len() as u64;
    let t = prep.model.triangles.len() as u64;
    let frames_left = prep.frames.saturating_sub(from) as u64;
    let written = written_frames(from, prep.frames, out.every);
    let cloth = obj_bytes(n, t, prep.garment.is_some());
    let mut per_frame = 0;
    let mut once = 0;
    if out.obj {
        per_frame += cloth;
        for c in &prep.model.colliders {
            let body = &c.body.mesh;
            let bytes = obj_bytes(
                body.positions.len() as u64,
                body.triangles.len() as u64,
                false,
            );
            if c.deformed.is_some() {
                // A deforming body is written at every frame (body_NNNN.obj): no node
                // animation holds its shape.
                per_frame += bytes;
                continue;
            }
            // One OBJ either way; a moving body's motion goes to body.glb: its mesh once
            // (positions and normals, 24 bytes a vertex; 12 a triangle) and a time, a rotation
            // and a translation (32 bytes) a written frame.
            once += bytes;
            if c.motion.moves() {
                once += 24 * body.positions.len() as u64 + 12 * body.triangles.len() as u64;
                per_frame += 32;
            }
        }
    }
    // The caches keep 12 bytes (three f32) per particle and frame; glTF adds a normal per
    // particle; a checkpoint holds the kept frames too, and briefly twice (written, renamed).
    let kept = if out.pc2 { 12 * n } else { 0 } + if out.gltf { 24 * n } else { 0 };
    per_frame += kept;
    if out.pc2 {
        once += cloth;
    }
    once += 2 * 32 * n;
    per_frame += 2 * 12 * n * (out.pc2 || out.gltf) as u64;
    // frames.csv has a row of about 100 bytes a simulated frame, and a checkpoint each row's
    // record (about 170 bytes), briefly twice: `every` simulated frames a written one (all of
    // them when fewer are left).
    per_frame += out.every.min(frames_left.max(1) as u32) as u64 * (100 + 2 * 170);
    let p = &scene.preview;
    let png = PNG_BYTES_PER_PIXEL * p.size.0 as u64 * p.size.1 as u64;
    once += p.last.len() as u64 * png;
    if let Some(every) = p.every {
        let share = p.every_modes.len() as u64 * png / every.max(1) as u64;
        per_frame += share * out.every as u64;
    }
    if p.animation.is_some() {
        // One byte per pixel and frame before the GIF's compression.
        per_frame += p.animation_size.0 as u64 * p.animation_size.1 as u64;
    }
    OutputEstimate {
        frames: written,
        bytes_per_frame: per_frame,
        bytes_once: once,
    }
}

/// Free bytes for an unprivileged writer on the disk that holds `dir` (or the nearest folder
/// above it that exists); `None` where this cannot be asked.
pub fn free_bytes(dir: &Path) -> Option<u64> {
    let absolute = std::path::absolute(dir).ok()?;
    let existing = absolute.ancestors().find(|p| p.is_dir())?;
    free_bytes_of(existing)
}

#[cfg(unix)]
fn free_bytes_of(dir: &Path) -> Option<u64> {
    use std::os::unix::ffi::OsStrExt;
    let path = std::ffi::CString::new(dir.as_os_str().as_bytes()).ok()?;
    let mut stat: libc::statvfs = unsafe { std::mem::zeroed() };
    // SAFETY: `path` is a NUL-terminated string and `stat` a writable statvfs; the call only
    // fills `stat`.
    if unsafe { libc::statvfs(path.as_ptr(), &mut stat) } != 0 {
        return None;
    }
    // Pseudo filesystems (sysfs, procfs) report no blocks at all: they have no capacity to
    // compare with, and whether they take files at all is the write's to say.
    if stat.f_blocks == 0 {
        return None;
    }
    Some((stat.f_bavail as u64).saturating_mul(stat.f_frsize as u64))
}

#[cfg(not(unix))]
fn free_bytes_of(_: &Path) -> Option<u64> {
    None
}

/// Refuses, before the output folder is made, a run whose files would not fit the free space
/// of `dir`'s disk, naming what fits: fewer frames, or a larger `every`.
pub fn check_space(
    scene: &Scene,
    prep: &Prepared,
    dir: &Path,
    from: u32,
) -> Result<OutputEstimate, InputError> {
    let estimate = estimate(scene, prep, from);
    let Some(free) = free_bytes(dir) else {
        return Ok(estimate);
    };
    let need = estimate.bytes();
    if need <= free {
        return Ok(estimate);
    }
    let per_frame = estimate.bytes_per_frame.max(1);
    let room = free.saturating_sub(estimate.bytes_once);
    // Frame 0 and the last are written whatever the schedule.
    let frames_fit = (room / per_frame).saturating_sub(2);
    let every_fit = (need as f64 / free.max(1) as f64 * scene.output.every as f64).ceil();
    Err(scene.error(
        "solver",
        "frames",
        format!(
            "the run would write about {} ({} frames of about {} each, plus {}), more than \
             the {} free on the disk of {}",
            size(need),
            estimate.frames,
            size(estimate.bytes_per_frame),
            size(estimate.bytes_once),
            size(free),
            dir.display()
        ),
        format!(
            "write fewer frames (at most about {} with these outputs: --frames or \
             solver.frames), fewer of them ([output] every = {every_fit:.0} or more, or fewer \
             formats), or free space on that disk",
            frames_fit.saturating_mul(scene.output.every as u64) + from as u64
        ),
    ))
}

/// `bytes` for people: "512 B", "3.2 KiB", "78.4 GiB".
pub fn size(bytes: u64) -> String {
    let units = ["B", "KiB", "MiB", "GiB", "TiB", "PiB"];
    let mut v = bytes as f64;
    let mut u = 0;
    while v >= 1024.0 && u + 1 < units.len() {
        v /= 1024.0;
        u += 1;
    }
    match u {
        0 => format!("{bytes} B"),
        _ => format!("{v:.1} {}", units[u]),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn obj_estimate_bounds_a_written_frame() {
        // A 32 × 32 grid frame as the exporter writes it, against the estimate: the estimate
        // counts 13 bytes per number where most coordinates take fewer, so it is an upper
        // bound, and not a loose one (within 2×).
        use glam::Vec3;
        let mesh = crate::mesh::TriMesh::grid(
            1.0,
            1.0,
            32,
            32,
            Vec3::new(0.0, 1.5, 0.0),
            crate::mesh::GridPlane::Xy,
        );
        let group = super::super::obj::Group {
            name: "cloth".into(),
            triangles: (0..mesh.triangles.len() as u32).collect(),
        };
        let text = super::super::obj::cloth_obj(&mesh.positions, &mesh.triangles, None, &[group]);
        let estimate = obj_bytes(
            mesh.positions.len() as u64,
            mesh.triangles.len() as u64,
            false,
        );
        let actual = text.len() as u64;
        assert!(
            estimate >= actual && estimate < 2 * actual,
            "{estimate} vs {actual}"
        );
    }

    #[test]
    fn written_frames_are_frame_0_the_schedule_and_the_last() {
        // (from, frames, every) → the frames a run writes, counted by hand: 0–3; 0, 6, …,
        // 48, 52; 0, 6, …, 48; after a checkpoint at 8: 9, 10; at 8 with every 6: 12, 13.
        for ((from, frames, every), want) in [
            ((0, 3, 1), 4),
            ((0, 52, 6), 10),
            ((0, 48, 6), 9),
            ((8, 10, 1), 2),
            ((8, 13, 6), 2),
            ((8, 8, 6), 0),
        ] {
            assert_eq!(
                written_frames(from, frames, every),
                want,
                "{from}, {frames}, {every}"
            );
        }
    }

    #[test]
    fn the_free_space_of_a_folder_yet_to_be_made_is_its_disk_s() {
        let tmp = std::env::temp_dir();
        let here = free_bytes(&tmp).expect("statvfs answers on unix");
        let below = free_bytes(&tmp.join("not/yet/made")).expect("asks the nearest folder");
        // Other processes write meanwhile: the same disk, within 1 GiB.
        assert!(here.abs_diff(below) < 1 << 30, "{here} vs {below}");
    }
}
