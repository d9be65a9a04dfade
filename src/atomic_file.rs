//! Atomic file writing: a reader never sees a half-written result, and a failed write (a full
//! disk) leaves nothing behind.

use crate::error::Error;
use std::io::Write;
use std::path::Path;
use std::sync::atomic::{AtomicU64, Ordering};

/// Writes `bytes` to `path` through a temporary file in the same folder and a rename, so that a
/// reader never sees a half-written file. The temporary name carries the process id and a
/// counter: threads of one process (batch items baking the same SDF cache file) must not share
/// it. On any failure the temporary file is removed and the error names `path`'s file and
/// folder. Only files are replaced: a rename would put a file in place of a folder's, a
/// device's or a pipe's name (as root, of /dev/null), so those are refused.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), Error> {
    static NEXT: AtomicU64 = AtomicU64::new(0);
    let dir = path.parent().unwrap_or(Path::new("."));
    let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("out");
    if std::fs::metadata(path).is_ok_and(|m| !m.is_file()) {
        return Err(Error::Write {
            file: name.to_string(),
            dir: dir.to_path_buf(),
            source: std::io::Error::other(
                "it exists and is not a file (a folder, device or pipe), which drapekit does not \
                 replace",
            ),
        });
    }
    let n = NEXT.fetch_add(1, Ordering::Relaxed);
    // File names end at 255 bytes: the temporary name keeps the start of a long one, so that
    // a name near the limit can still be written.
    let mut end = name.len().min(TEMP_NAME_BYTES);
    while !name.is_char_boundary(end) {
        end -= 1;
    }
    let short = &name[..end];
    let tmp = dir.join(format!(".{short}.{}.{n}{TEMP_SUFFIX}", std::process::id()));
    let written = write_file(&tmp, bytes).and_then(|()| std::fs::rename(&tmp, path));
    written.map_err(|source| {
        let _ = std::fs::remove_file(&tmp);
        Error::Write {
            file: name.to_string(),
            dir: dir.to_path_buf(),
            source,
        }
    })
}

/// The most bytes of the file's name a temporary name keeps: with the dot, process id, counter
/// and suffix (at most 1 + 1 + 10 + 1 + 20 + 4 bytes) it stays within 255.
const TEMP_NAME_BYTES: usize = 200;

/// How `write_atomic`'s temporary files end: `.NAME.PID.N.tmp`.
const TEMP_SUFFIX: &str = ".tmp";

/// Whether `name` is one of `write_atomic`'s temporary files.
fn is_temporary(name: &str) -> bool {
    let Some(rest) = name
        .strip_prefix('.')
        .and_then(|r| r.strip_suffix(TEMP_SUFFIX))
    else {
        return false;
    };
    let mut parts = rest.rsplitn(3, '.');
    let numeric =
        |p: Option<&str>| p.is_some_and(|p| !p.is_empty() && p.bytes().all(|b| b.is_ascii_digit()));
    numeric(parts.next()) && numeric(parts.next()) && parts.next().is_some_and(|n| !n.is_empty())
}

/// Removes the temporary files a killed run left in `dir` (a run writes its folder alone, so
/// none of them is in flight); returns their names.
pub fn remove_stale_temporaries(dir: &Path) -> Vec<String> {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return Vec::new();
    };
    let mut removed = Vec::new();
    for entry in entries.flatten() {
        let name = entry.file_name().to_string_lossy().into_owned();
        let temporary = is_temporary(&name) && entry.file_type().is_ok_and(|t| t.is_file());
        if temporary && std::fs::remove_file(entry.path()).is_ok() {
            removed.push(name);
        }
    }
    removed.sort();
    removed
}

/// Test seam: once this many bytes (`u64::MAX`: no limit) have gone through `write_atomic` in
/// this process, every write fails as a full disk would, after writing what fit.
static WRITE_BUDGET: AtomicU64 = AtomicU64::new(u64::MAX);

/// Makes every `write_atomic` after `bytes` more bytes fail with "no space left on device", as
/// a full disk would (`None`: no limit). For tests of what a failed write leaves behind.
#[doc(hidden)]
pub fn fail_writes_after(bytes: Option<u64>) {
    WRITE_BUDGET.store(bytes.unwrap_or(u64::MAX), Ordering::SeqCst);
}

fn write_file(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let budget = WRITE_BUDGET.load(Ordering::SeqCst);
    let fits = (budget as usize).min(bytes.len());
    if budget != u64::MAX {
        WRITE_BUDGET.store(budget - fits as u64, Ordering::SeqCst);
    }
    let mut file = std::fs::File::create(path)?;
    file.write_all(&bytes[..fits])?;
    if fits < bytes.len() {
        return Err(std::io::Error::from(std::io::ErrorKind::StorageFull));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn temporary_names_are_recognised_exactly() {
        assert!(is_temporary(".frame_0033.obj.4242.33.tmp"));
        assert!(is_temporary(".summary.json.1.0.tmp"));
        for other in [
            "frame_0033.obj",
            ".frame.obj.tmp",
            ".x.12.tmp",
            "..1.2.tmp",
            ".a.b.c.tmp",
        ] {
            assert!(!is_temporary(other), "{other}");
        }
    }

    #[test]
    fn a_name_at_the_file_system_s_limit_is_written() {
        // 255 bytes, with a two-byte character across the cut: the temporary name keeps the
        // start of it, on a character boundary.
        let dir = std::env::temp_dir().join(format!("drapekit-long-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let name = format!("{}é{}.png", "a".repeat(199), "b".repeat(50));
        assert_eq!(name.len(), 255);
        write_atomic(&dir.join(&name), b"png").unwrap();
        assert_eq!(std::fs::read(dir.join(&name)).unwrap(), b"png");
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[cfg(unix)]
    #[test]
    fn a_name_that_is_not_a_file_is_not_replaced() {
        let dir = std::env::temp_dir().join(format!("drapekit-atomic-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        // A socket stands for a device or a pipe: renaming a file onto it would succeed.
        let socket = dir.join("out.png");
        let _listener = std::os::unix::net::UnixListener::bind(&socket).unwrap();
        let e = write_atomic(&socket, b"png").unwrap_err().to_string();
        assert!(e.contains("is not a file"), "{e}");
        assert!(!std::fs::metadata(&socket).unwrap().is_file());
        let file = dir.join("out.txt");
        write_atomic(&file, b"a").unwrap();
        write_atomic(&file, b"b").unwrap();
        assert_eq!(std::fs::read(&file).unwrap(), b"b");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
