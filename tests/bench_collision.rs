//! Smoke test of `drapekit bench collision --quick` on the shipped skirt: the command finishes
//! with a row per strategy, its CSV has the documented columns with finite values, and the
//! strategies that answer the same question agree on the contacts.

mod common;

use drapekit::bench::collision::CSV_COLUMNS;
use std::collections::HashMap;

type Row = HashMap<String, String>;

/// `drapekit bench collision --quick` on the scene `name` into a test folder called `folder`:
/// the folder, and its CSV's header and rows.
fn quick_run(name: &str, folder: &str) -> (std::path::PathBuf, Vec<String>, Vec<Row>) {
    let out = common::out_dir("bench-collision", folder);
    let scene = common::fixture(&format!("scenes/{name}"));
    let r = common::drapekit(&[
        "bench",
        "collision",
        "--quick",
        "--adapter",
        "fallback",
        "--scene",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let (header, rows) = common::read_csv(&out.join("collision.csv"), "note");
    (out, header, rows)
}

#[test]
fn bench_collision_quick_writes_every_strategy() {
    let gpu = common::gpu().is_some();
    let (out, header, rows) = quick_run("skirt_collision.toml", "quick");
    assert_eq!(header, CSV_COLUMNS);
    assert_eq!(
        header,
        documented_columns(),
        "the book and the CSV disagree"
    );
    let by_name: HashMap<&str, &Row> = rows.iter().map(|r| (r["strategy"].as_str(), r)).collect();
    let mut expected = vec![
        "sdf",
        "bvh-aabb",
        "bvh-obb",
        "bvh-sphere",
        "exact",
        "exact+edges",
        "brute",
    ];
    if gpu {
        expected.push("gpu-sdf");
    }
    assert_eq!(rows.len(), expected.len(), "{:?}", by_name.keys());
    for name in &expected {
        let row = by_name[name];
        for c in ["collision_us_per_substep", "substep_us", "build_ms"] {
            assert!(common::finite(row, c) >= 0.0, "{name}: {c}");
        }
        assert!(
            common::finite(row, "collision_us_per_substep") > 0.0,
            "{name}"
        );
        assert!(common::finite(row, "memory_bytes") > 0.0, "{name}");
        for c in [
            "collision_share_percent",
            "missed_percent",
            "extra_percent",
            "max_edge_penetration_mm",
        ] {
            common::finite(row, c);
        }
        // After the stage every contact sits at the 3 mm thickness by the strategy's own
        // distance; it can lie inside the exact body only if that distance errs by more than
        // 3 mm. The scene's SDF has 1 cm cells; trilinear interpolation errs by about h²κ/8 ≈
        // 1.3 mm where the surface curves at a 1 cm radius, and every other strategy measures
        // exact distances.
        let deepest = common::finite(row, "max_penetration_mm");
        assert!((0.0..3.0).contains(&deepest), "{name}: {deepest} mm inside");
    }
    let count = |name: &str, c: &str| common::finite(by_name[name], c);
    let exact = count("exact", "contacts");
    assert!(
        exact > 0.0,
        "the skirt touches the hips: exact found no contact"
    );
    // Our BVHs and brute force find the same nearest points as parry's exact queries (in f64
    // rather than f32): they may disagree only on a particle within float rounding (~1e-7 m)
    // of the thickness, and particles are spread over millimetres. At most 1% of the contacts.
    for name in ["bvh-aabb", "bvh-obb", "bvh-sphere", "brute"] {
        let differ = count(name, "missed") + count(name, "extra");
        assert!(differ <= 0.01 * exact, "{name}: {differ} of {exact} differ");
    }
    // Edge contacts hold cloth edges out of the body: whatever the particle contacts leave of
    // an edge inside, they leave no more.
    let edge_depth = |name: &str| count(name, "max_edge_penetration_mm");
    assert!(
        edge_depth("exact+edges") <= edge_depth("exact"),
        "edge contacts let an edge midpoint {} mm inside, against {} mm without",
        edge_depth("exact+edges"),
        edge_depth("exact")
    );
    if gpu {
        // The GPU pass is the CPU SDF's twin: the same field, the same interpolation; FMA
        // contraction may flip a particle within rounding of the thickness, no more than 1%
        // of the contacts, in either direction.
        for c in ["contacts", "missed", "extra"] {
            let (g, cpu) = (count("gpu-sdf", c), count("sdf", c));
            let contacts = count("sdf", "contacts");
            assert!(
                (g - cpu).abs() <= 0.01 * contacts,
                "{c}: gpu-sdf {g} against sdf {cpu}"
            );
        }
    }
    let md = std::fs::read_to_string(out.join("collision.md")).unwrap();
    assert!(md.contains("| bvh-sphere | cpu |"), "{md}");
    assert!(md.contains("### Findings"), "{md}");
    let svg = std::fs::read_to_string(out.join("collision.svg")).unwrap();
    assert!(
        svg.contains("bvh-aabb"),
        "the plot's legend names the strategies"
    );
}

/// The columns the book documents for `collision.csv`, in order.
fn documented_columns() -> Vec<String> {
    let readme = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/docs/src/benchmarks/collision.md"
    ))
    .unwrap();
    let from = readme
        .find("`collision.csv` columns:")
        .expect("the book documents the columns");
    let text = &readme[from..];
    let end = text.find("`note`").expect("the list ends with note") + "`note`".len();
    text[..end]
        .split('`')
        .skip(3)
        .step_by(2)
        .map(str::to_string)
        .collect()
}

#[test]
fn bad_strategies_and_bodiless_scenes_are_bad_input() {
    let out = common::out_dir("bench-collision", "bad");
    let r = common::drapekit(&[
        "bench",
        "collision",
        "--strategies",
        "sdf,octree",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(r.status.code(), Some(2));
    let err = String::from_utf8_lossy(&r.stderr);
    assert!(
        err.contains("--strategies") && err.contains("octree"),
        "{err}"
    );
    assert!(err.contains("bvh-aabb"), "the error lists the names: {err}");
    let scene = common::fixture("scenes/hanging_cloth.toml");
    let r = common::drapekit(&[
        "bench",
        "collision",
        "--scene",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(r.status.code(), Some(2));
    let err = String::from_utf8_lossy(&r.stderr);
    assert!(
        err.contains("hanging_cloth.toml") && err.contains("body"),
        "{err}"
    );
    assert!(!out.exists(), "bad input wrote {}", out.display());
}

#[test]
fn a_scene_with_two_bodies_is_refused_with_the_second_named() {
    // The bench builds every strategy's collider from one body: a second would be ignored on
    // the CPU and read past the SDF texture on the GPU.
    let out = common::out_dir("bench-collision", "two-bodies");
    let scene = common::fixture("scenes/cloth_pinched.toml");
    let r = common::drapekit(&[
        "bench",
        "collision",
        "--quick",
        "--scene",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&r.stderr);
    assert_eq!(r.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("body[1]") && stderr.contains("fix:"),
        "{stderr}"
    );
    assert!(!out.exists(), "wrote {}", out.display());
}

#[test]
fn bench_collision_quick_on_the_walking_mannequin_runs_the_deforming_contenders() {
    // The deforming body: the SDF contenders through the solver, `bvh-aabb` and `exact`
    // rebuilt over the deformed mesh each substep; the rigid-body-only ones left out.
    let gpu = common::gpu().is_some();
    let (out, _, rows) = quick_run("skirt_walk_collision.toml", "quick-walk");
    let by_name: HashMap<&str, &Row> = rows.iter().map(|r| (r["strategy"].as_str(), r)).collect();
    let mut expected = vec!["sdf", "bvh-aabb", "exact"];
    if gpu {
        expected.push("gpu-sdf");
    }
    assert_eq!(rows.len(), expected.len(), "{:?}", by_name.keys());
    for name in &expected {
        let row = by_name[name];
        assert!(
            common::finite(row, "collision_us_per_substep") > 0.0,
            "{name}"
        );
        assert!(common::finite(row, "substep_us") > 0.0, "{name}");
    }
    let count = |name: &str, c: &str| common::finite(by_name[name], c);
    let exact = count("exact", "contacts");
    assert!(
        exact > 0.0,
        "the skirt touches the walking hips: exact found none"
    );
    assert_eq!(count("exact", "missed") + count("exact", "extra"), 0.0);
    // The rebuilt BVH measures the same distances to the same deformed triangles as parry (in
    // f64 rather than f32); they can differ in sign only where the deformed mesh folds into
    // itself (a thigh into the hip mid-stride), where pseudo-normals disagree. At most 5% of
    // the contacts (4 of 240 at 25 mm spacing).
    let differ = count("bvh-aabb", "missed") + count("bvh-aabb", "extra");
    assert!(
        differ <= 0.05 * exact,
        "bvh-aabb: {differ} of {exact} differ"
    );
    // The SDF contenders are the solver's own collision: what they leave after the stage and
    // after the window lies no deeper than the 3 mm thickness inside the exact deformed mesh.
    for name in ["sdf"].into_iter().chain(gpu.then_some("gpu-sdf")) {
        let deepest = count(name, "max_penetration_mm");
        assert!((0.0..3.0).contains(&deepest), "{name}: {deepest} mm inside");
    }
    let md = std::fs::read_to_string(out.join("collision.md")).unwrap();
    assert!(md.contains("The body deforms"), "{md}");
}
