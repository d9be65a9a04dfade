//! Runs report their own health: the result block, warnings for implausible inputs and for
//! results that went wrong (open seams, the body showing through, a torn frame, a garment
//! thrown off, no rest, a slow but unbalanced cloth), `--strict`, `--frames 0`, and the
//! strain limiter's report.

mod common;

use drapekit::scene::Scene;
use drapekit::sim::prepare;
use glam::Vec4;
use std::path::{Path, PathBuf};

fn out_dir(name: &str) -> PathBuf {
    common::out_dir("health", name)
}

fn summary(dir: &Path) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(dir.join("summary.json")).unwrap()).unwrap()
}

/// `fixtures/scenes/NAME` with `edits` (text replacements) applied, written into `dir` with its
/// relative paths made absolute.
fn edited_scene(dir: &Path, name: &str, edits: &[(&str, &str)]) -> PathBuf {
    let mut text = std::fs::read_to_string(common::fixture(&format!("scenes/{name}"))).unwrap();
    let fixtures = common::fixture("");
    text = text.replace("\"../", &format!("\"{}/", fixtures.display()));
    for (from, to) in edits {
        assert!(text.contains(from), "{name} has no {from:?}");
        text = text.replace(from, to);
    }
    std::fs::create_dir_all(dir).unwrap();
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

/// The cotton T-shirt at 5 cm spacing on a 1 cm distance field: seconds, not minutes.
fn coarse_shirt(dir: &Path) -> PathBuf {
    edited_scene(
        dir,
        "tshirt_drape_cotton.toml",
        &[
            ("particle_distance_m = 0.02", "particle_distance_m = 0.05"),
            ("sdf_resolution_m = 0.005", "sdf_resolution_m = 0.01"),
        ],
    )
}

fn run(scene: &Path, out: &Path, frames: &str, extra: &[&str]) -> std::process::Output {
    let mut args = vec![
        "run",
        scene.to_str().unwrap(),
        "--backend",
        "cpu",
        "--frames",
        frames,
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ];
    args.extend(extra);
    common::drapekit(&args)
}

#[test]
fn implausible_fabric_values_are_warned_and_strict_refuses_them_before_the_run() {
    // The slips a new user made: density in g/m², stretch in kN/m.
    let dir = out_dir("fabric");
    let scene = edited_scene(
        &dir,
        "hanging_cloth.toml",
        &[
            ("density_kg_m2 = 0.15", "density_kg_m2 = 220"),
            ("stretch_stiffness_n_m = 300.0", "stretch_stiffness_n_m = 3"),
        ],
    );
    let out = dir.join("out");
    let r = run(&scene, &out, "1", &[]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let stdout = String::from_utf8_lossy(&r.stdout);
    assert!(
        stdout.contains("result:") && stdout.contains("  warnings 2"),
        "{stdout}"
    );
    let warnings = summary(&out)["warnings"].clone();
    let text = warnings.to_string();
    assert!(
        text.contains("fabric.density_kg_m2: 220 kg/m² is above any real garment fabric's"),
        "{text}"
    );
    assert!(
        text.contains("write 0.22") && text.contains("write 3000"),
        "{text}"
    );
    // --strict: exit 5 and nothing run (no new summary).
    let strict = dir.join("strict");
    let r = run(&scene, &strict, "1", &["--strict"]);
    assert_eq!(
        r.status.code(),
        Some(5),
        "{}",
        String::from_utf8_lossy(&r.stderr)
    );
    assert!(String::from_utf8_lossy(&r.stderr).contains("nothing was run"));
    assert!(!strict.join("summary.json").exists());
}

#[test]
fn a_body_in_centimetres_is_named_with_the_unit_to_use() {
    // The mannequin scaled to centimetres but read as metres: 170 m tall. Its distance field
    // is refused; the message says which unit the mesh is in.
    let dir = out_dir("units");
    let mesh = std::fs::read_to_string(common::fixture("bodies/mannequin.obj")).unwrap();
    let cm: String = (mesh.lines())
        .map(|l| match l.strip_prefix("v ") {
            Some(v) => {
                let c: Vec<f64> = v.split_whitespace().map(|x| x.parse().unwrap()).collect();
                format!("v {} {} {}\n", 100.0 * c[0], 100.0 * c[1], 100.0 * c[2])
            }
            None => format!("{l}\n"),
        })
        .collect();
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("cm.obj"), cm).unwrap();
    let body = dir.join("cm.obj");
    let scene = edited_scene(
        &dir,
        "tshirt_drape_cotton.toml",
        &[(
            &format!("\"{}/bodies/mannequin.obj\"", common::fixture("").display()),
            &format!("\"{}\"", body.display()),
        )],
    );
    let r = run(&scene, &dir.join("out"), "1", &[]);
    assert_eq!(r.status.code(), Some(2));
    let err = String::from_utf8_lossy(&r.stderr);
    assert!(err.contains("units = \"cm\""), "{err}");
    assert!(
        err.contains("warning: ") && err.contains("body.units"),
        "{err}"
    );
}

#[test]
fn open_seams_are_a_warning_and_strict_fails_after_writing_the_run() {
    let dir = out_dir("seams");
    let scene = coarse_shirt(&dir);
    // Three frames: the seams are drawn shut over 0.6 s, so they are still open.
    let out = dir.join("out");
    let r = run(&scene, &out, "3", &["--strict"]);
    assert_eq!(
        r.status.code(),
        Some(5),
        "{}",
        String::from_utf8_lossy(&r.stderr)
    );
    let stdout = String::from_utf8_lossy(&r.stdout);
    assert!(stdout.contains("  seams    0 of 12 closed"), "{stdout}");
    let s = summary(&out);
    let text = s["warnings"].to_string();
    assert!(
        text.contains("12 of 12 seams are still open at the last frame"),
        "{text}"
    );
    assert!(
        out.join("frame_0003.obj").is_file(),
        "the run's files are written"
    );
}

#[test]
fn the_body_shows_through_a_sheet_cut_by_it_and_not_one_above_it() {
    // The sphere scene's sheet moved down through the sphere: triangles inside it. Its start
    // position, above the sphere: none.
    let scene = Scene::load(&common::fixture("scenes/drape_sphere.toml")).unwrap();
    let prep = prepare(&scene).unwrap();
    let above: Vec<Vec4> = prep.model.positions.iter().map(|p| p.extend(1.0)).collect();
    let clear = drapekit::health::show_through(&prep, &above, 0).unwrap();
    assert_eq!((clear.particles, clear.triangles), (0, 0));
    let body = &prep.model.colliders[0].body.mesh.positions;
    let centre = body.iter().copied().sum::<glam::Vec3>() / body.len() as f32;
    let top = prep
        .model
        .positions
        .iter()
        .map(|p| p.y)
        .fold(f32::MIN, f32::max);
    let cut: Vec<Vec4> = (prep.model.positions.iter())
        .map(|p| (*p - glam::Vec3::Y * (top - centre.y)).extend(1.0))
        .collect();
    let through = drapekit::health::show_through(&prep, &cut, 0).unwrap();
    assert!(
        through.triangles > 0 && through.particles > 0,
        "{through:?}"
    );
    // The sheet through the centre: the deepest point is the sphere's radius deep, within the
    // mesh's facets (the sphere is a polyhedron inside the true sphere).
    let radius = body.iter().map(|p| p.distance(centre)).fold(0.0, f32::max);
    assert!(
        through.deepest_m <= radius && through.deepest_m > 0.8 * radius,
        "{through:?}"
    );
}

#[test]
fn zero_frames_are_refused() {
    let scene = common::fixture("scenes/hanging_cloth.toml");
    let out = out_dir("zero");
    let r = run(&scene, &out, "0", &[]);
    assert_eq!(r.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&r.stderr).contains("0 frames simulate nothing"));
    assert!(!out.exists());
}

#[test]
fn a_strain_limit_on_implicit_euler_reports_the_edges_it_holds() {
    // The hanging cloth (300 N/m, pinned at two corners) under implicit Euler: the corners'
    // edges carry the whole sheet's 1.5 N and stretch well past 0.5%. Off by default, the
    // limiter holds nothing and the summary says so with null; at 0.5% it holds those edges,
    // and the summary counts them, so that nobody mistakes the cap for the solve.
    let dir = out_dir("clamped");
    let implicit = [
        ("integrator = \"symplectic\"", "integrator = \"implicit\""),
        ("substeps = \"auto\"", "substeps = 4"),
    ];
    let free = edited_scene(&dir.join("free"), "hanging_cloth.toml", &implicit);
    let capped_edits = [
        implicit[0],
        ("substeps = \"auto\"", "substeps = 4\nstrain_limit = 0.005"),
    ];
    let capped = edited_scene(&dir.join("capped"), "hanging_cloth.toml", &capped_edits);
    for (scene, out) in [
        (&free, dir.join("free-run")),
        (&capped, dir.join("capped-run")),
    ] {
        let r = run(scene, &out, "6", &[]);
        assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    }
    let (free, capped) = (
        summary(&dir.join("free-run")),
        summary(&dir.join("capped-run")),
    );
    assert!(free["strain_limit"].is_null(), "{free:#}");
    assert!(free["strain_limit_clamped_edges"].is_null(), "{free:#}");
    assert!(
        free["last_frame_max_edge_strain"].as_f64().unwrap() > 0.005,
        "{free:#}"
    );
    assert!((capped["strain_limit"].as_f64().unwrap() - 0.005).abs() < 1e-9);
    let held = capped["strain_limit_clamped_edges"].as_u64().unwrap();
    assert!(held > 0, "{capped:#}");
}

#[test]
fn a_cloth_that_is_slow_because_the_solve_carries_no_load_has_not_settled() {
    // The cotton sheet hanging from two corners, stepped by plain sweeps (no multigrid) at one
    // sweep a substep: each particle's local solve meets springs 3,000 N/m stiff whose other
    // ends have not moved, so in the first frame the sheet hardly moves (measured 1.4 mm/s)
    // although nothing yet carries its weight. A speed rule alone (the force limit set out of
    // reach) calls that rest; the settle rule must not, and rests it only once the forces
    // balance.
    let dir = out_dir("unbalanced");
    let sweeps = "settle_speed_m_s = 0.005\nmultigrid = false";
    let speed_only = format!("{sweeps}\nsettle_force_residual = 1000.0");
    let name = "hanging_sheet_cotton.toml";
    let runs = [("speed-only", speed_only.as_str()), ("settle-rule", sweeps)];
    let mut summaries = Vec::new();
    for (tag, edit) in runs {
        let scene = edited_scene(&dir.join(tag), name, &[("settle_speed_m_s = 0.005", edit)]);
        let out = dir.join(format!("{tag}-run"));
        let r = run(&scene, &out, "96", &[]);
        assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
        summaries.push(summary(&out));
    }
    let f = |s: &serde_json::Value, key: &str| s[key].as_f64().unwrap_or(f64::NAN);
    let (slow, rested) = (&summaries[0], &summaries[1]);
    // The speed rule fires at once, with the weight unbalanced: an RMS force residual of a
    // particle's whole weight or more (measured 1.57), and the sheet barely stretched.
    assert_eq!(slow["settled"]["frame"], 1, "{slow:#}");
    assert!(f(slow, "force_residual_rms") >= 1.0, "{slow:#}");
    // And it is told so; the run that rests by the settle rule is not.
    let unbalanced = |s: &serde_json::Value| s["warnings"].to_string().contains("unbalanced");
    assert!(unbalanced(slow), "{slow:#}");
    assert!(!unbalanced(rested), "{rested:#}");
    // The settle rule waits for the balance (measured: frame 86, residual 0.038). By then the
    // sheet carries its weight to the pins, and its most loaded edge, at a corner, stretches
    // more than ten times as far as at the speed rule's stop (measured 0.45% and 0.031%).
    let frame = rested["settled"]["frame"].as_u64();
    assert!(frame.is_some_and(|f| f > 24), "{rested:#}");
    assert!(f(rested, "force_residual_rms") <= 0.05, "{rested:#}");
    let strain = |s| f(s, "last_frame_max_edge_strain");
    assert!(strain(rested) > 10.0 * strain(slow), "{slow:#}\n{rested:#}");
}

#[test]
fn a_torn_frame_and_a_garment_thrown_off_the_body_are_warned() {
    // The cotton T-shirt prepared as the coarse shirt runs it, and the stats a run would end
    // with. An edge stretched past 1.5 times its rest length at some frame (the walking skirt
    // stepped by one Newton step a substep reached 247% when the step diverged, and fell off
    // the body) is a warning even when the cloth came back together: 55% warns, 45% does not.
    // A sewn garment touching no body a second after its seams closed and gravity came on has
    // been thrown off; before that it may still be closing around the body or falling onto it.
    let dir = out_dir("thrown");
    let prep = prepare(&Scene::load(&coarse_shirt(&dir)).unwrap()).unwrap();
    let second = (1.0 / prep.frame_dt).round() as u32;
    let settled_in = prep.gravity.1 + second;
    let stats =
        |max_edge_strain: f32, body_contacts: usize, frames_run: u32| drapekit::sim::RunStats {
            max_edge_strain,
            body_contacts,
            frames_run,
            seams_closed_frame: Some(prep.gravity.1),
            ..Default::default()
        };
    // The stats leave the run unsettled, which is a warning of its own; these are the others.
    let warned = |s: &drapekit::sim::RunStats| -> Vec<String> {
        let all = drapekit::health::result_warnings(&prep, s, None, true);
        all.into_iter()
            .filter(|w| !w.contains("did not settle"))
            .collect()
    };
    let torn = warned(&stats(2.47, 200, settled_in));
    assert!(
        torn.len() == 1 && torn[0].contains("an edge stretched 247% at some frame"),
        "{torn:?}"
    );
    assert_eq!(warned(&stats(0.55, 200, settled_in)).len(), 1);
    assert!(warned(&stats(0.45, 200, settled_in)).is_empty());
    let thrown = warned(&stats(0.1, 0, settled_in));
    assert!(
        thrown.len() == 1 && thrown[0].contains("the garment touches no body"),
        "{thrown:?}"
    );
    // Less than a second after gravity and the seams, or never sewn: not yet.
    assert!(warned(&stats(0.1, 0, settled_in - 1)).is_empty());
    let unsewn = drapekit::sim::RunStats {
        seams_closed_frame: None,
        ..stats(0.1, 0, settled_in)
    };
    assert!(warned(&unsewn).is_empty());
}
