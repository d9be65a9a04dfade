//! A run folder that stands on its own: a copy of the scene beside the results, the absolute
//! paths of every file the run read (so that `preview`, `resume` and the exports work from any
//! directory), and never the frames of another run mixed with its own.

use crate::atomic_file::write_atomic;
use crate::error::{Error, InputError};
use crate::scene::{BodySource, ClothSource, Scene};
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};
use std::path::{Path, PathBuf};

/// The scene's text as the run read it, in the run folder.
pub const SCENE_COPY: &str = "scene.toml";

/// Each simulated frame's settle figures (`RunStats::frames_csv`).
pub const FRAMES_CSV: &str = "frames.csv";

/// The files a run read, by absolute path.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Inputs {
    /// The scene file (its text is `scene.toml` in the run folder).
    pub scene: String,
    /// The sewing pattern, for a pattern cloth.
    pub pattern: Option<String>,
    /// The cloth mesh, for an OBJ cloth.
    pub cloth_mesh: Option<String>,
    /// Each body's mesh file (shapes and the built-in mannequin have none), in scene order.
    pub bodies: Vec<Option<String>>,
    /// The preview's fabric image, if any.
    pub texture: Option<String>,
}

/// `path` as an absolute path without `.` or `..` (the file's canonical path when it exists;
/// else made absolute against the current directory).
pub fn absolute(path: &Path) -> PathBuf {
    std::fs::canonicalize(path)
        .or_else(|_| std::path::absolute(path))
        .unwrap_or_else(|_| path.to_path_buf())
}

fn shown(path: &Path) -> String {
    absolute(path).display().to_string()
}

/// What `scene` reads, by absolute path.
pub fn inputs(scene: &Scene) -> Inputs {
    Inputs {
        scene: shown(&scene.path),
        pattern: match &scene.cloth {
            ClothSource::Pattern { path, .. } => Some(shown(path)),
            _ => None,
        },
        cloth_mesh: match &scene.cloth {
            ClothSource::Mesh { path, .. } => Some(shown(path)),
            _ => None,
        },
        bodies: (scene.bodies.iter())
            .map(|b| match &b.source {
                BodySource::Mesh { path, .. } => Some(shown(path)),
                _ => None,
            })
            .collect(),
        texture: scene.preview.texture.as_ref().map(|t| shown(&t.path)),
    }
}

/// Whether `name` is a file `drapekit run` writes into its folder.
pub fn is_run_file(name: &str) -> bool {
    let numbered = |prefix: &str, suffix: &str| {
        name.strip_prefix(prefix)
            .and_then(|r| r.strip_suffix(suffix))
            .is_some_and(|n| !n.is_empty() && n.bytes().all(|b| b.is_ascii_digit() || b == b'_'))
    };
    matches!(
        name,
        "summary.json"
            | FRAMES_CSV
            | SCENE_COPY
            | "checkpoint.bin"
            | "cloth.pc2"
            | "rest.obj"
            | "garment.glb"
            | "body.obj"
            | "preview.gif"
    ) || numbered("frame_", ".obj")
        || numbered("body", ".obj")
        || (name.starts_with("preview_") && name.ends_with(".png"))
}

/// Checks that `dir` may take a new run of `scene` and returns the files of an earlier run
/// there, which the new run replaces (`clear`): an earlier run of the same scene file is
/// replaced (the edit-and-rerun loop); the results of another scene, or frames whose run left
/// no summary, only with `overwrite`, else the run is refused with the fix. Files drapekit does
/// not write are never touched. Nothing is removed here: a run refused later for bad input
/// leaves the earlier results as they were.
pub fn check(dir: &Path, scene: &Scene, overwrite: bool) -> Result<Vec<PathBuf>, Error> {
    let entries = match std::fs::read_dir(dir) {
        Ok(entries) => entries,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Vec::new()),
        Err(e) => return Err(Error::io(dir, e)),
    };
    let mut old: Vec<PathBuf> = entries
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_str().is_some_and(is_run_file))
        .map(|e| e.path())
        .collect();
    old.sort();
    let previous = previous_scene(dir);
    let same = previous.as_deref() == Some(absolute(&scene.path).as_path());
    if old.is_empty() || same || overwrite {
        return Ok(old);
    }
    let frames = (old.iter())
        .filter(|p| {
            (p.file_name().and_then(|n| n.to_str())).is_some_and(|n| n.starts_with("frame_"))
        })
        .count();
    let whose = match &previous {
        Some(p) => format!("a run of {}", p.display()),
        None if dir.join("summary.json").is_file() => {
            "a run whose summary.json does not read".to_string()
        }
        None => "a run that left no summary.json".to_string(),
    };
    Err(Error::Input(InputError::new(
        dir,
        "--out",
        format!(
            "the folder holds the results of {whose} ({} files, {frames} frames); a new run \
             would mix its frames with them",
            old.len()
        ),
        "add --overwrite to replace them (only drapekit's own files are removed), or choose \
         another folder with --out DIR",
    )))
}

/// Creates `dir` and removes `old` (from `check`) from it, saying so on stderr.
pub fn clear(dir: &Path, old: &[PathBuf]) -> Result<(), Error> {
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    for path in old {
        match std::fs::remove_file(path) {
            Err(e) if e.kind() != std::io::ErrorKind::NotFound => return Err(Error::io(path, e)),
            _ => {}
        }
    }
    if !old.is_empty() {
        crate::notice::note(&format!(
            "replaced the {} files of the previous run in {}",
            old.len(),
            dir.display()
        ));
    }
    Ok(())
}

/// The scene file of the run whose `summary.json` is in `dir`, as an absolute path.
fn previous_scene(dir: &Path) -> Option<PathBuf> {
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("summary.json")).ok()?).ok()?;
    Some(absolute(Path::new(summary["scene"].as_str()?)))
}

/// Writes the scene's text as `scene.toml` in `dir` and returns the name.
pub fn write_scene_copy(dir: &Path, scene: &Scene) -> Result<String, Error> {
    write_atomic(&dir.join(SCENE_COPY), scene.source.as_bytes())?;
    Ok(SCENE_COPY.to_string())
}

/// The scene of the run in `run`, as it ran: `scene.toml` read as if it stood where the
/// original did (its relative paths resolve from there, through the summary's absolute path),
/// or, for a folder written before runs kept a copy, the scene file itself. `None` when the
/// summary names no scene.
pub fn run_scene(run: &Path, summary: &serde_json::Value) -> Result<Option<Scene>, Error> {
    let Some(original) = summary["scene"].as_str().map(PathBuf::from) else {
        return Ok(None);
    };
    let copy = run.join(SCENE_COPY);
    match std::fs::read_to_string(&copy) {
        Ok(text) => {
            warn_if_edited(&copy, &text, summary);
            Ok(Some(Scene::parse(&text, &original).map_err(|e| {
                // Errors name the copy the user can open, not the original path.
                Error::Input(InputError {
                    file: copy.clone(),
                    ..e
                })
            })?))
        }
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(Some(Scene::load(&original)?)),
        Err(e) => Err(Error::io(&copy, e)),
    }
}

/// SHA-256 of `bytes`, in hex: how a run folder and a checkpoint record what they read.
pub fn sha256_hex(bytes: &[u8]) -> String {
    format!("{:x}", Sha256::digest(bytes))
}

/// Warns when the run folder's scene copy is not the text the run read (the summary's
/// `scene_sha256`; summaries written before it had none): a preview then draws the edited
/// scene's bodies, seams and fabric around frames simulated with the old ones.
fn warn_if_edited(copy: &Path, text: &str, summary: &serde_json::Value) {
    if let Some(ran) = summary["scene_sha256"].as_str() {
        if ran != sha256_hex(text.as_bytes()) {
            crate::notice::warn(&format!(
                "{} was edited after the run: the preview draws the edited scene's bodies, \
                 seams and fabric around frames simulated with the scene as it was; rerun \
                 the scene to simulate the edit",
                copy.display()
            ));
        }
    }
}

/// The frames `frame_NNNN.obj` the run in `run` wrote, in order, from its summary's outputs
/// (other frames in the folder are not this run's); `None` when there is no summary.
pub fn summary_frames(run: &Path, summary: &serde_json::Value) -> Option<Vec<(u32, PathBuf)>> {
    let outputs = summary["outputs"].as_array()?;
    let mut frames: Vec<(u32, PathBuf)> = (outputs.iter())
        .filter_map(|o| {
            let name = o.as_str()?;
            let n = name
                .strip_prefix("frame_")?
                .strip_suffix(".obj")?
                .parse()
                .ok()?;
            Some((n, run.join(name)))
        })
        .collect();
    frames.sort();
    Some(frames)
}

#[cfg(test)]
mod tests {
    use super::is_run_file;

    #[test]
    fn run_files_by_name() {
        for name in [
            "frame_0000.obj",
            "body.obj",
            "body_0012.obj",
            "body1.obj",
            "body1_0012.obj",
            "preview_fabric.png",
            "preview_strain_0024.png",
            "preview.gif",
            "summary.json",
            "frames.csv",
            "scene.toml",
            "garment.glb",
        ] {
            assert!(is_run_file(name), "{name}");
        }
        for name in [
            "notes.txt",
            "frame_.obj",
            "bodysuit.obj",
            "my_scene.toml",
            "frame_12.png",
        ] {
            assert!(!is_run_file(name), "{name}");
        }
    }
}
