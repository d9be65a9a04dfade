//! Errors, split by who must act: bad input (the user fixes a file, exit 2), an unstable
//! simulation (the user changes the scene, exit 3), warnings under `--strict` (exit 5), and
//! environment failures (exit 1).

use std::fmt;
use std::path::{Path, PathBuf};

/// Everything drapekit can fail with.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A scene, mesh or pattern file is wrong; the message says where and how to fix it.
    #[error("{0}")]
    Input(#[from] InputError),
    /// The simulation produced a non-finite value or left its stable range.
    #[error("simulation stopped: {0}")]
    Unstable(String),
    /// The GPU backend could not be created or failed while running.
    #[error("GPU backend: {0}")]
    Gpu(String),
    /// The user interrupted the run (Ctrl-C); a checkpoint holds everything up to `frame`.
    #[error("interrupted after frame {frame}; continue with: drapekit resume {}", dir.display())]
    Interrupted {
        /// The last completed frame.
        frame: u32,
        /// The output folder holding the checkpoint.
        dir: PathBuf,
    },
    /// Reading or writing a file failed.
    #[error("{}: {source}\n  fix: {}", path.display(), io_fix(path, source))]
    Io {
        /// The file that could not be read or written.
        path: PathBuf,
        /// The operating system's error.
        source: std::io::Error,
    },
    /// Writing an output file failed (a full disk, a lost permission); its temporary file was
    /// removed, so nothing half-written is left.
    #[error(
        "cannot write {file} in {}: {source}; nothing half-written was left there\n  fix: {}",
        dir.display(),
        io_fix(dir, source)
    )]
    Write {
        /// The file's name.
        file: String,
        /// The folder it was to be written in.
        dir: PathBuf,
        /// The operating system's error.
        source: std::io::Error,
    },
    /// Some items of a batch failed; each recorded its error in its own folder (exit 4).
    #[error("{0}")]
    ItemsFailed(String),
    /// `--strict`, and the run had warnings (exit 5); a finished run wrote its results first.
    #[error("{0}")]
    Warnings(String),
}

impl Error {
    /// Process exit code for this error: 2 for bad input, 3 for an unstable run, 4 for a batch
    /// with failed items, 5 for warnings under `--strict`, 130 for an interrupted run (the
    /// shell's code for SIGINT), 1 otherwise.
    pub fn exit_code(&self) -> i32 {
        match self {
            Error::Input(_) => 2,
            Error::Unstable(_) => 3,
            Error::Interrupted { .. } => 130,
            Error::ItemsFailed(_) => 4,
            Error::Warnings(_) => 5,
            Error::Gpu(_) | Error::Io { .. } | Error::Write { .. } => 1,
        }
    }

    /// Wraps an I/O error with the path it concerns.
    pub fn io(path: &Path, source: std::io::Error) -> Self {
        Error::Io {
            path: path.to_path_buf(),
            source,
        }
    }
}

/// What to do about an I/O error on `path`: the folder it is in, and the usual remedy for
/// this kind of failure (an unwritable output folder is the common case).
fn io_fix(path: &Path, source: &std::io::Error) -> String {
    use std::io::ErrorKind as K;
    let folder = if path.is_dir() {
        path
    } else {
        path.parent()
            .filter(|p| !p.as_os_str().is_empty())
            .unwrap_or(Path::new("."))
    };
    let folder = folder.display();
    match source.kind() {
        K::PermissionDenied | K::ReadOnlyFilesystem => format!(
            "you may not write (or read) in {folder}: choose a folder you can write to (for a \
             run's results, --out DIR), or change the folder's permissions"
        ),
        K::NotFound => format!("{folder} does not hold it: check the path"),
        K::NotADirectory | K::AlreadyExists => format!(
            "a file stands where a folder is needed on the way to {}: move it, or choose \
             another folder with --out DIR",
            path.display()
        ),
        K::StorageFull | K::QuotaExceeded | K::FileTooLarge => format!(
            "the disk holding {folder} is full: free space there, write fewer frames, or choose \
             a folder on another disk with --out DIR"
        ),
        _ => format!("check that {folder} exists and that you may read and write in it"),
    }
}

/// A problem with a user's file: which file, where in it, what is wrong, and what to do.
#[derive(Debug, Clone, PartialEq)]
pub struct InputError {
    /// The file at fault.
    pub file: PathBuf,
    /// 1-based line, where the format gives one.
    pub line: Option<usize>,
    /// The key, panel, edge or item at fault, e.g. `fabric.density_kg_m2` or `pins[1]`.
    pub location: String,
    /// What is wrong.
    pub problem: String,
    /// What to do about it.
    pub fix: String,
}

impl InputError {
    /// A new error about `location` in `file`.
    pub fn new(
        file: &Path,
        location: impl Into<String>,
        problem: impl Into<String>,
        fix: impl Into<String>,
    ) -> Self {
        InputError {
            file: file.to_path_buf(),
            line: None,
            location: location.into(),
            problem: problem.into(),
            fix: fix.into(),
        }
    }

    /// The same error with a line number.
    pub fn at_line(mut self, line: Option<usize>) -> Self {
        self.line = line;
        self
    }

    /// The text on one line, for a warning: "file:line: key: problem (fix: …)".
    pub fn one_line(&self) -> String {
        self.to_string().replace("\n  fix: ", " (fix: ") + ")"
    }
}

impl fmt::Display for InputError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.file.display())?;
        if let Some(line) = self.line {
            write!(f, ":{line}")?;
        }
        if !self.location.is_empty() {
            write!(f, ": {}", self.location)?;
        }
        write!(f, ": {}\n  fix: {}", self.problem, self.fix)
    }
}

impl std::error::Error for InputError {}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::{Error as IoError, ErrorKind};

    #[test]
    fn an_unwritable_output_folder_is_named_with_a_fix() {
        let e = Error::io(
            Path::new("/data/run/summary.json"),
            IoError::from(ErrorKind::PermissionDenied),
        );
        let text = e.to_string();
        assert!(
            text.starts_with("/data/run/summary.json: permission denied"),
            "{text}"
        );
        assert!(text.contains("fix: you may not write (or read) in /data/run: choose a folder you can write to (for a run's results, --out DIR)"), "{text}");
        let full = Error::io(
            Path::new("out/a.obj"),
            IoError::from(ErrorKind::StorageFull),
        );
        assert!(
            full.to_string().contains("the disk holding out is full"),
            "{full}"
        );
    }
}
