//! `drapekit bench peer`: the drapekit-only part runs in CI (the peers need Python packages and
//! minutes, and are not part of CI); a missing Python is a clear error.

mod common;

use common::{drapekit, out_dir};

/// Springs of Warp's benchmark cloth with n × n particles: structural 2n(n−1), bend 2n(n−2),
/// shear 2(n−1)².
fn warp_springs(n: usize) -> usize {
    2 * n * (n - 1) + 2 * n * (n - 2) + 2 * (n - 1) * (n - 1)
}

#[test]
fn peer_quick_drapekit_writes_the_documented_columns_with_finite_values() {
    let dir = out_dir("bench_peer", "quick");
    let r = drapekit(&[
        "bench",
        "peer",
        "--systems",
        "drapekit",
        "--quick",
        "--sizes",
        "8,12",
        "--newton-sizes",
        "8",
        "--adapter",
        "fallback",
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let csv = std::fs::read_to_string(dir.join("peer.csv")).unwrap();
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    assert_eq!(
        &header[..6],
        [
            "system",
            "backend",
            "grid",
            "particles",
            "springs",
            "particle_substeps_per_s"
        ],
        "{csv}"
    );
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    // Symplectic at 8² and 12², implicit at 8²; each on the CPU and, with an adapter, the GPU.
    let backends = if common::gpu().is_some() { 2 } else { 1 };
    assert_eq!(rows.len(), 3 * backends, "{csv}");
    for row in &rows {
        assert_eq!(row[col("system")], "drapekit");
        assert!(["cpu", "gpu"].contains(&row[col("backend")]), "{row:?}");
        let n: usize = row[col("grid")].parse().unwrap();
        assert!(n == 8 || n == 12, "{row:?}");
        assert_eq!(row[col("particles")].parse::<usize>().unwrap(), n * n);
        assert_eq!(
            row[col("springs")].parse::<usize>().unwrap(),
            warp_springs(n)
        );
        for name in ["particle_substeps_per_s", "wall_s_per_simulated_s"] {
            let v: f64 = row[col(name)].parse().unwrap();
            assert!(v.is_finite() && v > 0.0, "{name} = {v} in {row:?}");
        }
        let expected_substeps = if row[col("integrator")] == "implicit" {
            "10"
        } else {
            "16"
        };
        assert_eq!(row[col("substeps_per_frame")], expected_substeps, "{row:?}");
        // Without Warp there is no state to compare with.
        assert_eq!(row[col("max_distance_to_warp_m")], "", "{row:?}");
    }
    let md = std::fs::read_to_string(dir.join("peer.md")).unwrap();
    assert!(md.contains("## Warp's cloth benchmark"), "{md}");
    assert!(md.contains("| 12² | 144 |"), "{md}");
}

#[test]
fn peer_without_python_says_what_to_install() {
    let dir = out_dir("bench_peer", "no-python");
    let venv = dir.join("venv");
    let r = drapekit(&[
        "bench",
        "peer",
        "--systems",
        "warp",
        "--python",
        "/nonexistent/python3",
        "--venv",
        venv.to_str().unwrap(),
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert_eq!(r.status.code(), Some(2));
    let err = String::from_utf8_lossy(&r.stderr);
    assert!(err.contains("/nonexistent/python3"), "{err}");
    assert!(
        err.contains("python3-venv") && err.contains("--systems drapekit"),
        "{err}"
    );
    assert!(!venv.exists() && !dir.join("peer.csv").exists());
}
