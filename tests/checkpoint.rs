//! Long runs lose nothing: checkpoints, `drapekit resume`, Ctrl-C, and a golden hash of the CPU
//! path that changes only when a change means to alter the simulation.

mod common;

use drapekit::cpu::CpuSolver;
use drapekit::scene::Scene;
use drapekit::sim::{prepare, simulate, RunStats};
use drapekit::solver::Solver;
use std::path::{Path, PathBuf};
use std::process::Command;

fn drapekit(args: &[&str]) -> std::process::Output {
    common::drapekit(args)
}

fn out_dir(name: &str) -> PathBuf {
    common::out_dir("ckpt", name)
}

fn summary(dir: &Path) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(dir.join("summary.json")).unwrap()).unwrap()
}

/// Every summary field that does not measure time, list files or say whether the body's SDF
/// came from the cache must be equal.
fn assert_same_run(a: &Path, b: &Path, last: u32) {
    let mut compared = 0;
    for f in 1..=last {
        let name = format!("frame_{f:04}.obj");
        if let Ok(x) = std::fs::read(a.join(&name)) {
            let y = std::fs::read(b.join(&name)).unwrap_or_default();
            assert!(x == y, "{name} differs between the runs");
            compared += 1;
        }
    }
    assert!(compared > 0, "no frames to compare up to {last}");
    // Each frame's row once, the checkpoint's frames carried: the same file as the run's.
    let frames = |dir: &Path| std::fs::read_to_string(dir.join("frames.csv")).unwrap();
    assert_eq!(frames(a), frames(b), "frames.csv differs between the runs");
    let (sa, sb) = (summary(a), summary(b));
    for (key, value) in sa.as_object().unwrap() {
        if ["wall_seconds", "particle_substeps_per_second", "outputs"].contains(&key.as_str()) {
            continue;
        }
        if let (true, Some(sdf)) = (key == "sdf", value.as_object()) {
            // Whichever run bakes the body first writes the cache the other reads, so only the
            // bake's timing and cache hit may differ; the rest of the field must match.
            for (k, v) in sdf {
                if !["bake_seconds", "from_cache"].contains(&k.as_str()) {
                    assert_eq!(v, &sb[key][k], "summary field sdf.{k}");
                }
            }
            continue;
        }
        assert_eq!(value, &sb[key], "summary field {key}");
    }
}

#[test]
fn a_resumed_run_repeats_the_uninterrupted_one_bit_for_bit() {
    // The implicit T-shirt exercises the most state: seams sewn over time, gravity switched on
    // at frame 24, the body, the strain limit. 30 frames: the checkpoint at 20 is mid-sewing
    // and before gravity; the resumed part crosses the switch.
    let scene = common::fixture("scenes/tshirt_drape_cotton.toml");
    let scene = scene.to_str().unwrap();
    let (whole, parts) = (out_dir("whole"), out_dir("parts"));
    let run = |out: &Path, extra: &[&str]| {
        let mut args = vec!["run", scene, "--backend", "cpu", "--quiet", "--out"];
        args.push(out.to_str().unwrap());
        args.extend_from_slice(extra);
        let r = drapekit(&args);
        assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    };
    run(&whole, &["--frames", "30"]);
    run(&parts, &["--frames", "20", "--checkpoint-every", "10"]);
    assert!(parts.join("checkpoint.bin").is_file());
    let r = drapekit(&[
        "resume",
        parts.to_str().unwrap(),
        "--frames",
        "30",
        "--quiet",
    ]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    assert_same_run(&whole, &parts, 30);
    let outputs = summary(&parts)["outputs"].clone();
    assert!(outputs
        .as_array()
        .unwrap()
        .iter()
        .any(|o| o == "checkpoint.bin"));
}

#[cfg(unix)]
/// Runs the hanging cloth for far more frames than the test waits for, sends `signal` once
/// frame 2 is written (so it always arrives mid-run), and returns the run's folder, exit code
/// and stderr.
fn interrupted_run(signal: &str, name: &str) -> (PathBuf, Option<i32>, String) {
    let scene = common::fixture("scenes/hanging_cloth.toml");
    let out = out_dir(name);
    // Far more frames than the test waits for: the signal always arrives mid-run.
    let child = Command::new(env!("CARGO_BIN_EXE_drapekit"))
        .args([
            "run",
            scene.to_str().unwrap(),
            "--backend",
            "cpu",
            "--quiet",
            "--frames",
            "100000",
        ])
        .args(["--out", out.to_str().unwrap()])
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let started = std::time::Instant::now();
    while !out.join("frame_0002.obj").exists() {
        assert!(started.elapsed().as_secs() < 60, "the run wrote no frames");
        std::thread::sleep(std::time::Duration::from_millis(10));
    }
    let kill = Command::new("kill")
        .args([signal, &child.id().to_string()])
        .status()
        .unwrap();
    assert!(kill.success());
    let r = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&r.stderr).into_owned();
    (out, r.status.code(), stderr)
}

#[test]
fn sigterm_stops_like_ctrl_c_with_a_checkpoint() {
    // What `timeout`, batch schedulers and container runtimes send before they kill.
    let (out, code, stderr) = interrupted_run("-TERM", "sigterm");
    assert_eq!(code, Some(130), "{stderr}");
    // 100,001 frames of the hanging cloth, each written: gigabytes, said before the run starts.
    assert!(stderr.contains("this run writes about 16."), "{stderr}");
    assert!(stderr.contains("drapekit resume"), "{stderr}");
    assert!(out.join("checkpoint.bin").exists());
}

#[test]
fn a_hang_up_that_nohup_ignores_does_not_stop_the_run() {
    // The handler catches hang-ups as it does SIGTERM; under nohup (SIGHUP ignored) a logout
    // must leave the run going.
    let out = out_dir("nohup");
    let scene = common::fixture("scenes/hanging_cloth.toml");
    let mut child = Command::new("nohup")
        .arg(env!("CARGO_BIN_EXE_drapekit"))
        .args([
            "run",
            scene.to_str().unwrap(),
            "--backend",
            "cpu",
            "--quiet",
        ])
        .args(["--frames", "100000", "--out", out.to_str().unwrap()])
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let wait_for = |frame: &str| {
        let started = std::time::Instant::now();
        while !out.join(frame).exists() {
            assert!(started.elapsed().as_secs() < 60, "the run wrote no {frame}");
            std::thread::sleep(std::time::Duration::from_millis(10));
        }
    };
    wait_for("frame_0002.obj");
    let id = child.id().to_string();
    let signal = |name: &str| {
        let status = Command::new("kill").args([name, &id]).status().unwrap();
        assert!(status.success());
    };
    signal("-HUP");
    // Frames keep coming after the hang-up: the run did not stop after its frame.
    let written = std::fs::read_dir(&out).unwrap().count();
    wait_for(&format!("frame_{:04}.obj", written + 5));
    assert!(
        child.try_wait().unwrap().is_none(),
        "the hang-up stopped the run"
    );
    signal("-TERM");
    assert_eq!(child.wait().unwrap().code(), Some(130));
}

#[test]
fn ctrl_c_stops_after_the_frame_with_a_checkpoint_that_resumes() {
    let scene = common::fixture("scenes/hanging_cloth.toml");
    let scene = scene.to_str().unwrap();
    let (out, code, stderr) = interrupted_run("-INT", "ctrl-c");
    assert_eq!(code, Some(130), "{stderr}");
    assert!(stderr.contains("drapekit resume"), "{stderr}");
    let done = summary(&out)["frames"].as_u64().unwrap() as u32;
    assert!(summary(&out)["error"]
        .as_str()
        .unwrap()
        .contains("interrupted"));
    // Resume to a few frames past the interruption and compare with a straight run.
    let last = (done + 5).to_string();
    let r = drapekit(&[
        "resume",
        out.to_str().unwrap(),
        "--frames",
        &last,
        "--quiet",
    ]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let straight = out_dir("ctrl-c-straight");
    let r = drapekit(
        &[
            "run",
            scene,
            "--backend",
            "cpu",
            "--quiet",
            "--frames",
            &last,
            "--out",
        ]
        .into_iter()
        .chain([straight.to_str().unwrap()])
        .collect::<Vec<_>>(),
    );
    assert!(r.status.success());
    assert_same_run(&straight, &out, done + 5);
}

#[test]
fn a_changed_scene_or_a_damaged_checkpoint_is_refused() {
    let dir = out_dir("refused");
    std::fs::create_dir_all(&dir).unwrap();
    let scene = dir.join("scene.toml");
    let text = std::fs::read_to_string(common::fixture("scenes/hanging_cloth.toml")).unwrap();
    std::fs::write(&scene, &text).unwrap();
    let out = dir.join("out");
    let r = drapekit(&[
        "run",
        scene.to_str().unwrap(),
        "--backend",
        "cpu",
        "--quiet",
        "--frames",
        "2",
        "--checkpoint-every",
        "1",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(r.status.success());
    std::fs::write(&scene, text.replace("frames = ", "frames = 1")).unwrap();
    let r = drapekit(&["resume", out.to_str().unwrap()]);
    let stderr = String::from_utf8_lossy(&r.stderr);
    assert_eq!(r.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("scene changed"), "{stderr}");
    // A truncated checkpoint: bad input, named, never a panic.
    let ckpt = out.join("checkpoint.bin");
    let bytes = std::fs::read(&ckpt).unwrap();
    std::fs::write(&ckpt, &bytes[..bytes.len() / 2]).unwrap();
    let r = drapekit(&["resume", out.to_str().unwrap()]);
    let stderr = String::from_utf8_lossy(&r.stderr);
    assert_eq!(r.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("checkpoint.bin"), "{stderr}");
    let r = drapekit(&["resume", dir.join("nowhere").to_str().unwrap()]);
    assert_eq!(r.status.code(), Some(2));
    // The scene as it ran, so that only the checkpoint is at fault below.
    std::fs::write(&scene, &text).unwrap();
    let (header, arrays) = split_checkpoint(&bytes);
    // A header whose particle count makes the arrays' size overflow (2⁶¹ particles × 32 bytes
    // wraps to 0, which an empty array section would match).
    let huge = serde_json::Value::from(1u64 << 61);
    let damaged = [
        (
            with_header(&header, "particles", huge),
            Vec::new(),
            "bytes of arrays",
        ),
        // A position that is not a number: a run never checkpoints one.
        (header.clone(), with_nan(&arrays), "not a finite number"),
    ];
    // One bit flipped in the first particle's position: a file that parses, with a state the
    // run never had. The checksum refuses it.
    let mut flipped = bytes.clone();
    let first_float = bytes.len() - 32 - arrays.len();
    flipped[first_float] ^= 1;
    std::fs::write(&ckpt, &flipped).unwrap();
    let r = drapekit(&["resume", out.to_str().unwrap()]);
    let stderr = String::from_utf8_lossy(&r.stderr);
    assert_eq!(r.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("checksum does not match"), "{stderr}");
    for (header, arrays, expected) in damaged {
        std::fs::write(&ckpt, join_checkpoint(&header, &arrays)).unwrap();
        let r = drapekit(&["resume", out.to_str().unwrap()]);
        let stderr = String::from_utf8_lossy(&r.stderr);
        assert_eq!(r.status.code(), Some(2), "{stderr}");
        assert!(stderr.contains("checkpoint.bin"), "{stderr}");
        assert!(stderr.contains(expected), "{stderr}");
        assert!(!stderr.contains("panicked"), "{stderr}");
    }
}

#[test]
fn resume_refuses_frames_it_already_has_and_runs_from_the_checkpoint_s_scene_when_the_file_is_gone()
{
    let dir = out_dir("gone");
    std::fs::create_dir_all(&dir).unwrap();
    let scene = dir.join("scene.toml");
    let text = std::fs::read_to_string(common::fixture("scenes/hanging_cloth.toml")).unwrap();
    std::fs::write(&scene, &text).unwrap();
    let out = dir.join("out");
    let args = ["--backend", "cpu", "--quiet", "--checkpoint-every", "1"];
    let r = drapekit(
        &[
            &["run", scene.to_str().unwrap()][..],
            &args[..],
            &["--frames", "3", "--out", out.to_str().unwrap()],
        ]
        .concat(),
    );
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    // Frames 1–3 are done: --frames 2 has nothing to continue, and would leave frame 3
    // beside a two-frame summary.
    let r = drapekit(&["resume", out.to_str().unwrap(), "--frames", "2"]);
    let stderr = String::from_utf8_lossy(&r.stderr);
    assert_eq!(r.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("give --frames 4 or more"), "{stderr}");
    // Nor may it end a run sooner than it went on past its checkpoint: checkpoints at 3, a
    // run of 5, resumed to 4.
    let further = dir.join("further");
    let r = drapekit(
        &[
            &[
                "run",
                scene.to_str().unwrap(),
                "--backend",
                "cpu",
                "--quiet",
            ][..],
            &["--checkpoint-every", "3", "--frames", "5"],
            &["--out", further.to_str().unwrap()],
        ]
        .concat(),
    );
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let r = drapekit(&["resume", further.to_str().unwrap(), "--frames", "4"]);
    let stderr = String::from_utf8_lossy(&r.stderr);
    assert_eq!(r.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("would end it sooner"), "{stderr}");
    assert!(stderr.contains("give --frames 5 or more"), "{stderr}");
    // The scene file deleted: the checkpoint's copy continues the run.
    std::fs::remove_file(&scene).unwrap();
    let r = drapekit(&["resume", out.to_str().unwrap(), "--frames", "4"]);
    let stderr = String::from_utf8_lossy(&r.stderr);
    assert!(r.status.success(), "{stderr}");
    assert!(
        stderr.contains("is gone; resuming with the scene"),
        "{stderr}"
    );
    assert_eq!(summary(&out)["frames"], 4);
}

#[test]
fn resume_refuses_a_cloth_mesh_changed_since_the_checkpoint() {
    // The same vertex count, so that only the file's contents can tell: a comment is enough.
    let dir = out_dir("input-changed");
    std::fs::create_dir_all(&dir).unwrap();
    let mesh = dir.join("strip.obj");
    std::fs::copy(common::fixture("meshes/folded_strip.obj"), &mesh).unwrap();
    let scene = dir.join("scene.toml");
    std::fs::write(
        &scene,
        "[cloth.mesh]\npath = \"strip.obj\"\n[fabric]\npreset = \"cotton\"\n\
         [solver]\nframes = 2\n[output]\nobj = false\n",
    )
    .unwrap();
    let out = dir.join("out");
    let r = drapekit(&[
        "run",
        scene.to_str().unwrap(),
        "--backend",
        "cpu",
        "--quiet",
        "--checkpoint-every",
        "1",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let original = std::fs::read_to_string(&mesh).unwrap();
    std::fs::write(&mesh, format!("# edited\n{original}")).unwrap();
    let r = drapekit(&["resume", out.to_str().unwrap(), "--frames", "3"]);
    let stderr = String::from_utf8_lossy(&r.stderr);
    assert_eq!(r.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("strip.obj: contents: the file changed since the checkpoint"),
        "{stderr}"
    );
    std::fs::write(&mesh, original).unwrap();
    let r = drapekit(&["resume", out.to_str().unwrap(), "--frames", "3"]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
}

/// A checkpoint file's magic line, then its header's length (8 bytes, little-endian), header
/// (JSON), arrays and the SHA-256 of all that (32 bytes): the header and the arrays.
fn split_checkpoint(bytes: &[u8]) -> (serde_json::Value, Vec<u8>) {
    assert!(bytes.starts_with(MAGIC));
    let magic = MAGIC.len();
    let len = u64::from_le_bytes(bytes[magic..magic + 8].try_into().unwrap()) as usize;
    let header = &bytes[magic + 8..magic + 8 + len];
    (
        serde_json::from_slice(header).unwrap(),
        bytes[magic + 8 + len..bytes.len() - 32].to_vec(),
    )
}

/// The checkpoint of `header` and `arrays`, its checksum theirs: what is wrong with it is
/// for the checks after the checksum to find.
fn join_checkpoint(header: &serde_json::Value, arrays: &[u8]) -> Vec<u8> {
    use sha2::Digest;
    let json = serde_json::to_vec(header).unwrap();
    let mut out = MAGIC.to_vec();
    out.extend_from_slice(&(json.len() as u64).to_le_bytes());
    out.extend_from_slice(&json);
    out.extend_from_slice(arrays);
    let checksum = sha2::Sha256::digest(&out);
    out.extend_from_slice(&checksum);
    out
}

const MAGIC: &[u8] = b"DRAPEKIT CHECKPOINT 2\n";

fn with_header(
    header: &serde_json::Value,
    key: &str,
    value: serde_json::Value,
) -> serde_json::Value {
    let mut header = header.clone();
    header[key] = value;
    header
}

/// The arrays with the first particle's x position NaN.
fn with_nan(arrays: &[u8]) -> Vec<u8> {
    let mut out = arrays.to_vec();
    out[..4].copy_from_slice(&f32::NAN.to_le_bytes());
    out
}

/// FNV-1a over bytes: a fixed, documented hash (std's hasher may change between releases).
fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf29ce484222325, |h, &b| {
        (h ^ b as u64).wrapping_mul(0x100000001b3)
    })
}

/// The CPU path is deterministic: the hanging cloth (springs only, no trigonometry, so only
/// IEEE-exact +, −, ×, ÷ and √ are involved) after 24 frames hashes to a fixed value. When a
/// change means to alter the simulation, re-mint: run this test, check the change in the
/// physics, and paste the printed hash here with the reason in the commit message.
#[test]
fn the_cpu_path_matches_its_golden_hash() {
    const GOLDEN: u64 = 0xb9e379a04d973a2d;
    let mut scene = Scene::load(&common::fixture("scenes/hanging_cloth.toml")).unwrap();
    scene.fabric.bending_stiffness = None;
    scene.solver.frames = 24;
    let prep = prepare(&scene).unwrap();
    let mut solver = CpuSolver::new(&prep.model, prep.params, &prep.plan);
    simulate(&prep, &mut solver, &mut RunStats::default(), |_, _| Ok(())).unwrap();
    let state = solver.state().unwrap();
    let bytes: Vec<u8> = (state.positions.iter())
        .chain(&state.velocities)
        .flat_map(|v| v.to_array())
        .flat_map(f32::to_le_bytes)
        .collect();
    let hash = fnv1a(&bytes);
    assert_eq!(
        hash, GOLDEN,
        "the CPU path's state hashes to {hash:#018x}: if the simulation was meant to change, \
         set GOLDEN to it"
    );
}
