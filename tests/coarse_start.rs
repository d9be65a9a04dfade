//! The coarse start (`[cloth.pattern] coarse_start_distance_m`): the pattern-coordinate
//! transfer between two meshings, and whole runs that sew and drape a coarse copy first and
//! continue on the full mesh, on both backends.

mod common;

use common::fixture;
use drapekit::pattern::garment::{Garment, GarmentOptions};
use drapekit::pattern::transfer::Transfer;
use drapekit::pattern::Pattern;
use drapekit::scene::Scene;
use glam::Vec4;
use std::path::{Path, PathBuf};

fn build(p: &Pattern, spacing_m: f64) -> Garment {
    let options = GarmentOptions {
        particle_distance: spacing_m,
        placement: Default::default(),
    };
    Garment::build(p, &options).unwrap()
}

#[test]
fn a_coarse_meshing_carries_the_placed_panels_onto_a_fine_one() {
    // Each panel is placed rigidly, so its particles' 3D positions are an affine function of
    // their pattern coordinates, which the barycentric blend reproduces: inside the coarse
    // triangles to the rounding of f32 coordinates of about 1 m (a few ulps of 1.2e-7 m; we
    // allow 1e-5 m), and at points of a curved edge outside the coarse chords to within their
    // pattern gap, which a rigid placement keeps as a distance.
    let p = Pattern::load(&fixture("patterns/tshirt_apose_woven.json")).unwrap();
    let (coarse, fine) = (build(&p, 0.04), build(&p, 0.01));
    let transfer = Transfer::new(&coarse, &fine);
    let placed: Vec<Vec4> = (coarse.mesh.positions.iter())
        .map(|x| x.extend(0.0))
        .collect();
    let mapped = transfer.apply(&placed);
    assert_eq!(mapped.len(), fine.mesh.positions.len());
    let mut exact = 0;
    for (i, (m, f)) in mapped.iter().zip(&fine.mesh.positions).enumerate() {
        let err = m.distance(*f);
        assert!(
            err <= transfer.max_gap_m + 1e-5,
            "particle {i}: {err} m from its placed position (largest gap {} m)",
            transfer.max_gap_m
        );
        exact += (err < 1e-5) as usize;
    }
    // Only the outline's curved stretches lie outside the chords: most particles are inside.
    assert!(
        exact * 10 >= mapped.len() * 9,
        "{exact} of {} reproduced",
        mapped.len()
    );
    // A chord of length s on an edge of curvature radius R strays s²/(8R) from it: for the
    // 4 cm chords on this pattern's tightest curves (armholes and neckline, R ≥ 5 cm) at most
    // 4 mm. The gap is measured from the fine outline's points, which lie on the curve.
    assert!(
        transfer.max_gap_m > 0.0 && transfer.max_gap_m < 4e-3,
        "{}",
        transfer.max_gap_m
    );
}

/// `tshirt_drape_cotton.toml` (2 cm) with a coarse start at 4 cm and 15 s, written as a copy
/// that names its pattern and body by absolute path.
fn coarse_started_shirt(dir: &Path) -> PathBuf {
    let text = std::fs::read_to_string(fixture("scenes/tshirt_drape_cotton.toml")).unwrap();
    let patterns = fixture("patterns").display().to_string() + "/";
    let bodies = fixture("bodies").display().to_string() + "/";
    let text = text
        .replace("../patterns/", &patterns)
        .replace("../bodies/", &bodies)
        .replace(
            "particle_distance_m = 0.02\n",
            "particle_distance_m = 0.02\ncoarse_start_distance_m = 0.04\n",
        )
        // From the 4 cm start (settled near frame 30) the 2 cm mesh settles near frame 55 on
        // the CPU: 15 s leave ample room for the GPU's slightly different rounding.
        .replace("frames = 240\n", "frames = 360\n");
    assert!(
        text.contains("coarse_start_distance_m") && text.contains("frames = 360"),
        "the scene changed"
    );
    std::fs::create_dir_all(dir).unwrap();
    let path = dir.join("shirt_coarse_start.toml");
    std::fs::write(&path, text).unwrap();
    path
}

/// Runs the coarse-started shirt on `backend` and checks what every run must show.
fn run_coarse_started_shirt(backend: &[&str], tag: &str) -> serde_json::Value {
    let out = common::out_dir("coarse_start", tag);
    let scene = coarse_started_shirt(&out.with_extension("scene"));
    let mut args = vec![
        "run",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend(backend);
    let r = common::drapekit(&args);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let coarse = &summary["coarse_start"];
    let f = |v: &serde_json::Value| v.as_f64().unwrap_or(f64::NAN);
    // The coarse copy settled, and the full mesh went on from there.
    let start = coarse["frame"].as_u64().unwrap();
    assert_eq!(coarse["settled_frame"].as_u64(), Some(start), "{summary:#}");
    assert!(coarse["particles"].as_u64().unwrap() * 3 < summary["particles"].as_u64().unwrap());
    // The settle rule cannot fire on the mapped state: the full mesh simulated at least a frame.
    let settled = summary["settled"]["frame"].as_u64().expect("settled");
    assert!(
        settled > start,
        "settled at {settled}, the coarse start ended at {start}"
    );
    // No simulated full-mesh frame before the coarse start's end is written: the first is the
    // next one on the `every = 6` schedule. Frame 0 is the full mesh's flat panels (the strain
    // preview's rest shape), as in every run.
    let first = (start / 6 + 1) * 6;
    assert!(!out.join(format!("frame_{:04}.obj", start)).exists());
    assert!(!out.join(format!("frame_{:04}.obj", first - 6)).exists());
    assert!(out.join(format!("frame_{first:04}.obj")).is_file());
    assert!(out.join("frame_0000.obj").is_file());
    if common::gpu().is_some() {
        for name in ["preview_fabric.png", "preview_strain.png"] {
            assert!(out.join(name).is_file(), "{name} missing: {summary:#}");
        }
    }
    // One Newton step a substep with two smoothing sweeps before and after it, and no
    // tolerance: the means over the full mesh's frames are exactly 1 and 4.
    assert_eq!(f(&summary["newton_steps_mean"]), 1.0, "{summary:#}");
    assert_eq!(f(&summary["iterations_mean"]), 4.0, "{summary:#}");
    // Seams closed and nothing deeper in the body than the 3 mm thickness, as without a coarse
    // start (tests/cli.rs). The strain is not that shirt's: static friction holds part of what
    // the 4 cm mesh left (largest 4.3-5.0% and 1.9-2.0% at the 99th percentile here, against
    // 2.1% and 0.8% without a coarse start; 3.4% largest with five times the friction's creep
    // speed: docs/src/implicit.md). The carry and the full mesh's own solve must not add to it.
    assert_eq!(summary["seams_closed"], summary["seams"], "{summary:#}");
    assert!(f(&summary["max_penetration_m"]) <= 0.003, "{summary:#}");
    assert!(
        f(&summary["last_frame_max_edge_strain"]) <= f(&coarse["max_edge_strain"]),
        "{summary:#}"
    );
    // The full mesh's rate counts its own frames and time only.
    assert!(f(&summary["wall_seconds"]) > f(&coarse["wall_seconds"]));
    assert!(f(&summary["particle_substeps_per_second"]) > 0.0);
    let prep = drapekit::sim::prepare(&Scene::load(&scene).unwrap()).unwrap();
    let rule = (
        prep.settle_speed.unwrap(),
        prep.settle_force_residual.unwrap(),
    );
    check_frames_csv(&out, &summary, rule);
    summary
}

/// `frames.csv` of a coarse-started run: a row for every frame, the coarse start's then the
/// full mesh's, that agrees with the summary to the last digit, and whose rows before the
/// settled frame each fail the settle rule, (speed, force residual) (else it would have fired
/// there).
fn check_frames_csv(out: &Path, summary: &serde_json::Value, rule: (f32, f32)) {
    let outputs = summary["outputs"].as_array().unwrap();
    assert!(outputs.iter().any(|o| o == "frames.csv"), "{summary:#}");
    let text = std::fs::read_to_string(out.join("frames.csv")).unwrap();
    let mut lines = text.lines();
    assert_eq!(
        lines.next(),
        Some(
            "frame,particles,rms_speed_m_s,force_residual_max,force_residual_rms,\
             max_edge_strain,max_seam_gap_m,body_contacts"
        )
    );
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
        .collect();
    let number = |v: &serde_json::Value| v.as_f64().unwrap();
    let start = number(&summary["coarse_start"]["frame"]) as usize;
    let settled = number(&summary["settled"]["frame"]) as usize;
    assert_eq!(rows.len(), settled, "one row a frame");
    let coarse_particles = number(&summary["coarse_start"]["particles"]);
    for (k, row) in rows.iter().enumerate() {
        assert_eq!(row[0], (k + 1) as f64, "frames in order");
        let particles = if k < start {
            coarse_particles
        } else {
            number(&summary["particles"])
        };
        assert_eq!(row[1], particles, "frame {}", k + 1);
    }
    // Each figure is written in its shortest exact form, as the summary writes it.
    let last = &rows[settled - 1];
    assert_eq!(last[2], number(&summary["last_frame_rms_speed_m_s"]));
    assert_eq!(
        last[4] as f32,
        number(&summary["force_residual_rms"]) as f32
    );
    assert_eq!(
        last[5] as f32,
        number(&summary["last_frame_max_edge_strain"]) as f32
    );
    assert_eq!(last[6] as f32, number(&summary["max_seam_gap_m"]) as f32);
    assert_eq!(last[7], number(&summary["body_contacts"]));
    let full_mesh_largest = rows[start..].iter().map(|r| r[5]).fold(0.0, f64::max);
    assert_eq!(
        full_mesh_largest as f32,
        number(&summary["max_edge_strain"]) as f32
    );
    // Compared as `sim::settle` compares them.
    assert!(
        settled > start + 1,
        "the full mesh ran one frame: no row to check"
    );
    for row in &rows[start..settled - 1] {
        let meets = row[2] < rule.0 as f64 && (row[4] as f32) <= rule.1;
        assert!(!meets, "frame {} meets the rule {rule:?}", row[0]);
    }
}

#[test]
fn a_coarse_started_shirt_settles_sewn_and_unstretched_on_the_cpu() {
    run_coarse_started_shirt(&["--backend", "cpu"], "cpu");
}

#[test]
fn a_coarse_started_shirt_settles_sewn_and_unstretched_on_the_gpu() {
    if common::gpu().is_none() {
        return;
    }
    run_coarse_started_shirt(&["--backend", "gpu", "--adapter", "fallback"], "gpu");
}

#[test]
fn a_resumed_coarse_started_run_repeats_the_uninterrupted_one() {
    // Stopped halfway between the end of the coarse start and the frame where the whole run
    // settled, then resumed from the checkpoint: the full mesh continues from it without
    // redoing the coarse start, and the CPU path gives the same bits as the run that was never
    // stopped.
    let whole = common::out_dir("coarse_start", "whole");
    let parts = common::out_dir("coarse_start", "parts");
    let scene = coarse_started_shirt(&whole.with_extension("scene"));
    let scene = scene.to_str().unwrap();
    let run = |args: &[&str]| {
        let r = common::drapekit(args);
        assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
        String::from_utf8_lossy(&r.stdout).to_string()
    };
    let summary = |dir: &Path| -> serde_json::Value {
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap()
    };
    run(&[
        "run",
        scene,
        "--backend",
        "cpu",
        "--out",
        whole.to_str().unwrap(),
    ]);
    let frame = |v: &serde_json::Value| v.as_u64().expect("a frame number");
    let whole_summary = summary(&whole);
    let coarse_end = frame(&whole_summary["coarse_start"]["frame"]);
    let settled = frame(&whole_summary["settled"]["frame"]);
    assert!(
        settled >= coarse_end + 4,
        "the full mesh ran only {coarse_end}..{settled}: nothing to stop in between"
    );
    let stop = ((coarse_end + settled) / 2).to_string();
    let first = run(&[
        "run",
        scene,
        "--backend",
        "cpu",
        "--frames",
        &stop,
        "--checkpoint-every",
        "1",
        "--out",
        parts.to_str().unwrap(),
    ]);
    assert!(first.contains("coarse start"), "{first}");
    let resumed = run(&["resume", parts.to_str().unwrap(), "--frames", "360"]);
    assert!(resumed.contains("coarse start"), "{resumed}");
    let (a, b) = (whole_summary, summary(&parts));
    for key in [
        "settled",
        "frames",
        "coarse_start",
        "last_frame_rms_speed_m_s",
        "max_edge_strain",
        "seam_gaps_m",
        "kinetic_energy_j",
    ] {
        let mut pair = [a[key].clone(), b[key].clone()];
        for v in &mut pair {
            // The coarse start's time is the one field a rerun does not repeat.
            if let Some(c) = v.as_object_mut() {
                c.remove("wall_seconds");
            }
        }
        assert_eq!(pair[0], pair[1], "{key}");
    }
    assert_eq!(
        std::fs::read_to_string(whole.join("frames.csv")).unwrap(),
        std::fs::read_to_string(parts.join("frames.csv")).unwrap(),
        "frames.csv"
    );
    let last = format!("frame_{:04}.obj", a["frames"].as_u64().unwrap());
    assert_eq!(
        std::fs::read(whole.join(&last)).unwrap(),
        std::fs::read(parts.join(&last)).unwrap(),
        "{last}"
    );
}

#[test]
fn plan_names_the_coarse_start() {
    let dir = common::out_dir("coarse_start", "plan");
    let scene = coarse_started_shirt(&dir);
    let r = common::drapekit(&["plan", scene.to_str().unwrap(), "--json"]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let plan: serde_json::Value = serde_json::from_slice(&r.stdout).unwrap();
    assert_eq!(plan["coarse_start_distance_m"], 0.04);
    let r = common::drapekit(&["plan", scene.to_str().unwrap()]);
    let text = String::from_utf8_lossy(&r.stdout);
    assert!(text.contains("meshed at 0.040 m"), "{text}");
}
