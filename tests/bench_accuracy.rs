//! Smoke tests of `drapekit bench accuracy` and `drapekit bench effects` with `--quick` on a
//! tiny scene: the commands finish, and their CSVs have the documented columns and finite
//! values where the book says a value is there.

mod common;

use drapekit::bench::accuracy::report::CSV_COLUMNS as ACCURACY_COLUMNS;
use drapekit::bench::effects::CSV_COLUMNS as EFFECTS_COLUMNS;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// A 9 × 9 cloth, 0.4 m square, falling 5 cm onto a sphere; no bending, so the solver's energy
/// sum is complete and the energy drift applies.
const TINY: &str = r#"
[cloth.grid]
width_m = 0.4
height_m = 0.4
columns = 9
rows = 9
center_m = [0.0, 0.2, 0.0]
plane = "xz"

[fabric]
density_kg_m2 = 0.15
stretch_stiffness_n_m = 100.0
damping_ratio = 0.1

[body]
shape = "sphere"
center_m = [0.0, 0.0, 0.0]
radius_m = 0.15
sdf_resolution_m = 0.02

[solver]
frames = 6
substeps = "auto"
integrator = "symplectic"
"#;

fn tiny_scene(dir: &Path) -> PathBuf {
    std::fs::create_dir_all(dir).unwrap();
    let path = dir.join("tiny.toml");
    std::fs::write(&path, TINY).unwrap();
    path
}

#[test]
fn accuracy_quick_writes_every_documented_column() {
    let dir = common::out_dir("bench_accuracy", "accuracy");
    let scene = tiny_scene(&dir);
    let out = dir.join("out");
    let run = common::drapekit(&[
        "bench",
        "accuracy",
        scene.to_str().unwrap(),
        "--quick",
        "--backend",
        "cpu",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let (header, rows) = common::read_csv(&out.join("accuracy.csv"), "error");
    assert_eq!(
        header[..header.len() - 1],
        ACCURACY_COLUMNS.map(String::from)
    );
    assert!(out.join("accuracy.md").is_file() && out.join("accuracy.svg").is_file());
    let knobs: Vec<&str> = rows.iter().map(|r| r["knob"].as_str()).collect();
    for knob in [
        "scene",
        "nudged_scene",
        "step",
        "particle_distance",
        "sdf_resolution",
        "body_simplification",
        "reference",
        "combined_best",
        "combined_cheapest",
    ] {
        assert!(knobs.contains(&knob), "no {knob} row in {knobs:?}");
    }
    // Any cell that holds a number holds a finite one.
    for row in &rows {
        for column in &ACCURACY_COLUMNS[3..] {
            let cell = &row[*column];
            if let Ok(v) = cell.parse::<f64>() {
                assert!(v.is_finite(), "{column} = {cell} in {row:?}");
            }
        }
    }
    // Rows that ran to the end have every figure this scene has: no seams, so no seam gap.
    let ok: Vec<&HashMap<String, String>> = rows.iter().filter(|r| r["status"] == "ok").collect();
    assert!(ok.len() >= rows.len() - 1, "{rows:?}");
    for row in &ok {
        for column in [
            "substeps_per_frame",
            "particles",
            "particle_distance_m",
            "sdf_resolution_m",
            "body_triangles",
            "sdf_bake_s",
            "simulated_s",
            "wall_s",
            "wall_s_per_simulated_s",
            "particle_substeps_per_s",
            "rms_error_m",
            "max_error_m",
            "max_penetration_m",
            "max_strain",
            "final_strain",
            "final_ke_per_particle_j",
            "energy_drift",
        ] {
            common::finite(row, column);
        }
        assert_eq!(row["max_seam_gap_m"], "", "{row:?}");
        assert_eq!(common::finite(row, "frames"), 6.0);
    }
    let reference = rows.iter().find(|r| r["knob"] == "reference").unwrap();
    assert_eq!(common::finite(reference, "rms_error_m"), 0.0);
    assert_eq!(common::finite(reference, "energy_drift"), 0.0);
    // A coarser cloth is compared through its grid coordinates: its error is real (non-zero)
    // but smaller than the cloth (0.4 m).
    let coarse = rows
        .iter()
        .find(|r| r["knob"] == "particle_distance")
        .unwrap();
    let e = common::finite(coarse, "rms_error_m");
    assert!(e > 0.0 && e < 0.4, "{e}");
    let simplified = rows
        .iter()
        .find(|r| r["knob"] == "body_simplification")
        .unwrap();
    assert!(
        common::finite(simplified, "body_triangles") < common::finite(reference, "body_triangles")
    );
}

#[test]
fn effects_quick_writes_every_documented_column() {
    let dir = common::out_dir("bench_accuracy", "effects");
    let scene = tiny_scene(&dir);
    let out = dir.join("out");
    let gpu = common::gpu().is_some();
    let run = common::drapekit(&[
        "bench",
        "effects",
        scene.to_str().unwrap(),
        "--quick",
        "--adapter",
        "fallback",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let (header, rows) = common::read_csv(&out.join("effects.csv"), "note");
    assert_eq!(header, EFFECTS_COLUMNS.map(String::from));
    assert!(out.join("effects.md").is_file());
    let backends = if gpu { 2 } else { 1 };
    assert_eq!(rows.len(), 7 * backends, "{rows:?}");
    for row in &rows {
        if row["effect"] == "seams" {
            // A grid has no pattern to sew: no figures, and a note that says so.
            assert_eq!(row["us_per_substep_with"], "");
            assert!(row["note"].contains("no pattern"), "{row:?}");
            continue;
        }
        for column in [
            "us_per_substep_with",
            "us_per_substep_without",
            "cost_us",
            "cost_percent",
            "us_per_substep_own_passes",
            "us_per_substep_empty_plan",
            "residue_us",
            "residue_percent",
            "spread_percent",
        ] {
            assert!(common::finite(row, column) > -1e12);
        }
        // Every pass the effect adds is a stage (pipeline or CPU pass) that goes with it.
        let added = row["passes_added"]
            .split(' ')
            .filter(|p| !p.is_empty())
            .count();
        assert!(added > 0, "{row:?}");
        // The membrane replaces spring_forces by membrane_forces: one stage out, one in.
        let replaced = if row["effect"] == "membrane" {
            assert_eq!(row["passes_added"], "membrane_forces", "{row:?}");
            1
        } else {
            0
        };
        assert_eq!(
            common::finite(row, "stages_with") - common::finite(row, "stages_without"),
            (added - replaced) as f64,
            "{row:?}"
        );
        assert!(common::finite(row, "resources_with") >= common::finite(row, "resources_without"));
    }
}

#[test]
fn accuracy_refuses_a_scene_with_two_bodies() {
    // The sweep's SDF and simplification knobs and its penetration measure are one body's.
    let out = common::out_dir("bench-accuracy", "two-bodies");
    let scene = common::fixture("scenes/cloth_pinched.toml");
    let r = common::drapekit(&[
        "bench",
        "accuracy",
        scene.to_str().unwrap(),
        "--quick",
        "--out",
        out.to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&r.stderr);
    assert_eq!(r.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("body[1]") && stderr.contains("fix:"),
        "{stderr}"
    );
}
