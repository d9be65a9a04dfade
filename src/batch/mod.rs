//! `drapekit batch`: many scenes from a JSON Lines manifest, sharded over the processes of a
//! cluster job (Slurm array, Kubernetes indexed Job), each item resumable and isolated from the
//! others' failures. docs/src/batches.md is the user's guide.
//!
//! - [`manifest`]: parse and validate the whole manifest, every bad line reported at once;
//! - [`overrides`]: an item's overrides merged into its scene's tables;
//! - [`shard`]: which items this process runs (a pure function of the item's position);
//! - [`item`]: one item, built in a hidden folder and renamed into place with its `done` marker;
//! - [`report`]: `batch.csv` and `batch.md` from the item folders.

pub mod item;
pub mod manifest;
pub mod origin;
pub mod overrides;
pub mod report;
pub mod shard;
mod unique_keys;

pub use item::{ItemOptions, Outcome};
pub use manifest::{Item, Manifest};
pub use shard::Shard;

use crate::error::{Error, InputError};
use crate::run::BackendChoice;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

/// `drapekit batch`'s options.
#[derive(Clone, Debug)]
pub struct BatchOptions {
    /// The manifest (JSON Lines).
    pub manifest: PathBuf,
    /// The batch's output folder: one folder per item.
    pub out: PathBuf,
    /// `--shard i/n`.
    pub shard: Option<Shard>,
    /// `--shards n`: the count for `JOB_COMPLETION_INDEX`.
    pub shards: Option<u32>,
    /// Items at once; `None`: one per core on the CPU backend, one at a time otherwise.
    pub jobs: Option<usize>,
    /// What every item runs with.
    pub item: ItemOptions,
}

/// What one batch process did.
#[derive(Clone, Debug)]
pub struct BatchResult {
    /// The shard it ran.
    pub shard: Shard,
    /// Items at once.
    pub jobs: usize,
    /// Each item of the shard, in manifest order, with how it ended.
    pub outcomes: Vec<(String, Outcome)>,
}

impl BatchResult {
    /// Ids of the items that failed in this run or had failed before (marker "failed").
    pub fn failed(&self) -> Vec<&str> {
        (self.outcomes.iter())
            .filter(|(_, o)| matches!(o, Outcome::Failed(_) | Outcome::Skipped(Some(_))))
            .map(|(id, _)| id.as_str())
            .collect()
    }
}

/// The number of items run at once. Threads, not child processes: an item is one CPU
/// solver with no shared mutable state (its particle loops share rayon's global pool), a panic is caught per item
/// ([`item::run`]), and threads need no re-executing and re-validating per item. An abort or
/// an out-of-memory kill does take the whole process down; the rerun then resumes it.
/// On a GPU, items run one after another: one queue, and one item already fills it.
pub fn jobs(requested: Option<usize>, backend: BackendChoice) -> Result<usize, InputError> {
    let cli = Path::new("drapekit batch");
    match (requested, backend) {
        (Some(0), _) => Err(InputError::new(
            cli,
            "--jobs",
            "0 items at once",
            "give --jobs 1 or more",
        )),
        (Some(n), BackendChoice::Cpu) => Ok(n),
        (Some(1), _) => Ok(1),
        (Some(n), b) => Err(InputError::new(
            cli,
            "--jobs",
            format!(
                "--jobs {n} with --backend {}: GPU items run one after another",
                format!("{b:?}").to_lowercase()
            ),
            "use --backend cpu to run items side by side, or leave --jobs out",
        )),
        (None, BackendChoice::Cpu) => {
            Ok(std::thread::available_parallelism().map_or(1, |n| n.get()))
        }
        (None, _) => Ok(1),
    }
}

/// Validates the whole manifest, picks the shard (`env` reads the scheduler's variables) and
/// runs its items into `opts.out`. Bad input anywhere in the manifest fails before any item
/// runs; a failing item is recorded in its folder and the batch goes on.
pub fn run(
    opts: &BatchOptions,
    env: &dyn Fn(&str) -> Option<String>,
    log: &(dyn Fn(&str) + Sync),
) -> Result<BatchResult, Error> {
    let cli = Path::new("drapekit batch");
    // A panicking item is this item's failure (`item::attempt`); its report names the item.
    crate::notice::label_panics();
    let (shard, source) = shard::resolve(opts.shard, opts.shards, env)
        .map_err(|e| InputError::new(cli, "--shard", e, "see `drapekit batch --help`"))?;
    let jobs_wanted = jobs(opts.jobs, opts.item.backend)?;
    let manifest = Manifest::load(&opts.manifest)?;
    let mine: Vec<&Item> = (manifest.items.iter())
        .filter(|it| shard.owns(it.index))
        .collect();
    // This shard's items only: each of N shard jobs would repeat the others'.
    for item in &mine {
        for w in &item.warnings {
            crate::notice::warn(&format!(
                "{} line {}, item {}: {w}",
                manifest.path.display(),
                item.line,
                item.id
            ));
        }
    }
    std::fs::create_dir_all(&opts.out).map_err(|e| Error::io(&opts.out, e))?;
    let jobs = jobs_wanted.min(mine.len()).max(1);
    log(&format!(
        "shard {shard} ({source}): {} of {} items, {jobs} at a time, into {}",
        mine.len(),
        manifest.items.len(),
        opts.out.display()
    ));
    let next = AtomicUsize::new(0);
    let results: Mutex<Vec<Option<Outcome>>> = Mutex::new(vec![None; mine.len()]);
    std::thread::scope(|s| {
        for _ in 0..jobs {
            s.spawn(|| loop {
                let k = next.fetch_add(1, Ordering::Relaxed);
                let Some(item) = mine.get(k) else { break };
                let outcome = item::run(item, &opts.out, &opts.item).unwrap_or_else(|e| {
                    // The item's folder could not be written, or is not the batch's to
                    // replace: still only this item's failure.
                    Outcome::Failed(item::Failure::from_error(&e))
                });
                log(&format!(
                    "[{}/{}] {}: {}",
                    k + 1,
                    mine.len(),
                    item.id,
                    describe(&outcome)
                ));
                results.lock().expect("no panic holds the lock")[k] = Some(outcome);
            });
        }
    });
    let results = results.into_inner().expect("no panic holds the lock");
    Ok(BatchResult {
        shard,
        jobs,
        outcomes: (mine.iter().zip(results))
            .map(|(it, o)| (it.id.clone(), o.expect("every item ran")))
            .collect(),
    })
}

fn describe(outcome: &Outcome) -> String {
    match outcome {
        Outcome::Skipped(None) => "done before, skipped".into(),
        Outcome::Skipped(Some(kind)) => format!("failed before ({kind}), skipped"),
        Outcome::Done { seconds } => format!("ok in {seconds:.2} s"),
        Outcome::Failed(f) => format!(
            "FAILED ({}): {}",
            f.kind,
            f.message.lines().next().unwrap_or("")
        ),
    }
}

/// `drapekit batch` from the command line: runs, prints a line per item and a total, and
/// returns [`Error::ItemsFailed`] (exit code 4) when any item of the shard failed.
pub fn run_cli(opts: &BatchOptions) -> Result<(), Error> {
    let env = |name: &str| std::env::var(name).ok();
    let result = run(opts, &env, &|line| println!("{line}"))?;
    let ran = (result.outcomes.iter())
        .filter(|(_, o)| !matches!(o, Outcome::Skipped(_)))
        .count();
    let failed = result.failed();
    println!(
        "shard {}: {} items, {ran} run, {} skipped, {} failed",
        result.shard,
        result.outcomes.len(),
        result.outcomes.len() - ran,
        failed.len()
    );
    if failed.is_empty() {
        Ok(())
    } else {
        Err(Error::ItemsFailed(format!(
            "{} of {} items failed: {} (each folder's error.json says why; `drapekit batch \
             report {}` tabulates them)",
            failed.len(),
            result.outcomes.len(),
            failed.join(", "),
            opts.out.display()
        )))
    }
}
