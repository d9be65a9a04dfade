//! `benches/device-check.sh --quick` with the built binary: every step passes on this machine
//! (lavapipe or a real GPU), and the folder holds each step's results and summary.md.

mod common;

use std::path::Path;
use std::process::Command;

#[test]
fn device_check_quick_writes_its_folder_and_summary() {
    // Its GPU steps need an adapter: skipped without one, a failure under CI=true.
    if common::gpu().is_none() {
        return;
    }
    let root = common::repo_root();
    let out = common::out_dir("device_check", "quick");
    let started = std::time::Instant::now();
    let result = Command::new("bash")
        .arg(root.join("benches/device-check.sh"))
        .args([
            "--quick",
            "--drapekit",
            env!("CARGO_BIN_EXE_drapekit"),
            "--out",
        ])
        .arg(&out)
        .current_dir(&root)
        .env("XDG_RUNTIME_DIR", std::env::temp_dir())
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&result.stderr);
    let steps = std::fs::read_to_string(out.join("steps.tsv")).unwrap_or_default();
    assert!(
        result.status.success(),
        "device-check failed ({}):\n{stderr}\n{steps}",
        result.status
    );
    eprintln!(
        "device-check --quick took {:.1} s",
        started.elapsed().as_secs_f64()
    );

    // Every step ran and passed (the Warp and Newton step is skipped without them).
    let names: Vec<&str> = steps
        .lines()
        .skip(1)
        .map(|l| l.split('\t').next().unwrap())
        .collect();
    for want in [
        "info",
        "shirt_cotton_gpu",
        "shirt_cotton_cpu",
        "bench",
        "bench_layout_textures",
        "bench_layout_buffers",
        "profile",
        "peer",
        "threads_1",
    ] {
        assert!(names.contains(&want), "no step {want} in\n{steps}");
    }
    for line in steps.lines().skip(1) {
        let status = line.split('\t').nth(1).unwrap();
        assert!(status == "ok" || status.starts_with("skipped"), "{line}");
    }
    for file in [
        "machine.txt",
        "shirt_cotton_gpu/summary.json",
        "shirt_cotton_cpu/summary.json",
        "bench/bench.csv",
        "bench_layout_buffers/bench.csv",
        "peer/peer.csv",
        "threads_1/peer.csv",
    ] {
        assert!(out.join(file).is_file(), "no {file} in {}", out.display());
    }

    // summary.md names the machine and carries the figures with their commands.
    let summary = std::fs::read_to_string(out.join("summary.md")).unwrap();
    for want in [
        "## Machine",
        "drapekit info: `adapter:",
        "## Garments",
        "tshirt_drape_cotton.toml",
        "DRAPEKIT_GPU_LAYOUT: buffers",
        "drapekit bench peer --systems drapekit",
        "| 8² | 1 |",
    ] {
        assert!(
            summary.contains(want),
            "summary.md lacks {want:?}:\n{summary}"
        );
    }
    // Every measured cell is a number: a figure the script failed to read shows as "—".
    let bench_rows: Vec<&str> = summary
        .lines()
        .filter(|l| l.starts_with("| 8² | gpu"))
        .collect();
    assert!(
        !bench_rows.is_empty() && bench_rows.iter().all(|l| !l.contains('—')),
        "{summary}"
    );
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn device_check_refuses_a_missing_binary_with_exit_2() {
    let root = common::repo_root();
    let out = common::out_dir("device_check", "missing");
    let result = Command::new("bash")
        .arg(root.join("benches/device-check.sh"))
        .args(["--quick", "--drapekit", "/nonexistent/drapekit", "--out"])
        .arg(&out)
        .current_dir(&root)
        .output()
        .unwrap();
    assert_eq!(result.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&result.stderr).contains("no drapekit binary"));
    assert!(
        !Path::new(&out).exists(),
        "it wrote {} anyway",
        out.display()
    );
}
