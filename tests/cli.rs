//! The command line end to end: summary fields, the plan, effects on demand, the NaN guard.

mod common;

use drapekit::gpu::GpuSolver;
use drapekit::plan::Pass;
use drapekit::scene::Scene;
use drapekit::sim::prepare;
use std::path::{Path, PathBuf};

fn drapekit(args: &[&str]) -> std::process::Output {
    common::drapekit(args)
}

fn out_dir(name: &str) -> PathBuf {
    common::out_dir("cli", name)
}

#[test]
fn run_writes_frames_and_a_complete_summary() {
    let out = out_dir("run");
    let scene = common::fixture("scenes/hanging_cloth.toml");
    let r = drapekit(&[
        "run",
        scene.to_str().unwrap(),
        "--backend",
        "cpu",
        "--frames",
        "3",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
    for key in [
        "backend",
        "adapter",
        "particles",
        "triangles",
        "frames",
        "substeps_per_frame",
        "dt",
        "integrator",
        "simulated_seconds",
        "wall_seconds",
        "particle_substeps_per_second",
        "passes",
        "max_edge_strain",
        "kinetic_energy_j",
        "finite",
        "outputs",
    ] {
        assert!(summary.get(key).is_some(), "summary lacks {key}");
    }
    assert_eq!(summary["backend"], "cpu");
    assert_eq!(summary["particles"], 32 * 32);
    assert_eq!(summary["frames"], 3);
    assert_eq!(summary["finite"], true);
    assert_eq!(
        summary["passes"],
        serde_json::json!(["hinge_forces", "spring_forces", "integrate", "strain_limit"])
    );
    // The scene's copy, frames 0..=3, frames.csv and the summary, and each listed file exists.
    let outputs = summary["outputs"].as_array().unwrap();
    assert_eq!(outputs.len(), 7);
    for f in outputs {
        assert!(out.join(f.as_str().unwrap()).is_file(), "{f} missing");
    }
    // No temporary files are left behind by the atomic writes.
    assert!(std::fs::read_dir(&out).unwrap().all(|e| !e
        .unwrap()
        .file_name()
        .to_string_lossy()
        .ends_with(".tmp")));
}

#[test]
fn plan_json_lists_the_stages() {
    let scene = common::fixture("scenes/flag_wind.toml");
    let r = drapekit(&["plan", scene.to_str().unwrap(), "--json"]);
    assert!(r.status.success());
    let plan: serde_json::Value = serde_json::from_slice(&r.stdout).unwrap();
    assert_eq!(
        plan["passes"],
        serde_json::json!([
            "spring_forces",
            "bending_forces",
            "wind_forces",
            "integrate",
            "strain_limit"
        ])
    );
    let scene = common::fixture("scenes/free_fall.toml");
    let plan: serde_json::Value =
        serde_json::from_slice(&drapekit(&["plan", scene.to_str().unwrap(), "--json"]).stdout)
            .unwrap();
    // free_fall has no bending key, no wind and no pins.
    assert_eq!(
        plan["passes"],
        serde_json::json!(["spring_forces", "integrate", "strain_limit"])
    );
}

#[test]
fn plan_gives_the_buckling_onset_of_a_scene_that_buckles() {
    // The hanging cloth (hinge coefficient 2e-5 N·m, so B = 5e-6 N·m; Y = 300 N/m) with
    // springs that buckle: each spring of rest length L buckles at strain π²B/(Y·L²).
    let text = std::fs::read_to_string(common::fixture("scenes/hanging_cloth.toml")).unwrap();
    let dir = common::out_dir("cli", "plan-buckling");
    std::fs::create_dir_all(&dir).unwrap();
    let scene = dir.join("buckling.toml");
    let buckling = text.replacen(
        "\n[fabric]\n",
        "\n[fabric]\ncompression = \"buckling\"\n",
        1,
    );
    std::fs::write(&scene, &buckling).unwrap();
    let plan = |path: &Path| -> serde_json::Value {
        let r = drapekit(&["plan", path.to_str().unwrap(), "--json"]);
        assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
        serde_json::from_slice(&r.stdout).unwrap()
    };
    let linear = plan(&common::fixture("scenes/hanging_cloth.toml"));
    assert!(linear["buckling_onset_strain"].is_null());
    let onset = plan(&scene)["buckling_onset_strain"].as_f64().unwrap();
    let prep = prepare(&Scene::load(&scene).unwrap()).unwrap();
    let springs = &prep.model.springs;
    let mean_inverse_square = springs
        .iter()
        .map(|s| 1.0 / (s.rest_length as f64).powi(2))
        .sum::<f64>()
        / springs.len() as f64;
    let expected = std::f64::consts::PI.powi(2) * 5e-6 / 300.0 * mean_inverse_square;
    // f32 parameters (π²B/Y and each L) against f64 here: a few 1e-7 relative.
    assert!(
        (onset / expected - 1.0).abs() < 1e-5,
        "{onset} against {expected}"
    );
    let text = drapekit(&["plan", scene.to_str().unwrap()]);
    let out = String::from_utf8_lossy(&text.stdout);
    assert!(out.contains("cloth buckles in compression"), "{out}");
}

#[test]
fn a_scene_without_wind_builds_no_wind_pipeline_or_buffer() {
    let Some(ctx) = common::gpu() else { return };
    let hanging =
        prepare(&Scene::load(&common::fixture("scenes/hanging_cloth.toml")).unwrap()).unwrap();
    let solver = GpuSolver::new(ctx, &hanging.model, hanging.params, &hanging.plan, 4).unwrap();
    assert!(!solver.pipeline_passes().contains(&Pass::WindForces));
    for label in [
        "triangles",
        "triangle_offsets",
        "triangle_refs",
        "substep_params",
    ] {
        assert!(
            !solver.resource_labels().contains(&label),
            "no-wind scene created buffer {label}"
        );
    }
    // The control: the flag scene does build them, so the assertion above can fail.
    let flag = prepare(&Scene::load(&common::fixture("scenes/flag_wind.toml")).unwrap()).unwrap();
    let solver = GpuSolver::new(ctx, &flag.model, flag.params, &flag.plan, 4).unwrap();
    assert!(solver.pipeline_passes().contains(&Pass::WindForces));
    assert!(solver.resource_labels().contains(&"triangles"));
}

/// The hanging cloth with 1 substep per frame, ~200× past its stable step, with `extra` added
/// to `[solver]`: it blows up. Returns the run's stderr and output folder after checking that
/// it stopped with exit 3 and left every frame up to the last good one, and not the next.
fn unstable_run(name: &str, extra: &str) -> (String, PathBuf) {
    let src = std::fs::read_to_string(common::fixture("scenes/hanging_cloth.toml"))
        .unwrap()
        .replace("substeps = \"auto\"", &format!("substeps = 1\n{extra}"));
    let dir = out_dir(name);
    std::fs::create_dir_all(&dir).unwrap();
    let scene = dir.join("unstable.toml");
    std::fs::write(&scene, src).unwrap();
    let out = dir.join("out");
    let r = drapekit(&[
        "run",
        scene.to_str().unwrap(),
        "--backend",
        "cpu",
        "--out",
        out.to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&r.stderr).to_string();
    assert_eq!(r.status.code(), Some(3), "{stderr}");
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
    let last_good = summary["frames"].as_u64().unwrap();
    // Every frame up to the last good one is on disk; the bad one is not.
    for f in 0..=last_good {
        assert!(out.join(format!("frame_{f:04}.obj")).is_file());
    }
    assert!(!out.join(format!("frame_{:04}.obj", last_good + 1)).exists());
    assert!(frame_is_finite(
        &out.join(format!("frame_{last_good:04}.obj"))
    ));
    (stderr, out)
}

#[test]
fn an_exploded_frame_stops_the_run_and_is_not_written() {
    // It passes solver.max_strain (500% by default) while still finite.
    let (stderr, out) = unstable_run("exploded", "");
    assert!(
        stderr.contains("exploded") && stderr.contains("max_strain"),
        "{stderr}"
    );
    // The monitor names where: the substeps and the worst particle.
    assert!(
        stderr.contains("substeps ") && stderr.contains("a spring at particle "),
        "{stderr}"
    );
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
    assert!(summary["max_edge_strain"].as_f64().unwrap() <= 5.0);
    // frames.csv is written too, with a row for each good frame and none for the exploded one.
    let frames = std::fs::read_to_string(out.join("frames.csv")).unwrap();
    let good = summary["frames"].as_u64().unwrap() as usize;
    assert_eq!(frames.lines().count(), 1 + good, "{frames}");
}

/// A solver whose state turns NaN after its first advance.
struct GoesNan(drapekit::cpu::CpuSolver);

impl drapekit::solver::Solver for GoesNan {
    fn backend_name(&self) -> &'static str {
        "cpu"
    }
    fn adapter(&self) -> Option<drapekit::solver::AdapterReport> {
        None
    }
    fn advance(
        &mut self,
        steps: &[drapekit::model::layout::SubstepParams],
    ) -> Result<(), drapekit::Error> {
        self.0.advance(steps)?;
        self.0.pos[7].y = f32::NAN;
        Ok(())
    }
    fn state(&mut self) -> Result<drapekit::solver::ParticleState, drapekit::Error> {
        self.0.state()
    }
    fn health(&mut self) -> Result<drapekit::solver::Health, drapekit::Error> {
        self.0.health()
    }
    fn set_state(&mut self, state: &drapekit::solver::ParticleState) {
        self.0.set_state(state)
    }
    fn set_params(&mut self, params: &drapekit::model::layout::SimParams) {
        self.0.set_params(params)
    }
}

#[test]
fn a_non_finite_frame_stops_the_run_and_is_not_used() {
    let prep =
        prepare(&Scene::load(&common::fixture("scenes/hanging_cloth.toml")).unwrap()).unwrap();
    let mut solver = GoesNan(drapekit::cpu::CpuSolver::new(
        &prep.model,
        prep.params,
        &prep.plan,
    ));
    let mut stats = drapekit::sim::RunStats::default();
    let mut seen = Vec::new();
    let err = drapekit::sim::simulate(&prep, &mut solver, &mut stats, |f, _| {
        seen.push(f);
        Ok(())
    })
    .unwrap_err();
    assert_eq!(seen, vec![0], "only the initial frame was handed on");
    assert!(!stats.finite);
    let msg = err.to_string();
    assert!(
        msg.contains("non-finite") && msg.contains("particle 7"),
        "{msg}"
    );
}

fn frame_is_finite(path: &Path) -> bool {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .filter(|l| l.starts_with("v "))
        .all(|l| {
            l[2..]
                .split(' ')
                .all(|x| x.parse::<f32>().map(f32::is_finite).unwrap_or(false))
        })
}

#[test]
fn bench_writes_tables_and_a_plot() {
    let dir = out_dir("bench");
    let r = drapekit(&[
        "bench",
        "--sizes",
        "4,6",
        "--substeps",
        "2",
        "--repeats",
        "1",
        "--adapter",
        "fallback",
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let csv = std::fs::read_to_string(dir.join("bench.csv")).unwrap();
    // A header plus one row per size and backend (the GPU rows need an adapter).
    let backends = if common::gpu().is_some() { 2 } else { 1 };
    assert_eq!(csv.lines().count(), 1 + 2 * backends, "{csv}");
    assert!(csv
        .lines()
        .skip(1)
        .all(|l| l.starts_with("4,") || l.starts_with("6,")));
    let svg = std::fs::read_to_string(dir.join("bench.svg")).unwrap();
    assert!(svg.starts_with("<svg") && svg.contains("particle-substeps / s"));
    assert!(dir.join("bench.md").exists());
}

#[test]
fn tshirt_sew_writes_a_sewn_tshirt() {
    // The acceptance run, shortened from 12 to 6 frames: the seams close by frame 4.
    let out = out_dir("tshirt_sew");
    let r = drapekit(&[
        "run",
        common::fixture("scenes/tshirt_sew.toml").to_str().unwrap(),
        "--frames",
        "6",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["seams"], 10);
    assert_eq!(summary["seams_closed"], 10, "{summary:#}");
    assert!(summary["max_seam_gap_m"].as_f64().unwrap() < 1e-3);
    let obj = std::fs::read_to_string(out.join("frame_0004.obj")).unwrap();
    assert!(
        obj.contains("\nvt ") && obj.contains("/"),
        "frames carry pattern coordinates"
    );
}

#[test]
fn tshirt_drape_sews_a_tshirt_that_rests_on_the_mannequin() {
    // The acceptance run, whole: sewn in zero gravity over 0.6 s, gravity from 1 s, and
    // stopped by the settle rule once the shirt rests (frame 78 of at most 96 when recorded).
    let out = out_dir("tshirt_drape");
    let r = drapekit(&[
        "run",
        common::fixture("scenes/tshirt_drape.toml")
            .to_str()
            .unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let f = |key: &str| {
        summary[key]
            .as_f64()
            .unwrap_or_else(|| panic!("{key}: {summary:#}"))
    };
    // Sewn: every seam closed, and still closed under gravity at the end.
    assert_eq!(summary["seams"], 12);
    assert_eq!(summary["seams_closed"], 12, "{summary:#}");
    assert!(f("max_seam_gap_m") < 1e-3, "{summary:#}");
    // Not penetrating: the collision holds particles 3 mm out on the SDF, and the SDF is within
    // 1.5 mm of the exact mesh where the shirt rests (measured), so no particle at any output
    // frame may be inside the exact mesh at all.
    assert_eq!(f("max_penetration_m"), 0.0, "{summary:#}");
    // Resting: stopped by the settle rule after gravity came on (frame 24), with the shoulders,
    // chest and back carrying the shirt. 29% of the particles touched the body in the recorded
    // run; a shirt hanging from a few points, or one that slid off, touches far fewer.
    let settled = &summary["settled"];
    assert!(
        settled["frame"].as_u64().is_some_and(|f| f > 24),
        "{summary:#}"
    );
    let particles = f("particles");
    assert!(f("body_contacts") >= 0.1 * particles, "{summary:#}");
    // On the body, not below it: the hem was placed at 0.82 m, above the hips (widest at 0.80
    // m); a shirt that slid down over them would reach below 0.75 m.
    let lowest = (settled_heights(&out, &summary).into_iter()).fold(f64::INFINITY, f64::min);
    assert!(lowest > 0.75, "the hem hangs down to {lowest} m");
    // Not torn or tangled: the largest spring strain was 0.30 in the recorded run.
    assert!(f("max_edge_strain") < 0.5, "{summary:#}");
}

#[test]
fn the_last_frame_is_written_between_output_frames() {
    // drape_bar writes every 6th frame; a run of 8 frames still ends with frame 8 on disk.
    let out = out_dir("last_frame");
    let r = drapekit(&[
        "run",
        common::fixture("scenes/drape_bar.toml").to_str().unwrap(),
        "--backend",
        "cpu",
        "--frames",
        "8",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    for f in ["frame_0000.obj", "frame_0006.obj", "frame_0008.obj"] {
        assert!(out.join(f).exists(), "{f} missing");
    }
    assert!(!out.join("frame_0007.obj").exists());
}

#[test]
fn info_lists_the_adapters_and_the_cpu() {
    let r = drapekit(&["info"]);
    let stdout = String::from_utf8_lossy(&r.stdout);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    assert!(stdout.contains("cpu: "), "{stdout}");
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    assert!(
        stdout.contains(&format!("cpu threads: {threads} available")),
        "{stdout}"
    );
    if common::gpu().is_some() {
        assert!(
            stdout.contains("adapter: ") && stdout.contains("--adapter auto picks"),
            "{stdout}"
        );
        // The limits of auto's adapter, with what they mean for a run.
        assert!(
            stdout.contains("its limits: 2D textures up to ")
                && stdout.contains("particles on the GPU path"),
            "{stdout}"
        );
    }
}

#[test]
fn plan_names_what_limits_the_substep() {
    // The hanging cloth's fastest particle is held by its stretch springs; the sewn T-shirt's
    // seams are twice as stiff as its fabric; an implicit scene's step is the scene's.
    for (scene, term) in [
        ("hanging_cloth.toml", "stretch"),
        ("tshirt_sew.toml", "seam"),
        ("tshirt_drape_cotton.toml", "scene"),
    ] {
        let path = common::fixture(&format!("scenes/{scene}"));
        let r = drapekit(&["plan", path.to_str().unwrap(), "--json"]);
        let plan: serde_json::Value = serde_json::from_slice(&r.stdout).unwrap();
        assert_eq!(plan["dt_limited_by"], term, "{scene}");
    }
    // The flag in air a thousand times denser: the drag rate γ = ρ·C_d·|v|·(1 + gust)/σ
    // outruns the springs, and `auto` must take substeps with γ·dt < 2 (the explicit drag
    // update's bound), or the cloth's speed oscillates and blows up.
    let shipped = common::fixture("scenes/flag_wind.toml");
    let text = std::fs::read_to_string(&shipped).unwrap();
    assert!(text.contains("air_density_kg_m3 = 1.225") && text.contains("density_kg_m2 = 0.12"));
    let dense = out_dir("plan-dense-wind").join("flag_dense_air.toml");
    std::fs::create_dir_all(dense.parent().unwrap()).unwrap();
    std::fs::write(
        &dense,
        text.replace("air_density_kg_m3 = 1.225", "air_density_kg_m3 = 1000.0"),
    )
    .unwrap();
    let r = drapekit(&["plan", dense.to_str().unwrap(), "--json"]);
    let plan: serde_json::Value = serde_json::from_slice(&r.stdout).unwrap();
    assert_eq!(plan["dt_limited_by"], "wind drag", "{plan:#}");
    let speed = (6.0f64.hypot(1.5)) * 1.3;
    let rate = 1000.0 * 1.2 * speed / 0.12;
    let dt = plan["dt"].as_f64().unwrap();
    assert!(rate * dt < 2.0, "γ·dt = {}", rate * dt);
}

/// Runs the shipped scene `fixtures/scenes/{scene}.toml` whole on the CPU path: its output
/// folder and its summary.
fn run_on_cpu(scene: &str) -> (PathBuf, serde_json::Value) {
    let out = out_dir(scene);
    let summary = run_file_on_cpu(&common::fixture(&format!("scenes/{scene}.toml")), &out);
    (out, summary)
}

/// `drapekit run PATH --backend cpu --out OUT`, which must succeed, and its summary.
fn run_file_on_cpu(path: &std::path::Path, out: &std::path::Path) -> serde_json::Value {
    let r = drapekit(&[
        "run",
        path.to_str().unwrap(),
        "--backend",
        "cpu",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap()
}

/// A garment run by implicit Euler with the strain limiter off has come to rest (speed and
/// force residual), sewn, and outside the body.
fn assert_rests_sewn_outside_the_body(scene: &str, summary: &serde_json::Value) {
    let f = |key: &str| summary[key].as_f64().unwrap_or(f64::NAN);
    assert_eq!(summary["integrator"], "implicit", "{scene}");
    assert!(
        summary["strain_limit"].is_null(),
        "{scene}: the cap must be off"
    );
    assert!(
        summary["settled"].is_object(),
        "{scene} not settled: {summary:#}"
    );
    // Settled means the solve balanced the forces, not only that the cloth slowed down.
    assert!(f("force_residual_rms") <= 0.05, "{scene}: {summary:#}");
    assert_eq!(
        summary["seams_closed"], summary["seams"],
        "{scene}: {summary:#}"
    );
    // The collision thickness is 3 mm; particles are measured against the exact mesh.
    assert!(f("max_penetration_m") <= 0.003, "{scene}: {summary:#}");
}

#[test]
fn tshirt_drape_cotton_sews_rests_and_stays_out_of_the_body() {
    // Woven cotton at its measured stiffness, implicit Euler at 8 substeps of one Newton step a
    // frame, the strain limiter off, run whole on the CPU path: sewn, then gravity, then the
    // settle rule (speed and force residual) stops it.
    let (out, summary) = run_on_cpu("tshirt_drape_cotton");
    assert_rests_sewn_outside_the_body("tshirt_drape_cotton", &summary);
    let f = |key: &str| summary[key].as_f64().unwrap_or(f64::NAN);
    // Woven cotton carries a draped shirt's few N/m at a fraction of a percent of strain: 99% of
    // the edges must rest under 2%. The few most stretched edges sit where the pattern is tight
    // on the mannequin; symplectic Euler at its stable step (the converged reference, 2,249
    // substeps a frame; docs/src/implicit.md) rests at 2.15% there, and the implicit solve must
    // stay within 1.5 times that. The CPU path gives the same bits on every machine and thread
    // count (2.77% and 1.02% when measured; 2.05% and 1.02% with each hinge's corners as world
    // positions).
    assert!(f("last_frame_edge_strain_p99") <= 0.02, "{summary:#}");
    assert!(
        f("last_frame_max_edge_strain") <= 1.5 * 0.0215,
        "{summary:#}"
    );
    for name in ["preview_fabric.png", "preview_strain.png"] {
        let path = out.join(name);
        if common::gpu().is_some() {
            assert!(path.is_file(), "{name} missing");
        }
    }
}

#[test]
fn the_gathered_skirt_rests_sewn_out_of_the_body() {
    // A cotton skirt gathered 3:2 into a waistband (a seam between edges of unequal length),
    // with springs that buckle, run whole on the CPU path until the settle rule stops it.
    let (_, summary) = run_on_cpu("skirt_gathered");
    assert_rests_sewn_outside_the_body("skirt_gathered", &summary);
    let f = |key: &str| summary[key].as_f64().unwrap_or(f64::NAN);
    // 99% of the edges under 2% (measured 1.86%). The largest (4.69% when measured) is in the
    // row along the gathered seam, where the 2.5 cm mesh is asked to take up a third of its
    // width between two particles; with linear springs the band stretched 26% there (15% at
    // the 99th percentile) and the gathered seams stayed open. So the largest must stay under
    // the strain limiter's 10% (the limiter is off): a band stretched as the linear one was
    // fails.
    assert!(f("last_frame_edge_strain_p99") <= 0.02, "{summary:#}");
    assert!(f("last_frame_max_edge_strain") <= 0.1, "{summary:#}");
}

#[test]
fn the_dart_fitted_pencil_skirt_rests_sewn_out_of_the_body() {
    // A cotton pencil skirt fitted by darts (seams between two edges of one panel) and side
    // seams, linear springs, run whole on the CPU path until the settle rule stops it: every
    // dart and side seam closed.
    let (_, summary) = run_on_cpu("skirt_pencil");
    assert_rests_sewn_outside_the_body("skirt_pencil", &summary);
    assert_eq!(
        summary["seams"], 8,
        "four darts, and two side seams sewn in two pieces each"
    );
    let f = |key: &str| summary[key].as_f64().unwrap_or(f64::NAN);
    // 99% of the edges under 2% (measured 1.1%); the largest (3.0% when measured, at the
    // waist's sides, where the 86 cm waist sits on the mannequin's widening hips) under the
    // strain limiter's 10% (the limiter is off), which a skirt held by the cap would reach.
    assert!(f("last_frame_edge_strain_p99") <= 0.02, "{summary:#}");
    assert!(f("last_frame_max_edge_strain") <= 0.1, "{summary:#}");
}

/// The cotton T-shirt scene in the jersey preset as the orthotropic membrane, `tension` =
/// `tension` ("linear" or "stiffening"), its seams as stiff as the cotton shirt's (8,100 N/m:
/// the knit's own default, twice its small-strain 42.9 N/m, leaves two seams open under either
/// law), written beside the run (its fixture paths made absolute), and its run on the CPU path.
fn run_jersey_shirt(tension: &str) -> serde_json::Value {
    let out = out_dir(&format!("jersey_{tension}"));
    std::fs::create_dir_all(&out).unwrap();
    let shipped = common::fixture("scenes/tshirt_drape_cotton.toml");
    let fixtures = shipped.parent().unwrap().parent().unwrap();
    let text = std::fs::read_to_string(&shipped).unwrap();
    let fabric = format!("preset = \"jersey\"\nmodel = \"membrane\"\ntension = \"{tension}\"");
    let text = (text.replace("preset = \"cotton\"", &fabric))
        .replace("\"../", &format!("\"{}/", fixtures.display()))
        .replace(
            "seam_sewing_time_s = 0.6",
            "seam_sewing_time_s = 0.6\nseam_stiffness_n_m = 8100.0",
        );
    let scene = out.join("scene_jersey.toml");
    std::fs::write(&scene, text).unwrap();
    run_file_on_cpu(&scene, &out.join("run"))
}

#[test]
fn a_stiffening_jersey_shirt_stretches_half_as_far_as_the_linear_knit() {
    // At the knit's small-strain stiffness (20.7 and 42.9 N/m) a hundredth of the shirt's
    // threads stretch 11.8% or more (measured); stiffening as W11 measured it (to 158 and 1,717
    // N/m by 1/6), 6.1%. The bound, 9%, lies between the two: a law that did not stiffen
    // fails it.
    let summary = run_jersey_shirt("stiffening");
    assert_rests_sewn_outside_the_body("jersey stiffening", &summary);
    let p99 = summary["last_frame_thread_strain"]["p99"].as_f64().unwrap();
    assert!(p99 <= 0.09, "{summary:#}");
}

#[test]
fn the_5_mm_shirts_rest_sewn_out_of_the_body_after_their_coarse_start() {
    // The shipped 5 mm T-shirts (37k particles), with linear springs and with springs that
    // buckle, run whole on the CPU path: the 2 cm shirt sewn and draped until it settles,
    // carried onto the 5 mm mesh, which then runs until the settle rule (speed and force
    // residual) stops it. One to one and a half minutes each on 2 cores (docs/src/implicit.md,
    // "Four steps a frame at 5 mm").
    for scene in ["tshirt_drape_hires", "tshirt_drape_hires_buckling"] {
        let (_, summary) = run_on_cpu(scene);
        assert_rests_sewn_outside_the_body(scene, &summary);
        let f = |key: &str| summary[key].as_f64().unwrap_or(f64::NAN);
        // The 2 cm shirt settled and handed over, and the 5 mm mesh then ran frames of its own
        // before the rule fired (it cannot fire on the hand-over frame).
        let coarse = &summary["coarse_start"];
        assert!(
            coarse["settled_frame"].is_u64(),
            "{scene}: the coarse start did not settle: {summary:#}"
        );
        let (handed_over, settled) = (
            coarse["frame"].as_u64(),
            summary["settled"]["frame"].as_u64(),
        );
        assert!(
            handed_over.is_some_and(|c| settled.is_some_and(|s| s > c)),
            "{scene}: {summary:#}"
        );
        // As the 2 cm shirt's: 99% of the edges under 2%, and the most stretched, where the
        // pattern is tight on the mannequin, within 1.5 times the 2 cm shirt's converged
        // reference (2.15%; the same pattern on the same body). Measured: 0.40% and 2.21%
        // (linear), 0.33% and 2.29% (buckling).
        assert!(
            f("last_frame_edge_strain_p99") <= 0.02,
            "{scene}: {summary:#}"
        );
        assert!(
            f("last_frame_max_edge_strain") <= 1.5 * 0.0215,
            "{scene}: {summary:#}"
        );
    }
}

#[test]
fn membrane_skirts_rest_sewn_at_their_thread_strain_and_the_bias_cut_rests_lower() {
    // The shipped cotton skirts as an orthotropic membrane, implicit Euler with the strain
    // limiter off, run whole on the CPU path until the settle rule (speed and force residual)
    // stops them. Cut on the bias, the waist takes the hips' pull in shear, 20 times softer,
    // and the skirt slides about 10 cm down before it rests: it must rest all the same.
    // (Measured: settled at frames 93 and 232 of 144 and 240.)
    let mut waists = Vec::new();
    for scene in ["skirt_straight_grain", "skirt_bias_cut"] {
        let (out, summary) = run_on_cpu(scene);
        assert_rests_sewn_outside_the_body(scene, &summary);
        waists.push((settled_heights(&out, &summary).into_iter()).fold(f64::MIN, f64::max));
        // Strain along the threads, the membrane's own measure (an edge across the grain also
        // stretches under shear): a skirt's weight is a few N/m against 4,000 N/m, so it rests
        // under 2% (measured: 1.97% and 1.09% largest).
        let threads = &summary["last_frame_thread_strain"];
        assert!(
            threads["max"].as_f64().unwrap() <= 0.02,
            "{scene}: {summary:#}"
        );
    }
    // Cut on the bias the skirt drapes differently: its waist gives and the skirt rests lower
    // on the hips (measured: 0.930 m and 0.829 m). Half the measured drop, two particle
    // spacings of this 2.5 cm mesh, is far beyond what a fold more or fewer moves the waist.
    let drop = waists[0] - waists[1];
    assert!(
        drop >= 0.05,
        "bias waist {} m against {} m",
        waists[1],
        waists[0]
    );
}

/// The height of every particle in the frame a run settled at (written as its last frame).
fn settled_heights(out: &std::path::Path, summary: &serde_json::Value) -> Vec<f64> {
    let frame = summary["settled"]["frame"]
        .as_u64()
        .expect("the run settled");
    let text = std::fs::read_to_string(out.join(format!("frame_{frame:04}.obj"))).unwrap();
    (text.lines().filter_map(|l| l.strip_prefix("v ")))
        .map(|v| v.split_whitespace().nth(1).unwrap().parse::<f64>().unwrap())
        .collect()
}

#[test]
fn every_subcommand_help_shows_an_example() {
    for sub in ["run", "resume", "info", "preview", "plan", "batch", "bench"] {
        let out = drapekit(&[sub, "--help"]);
        assert!(out.status.success(), "{sub} --help");
        let text = String::from_utf8_lossy(&out.stdout);
        // Each example is a full command line.
        assert!(
            text.contains("Example") && text.contains(&format!("drapekit {sub}")),
            "{sub} --help has no example:\n{text}"
        );
    }
}

#[test]
fn a_closed_stdout_ends_the_command_quietly() {
    // `drapekit info | head -0`: the reader is gone before drapekit prints. Rust ignores
    // SIGPIPE and would panic at the first println; drapekit restores the default action.
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_drapekit"))
        .arg("info")
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!stderr.contains("panicked"), "{stderr}");
}

#[test]
fn the_buckling_hires_shirt_is_the_hires_shirt_with_springs_that_buckle() {
    // The two scenes the book compares must stay one garment: parsed, they differ in the
    // fabric's compression law alone.
    let load = |name: &str| Scene::load(&common::fixture(&format!("scenes/{name}.toml"))).unwrap();
    let (linear, mut buckling) = (
        load("tshirt_drape_hires"),
        load("tshirt_drape_hires_buckling"),
    );
    assert!(!linear.fabric.buckling && buckling.fabric.buckling);
    buckling.fabric.buckling = false;
    // Their files, text and default output folders are their own.
    buckling.path = linear.path.clone();
    buckling.source = linear.source.clone();
    buckling.output.dir = linear.output.dir.clone();
    assert_eq!(buckling, linear);
}

#[test]
fn a_fas_coarsening_the_grid_cannot_take_is_warned_and_the_other_curves_written() {
    // The 17² hanging sheet has 16 intervals a side: a factor of 3 leaves no coarser grid, so
    // the benchmark says why it has no FAS curve instead of leaving it out in silence.
    let out = out_dir("convergence_fas_3");
    let scene = common::fixture("scenes/hanging_sheet_cotton.toml");
    let r = drapekit(&[
        "bench",
        "convergence",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--frames",
        "0",
        "--refinements",
        "1",
        "--max-sweeps",
        "2",
        "--max-newton",
        "1",
        "--fas-coarsening",
        "3",
    ]);
    let stderr = String::from_utf8_lossy(&r.stderr);
    assert!(r.status.success(), "{stderr}");
    assert!(
        stderr.contains("no FAS curve") && stderr.contains("--fas-coarsening 3"),
        "{stderr}"
    );
    let csv = std::fs::read_to_string(out.join("convergence.csv")).unwrap();
    assert!(
        csv.contains(",newton-multigrid,") && !csv.contains(",fas,"),
        "{csv}"
    );
}

#[test]
fn a_cloth_too_small_for_coarse_levels_is_refused_by_the_convergence_benchmark() {
    // A 3×3 sheet has no coarser grid, so there is no Newton step to measure: a clear error
    // (exit 2) naming the scene, not a panic.
    let dir = out_dir("convergence_small");
    std::fs::create_dir_all(&dir).unwrap();
    let text = std::fs::read_to_string(common::fixture("scenes/hanging_sheet_cotton.toml"))
        .unwrap()
        .replace("columns = 17", "columns = 3")
        .replace("rows = 17", "rows = 3");
    let scene = dir.join("small.toml");
    std::fs::write(&scene, text).unwrap();
    let r = drapekit(&[
        "bench",
        "convergence",
        scene.to_str().unwrap(),
        "--out",
        dir.join("out").to_str().unwrap(),
        "--frames",
        "0",
        "--refinements",
        "1",
    ]);
    let stderr = String::from_utf8_lossy(&r.stderr);
    assert_eq!(r.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("small.toml") && stderr.contains("no coarser levels"),
        "{stderr}"
    );
    assert!(!stderr.contains("panicked"), "{stderr}");
}
