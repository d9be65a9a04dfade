//! Checkpoints: everything a run needs to continue where it stopped, in one file written
//! atomically, `checkpoint.bin` in the output folder. The layout: a magic line, the length of a
//! JSON header (u64, little endian), the header, then f32 little-endian arrays: positions and
//! velocities (4 per particle each), and the frames the point cache and glTF export keep
//! (3 per particle per kept frame), and a SHA-256 of all that, so that a damaged file is refused
//! rather than resumed from. The solver's other arrays are rebuilt every substep, so the state
//! and the run's statistics are all there is to save.

use crate::atomic_file::write_atomic;
use crate::error::{Error, InputError};
use crate::sim::RunStats;
use crate::solver::ParticleState;
use glam::{Vec3, Vec4};
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};
use std::path::{Path, PathBuf};

/// The checkpoint's file name inside the output folder.
pub const CHECKPOINT_FILE: &str = "checkpoint.bin";
const MAGIC: &[u8] = b"DRAPEKIT CHECKPOINT 2\n";
/// The first layout, without the checksum; still read.
const MAGIC_V1: &[u8] = b"DRAPEKIT CHECKPOINT 1\n";
/// Bytes of the SHA-256 that ends the file, over everything before it.
const CHECKSUM_LEN: usize = 32;

/// The JSON header: the run's inputs (to refuse a resume after they changed) and its progress.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CheckpointHeader {
    /// drapekit's version that wrote it.
    pub drapekit_version: String,
    /// The scene file, as given to `drapekit run`.
    pub scene_path: PathBuf,
    /// The scene file's text then: a resume refuses a changed scene.
    pub scene_text: String,
    /// `--backend` as given ("auto", "cpu" or "gpu").
    pub backend: String,
    /// `--adapter` as given.
    pub adapter: String,
    /// `--frames`, when given.
    pub frames: Option<u32>,
    /// `--checkpoint-every`, when given.
    pub checkpoint_every: Option<u32>,
    /// The last completed output frame.
    pub frame: u32,
    /// Particles in the state.
    pub particles: usize,
    /// The statistics of frames 0..=frame.
    pub stats: RunStats,
    /// Files written so far.
    pub outputs: Vec<String>,
    /// Frame numbers of the kept export frames.
    pub kept_frames: Vec<u32>,
    /// Frames the exporter had written.
    pub exported_frames: usize,
    /// Each file the scene reads besides itself (pattern, cloth mesh, bodies, texture) and
    /// the SHA-256 of its contents then: a resume refuses a changed one (empty in checkpoints
    /// written before it was kept).
    #[serde(default)]
    pub input_files: Vec<(String, String)>,
}

/// The files `scene` reads besides itself, each with the SHA-256 of its contents ("missing"
/// for one that cannot be read): its pattern or cloth mesh, each body's OBJ or glTF file (not
/// a .gltf's separate buffers) and `.pc2` vertex cache (not an OBJ sequence's frames), and
/// the preview's texture.
pub fn input_files(scene: &crate::scene::Scene) -> Vec<(String, String)> {
    use crate::scene::{BodySource, DeformMotion};
    let inputs = crate::run_folder::inputs(scene);
    let body_files = scene.bodies.iter().flat_map(|b| {
        let skin = match &b.source {
            BodySource::Skinned { path: Some(p), .. } => Some(p.clone()),
            _ => None,
        };
        let cache = match b.deform.as_ref().map(|d| &d.motion) {
            Some(DeformMotion::Cache { path, .. }) if !path.to_string_lossy().contains('#') => {
                Some(path.clone())
            }
            _ => None,
        };
        skin.into_iter()
            .chain(cache)
            .map(|p| crate::run_folder::absolute(&p).display().to_string())
    });
    let paths = (inputs.pattern.into_iter())
        .chain(inputs.cloth_mesh)
        .chain(inputs.bodies.into_iter().flatten())
        .chain(body_files.collect::<Vec<_>>())
        .chain(inputs.texture);
    paths
        .map(|path| {
            let sha = std::fs::read(&path).map_or_else(
                |_| "missing".to_string(),
                |bytes| crate::run_folder::sha256_hex(&bytes),
            );
            (path, sha)
        })
        .collect()
}

impl CheckpointHeader {
    /// The first of the files the checkpoint's run read that has changed since, if any.
    pub fn changed_input(&self, now: &[(String, String)]) -> Option<&str> {
        (self.input_files.iter())
            .find(|(path, sha)| now.iter().all(|(p, s)| p != path || s != sha))
            .map(|(path, _)| path.as_str())
    }
}

/// A checkpoint: its header and arrays.
#[derive(Clone, Debug, PartialEq)]
pub struct Checkpoint {
    /// Inputs and progress.
    pub header: CheckpointHeader,
    /// The state at the end of `header.frame`.
    pub state: ParticleState,
    /// The export frames kept so far, one per `header.kept_frames`.
    pub kept: Vec<Vec<Vec3>>,
}

impl Checkpoint {
    /// Writes `dir/checkpoint.bin` atomically.
    pub fn write(&self, dir: &Path) -> Result<(), Error> {
        let header = serde_json::to_vec(&self.header).expect("checkpoint header serialises");
        let n = self.state.positions.len();
        let mut bytes = Vec::with_capacity(MAGIC.len() + 8 + header.len() + n * 32);
        bytes.extend_from_slice(MAGIC);
        bytes.extend_from_slice(&(header.len() as u64).to_le_bytes());
        bytes.extend_from_slice(&header);
        let floats = (self.state.positions.iter())
            .chain(&self.state.velocities)
            .flat_map(|v| v.to_array())
            .chain(self.kept.iter().flatten().flat_map(|v| v.to_array()));
        for f in floats {
            bytes.extend_from_slice(&f.to_le_bytes());
        }
        let checksum = Sha256::digest(&bytes);
        bytes.extend_from_slice(&checksum);
        write_atomic(&dir.join(CHECKPOINT_FILE), &bytes)
    }

    /// Reads `dir/checkpoint.bin`; a missing, truncated or foreign file is bad input.
    pub fn read(dir: &Path) -> Result<Checkpoint, Error> {
        let path = dir.join(CHECKPOINT_FILE);
        let bytes = std::fs::read(&path).map_err(|e| {
            Error::Input(InputError::new(
                &path,
                "checkpoint",
                format!("cannot read it ({e})"),
                "give the output folder of a run started with --checkpoint-every N (or one that \
                 was interrupted with Ctrl-C)",
            ))
        })?;
        let bad = |problem: &str| {
            Error::Input(InputError::new(
                &path,
                "checkpoint",
                problem.to_string(),
                "the file is damaged or not a drapekit checkpoint: rerun the scene",
            ))
        };
        let rest = match (bytes.strip_prefix(MAGIC), bytes.strip_prefix(MAGIC_V1)) {
            (Some(rest), _) => {
                let body = (bytes.len().checked_sub(CHECKSUM_LEN))
                    .filter(|&end| end >= MAGIC.len())
                    .ok_or_else(|| bad("it ends inside its checksum"))?;
                if Sha256::digest(&bytes[..body]).as_slice() != &bytes[body..] {
                    return Err(bad("its checksum does not match its contents"));
                }
                &rest[..rest.len() - CHECKSUM_LEN]
            }
            (None, Some(rest)) => rest,
            (None, None) => return Err(bad("it does not start with the checkpoint magic line")),
        };
        let len = rest
            .get(..8)
            .map(|b| u64::from_le_bytes(b.try_into().expect("8 bytes")) as usize)
            .ok_or_else(|| bad("it ends inside its header length"))?;
        let header_bytes = (len.checked_add(8))
            .and_then(|end| rest.get(8..end))
            .ok_or_else(|| bad("it ends inside its header"))?;
        let header: CheckpointHeader = serde_json::from_slice(header_bytes)
            .map_err(|e| bad(&format!("its header is not valid ({e})")))?;
        let data = &rest[8 + len..];
        let n = header.particles;
        // Each particle's position and velocity (8 floats) and 3 per kept frame, 4 bytes each;
        // a count too large to compute is a damaged header, not a size.
        let expected = (header.kept_frames.len().checked_mul(3))
            .and_then(|k| k.checked_add(8))
            .and_then(|floats| floats.checked_mul(n))
            .and_then(|floats| floats.checked_mul(4));
        if expected != Some(data.len()) {
            return Err(bad(&format!(
                "it holds {} bytes of arrays where its header says {}",
                data.len(),
                expected.map_or("more than this machine can count".into(), |e| e.to_string())
            )));
        }
        let floats: Vec<f32> = data
            .chunks_exact(4)
            .map(|c| f32::from_le_bytes(c.try_into().expect("4 bytes")))
            .collect();
        if let Some(k) = floats.iter().position(|f| !f.is_finite()) {
            return Err(bad(&format!(
                "value {k} of its arrays is not a finite number (a run never checkpoints one)"
            )));
        }
        let vec4s = |from: usize| -> Vec<Vec4> {
            floats[from..from + 4 * n]
                .chunks_exact(4)
                .map(Vec4::from_slice)
                .collect()
        };
        let kept = floats[8 * n..]
            .chunks_exact(3 * n.max(1))
            .take(header.kept_frames.len())
            .map(|f| f.chunks_exact(3).map(Vec3::from_slice).collect())
            .collect();
        Ok(Checkpoint {
            state: ParticleState {
                positions: vec4s(0),
                velocities: vec4s(4 * n),
            },
            kept,
            header,
        })
    }
}
