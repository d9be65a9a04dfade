//! A full disk in the middle of a run: the error names the file that could not be written and
//! its folder (the frame, not the summary after it), no temporary file is left behind, and a
//! resumed run removes temporaries a killed run left. Once through the writer's fault seam
//! (always), once on a real 12 MiB tmpfs (where this machine lets the test mount one).

mod common;

use drapekit::atomic_file::fail_writes_after;
use drapekit::run::{resume_run, run_scene, BackendChoice, RunOptions};
use drapekit::scene::Scene;
use drapekit::Error;
use std::path::{Path, PathBuf};
use std::process::Command;

fn temporaries(dir: &Path) -> Vec<String> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".tmp"))
        .collect()
}

fn fresh_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("drapekit-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

#[test]
fn a_write_that_fails_names_its_file_and_leaves_nothing() {
    let scene = Scene::load(&common::fixture("scenes/hanging_cloth.toml")).unwrap();
    let out = fresh_dir("seam");
    let opts = RunOptions {
        backend: BackendChoice::Cpu,
        adapter: drapekit::gpu::AdapterChoice::Auto,
        out_dir: Some(out.clone()),
        frames: Some(12),
        progress: false,
        checkpoint_every: Some(1),
        overwrite: false,
    };
    // A frame file of this cloth is about 100 KB and a checkpoint about 35 KB: the disk
    // fills in the middle of the fourth or fifth frame file.
    fail_writes_after(Some(500_000));
    let failed = run_scene(&scene, &opts);
    fail_writes_after(None);
    match &failed {
        Err(Error::Write { file, dir, .. }) => {
            assert!(
                file.starts_with("frame_") || file == "checkpoint.bin",
                "the first failed write is the cause, not the summary after it: {file}"
            );
            assert_eq!(dir, &out);
        }
        other => panic!("expected a write error, got {other:?}"),
    }
    let message = failed.unwrap_err().to_string();
    assert!(message.contains(&out.display().to_string()), "{message}");
    assert!(temporaries(&out).is_empty(), "{:?}", temporaries(&out));
    // A temporary left by a killed run (no error handling ran) is removed on resume.
    let stale = out.join(".frame_0011.obj.4242.7.tmp");
    std::fs::write(&stale, b"partial").unwrap();
    let summary = resume_run(&out, None, false).expect("resumes once there is space");
    assert_eq!(summary.frames, 12);
    assert!(temporaries(&out).is_empty(), "{:?}", temporaries(&out));
    assert!(out.join("frame_0012.obj").is_file() && out.join("summary.json").is_file());
    let _ = std::fs::remove_dir_all(&out);
}

/// Mounts a tmpfs of `mib` MiB at a new folder; `None` where mounting is not allowed.
fn mount_tmpfs(mib: u32) -> Option<PathBuf> {
    let dir = fresh_dir("tmpfs");
    std::fs::create_dir_all(&dir).ok()?;
    let mounted = Command::new("mount")
        .args(["-t", "tmpfs", "-o", &format!("size={mib}m"), "tmpfs"])
        .arg(&dir)
        .output()
        .ok()?;
    if mounted.status.success() {
        Some(dir)
    } else {
        eprintln!(
            "SKIPPED the tmpfs case (cannot mount: {}); the fault-seam case covers the writer",
            String::from_utf8_lossy(&mounted.stderr).trim()
        );
        let _ = std::fs::remove_dir(&dir);
        None
    }
}

#[test]
fn a_full_tmpfs_mid_run_leaves_nothing_and_resume_finishes() {
    let Some(disk) = mount_tmpfs(12) else {
        return;
    };
    // Unmounted whatever happens below.
    let outcome = std::panic::catch_unwind(|| fill_mid_run_then_resume(&disk));
    let _ = Command::new("umount").arg(&disk).status();
    let _ = std::fs::remove_dir(&disk);
    if let Err(p) = outcome {
        std::panic::resume_unwind(p);
    }
}

fn fill_mid_run_then_resume(disk: &Path) {
    let out = disk.join("out");
    let scene = common::fixture("scenes/hanging_cloth.toml");
    // 60 frames of about 100 KB fit 12 MiB, so the run starts; once its fourth frame is on
    // disk, a filler takes the rest of the space.
    let mut run = Command::new(env!("CARGO_BIN_EXE_drapekit"))
        .args([
            "run",
            scene.to_str().unwrap(),
            "--backend",
            "cpu",
            "--quiet",
        ])
        .args([
            "--frames",
            "60",
            "--checkpoint-every",
            "1",
            "--threads",
            "1",
        ])
        .arg("--out")
        .arg(&out)
        .stderr(std::process::Stdio::piped())
        .stdout(std::process::Stdio::null())
        .spawn()
        .unwrap();
    while !out.join("frame_0004.obj").exists() {
        assert!(run.try_wait().unwrap().is_none(), "the run ended early");
        std::thread::sleep(std::time::Duration::from_millis(1));
    }
    let filler = disk.join("filler");
    {
        use std::io::Write;
        let mut f = std::fs::File::create(&filler).unwrap();
        let block = vec![0u8; 64 << 10];
        while f.write_all(&block).is_ok() {}
        let _ = f.write_all(&block[..1]);
    }
    let result = run.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&result.stderr);
    {
        assert_eq!(result.status.code(), Some(1), "{stderr}");
        let error = stderr
            .lines()
            .find(|l| l.starts_with("drapekit: cannot write"));
        let error = error.unwrap_or_else(|| panic!("no write error in:\n{stderr}"));
        assert!(
            !error.contains("summary.json"),
            "the frame or checkpoint failed first: {error}"
        );
        assert!(error.contains(&format!("in {}", out.display())), "{error}");
        assert!(error.contains("No space left"), "{error}");
        assert!(stderr.contains("fix: the disk holding"), "{stderr}");
        assert!(temporaries(&out).is_empty(), "{:?}", temporaries(&out));
        std::fs::remove_file(&filler).unwrap();
        std::fs::write(out.join(".frame_0050.obj.4242.9.tmp"), b"partial").unwrap();
        let resumed = Command::new(env!("CARGO_BIN_EXE_drapekit"))
            .args(["resume", out.to_str().unwrap(), "--quiet"])
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&resumed.stderr);
        assert_eq!(resumed.status.code(), Some(0), "{stderr}");
        assert!(temporaries(&out).is_empty(), "{:?}", temporaries(&out));
        assert!(out.join("frame_0060.obj").is_file());
    }
}
