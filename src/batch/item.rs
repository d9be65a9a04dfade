//! One batch item, run so that a kill at any moment never leaves a folder that looks done: the
//! item is built in a hidden temporary folder beside its final one, its `done` marker is written
//! last, and the folder is renamed into place (one atomic rename on a POSIX file system).

use super::manifest::{hex, Item};
use crate::atomic_file::write_atomic;
use crate::error::Error;
use crate::gpu::AdapterChoice;
use crate::run::{run_scene, BackendChoice, RunOptions};
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// The marker file, written last into an item's folder.
pub const DONE: &str = "done";
/// What the item was (manifest line, scene, overrides, files read, time taken).
pub const ITEM_JSON: &str = "item.json";
/// A failed item's error.
pub const ERROR_JSON: &str = "error.json";
/// Hidden folders: an item being built, and a replaced result about to be deleted.
pub const PARTIAL: &str = ".partial~";
const REPLACED: &str = ".replaced~";

/// What every item of a batch runs with.
#[derive(Clone, Debug)]
pub struct ItemOptions {
    /// Backend.
    pub backend: BackendChoice,
    /// Adapter, for the GPU backend.
    pub adapter: AdapterChoice,
    /// Overrides every scene's `[solver] frames`.
    pub frames: Option<u32>,
    /// Extra attempts after a transient failure (GPU error, device lost, I/O).
    pub retries: u32,
}

impl ItemOptions {
    /// The options that change an item's result, for its marker hash.
    fn key(&self) -> String {
        format!(
            "backend={:?} adapter={:?} frames={:?}",
            self.backend, self.adapter, self.frames
        )
    }
}

/// The `done` marker: the item's inputs hash and how it ended.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Marker {
    /// SHA-256 over drapekit's version, the batch options and the item's inputs.
    pub inputs_sha256: String,
    /// drapekit's version that wrote it.
    pub drapekit: String,
    /// "ok", or "failed" for a failure that a rerun would repeat (bad input, unstable).
    pub status: String,
}

/// A failure, as `error.json` records it.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Failure {
    /// `bad_input`, `unstable`, `gpu`, `io` or `panic`.
    pub kind: String,
    /// The exit code `drapekit run` would give it.
    pub exit_code: i32,
    /// The message.
    pub message: String,
}

impl Failure {
    /// The failure `e` is, by its kind.
    pub fn from_error(e: &Error) -> Failure {
        let kind = match e {
            Error::Input(_) => "bad_input",
            Error::Unstable(_) => "unstable",
            Error::Gpu(_) => "gpu",
            Error::Io { .. } | Error::Write { .. } => "io",
            _ => "other",
        };
        Failure {
            kind: kind.into(),
            exit_code: e.exit_code(),
            message: e.to_string(),
        }
    }

    /// A failure that a rerun with the same inputs would repeat; the others are retried.
    pub fn is_deterministic(&self) -> bool {
        matches!(self.kind.as_str(), "bad_input" | "unstable")
    }
}

/// How an item ended in this run.
#[derive(Clone, Debug, PartialEq)]
pub enum Outcome {
    /// Its marker matched: not run again. `Some` when it had failed.
    Skipped(Option<String>),
    /// Ran and succeeded.
    Done {
        /// Wall time of the item, all attempts, in s.
        seconds: f64,
    },
    /// Ran and failed.
    Failed(Failure),
}

/// The marker hash of `item` under `opts`.
pub fn marker_hash(item: &Item, opts: &ItemOptions) -> String {
    let mut h = Sha256::new();
    for part in [
        concat!("drapekit ", env!("CARGO_PKG_VERSION")),
        &opts.key(),
        &item.inputs_sha256,
    ] {
        h.update((part.len() as u64).to_le_bytes());
        h.update(part.as_bytes());
    }
    hex(&h.finalize())
}

/// Reads an item folder's marker, if it has a readable one.
pub fn read_marker(dir: &Path) -> Option<Marker> {
    serde_json::from_slice(&std::fs::read(dir.join(DONE)).ok()?).ok()
}

/// Runs `item` into `out/<id>/` unless its marker there already matches.
pub fn run(item: &Item, out: &Path, opts: &ItemOptions) -> Result<Outcome, Error> {
    let hash = marker_hash(item, opts);
    let dest = out.join(&item.id);
    if let Some(m) = read_marker(&dest).filter(|m| m.inputs_sha256 == hash) {
        let failed = (m.status != "ok").then(|| read_failure(&dest));
        return Ok(Outcome::Skipped(failed));
    }
    refuse_foreign(&dest)?;
    remove_leftovers(out, &item.id);
    let tmp = out.join(hidden_name(PARTIAL, &item.id));
    let started = std::time::Instant::now();
    let mut attempts = 0;
    let failure = loop {
        attempts += 1;
        let _ = std::fs::remove_dir_all(&tmp);
        std::fs::create_dir_all(&tmp).map_err(|e| Error::io(&tmp, e))?;
        match attempt(item, &tmp, opts) {
            Ok(()) => break None,
            Err(f) if !f.is_deterministic() && attempts <= opts.retries => {
                eprintln!(
                    "drapekit: item {}: attempt {attempts} failed ({}), retrying",
                    item.id, f.kind
                );
            }
            Err(f) => break Some(f),
        }
    };
    let seconds = started.elapsed().as_secs_f64();
    if let Some(f) = &failure {
        write_json(&tmp.join(ERROR_JSON), f)?;
    }
    write_json(
        &tmp.join(ITEM_JSON),
        &serde_json::json!({
            "id": item.id,
            "manifest_line": item.line,
            "scene": item.scene_arg,
            "scene_path": item.scene_path.display().to_string(),
            "overrides": item.overrides,
            "fabric": item.fabric,
            "particle_distance_m": item.particle_distance_m,
            "files": item.files.iter().map(|(role, path, sha)| serde_json::json!({
                "role": role, "path": path.display().to_string(), "sha256": sha,
            })).collect::<Vec<_>>(),
            "inputs_sha256": hash,
            "attempts": attempts,
            "item_seconds": seconds,
            "status": if failure.is_none() { "ok" } else { "failed" },
        }),
    )?;
    // A transient failure gets no marker, so the next run tries it again.
    if failure.as_ref().is_none_or(|f| f.is_deterministic()) {
        let marker = Marker {
            inputs_sha256: hash.clone(),
            drapekit: env!("CARGO_PKG_VERSION").into(),
            status: if failure.is_none() { "ok" } else { "failed" }.into(),
        };
        write_json(&tmp.join(DONE), &marker)?;
    }
    publish(&tmp, &dest, &hash)?;
    Ok(match failure {
        None => Outcome::Done { seconds },
        Some(f) => Outcome::Failed(f),
    })
}

/// Refuses to replace `dest` unless it is absent, an empty folder, or an item's folder (it
/// holds `item.json` or the `done` marker): a file or folder of the user's that happens to
/// bear the item's name is never moved or deleted.
fn refuse_foreign(dest: &Path) -> Result<(), Error> {
    let Ok(meta) = std::fs::symlink_metadata(dest) else {
        return Ok(());
    };
    let is_item = |dir: &Path| {
        dir.join(ITEM_JSON).is_file()
            || dir.join(DONE).is_file()
            || std::fs::read_dir(dir).is_ok_and(|mut e| e.next().is_none())
    };
    if meta.is_dir() && is_item(dest) {
        return Ok(());
    }
    let what = if meta.is_dir() {
        "a folder that is not a batch item's (it has no item.json)"
    } else if meta.is_symlink() {
        "a link, not a batch item's folder"
    } else {
        "a file, not a batch item's folder"
    };
    Err(Error::Input(crate::error::InputError::new(
        dest,
        "--out",
        format!("is {what}: the item's results would replace it"),
        "move or rename it, or give batch another output folder with --out DIR",
    )))
}

/// One attempt: the scene into `tmp`. A panic is this item's failure, not the batch's.
fn attempt(item: &Item, tmp: &Path, opts: &ItemOptions) -> Result<(), Failure> {
    let run_opts = RunOptions {
        backend: opts.backend,
        adapter: opts.adapter.clone(),
        // The item's folder replaces the scene's `[output] dir`: nothing lands outside it.
        out_dir: Some(tmp.to_path_buf()),
        frames: opts.frames,
        progress: false,
        // An item is short; a killed batch redoes the item in flight (see "Batches").
        checkpoint_every: None,
        // A fresh folder per attempt: nothing to replace.
        overwrite: false,
    };
    let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        crate::notice::as_item(&item.id, || run_scene(&item.scene, &run_opts))
    }));
    match result {
        Ok(Ok(_)) => Ok(()),
        Ok(Err(e)) => Err(Failure::from_error(&super::origin::locate(item, e))),
        Err(panic) => Err(Failure {
            kind: "panic".into(),
            exit_code: 101,
            message: panic
                .downcast_ref::<String>()
                .cloned()
                .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()))
                .unwrap_or_else(|| "panicked".into()),
        }),
    }
}

/// Moves the finished `tmp` to `dest`. A rename cannot replace a non-empty folder, so an old
/// result is first renamed aside (between the two renames `dest` is absent, which reads as
/// "not done", never as done with the old inputs), then deleted.
fn publish(tmp: &Path, dest: &Path, hash: &str) -> Result<(), Error> {
    let out = dest.parent().unwrap_or(Path::new("."));
    let id = dest.file_name().and_then(|n| n.to_str()).unwrap_or("item");
    let aside = out.join(hidden_name(REPLACED, id));
    let moved_aside = match std::fs::rename(dest, &aside) {
        Ok(()) => true,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => false,
        Err(e) => return Err(Error::io(dest, e)),
    };
    if let Err(e) = std::fs::rename(tmp, dest) {
        // Another process (a resubmitted task) published the same inputs first: keep theirs.
        if read_marker(dest).is_some_and(|m| m.inputs_sha256 == hash) {
            let _ = std::fs::remove_dir_all(tmp);
        } else {
            return Err(Error::io(dest, e));
        }
    }
    if moved_aside {
        let _ = std::fs::remove_dir_all(&aside);
    }
    Ok(())
}

/// Deletes hidden folders this item left when a run was killed. Only this item's: another
/// shard may be building its own items in the same folder right now.
fn remove_leftovers(out: &Path, id: &str) {
    let Ok(entries) = std::fs::read_dir(out) else {
        return;
    };
    for entry in entries.flatten() {
        let name = entry.file_name();
        let Some(name) = name.to_str() else { continue };
        for prefix in [PARTIAL, REPLACED] {
            if name
                .strip_prefix(prefix)
                .and_then(|rest| rest.split('~').next())
                == Some(id)
            {
                let _ = std::fs::remove_dir_all(entry.path());
            }
        }
    }
}

/// `<prefix><id>~<pid>~<n>`: '~' never appears in an id, so the id can be read back exactly;
/// the pid and counter keep two processes (or threads) from sharing a folder.
fn hidden_name(prefix: &str, id: &str) -> PathBuf {
    static NEXT: AtomicU64 = AtomicU64::new(0);
    let n = NEXT.fetch_add(1, Ordering::Relaxed);
    PathBuf::from(format!("{prefix}{id}~{}~{n}", std::process::id()))
}

fn read_failure(dir: &Path) -> String {
    std::fs::read(dir.join(ERROR_JSON))
        .ok()
        .and_then(|b| serde_json::from_slice::<Failure>(&b).ok())
        .map_or_else(|| "failed".into(), |f| f.kind)
}

fn write_json(path: &Path, value: &impl Serialize) -> Result<(), Error> {
    let json = serde_json::to_string_pretty(value).expect("plain data serialises");
    write_atomic(path, json.as_bytes())
}
