//! The bad-input corpus in fixtures/bad/: every file makes `drapekit run` exit with code 2 (or
//! the code its `# exit:` line gives: 1 for a folder that cannot be written), a message naming
//! the file, the key (with its line where the format has one) and a fix, no panic, and no output
//! folder.

mod common;

use std::process::Command;

/// `drapekit run s.toml --backend cpu --quiet --overwrite --out OUT` on `scene` (its
/// text), written as s.toml in this test's own temporary folder `tag`: the exit code and
/// stderr. The folder is removed afterwards.
fn run_scene_text(tag: &str, scene: &str) -> (Option<i32>, String) {
    let work = std::env::temp_dir().join(format!("drapekit-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&work).unwrap();
    std::fs::write(work.join("s.toml"), scene).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_drapekit"))
        .args([
            "run",
            work.join("s.toml").to_str().unwrap(),
            "--backend",
            "cpu",
        ])
        .args([
            "--quiet",
            "--overwrite",
            "--out",
            work.join("out").to_str().unwrap(),
        ])
        .output()
        .unwrap();
    let _ = std::fs::remove_dir_all(&work);
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// What a run that stopped (exit 3) says after "simulation stopped": the advice.
fn advice_after_stop(code: Option<i32>, stderr: &str) -> &str {
    assert_eq!(code, Some(3), "{stderr}");
    let stopped = stderr.find("simulation stopped").expect("the run stops");
    &stderr[stopped..]
}

#[test]
fn every_bad_scene_is_refused_cleanly() {
    let dir = common::fixture("bad");
    let mut checked = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().and_then(|e| e.to_str()) != Some("toml") {
            continue;
        }
        let text = std::fs::read_to_string(&path).unwrap();
        let header = Header::read(&text);
        assert!(
            !header.expect.is_empty(),
            "{} lacks its '# expect: ' line",
            path.display()
        );
        // "# backend: gpu": a limit of the GPU path, checked on the fallback adapter.
        let gpu = header.backend.as_deref() == Some("gpu");
        if gpu && common::gpu().is_none() {
            continue;
        }
        // "# out: PATH": the run writes there instead of a fresh folder ({scene} is this file).
        let given_out = header
            .out
            .as_ref()
            .map(|o| std::path::PathBuf::from(o.replace("{scene}", path.to_str().unwrap())));
        if given_out
            .as_ref()
            .is_some_and(|o| !o.parent().is_some_and(|p| p.exists()))
        {
            continue; // e.g. no /sys on this system
        }
        let out = given_out.clone().unwrap_or_else(|| tempdir(&path));
        let existed = out.exists();
        let backend: &[&str] = if gpu {
            &["--backend", "gpu", "--adapter", "fallback"]
        } else {
            &["--backend", "cpu"]
        };
        let result = Command::new(env!("CARGO_BIN_EXE_drapekit"))
            .args(["run", path.to_str().unwrap()])
            .args(backend)
            .args(["--out", out.to_str().unwrap()])
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&result.stderr);
        let name = path.file_name().unwrap().to_str().unwrap();
        assert_eq!(
            result.status.code(),
            Some(header.exit),
            "{name}: exit code; stderr:\n{stderr}"
        );
        for expect in &header.expect {
            assert!(
                stderr.contains(expect.as_str()),
                "{name}: expected {expect:?} in:\n{stderr}"
            );
        }
        assert!(stderr.contains("fix:"), "{name}: no fix in:\n{stderr}");
        assert!(!stderr.contains("panicked"), "{name}: panicked:\n{stderr}");
        assert_eq!(out.exists(), existed, "{name}: wrote {}", out.display());
        checked += 1;
    }
    assert!(checked >= 13, "only {checked} bad scenes found");
}

/// The `# key: value` comment lines that open a corpus scene.
#[derive(Default)]
struct Header {
    /// Texts the error must contain (`# expect:`, one or more).
    expect: Vec<String>,
    /// `# backend: gpu` for a limit of the GPU path.
    backend: Option<String>,
    /// `# out: PATH`, the output folder to give the run.
    out: Option<String>,
    /// `# exit: N`, the exit code (2, bad input, unless given).
    exit: i32,
}

impl Header {
    fn read(text: &str) -> Header {
        let mut h = Header {
            exit: 2,
            ..Header::default()
        };
        for line in text.lines().map_while(|l| l.strip_prefix("# ")) {
            match line.split_once(": ") {
                Some(("expect", v)) => h.expect.push(v.to_string()),
                Some(("backend", v)) => h.backend = Some(v.to_string()),
                Some(("out", v)) => h.out = Some(v.to_string()),
                Some(("exit", v)) => h.exit = v.parse().expect("# exit: takes a number"),
                _ => break,
            }
        }
        h
    }
}

fn tempdir(scene: &std::path::Path) -> std::path::PathBuf {
    let stem = scene.file_stem().unwrap().to_str().unwrap();
    let dir = std::env::temp_dir().join(format!("drapekit-bad-{}-{stem}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

/// fixtures/bad/patterns/: each `X.json` is a broken GarmentCode pattern and `X.expect` lists
/// the texts its error must contain (the panel and edge or stitch, and what is wrong).
#[test]
fn every_bad_pattern_is_refused_cleanly() {
    let dir = common::fixture("bad/patterns");
    let mut checked = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().and_then(|e| e.to_str()) != Some("json") {
            continue;
        }
        let name = path.file_name().unwrap().to_str().unwrap().to_string();
        let expect = std::fs::read_to_string(path.with_extension("expect"))
            .unwrap_or_else(|_| panic!("{name} lacks its .expect file"));
        // Not tempdir(): a bad scene may share this stem, and the two tests run in parallel.
        let stem = path.file_stem().unwrap().to_str().unwrap();
        let work =
            std::env::temp_dir().join(format!("drapekit-badpattern-{}-{stem}", std::process::id()));
        let _ = std::fs::remove_dir_all(&work);
        std::fs::create_dir_all(&work).unwrap();
        let scene = work.join("scene.toml");
        let scene_text = format!(
            "[cloth.pattern]\npath = {:?}\n\n[fabric]\ndensity_kg_m2 = 0.15\n\
             stretch_stiffness_n_m = 300.0\n\n[solver]\nfps = 24\nframes = 2\n",
            path.to_str().unwrap()
        );
        std::fs::write(&scene, scene_text).unwrap();
        let out = work.join("out");
        let result = Command::new(env!("CARGO_BIN_EXE_drapekit"))
            .args(["run", scene.to_str().unwrap(), "--backend", "cpu"])
            .args(["--out", out.to_str().unwrap()])
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&result.stderr);
        assert_eq!(
            result.status.code(),
            Some(2),
            "{name}: exit code; stderr:\n{stderr}"
        );
        assert!(
            stderr.contains(&name),
            "{name}: the error does not name the file:\n{stderr}"
        );
        for line in expect.lines().filter(|l| !l.is_empty()) {
            assert!(
                stderr.contains(line),
                "{name}: expected {line:?} in:\n{stderr}"
            );
        }
        assert!(stderr.contains("fix:"), "{name}: no fix in:\n{stderr}");
        assert!(!stderr.contains("panicked"), "{name}: panicked:\n{stderr}");
        assert!(!out.exists(), "{name}: wrote {}", out.display());
        checked += 1;
    }
    assert!(checked >= 9, "only {checked} bad patterns found");
}

#[test]
fn particle_estimates_are_close_for_the_shipped_garments() {
    // The memory check refuses scenes from this estimate before building anything; it must be
    // close to what is built. The pattern estimate counts panel area over the area of one
    // equilateral-mesh particle, and the mesher keeps the outline's samples, so it may be off
    // by the boundary's share: 20% bounds it at 2 cm and finer.
    for scene in ["tshirt_drape_cotton.toml", "skirt_rotating.toml"] {
        let mut scene =
            drapekit::scene::Scene::load(&common::fixture(&format!("scenes/{scene}"))).unwrap();
        scene.bodies.clear();
        let estimate = drapekit::model::budget::estimated_particles(&scene)
            .unwrap()
            .unwrap() as f64;
        let built = scene.build_model().unwrap().model.len() as f64;
        eprintln!("estimate {estimate}, built {built}");
        assert!(
            (estimate / built - 1.0).abs() < 0.2,
            "{estimate} vs {built}"
        );
    }
}

#[test]
fn budgets_are_refused_in_well_under_a_second() {
    // Each of these would take minutes, or abort, if it were built: a 64M-particle grid, a
    // 400M-particle grid under a cap above the machine's memory, a 2.9 TB SDF, 4 billion OBJ
    // frames. Process start, a TOML parse and a sphere's bounding box take milliseconds.
    for (fixture, key) in [
        ("grid_too_big.toml", "max_memory_mb"),
        ("grid_beyond_machine_memory.toml", "more than it has"),
        ("body_sdf_beyond_memory.toml", "sdf_resolution_m = "),
        ("frames_beyond_disk.toml", "free on the disk"),
    ] {
        let start = std::time::Instant::now();
        let out = Command::new(env!("CARGO_BIN_EXE_drapekit"))
            .args([
                "plan",
                common::fixture(&format!("bad/{fixture}")).to_str().unwrap(),
            ])
            .output()
            .unwrap();
        let elapsed = start.elapsed().as_secs_f64();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{fixture}: {stderr}");
        assert!(stderr.contains(key), "{fixture}: {stderr}");
        assert!(elapsed < 1.0, "{fixture} took {elapsed} s");
    }
}

#[test]
fn a_unit_slip_is_warned_before_the_garment_is_meshed() {
    // The T-shirt in cm read as metres (units_in_meter = 1) is 60 m across: 7.6 million
    // particles at 2 cm. The warning names units_in_meter; the memory cap then refuses it
    // before anything is meshed.
    let work = std::env::temp_dir().join(format!("drapekit-units-{}", std::process::id()));
    std::fs::create_dir_all(&work).unwrap();
    let mut pattern: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(common::fixture("patterns/tshirt.json")).unwrap(),
    )
    .unwrap();
    pattern["properties"]["units_in_meter"] = serde_json::json!(1);
    std::fs::write(work.join("p.json"), pattern.to_string()).unwrap();
    std::fs::write(
        work.join("s.toml"),
        "[cloth.pattern]\npath = \"p.json\"\nparticle_distance_m = 0.02\n[fabric]\n\
         preset = \"cotton\"\n[solver]\nframes = 1\nmax_memory_mb = 512\n",
    )
    .unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_drapekit"))
        .args(["plan", work.join("s.toml").to_str().unwrap()])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    let warning = stderr.find("warning").expect("a warning");
    assert!(
        stderr[warning..].contains("units_in_meter = 1 the garment spans"),
        "{stderr}"
    );
    assert!(stderr.contains("larger than any garment"), "{stderr}");
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.find("max_memory_mb").unwrap() > warning, "{stderr}");
    // The refusal's fix names the unit before a coarser spacing, which would mesh millions of
    // particles of a garment 60 m across.
    let fix = stderr.rfind("fix: ").expect("a fix");
    assert!(
        stderr[fix..].starts_with("fix: first check units_in_meter in"),
        "{stderr}"
    );
    let _ = std::fs::remove_dir_all(&work);
}

#[test]
fn a_spacing_too_coarse_for_the_garment_is_warned_with_one_that_keeps_its_cut() {
    // The T-shirt's panels span 1.1 m as the pattern places them: at 0.5 m, 2.2 spacings, a
    // few dozen particles. The warning names the scene's line and key, and the spacing with
    // ten across (0.11 m); the shipped 2 cm is not warned.
    let work = std::env::temp_dir().join(format!("drapekit-coarse-{}", std::process::id()));
    std::fs::create_dir_all(&work).unwrap();
    let pattern = common::fixture("patterns/tshirt.json");
    let plan = |spacing: &str| {
        let scene = format!(
            "[cloth.pattern]\npath = {:?}\nparticle_distance_m = {spacing}\n[fabric]\n\
             preset = \"cotton\"\n[solver]\nframes = 1\n",
            pattern.to_str().unwrap()
        );
        std::fs::write(work.join("s.toml"), scene).unwrap();
        let out = Command::new(env!("CARGO_BIN_EXE_drapekit"))
            .args(["plan", work.join("s.toml").to_str().unwrap()])
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(0));
        String::from_utf8_lossy(&out.stderr).into_owned()
    };
    let coarse = plan("0.5");
    assert!(
        coarse.contains("s.toml:3: cloth.pattern.particle_distance_m: 0.500 m is 2.2 spacings"),
        "{coarse}"
    );
    assert!(
        coarse.contains("fix: use particle_distance_m = 0.110 or less"),
        "{coarse}"
    );
    let shipped = plan("0.02");
    assert!(!shipped.contains("spacings across"), "{shipped}");
    let _ = std::fs::remove_dir_all(&work);
}

#[test]
fn seams_far_stiffer_than_the_fabric_are_warned_and_named_when_the_run_explodes() {
    // Seams at 1e9 N/m, about 250,000 times cotton's stretch stiffness, pull the T-shirt's
    // panels shut within the first frame and tear it. The scene is warned at its line, and the
    // explosion names the seams rather than the substeps. (100 times the fabric's runs: 6% at
    // most over 30 frames at 4 cm.)
    let scene = format!(
        "[cloth.pattern]\npath = {:?}\nparticle_distance_m = 0.04\nseam_stiffness_n_m = 1e9\n\
         seam_sewing_time_s = 0.6\n[fabric]\npreset = \"cotton\"\n[solver]\nframes = 2\n\
         substeps = 8\nintegrator = \"implicit\"\n[output]\nobj = false\n",
        common::fixture("patterns/tshirt_apose_woven.json")
    );
    let (code, stderr) = run_scene_text("seams", &scene);
    assert!(
        stderr.contains("s.toml:4: cloth.pattern.seam_stiffness_n_m: 246914 times the fabric's"),
        "{stderr}"
    );
    assert!(
        advice_after_stop(code, &stderr).contains("the seams pulled the panels together at once"),
        "{stderr}"
    );
}

#[test]
fn a_wind_past_any_storm_is_warned_and_blamed_when_the_cloth_flies_apart() {
    // 500 m/s with 30% gusts on a flag pinned at one edge: the drag sets the substep (auto),
    // and the cloth is flung past 100 m/s within a few frames. The advice names the wind, not
    // the substep the drag already chose.
    let (code, stderr) = run_scene_text(
        "gale",
        "[cloth.grid]\nwidth_m = 1.5\nheight_m = 1.0\ncolumns = 36\nrows = 24\n\
         center_m = [0.75, 2.0, 0.0]\nplane = \"xy\"\n[fabric]\ndensity_kg_m2 = 0.12\n\
         stretch_stiffness_n_m = 400.0\nbending_stiffness_n_m = 1e-5\ndamping_ratio = 0.1\n\
         [[pins]]\nedge = \"left\"\n[wind]\nvelocity_m_s = [500.0, 0.0, 0.0]\n\
         gust_amplitude = 0.3\n[solver]\nframes = 6\nsubsteps = \"auto\"\n\
         integrator = \"symplectic\"\n[output]\nobj = false\n",
    );
    assert!(
        stderr.contains("s.toml:16: wind.velocity_m_s: its gusts reach 650 m/s"),
        "{stderr}"
    );
    assert!(
        advice_after_stop(code, &stderr)
            .contains("chosen for the wind's drag, the wind tore the cloth"),
        "{stderr}"
    );
}

#[test]
fn a_body_the_cloth_cannot_reach_in_the_run_is_warned() {
    // A 1 m cloth at 0.65 m over a 0.3 m sphere: reached. The same sphere 100 m to the side:
    // in 2 frames the cloth falls 3 cm and reaches 1 m around itself, so it touches nothing.
    // Below by 5 m, 48 frames (2 s): a free fall covers 19.6 m, so the sphere is reached.
    let warned_with = |center: &str, frames: u32, extra: &str| {
        let (code, stderr) = run_scene_text(
            "far",
            &format!(
                "[cloth.grid]\nwidth_m = 1.0\nheight_m = 1.0\ncolumns = 6\nrows = 6\n\
                 center_m = [0.0, 0.65, 0.0]\n[fabric]\npreset = \"cotton\"\n[body]\n\
                 shape = \"sphere\"\nradius_m = 0.3\ncenter_m = {center}\n\
                 sdf_resolution_m = 0.05\n[solver]\nframes = {frames}\nsubsteps = 4\n\
                 integrator = \"implicit\"\n[output]\nobj = false\n{extra}"
            ),
        );
        assert_eq!(code, Some(0), "{stderr}");
        stderr.contains("touches nothing").then_some(stderr)
    };
    let warned = |center: &str, frames: u32| warned_with(center, frames, "");
    assert_eq!(warned("[0.0, 0.0, 0.0]", 2), None);
    let far = warned("[100.0, 0.0, 0.0]", 2).expect("warned");
    assert!(
        far.contains("s.toml:12: body.center_m: the body is 99.20 m from the cloth"),
        "{far}"
    );
    assert_eq!(warned("[0.0, -5.0, 0.0]", 48), None);
    // An updraft of 10 m/s for 2 s against gravity: the fall and the lift each count, so a
    // sphere 3.35 m above is within reach though ½gt² + wt ends 0.38 m up.
    let updraft = "[wind]\nvelocity_m_s = [0.0, 10.0, 0.0]\n";
    assert_eq!(warned_with("[0.0, 4.0, 0.0]", 48, updraft), None);
}

#[test]
fn panels_placed_far_apart_are_warned_for_their_placement_not_their_unit() {
    // The two-panel skirt with one panel moved 1 km (in the pattern's centimetres): each panel
    // is 0.63 m, so the unit is right and the translation is what to check.
    let work = std::env::temp_dir().join(format!("drapekit-apart-{}", std::process::id()));
    std::fs::create_dir_all(&work).unwrap();
    let scene = format!(
        "[cloth.pattern]\npath = {:?}\nparticle_distance_m = 0.04\n\
         [cloth.pattern.placement.skirt_front]\ntranslation = [100000.0, 0.0, 0.0]\n\
         [fabric]\npreset = \"cotton\"\n[solver]\nframes = 1\n",
        common::fixture("patterns/skirt_2panel.json")
    );
    std::fs::write(work.join("s.toml"), scene).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_drapekit"))
        .args(["plan", work.join("s.toml").to_str().unwrap()])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("the panels are placed across 100"),
        "{stderr}"
    );
    assert!(stderr.contains("check their translations"), "{stderr}");
    assert!(!stderr.contains("units_in_meter"), "{stderr}");
    let _ = std::fs::remove_dir_all(&work);
}

#[test]
fn a_self_collision_layer_of_metres_is_blamed_when_the_cloth_flies_apart() {
    // A 10 m self-collision thickness on a 0.5 m cloth of 7 cm edges: every particle repels
    // every other, the first frame tears it, and the advice names the thickness (it is
    // warned before the run too), not the substep.
    let (code, stderr) = run_scene_text(
        "selfthick",
        "[cloth.grid]\nwidth_m = 0.5\nheight_m = 0.5\ncolumns = 8\nrows = 8\n\
         [fabric]\npreset = \"cotton\"\n[self_collision]\nthickness_m = 10\n\
         [solver]\nframes = 2\n[output]\nobj = false\n",
    );
    assert!(
        advice_after_stop(code, &stderr).contains("self-collision pushed the cloth apart"),
        "{stderr}"
    );
}

#[test]
fn a_shape_thinner_than_its_distance_field_s_spacing_is_warned() {
    // A sphere of radius 1 µm under the default 1 cm field: nothing for the cloth to meet. At
    // 2 cm across (radius 1 cm) it is resolved.
    let warned = |radius: &str| {
        let (code, stderr) = run_scene_text(
            "thin",
            &format!(
                "[cloth.grid]\nwidth_m = 0.5\nheight_m = 0.5\ncolumns = 6\nrows = 6\n\
                 center_m = [0.0, 0.1, 0.0]\n[fabric]\npreset = \"cotton\"\n[body]\n\
                 shape = \"sphere\"\nradius_m = {radius}\n[solver]\nframes = 1\n\
                 [output]\nobj = false\n"
            ),
        );
        assert_eq!(code, Some(0), "{stderr}");
        stderr.contains("thick at its thinnest").then_some(stderr)
    };
    let tiny = warned("1e-6").expect("warned");
    assert!(
        tiny.contains("s.toml:11: body.radius_m: the shape is 2.000e-6 m thick"),
        "{tiny}"
    );
    assert_eq!(warned("0.01"), None);
}

#[test]
fn a_long_crossing_outline_is_found_in_seconds() {
    // A thin panel 75 m long that folds over itself at the far end, meshed at 1 mm: 150,000
    // outline particles. Testing every pair of segments took seconds (and 726 s for a typo's
    // longer outline); the R-tree finds the crossing in a fraction of a second.
    let work = std::env::temp_dir().join(format!("drapekit-cross-{}", std::process::id()));
    std::fs::create_dir_all(&work).unwrap();
    let pattern = serde_json::json!({
        "properties": {"units_in_meter": 100},
        "pattern": {"panels": {"strip": {
            "vertices": [[0, 0], [7500, 0], [7490, 1], [7495, -1], [0, 1]],
            "edges": [{"endpoints": [0, 1]}, {"endpoints": [1, 2]}, {"endpoints": [2, 3]},
                      {"endpoints": [3, 4]}, {"endpoints": [4, 0]}]
        }}, "stitches": []}
    });
    std::fs::write(work.join("p.json"), pattern.to_string()).unwrap();
    std::fs::write(
        work.join("s.toml"),
        "[cloth.pattern]\npath = \"p.json\"\nparticle_distance_m = 0.001\n[fabric]\n\
         preset = \"cotton\"\n[solver]\nframes = 1\n",
    )
    .unwrap();
    let start = std::time::Instant::now();
    let out = Command::new(env!("CARGO_BIN_EXE_drapekit"))
        .args(["plan", work.join("s.toml").to_str().unwrap()])
        .output()
        .unwrap();
    let elapsed = start.elapsed().as_secs_f64();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("panel 'strip': outline intersects itself"),
        "{stderr}"
    );
    // Sampling 160,000 points and the test itself: well under a second; 3 s leaves room for
    // a loaded machine.
    assert!(elapsed < 3.0, "took {elapsed} s");
    let _ = std::fs::remove_dir_all(&work);
}

#[test]
fn a_built_model_too_large_for_the_gpu_names_its_largest_array() {
    // An OBJ cloth has no estimate, so the GPU path checks the built model. A limit just
    // below the hanging cloth's largest array (its hinge list: 4 entries per hinge) must
    // refuse it with the array's size and a vertex count that fits; at the array's size it fits.
    let scene =
        drapekit::scene::Scene::load(&common::fixture("scenes/hanging_cloth.toml")).unwrap();
    let model = scene.build_model().unwrap().model;
    let largest = model.largest_array() as u64;
    assert_eq!(
        largest,
        4 * model.hinges.len() as u64,
        "the hinge list is the largest"
    );
    let check = |limit| drapekit::model::budget::check_model_textures(&scene, &model, limit);
    assert!(check(largest).is_ok());
    let refused = check(largest - 1).unwrap_err().to_string();
    assert!(
        refused.contains(&format!("an array of {largest} elements")) && refused.contains("fix:"),
        "{refused}"
    );
}
