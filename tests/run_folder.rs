//! Run folders stand on their own: the scene's copy and the absolute paths of its inputs let
//! `preview` and `resume` work from any directory, and a new run never mixes its frames with
//! another run's.

mod common;

use std::path::Path;

fn out_dir(name: &str) -> std::path::PathBuf {
    common::out_dir("run-folder", name)
}

/// `drapekit ARGS` run from `cwd`.
fn drapekit_in(cwd: &Path, args: &[&str]) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_drapekit"))
        .args(args)
        .current_dir(cwd)
        .env("XDG_RUNTIME_DIR", std::env::temp_dir())
        .output()
        .unwrap()
}

fn summary(dir: &Path) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(dir.join("summary.json")).unwrap()).unwrap()
}

fn frames_in(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with("frame_"))
        .collect();
    names.sort();
    names
}

#[test]
fn a_run_folder_previews_and_resumes_from_another_directory() {
    // The skirt's scene names its pattern relative to itself ("../patterns/…"), and is given
    // here relative to the repository: neither path means anything from elsewhere.
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let out = out_dir("elsewhere");
    let out_s = out.to_str().unwrap();
    let scene = "fixtures/scenes/skirt_sew.toml";
    let args = [
        "run",
        scene,
        "--backend",
        "cpu",
        "--frames",
        "4",
        "--checkpoint-every",
        "4",
        "--out",
        out_s,
        "--quiet",
    ];
    let r = drapekit_in(root, &args);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let s = summary(&out);
    let absolute = root.join(scene);
    assert_eq!(s["scene"], absolute.to_str().unwrap());
    let pattern = s["inputs"]["pattern"].as_str().unwrap();
    assert!(
        Path::new(pattern).is_absolute() && Path::new(pattern).is_file(),
        "{pattern}"
    );
    assert_eq!(
        std::fs::read_to_string(out.join("scene.toml")).unwrap(),
        std::fs::read_to_string(&absolute).unwrap(),
        "the copy is the scene's text"
    );
    assert!(s["outputs"]
        .as_array()
        .unwrap()
        .contains(&"scene.toml".into()));

    // From the temporary directory: the preview draws the seams, which needs the pattern.
    let elsewhere = std::env::temp_dir();
    let png = out.join("seams.png");
    let args = [
        "preview",
        out_s,
        "--seams",
        "--adapter",
        "fallback",
        "--size",
        "160x120",
    ];
    let mut args = args.to_vec();
    args.extend(["--out", png.to_str().unwrap()]);
    const EDITED: &str = "scene.toml was edited after the run";
    if common::gpu().is_some() {
        let r = drapekit_in(&elsewhere, &args);
        let log = String::from_utf8_lossy(&r.stderr);
        assert!(r.status.success(), "{log}");
        assert!(!log.contains(EDITED), "{log}");
        assert!(png.is_file());
    }
    let r = drapekit_in(&elsewhere, &["resume", out_s, "--frames", "6", "--quiet"]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    assert_eq!(summary(&out)["frames"], 6);

    // The copy edited afterwards: the preview says that it draws a scene that did not run.
    let copy = out.join("scene.toml");
    let text = std::fs::read_to_string(&copy).unwrap();
    std::fs::write(&copy, format!("{text}\n# edited\n")).unwrap();
    if common::gpu().is_some() {
        let r = drapekit_in(&elsewhere, &args);
        let log = String::from_utf8_lossy(&r.stderr);
        assert!(r.status.success(), "{log}");
        assert!(log.contains(EDITED), "{log}");
    }
}

#[test]
fn a_rerun_replaces_its_own_frames_and_another_scene_needs_overwrite() {
    let out = out_dir("stale");
    let out_s = out.to_str().unwrap();
    let hanging = common::fixture("scenes/hanging_cloth.toml");
    let run = |scene: &Path, frames: &str, extra: &[&str]| {
        let mut args = vec![
            "run",
            scene.to_str().unwrap(),
            "--backend",
            "cpu",
            "--frames",
            frames,
            "--out",
            out_s,
            "--quiet",
        ];
        args.extend(extra);
        common::drapekit(&args)
    };
    // A file of the user's stays through all of this.
    std::fs::create_dir_all(&out).unwrap();
    std::fs::write(out.join("notes.txt"), "mine").unwrap();
    assert!(run(&hanging, "4", &[]).status.success());
    assert_eq!(frames_in(&out).len(), 5);
    // The same scene with fewer frames: only its own frames remain, and the preview's frame
    // list (the summary's) agrees.
    let r = run(&hanging, "2", &[]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    // Frames 0..=4, the scene's copy, frames.csv and the summary.
    assert!(String::from_utf8_lossy(&r.stderr).contains("replaced the 8 files"));
    assert_eq!(
        frames_in(&out),
        ["frame_0000.obj", "frame_0001.obj", "frame_0002.obj"]
    );
    let s = summary(&out);
    let listed: Vec<&str> = (s["outputs"].as_array().unwrap().iter())
        .filter_map(|o| o.as_str().filter(|n| n.starts_with("frame_")))
        .collect();
    assert_eq!(listed, frames_in(&out));
    // Another scene into the same folder is refused, with the fix, and changes nothing.
    let sphere = common::fixture("scenes/drape_sphere.toml");
    let r = run(&sphere, "2", &[]);
    assert_eq!(r.status.code(), Some(2));
    let err = String::from_utf8_lossy(&r.stderr);
    assert!(
        err.contains("holds the results of a run of") && err.contains("--overwrite"),
        "{err}"
    );
    assert_eq!(summary(&out)["scene"], hanging.to_str().unwrap());
    // With --overwrite it replaces them; the user's file stays.
    let r = run(&sphere, "1", &["--overwrite"]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    assert_eq!(frames_in(&out), ["frame_0000.obj", "frame_0001.obj"]);
    assert_eq!(summary(&out)["scene"], sphere.to_str().unwrap());
    assert_eq!(
        std::fs::read_to_string(out.join("notes.txt")).unwrap(),
        "mine"
    );
}

#[test]
fn frames_without_a_summary_are_kept_unless_overwrite() {
    let out = out_dir("orphans");
    std::fs::create_dir_all(&out).unwrap();
    std::fs::write(out.join("frame_0007.obj"), "v 0 0 0\n").unwrap();
    let scene = common::fixture("scenes/hanging_cloth.toml");
    let args = [
        "run",
        scene.to_str().unwrap(),
        "--backend",
        "cpu",
        "--frames",
        "1",
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ];
    let r = common::drapekit(&args);
    assert_eq!(r.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&r.stderr).contains("a run that left no summary.json"));
    assert!(out.join("frame_0007.obj").is_file());
    // A summary that does not read is not "no summary".
    std::fs::write(out.join("summary.json"), "{\"scene\": ").unwrap();
    let r = common::drapekit(&args);
    assert_eq!(r.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&r.stderr);
    assert!(
        stderr.contains("a run whose summary.json does not read"),
        "{stderr}"
    );
}
