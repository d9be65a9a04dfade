//! `drapekit batch` end to end: the manifest is validated whole, shards cover every item once,
//! a killed shard resumes to the same results as one process, markers decide what reruns, and
//! a failing item fails alone. Tiny grids on the CPU backend keep it to seconds.

use drapekit::batch::{shard, Manifest, Shard};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

fn drapekit() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_drapekit"));
    c.env("XDG_RUNTIME_DIR", std::env::temp_dir())
        .env_remove("SLURM_ARRAY_TASK_ID")
        .env_remove("JOB_COMPLETION_INDEX");
    c
}

fn batch(args: &[&str]) -> Output {
    drapekit().arg("batch").args(args).output().unwrap()
}

/// `drapekit batch MANIFEST --out OUT --backend cpu`.
fn batch_cpu(manifest: &Path, out: &Path) -> Output {
    batch(&[
        manifest.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--backend",
        "cpu",
    ])
}

fn text(o: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

/// A fresh folder for one test.
fn workdir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("drapekit-batch-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(dir.join("scenes")).unwrap();
    dir
}

/// A small hanging sheet; `frames` sets how long an item takes.
fn write_scene(dir: &Path, name: &str, frames: u32) -> PathBuf {
    let path = dir.join("scenes").join(name);
    std::fs::write(
        &path,
        format!(
            "[cloth.grid]\nwidth_m = 0.5\nheight_m = 0.5\ncolumns = 10\nrows = 10\n\
             center_m = [0.0, 1.0, 0.0]\n\n\
             [fabric]\ndensity_kg_m2 = 0.15\nstretch_stiffness_n_m = 300.0\n\
             bending_stiffness_n_m = 2e-5\ndamping_ratio = 0.1\n\n\
             [[pins]]\ncorners = [\"top-left\", \"top-right\"]\n\n\
             [solver]\nfps = 24\nframes = {frames}\n\n\
             [output]\nobj = true\nevery = 2\n"
        ),
    )
    .unwrap();
    path
}

/// `n` items over the scene, varying the grid and the damping.
fn write_manifest(dir: &Path, n: usize) -> PathBuf {
    let lines: Vec<String> = (0..n)
        .map(|k| {
            format!(
                r#"{{"id": "item-{k:02}", "scene": "scenes/sheet.toml", "overrides": {{"cloth": {{"grid": {{"columns": {}}}}}, "fabric": {{"damping_ratio": {}}}}}}}"#,
                8 + k % 4,
                0.05 + 0.01 * k as f64
            )
        })
        .collect();
    let path = dir.join("manifest.jsonl");
    std::fs::write(&path, lines.join("\n") + "\n").unwrap();
    path
}

/// Every summary under `out`, by item id, less the fields that time the run.
fn summaries(out: &Path) -> BTreeMap<String, serde_json::Value> {
    let mut all = BTreeMap::new();
    for entry in std::fs::read_dir(out).unwrap() {
        let path = entry.unwrap().path();
        let name = path.file_name().unwrap().to_str().unwrap().to_string();
        if name.starts_with('.') || !path.is_dir() {
            continue;
        }
        let mut s: serde_json::Value =
            serde_json::from_slice(&std::fs::read(path.join("summary.json")).unwrap()).unwrap();
        for timed in ["wall_seconds", "particle_substeps_per_second"] {
            s.as_object_mut().unwrap().remove(timed);
        }
        all.insert(name, s);
    }
    all
}

/// Every visible item folder is complete: it has its marker, and everything its summary lists.
fn assert_no_half_written_item(out: &Path) {
    for entry in std::fs::read_dir(out).unwrap() {
        let path = entry.unwrap().path();
        let name = path.file_name().unwrap().to_str().unwrap();
        if name.starts_with('.') || !path.is_dir() {
            continue;
        }
        assert!(path.join("done").is_file(), "{name} has no done marker");
        let s: serde_json::Value =
            serde_json::from_slice(&std::fs::read(path.join("summary.json")).unwrap()).unwrap();
        for f in s["outputs"].as_array().unwrap() {
            assert!(
                path.join(f.as_str().unwrap()).is_file(),
                "{name}/{f} missing"
            );
        }
    }
}

/// Items a batch's log says it skipped.
fn skips(log: &str) -> usize {
    log.matches(", skipped").count()
}

#[test]
fn a_bad_manifest_reports_every_bad_line_and_runs_nothing() {
    let dir = workdir("bad");
    write_scene(&dir, "sheet.toml", 2);
    let lines = [
        r#"{"id": "good", "scene": "scenes/sheet.toml"}"#,
        r#"{"id": "broken", "scene": "scenes/sheet.toml""#,
        r#"{"id": "typo", "scene": "scenes/sheet.toml", "overides": {}}"#,
        r#"{"id": "../escape", "scene": "scenes/sheet.toml"}"#,
        r#"{"id": "good", "scene": "scenes/sheet.toml"}"#,
        r#"{"id": "missing", "scene": "scenes/nowhere.toml"}"#,
        r#"{"id": "velvet", "scene": "scenes/sheet.toml", "overrides": {"fabric": {"preset": "velvet"}}}"#,
        "",
        r#"{"id": "zero-rows", "scene": "scenes/sheet.toml", "overrides": {"cloth": {"grid": {"rows": 1}}}}"#,
        r#"{"id": "fine", "scene": "scenes/sheet.toml", "overrides": {"solver": {"frames": 1}}}"#,
        r#"{"id": "twice", "scene": "scenes/sheet.toml", "overrides": {"solver": {"frames": 1}, "solver": {"substeps": 2}}}"#,
    ];
    let manifest = dir.join("m.jsonl");
    std::fs::write(&manifest, lines.join("\n")).unwrap();
    let out = dir.join("out");
    let r = batch_cpu(&manifest, &out);
    let msg = text(&r);
    assert_eq!(r.status.code(), Some(2), "{msg}");
    assert!(msg.contains("8 of 10 items are bad"), "{msg}");
    for (line, says) in [
        (2, "not JSON"),
        (3, "unknown key \"overides\""),
        (4, "not safe in a folder name"),
        (5, "already used on line 1"),
        (6, "cannot read the scene"),
        (7, "unknown fabric preset \"velvet\""),
        (9, "cloth.grid"),
        (11, "\"solver\" appears twice"),
    ] {
        let at = msg
            .lines()
            .find(|l| l.contains(&format!("line {line}: ")))
            .unwrap_or_else(|| panic!("line {line} not reported:\n{msg}"));
        let block = &msg[msg.find(at).unwrap()..];
        assert!(
            block.contains(says),
            "line {line} should say {says:?}:\n{msg}"
        );
    }
    for good in ["line 1:", "line 10:"] {
        assert!(!msg.contains(good), "a good line was reported: {msg}");
    }
    // Nothing was simulated, nothing written.
    assert!(!out.exists());
}

#[test]
fn shards_are_a_pure_round_robin_over_items() {
    let dir = workdir("shards");
    write_scene(&dir, "sheet.toml", 2);
    // Blank lines do not shift the items' shards.
    let m = write_manifest(&dir, 7);
    let text = std::fs::read_to_string(&m).unwrap().replace('\n', "\n\n");
    let manifest = Manifest::parse(&text, &m).unwrap();
    let mut seen = vec![0; manifest.items.len()];
    for i in 0..3 {
        let s = Shard::new(i, 3).unwrap();
        for item in manifest.items.iter().filter(|it| s.owns(it.index)) {
            assert_eq!(item.index % 3, i as usize);
            seen[item.index] += 1;
        }
    }
    assert_eq!(seen, vec![1; 7]);
    let env = |name: &str| match name {
        "SLURM_ARRAY_TASK_ID" => Some("1".to_string()),
        "SLURM_ARRAY_TASK_COUNT" => Some("3".to_string()),
        _ => None,
    };
    assert_eq!(
        shard::resolve(None, None, &env).unwrap().0,
        Shard::new(1, 3).unwrap()
    );
}

#[test]
fn three_shards_with_one_killed_midway_equal_one_process() {
    let dir = workdir("resume");
    write_scene(&dir, "sheet.toml", 72);
    let manifest = write_manifest(&dir, 9);
    let m = manifest.to_str().unwrap();
    let single = dir.join("single");
    let r = batch(&[m, "--out", single.to_str().unwrap(), "--backend", "cpu"]);
    assert!(r.status.success(), "{}", text(&r));

    let sharded = dir.join("sharded");
    let s = sharded.to_str().unwrap();
    let spawn = |shard: &str| {
        drapekit()
            .args(["batch", m, "--out", s, "--backend", "cpu", "--jobs", "1"])
            .args(["--shard", shard])
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap()
    };
    let mut victim = spawn("1/3");
    let others = [spawn("0/3"), spawn("2/3")];
    // Kill shard 1 once its first item is published and before its last.
    let mine = ["item-01", "item-04", "item-07"];
    let started = std::time::Instant::now();
    while !mine.iter().any(|id| sharded.join(id).join("done").exists()) {
        assert!(
            started.elapsed().as_secs() < 60,
            "shard 1 never finished an item"
        );
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    victim.kill().unwrap();
    victim.wait().unwrap();
    for o in others {
        let out = o.wait_with_output().unwrap();
        assert!(out.status.success(), "{}", text(&out));
    }
    let finished = mine.iter().filter(|id| sharded.join(id).exists()).count();
    assert!(
        finished < 3,
        "shard 1 finished before the kill; make its items slower"
    );
    assert_no_half_written_item(&sharded);

    let r = batch(&[m, "--out", s, "--backend", "cpu", "--shard", "1/3"]);
    let out = text(&r);
    assert!(r.status.success(), "{out}");
    assert_eq!(
        out.matches("done before, skipped").count(),
        finished,
        "{out}"
    );
    assert_no_half_written_item(&sharded);
    // No leftovers of the killed run.
    let hidden: Vec<_> = std::fs::read_dir(&sharded)
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().starts_with('.'))
        .collect();
    assert!(hidden.is_empty(), "{hidden:?}");
    let (a, b) = (summaries(&single), summaries(&sharded));
    assert_eq!(a.len(), 9);
    assert_eq!(
        a, b,
        "the sharded, killed and resumed batch differs from one process"
    );

    // The report holds every item exactly once.
    let r = batch(&["report", s]);
    assert!(r.status.success(), "{}", text(&r));
    let csv = std::fs::read_to_string(sharded.join("batch.csv")).unwrap();
    let ids: Vec<&str> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').next().unwrap())
        .collect();
    let want: Vec<String> = (0..9).map(|k| format!("item-{k:02}")).collect();
    assert_eq!(ids, want);
    assert!(csv
        .lines()
        .skip(1)
        .all(|l| l.split(',').nth(1) == Some("ok")));
}

#[test]
fn markers_decide_what_a_rerun_skips_and_redoes() {
    let dir = workdir("markers");
    let scene = write_scene(&dir, "sheet.toml", 2);
    let manifest = write_manifest(&dir, 3);
    let out = dir.join("out");
    let run = |extra: &[&str]| {
        let mut args = vec![
            manifest.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--backend",
            "cpu",
        ];
        args.extend_from_slice(extra);
        let r = batch(&args);
        assert!(r.status.success(), "{}", text(&r));
        text(&r)
    };
    let skipped = |log: &str, id: &str| {
        log.lines()
            .any(|l| l.contains(&format!("{id}: done before, skipped")))
    };
    run(&[]);
    let log = run(&[]);
    assert!(
        ["item-00", "item-01", "item-02"]
            .iter()
            .all(|id| skipped(&log, id)),
        "{log}"
    );

    // A changed line redoes that item only.
    let text_now = std::fs::read_to_string(&manifest).unwrap();
    std::fs::write(
        &manifest,
        text_now.replace("\"columns\": 9", "\"columns\": 12"),
    )
    .unwrap();
    let log = run(&[]);
    assert!(skipped(&log, "item-00") && !skipped(&log, "item-01") && skipped(&log, "item-02"));
    let s: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("item-01/summary.json")).unwrap()).unwrap();
    assert_eq!(s["particles"], 12 * 10);

    // An item whose marker is gone (never finished) is redone.
    std::fs::remove_file(out.join("item-02/done")).unwrap();
    let log = run(&[]);
    assert!(
        skipped(&log, "item-00") && !skipped(&log, "item-02"),
        "{log}"
    );

    // A changed scene file, or a changed option that alters results, redoes everything.
    let src = std::fs::read_to_string(&scene).unwrap();
    std::fs::write(
        &scene,
        src.replace("damping_ratio = 0.1", "damping_ratio = 0.2"),
    )
    .unwrap();
    let log = run(&[]);
    assert_eq!(skips(&log), 0, "{log}");
    let log = run(&["--frames", "3"]);
    assert_eq!(skips(&log), 0, "{log}");
    let log = run(&["--frames", "3"]);
    assert_eq!(skips(&log), 3, "{log}");
}

#[test]
fn a_folder_or_file_of_the_user_s_with_an_item_s_name_is_never_replaced() {
    let dir = workdir("foreign");
    write_scene(&dir, "sheet.toml", 2);
    let manifest = write_manifest(&dir, 3);
    let out = dir.join("out");
    // item-00: a folder of the user's; item-01: a file; item-02: an empty folder (nothing to
    // lose), which the item takes.
    std::fs::create_dir_all(out.join("item-00/sub")).unwrap();
    std::fs::write(out.join("item-00/sub/notes.txt"), "mine").unwrap();
    std::fs::write(out.join("item-01"), "mine too").unwrap();
    std::fs::create_dir_all(out.join("item-02")).unwrap();
    let r = batch_cpu(&manifest, &out);
    let log = text(&r);
    assert_eq!(r.status.code(), Some(4), "{log}");
    assert_eq!(
        std::fs::read_to_string(out.join("item-00/sub/notes.txt")).unwrap(),
        "mine"
    );
    assert_eq!(
        std::fs::read_to_string(out.join("item-01")).unwrap(),
        "mine too"
    );
    assert!(out.join("item-02/done").is_file(), "{log}");
    assert!(
        log.contains("not a batch item's (it has no item.json)"),
        "{log}"
    );
    assert!(log.contains("a file, not a batch item's folder"), "{log}");
    // Nothing of the refused items was left aside either.
    let hidden = std::fs::read_dir(&out)
        .unwrap()
        .filter(|e| {
            e.as_ref()
                .unwrap()
                .file_name()
                .to_string_lossy()
                .starts_with('.')
        })
        .count();
    assert_eq!(hidden, 0);
}

#[test]
fn an_item_s_warnings_name_the_item() {
    // Items run side by side and their stderr lines interleave: each warning says whose it is.
    let dir = workdir("warned");
    write_scene(&dir, "sheet.toml", 2);
    let manifest = dir.join("manifest.jsonl");
    std::fs::write(
        &manifest,
        r#"{"id": "creeping", "scene": "scenes/sheet.toml", "overrides": {"fabric": {"damping_ratio": 20.0}, "frames": null}}"#,
    )
    .unwrap();
    let out = dir.join("out");
    let r = batch_cpu(&manifest, &out);
    let log = text(&r);
    assert!(r.status.success(), "{log}");
    assert!(log.contains("warning: item creeping: "), "{log}");
    // Every warning, the run's and the result's as well as the setup's, and the manifest's
    // (here a null that removes nothing, `frames` being a key of [solver]).
    let warnings: Vec<&str> = log.lines().filter(|l| l.contains("warning:")).collect();
    assert!(warnings.len() >= 2, "{log}");
    assert!(
        warnings.iter().all(|l| l.contains("item creeping")),
        "{log}"
    );
    assert!(
        log.contains("frames is null, but the scene has no frames"),
        "{log}"
    );
}

#[test]
fn the_report_names_a_damaged_item_and_leaves_out_what_is_not_an_item() {
    let dir = workdir("report-damaged");
    write_scene(&dir, "sheet.toml", 2);
    let manifest = write_manifest(&dir, 2);
    let out = dir.join("out");
    let args = [manifest.to_str().unwrap(), "--out", out.to_str().unwrap()];
    let r = batch(&[&args[..], &["--backend", "cpu"]].concat());
    assert!(r.status.success(), "{}", text(&r));
    // item-00's summary cut in half after it was marked done, and a folder of the user's.
    let summary = out.join("item-00/summary.json");
    let bytes = std::fs::read(&summary).unwrap();
    std::fs::write(&summary, &bytes[..bytes.len() / 2]).unwrap();
    std::fs::create_dir_all(out.join("notes")).unwrap();
    let r = batch(&["report", out.to_str().unwrap()]);
    assert!(r.status.success(), "{}", text(&r));
    let md = std::fs::read_to_string(out.join("batch.md")).unwrap();
    assert!(md.contains("| 2 | 1 | 0 | 0 | 1 |"), "{md}");
    assert!(md.contains("| damaged | 1 | item-00 |"), "{md}");
    assert!(md.contains("left out: notes."), "{md}");
    // A run's own folder is not a batch's.
    let r = batch(&["report", out.join("item-01").to_str().unwrap()]);
    assert_eq!(r.status.code(), Some(2), "{}", text(&r));
    assert!(
        text(&r).contains("is a run's output folder"),
        "{}",
        text(&r)
    );
}

#[test]
fn a_failing_item_fails_alone_and_is_reported_by_cause() {
    let dir = workdir("failures");
    write_scene(&dir, "sheet.toml", 4);
    let lines = [
        r#"{"id": "ok-a", "scene": "scenes/sheet.toml"}"#,
        // ~200× past the stable step: it explodes (exit 3 under `drapekit run`).
        r#"{"id": "explodes", "scene": "scenes/sheet.toml", "overrides": {"solver": {"substeps": 1}}}"#,
        // Valid to read, refused when the model is sized: bad input found late.
        r#"{"id": "too-big", "scene": "scenes/sheet.toml", "overrides": {"solver": {"max_memory_mb": 0.01}}}"#,
        // The scene asks for a folder outside the batch: ignored, the item folder is used.
        r#"{"id": "ok-b", "scene": "scenes/sheet.toml", "overrides": {"output": {"dir": "elsewhere"}}}"#,
    ];
    let manifest = dir.join("m.jsonl");
    std::fs::write(&manifest, lines.join("\n")).unwrap();
    let out = dir.join("out");
    let args = [
        manifest.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--backend",
        "cpu",
        "--jobs",
        "2",
    ];
    let r = drapekit()
        .current_dir(&dir)
        .arg("batch")
        .args(args)
        .output()
        .unwrap();
    let log = text(&r);
    assert_eq!(r.status.code(), Some(4), "{log}");
    assert!(
        log.contains("2 of 4 items failed: explodes, too-big"),
        "{log}"
    );
    assert!(!dir.join("elsewhere").exists());
    for ok in ["ok-a", "ok-b"] {
        assert!(out.join(ok).join("summary.json").is_file());
        assert!(!out.join(ok).join("error.json").exists());
    }
    let error = |id: &str| -> serde_json::Value {
        serde_json::from_slice(&std::fs::read(out.join(id).join("error.json")).unwrap()).unwrap()
    };
    assert_eq!(error("explodes")["kind"], "unstable");
    assert_eq!(error("explodes")["exit_code"], 3);
    assert_eq!(error("too-big")["kind"], "bad_input");
    assert!(out.join("explodes/summary.json").is_file());
    // A failure a rerun would repeat is not rerun; the exit code still says it failed.
    let r = drapekit()
        .current_dir(&dir)
        .arg("batch")
        .args(args)
        .output()
        .unwrap();
    let log = text(&r);
    assert_eq!(r.status.code(), Some(4), "{log}");
    assert_eq!(skips(&log), 4, "{log}");

    let r = batch(&["report", out.to_str().unwrap()]);
    assert!(r.status.success(), "{}", text(&r));
    let md = std::fs::read_to_string(out.join("batch.md")).unwrap();
    assert!(md.contains("| 4 | 2 | 2 | 0 | 0 |"), "{md}");
    assert!(md.contains("| unstable | 1 | explodes |"), "{md}");
    assert!(md.contains("| bad_input | 1 | too-big |"), "{md}");
    let csv = std::fs::read_to_string(out.join("batch.csv")).unwrap();
    assert_eq!(
        csv.lines().next().unwrap(),
        drapekit::batch::report::COLUMNS.join(",")
    );
    assert_eq!(csv.lines().count(), 5);
}

#[test]
fn the_shipped_dataset_sweeps_garments_fabrics_and_spacings() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/datasets/skirts_small.jsonl");
    let manifest = Manifest::load(&path).unwrap_or_else(|e| panic!("{e}"));
    assert!(manifest.items.len() >= 24);
    let mut combos = std::collections::BTreeSet::new();
    for item in &manifest.items {
        let garment = item.files[0]
            .1
            .file_stem()
            .unwrap()
            .to_str()
            .unwrap()
            .to_string();
        combos.insert((
            garment,
            item.fabric.clone(),
            item.particle_distance_m.map(|d| (d * 1e3) as u32),
        ));
    }
    // Every combination once: 2 garments × 7 presets × 2 spacings.
    assert_eq!(combos.len(), manifest.items.len());
    let fabrics: std::collections::BTreeSet<_> = combos.iter().map(|c| c.1.as_str()).collect();
    assert_eq!(fabrics.len(), drapekit::scene::PRESETS.len());
}

#[test]
fn a_transient_failure_is_retried_then_left_unfinished_for_the_next_run() {
    let dir = workdir("transient");
    write_scene(&dir, "sheet.toml", 2);
    let manifest = write_manifest(&dir, 1);
    let out = dir.join("out");
    // No adapter has this name: the GPU backend cannot start, a GPU error.
    let args = [
        manifest.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--backend",
        "gpu",
        "--adapter",
        "no-such-adapter-anywhere",
        "--retries",
        "2",
    ];
    for _ in 0..2 {
        let r = batch(&args);
        let log = text(&r);
        assert_eq!(r.status.code(), Some(4), "{log}");
        // Never skipped: without a marker the item is redone.
        assert_eq!(skips(&log), 0, "{log}");
        assert_eq!(log.matches("retrying").count(), 2, "{log}");
    }
    let item = out.join("item-00");
    assert!(!item.join("done").exists());
    let meta: serde_json::Value =
        serde_json::from_slice(&std::fs::read(item.join("item.json")).unwrap()).unwrap();
    assert_eq!(meta["attempts"], 3);
    let error: serde_json::Value =
        serde_json::from_slice(&std::fs::read(item.join("error.json")).unwrap()).unwrap();
    assert_eq!(error["kind"], "gpu");
    let r = batch(&["report", out.to_str().unwrap()]);
    assert!(r.status.success(), "{}", text(&r));
    let csv = std::fs::read_to_string(out.join("batch.csv")).unwrap();
    assert!(
        csv.lines()
            .nth(1)
            .unwrap()
            .starts_with("item-00,unfinished,gpu,"),
        "{csv}"
    );
}

/// A closed 10 cm cube as OBJ text, its centre at `y`.
fn cube_obj(y: f32) -> String {
    let mut s = String::new();
    for k in 0..8 {
        let (x, yy, z) = ((k & 1) as f32, ((k >> 1) & 1) as f32, ((k >> 2) & 1) as f32);
        s += &format!(
            "v {} {} {}\n",
            0.1 * x - 0.05,
            0.1 * yy - 0.05 + y,
            0.1 * z - 0.05
        );
    }
    // Outward-facing quads, each as two triangles (1-based).
    for [a, b, c, d] in [
        [1, 3, 4, 2],
        [5, 6, 8, 7],
        [1, 2, 6, 5],
        [3, 7, 8, 4],
        [1, 5, 7, 3],
        [2, 4, 8, 6],
    ] {
        s += &format!("f {a} {b} {c}\nf {a} {c} {d}\n");
    }
    s
}

#[test]
fn every_body_mesh_is_in_an_items_input_hash() {
    // Two OBJ bodies: editing the second one must change the item's hash, or a rerun would
    // keep results made with the old mesh.
    let dir = workdir("two-bodies");
    std::fs::write(dir.join("scenes/low.obj"), cube_obj(0.0)).unwrap();
    std::fs::write(dir.join("scenes/high.obj"), cube_obj(1.0)).unwrap();
    let scene = std::fs::read_to_string(write_scene(&dir, "sheet.toml", 2)).unwrap();
    let scene = scene + "\n[[body]]\npath = \"low.obj\"\n\n[[body]]\npath = \"high.obj\"\n";
    std::fs::write(dir.join("scenes/sheet.toml"), scene).unwrap();
    let manifest = write_manifest(&dir, 1);
    let load = || Manifest::load(&manifest).unwrap().items.remove(0);
    let before = load();
    let roles: Vec<&str> = before.files.iter().map(|f| f.0.as_str()).collect();
    assert_eq!(roles, ["body[0]", "body[1]"], "{:?}", before.files);
    std::fs::write(dir.join("scenes/high.obj"), cube_obj(1.2)).unwrap();
    assert_ne!(load().inputs_sha256, before.inputs_sha256);
}

#[test]
fn an_items_bad_input_is_located_in_the_file_that_holds_the_key() {
    // Errors found while an item runs come from its merged scene, whose lines are neither
    // file's: a key the overrides set is reported at the manifest's line, any other key at its
    // own line in the scene file (write_scene puts `columns` on line 4).
    let dir = workdir("located");
    write_scene(&dir, "sheet.toml", 2);
    let manifest = dir.join("manifest.jsonl");
    std::fs::write(
        &manifest,
        "{\"id\": \"pin\", \"scene\": \"scenes/sheet.toml\", \"overrides\": {\"pins\": [{\"indices\": [5000]}]}}\n\
         {\"id\": \"cap\", \"scene\": \"scenes/sheet.toml\", \"overrides\": {\"solver\": {\"max_memory_mb\": 0.01}}}\n",
    )
    .unwrap();
    let out = dir.join("out");
    let o = batch_cpu(&manifest, &out);
    assert_eq!(o.status.code(), Some(4), "{}", text(&o));
    let message = |id: &str| {
        let e: serde_json::Value =
            serde_json::from_slice(&std::fs::read(out.join(id).join("error.json")).unwrap())
                .unwrap();
        e["message"].as_str().unwrap().to_string()
    };
    let pin = message("pin");
    assert!(
        pin.starts_with(&format!(
            "{}:1: item \"pin\": overrides.pins[0].indices",
            manifest.display()
        )),
        "{pin}"
    );
    let cap = message("cap");
    let scene = dir.join("scenes/sheet.toml");
    assert!(
        cap.starts_with(&format!("{}:4: cloth.grid.columns", scene.display())),
        "{cap}"
    );
}

#[test]
fn a_batch_on_a_one_thread_pool_finishes() {
    // Each job is a thread of its own whose parallel loops run on rayon's pool; had the batch
    // itself waited on a thread of a one-thread pool, those loops would never start. A 40 × 40
    // sheet is large enough for its loops to split.
    let dir = workdir("one-thread");
    write_scene(&dir, "sheet.toml", 4);
    let manifest = dir.join("m.jsonl");
    std::fs::write(
        &manifest,
        r#"{"id": "sheet", "scene": "scenes/sheet.toml", "overrides": {"cloth": {"grid": {"columns": 40, "rows": 40}}}}"#,
    )
    .unwrap();
    let out = dir.join("out");
    let mut child = drapekit()
        .args(["--threads", "1", "batch"])
        .arg(&manifest)
        .arg("--out")
        .arg(&out)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    // The item takes well under a second; a minute is a hang, not a slow machine.
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(60);
    let status = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break status;
        }
        if std::time::Instant::now() > deadline {
            child.kill().unwrap();
            panic!("a batch on one thread did not finish within a minute");
        }
        std::thread::sleep(std::time::Duration::from_millis(50));
    };
    assert!(status.success());
    assert_eq!(summaries(&out).len(), 1);
}

#[test]
fn a_panic_on_a_batch_item_s_thread_is_reported_with_the_item() {
    // A panic hook is the whole process's: the panics run in a child, this test binary itself.
    if std::env::var_os("DRAPEKIT_PANIC_CHILD").is_some() {
        drapekit::notice::label_panics();
        let item = std::panic::catch_unwind(|| {
            drapekit::notice::as_item("shirt-7", || panic!("boom {}", 6 * 7))
        });
        assert!(item.is_err());
        // Off an item's thread (or after its item unwound), Rust's own report.
        let plain = std::panic::catch_unwind(|| panic!("plain"));
        assert!(plain.is_err());
        return;
    }
    let name = "a_panic_on_a_batch_item_s_thread_is_reported_with_the_item";
    let child = Command::new(std::env::current_exe().unwrap())
        .args([name, "--exact", "--nocapture", "--test-threads", "1"])
        .env("DRAPEKIT_PANIC_CHILD", "1")
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&child.stderr);
    assert!(child.status.success(), "{stderr}");
    let item: Vec<&str> = (stderr.lines())
        .filter(|l| l.starts_with("drapekit: item shirt-7: panicked at tests/batch.rs:"))
        .collect();
    assert_eq!(item.len(), 1, "{stderr}");
    assert!(item[0].ends_with(": boom 42"), "{stderr}");
    assert!(
        stderr.contains("panicked at tests/batch.rs:") && stderr.lines().any(|l| l == "plain"),
        "the unlabelled panic keeps Rust's report: {stderr}"
    );
}
