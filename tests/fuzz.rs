//! A mutation fuzzer over the shipped scenes: each input is a shipped scene with one value
//! replaced by an extreme one (zero, negative, subnormal, huge, NaN, infinite, a string), or one
//! line removed. Every input goes through loading and, when it loads and is small enough to be
//! quick, planning and one frame on the CPU path. Nothing may panic; what fails must fail as a
//! typed error. `DRAPEKIT_FUZZ_INPUTS` sets the count (CI runs the default). The shipped
//! patterns have their own, structural fuzzer: `tests/fuzz_patterns.rs`.

mod common;

use drapekit::cpu::CpuSolver;
use drapekit::scene::Scene;
use drapekit::sim::{prepare, simulate, RunStats};
use std::panic::{catch_unwind, AssertUnwindSafe};

/// The inputs CI runs; a longer run: DRAPEKIT_FUZZ_INPUTS=100000 cargo test --release --test fuzz.
const DEFAULT_INPUTS: usize = 3000;

const EXTREMES: &[&str] = &[
    "0",
    "-1",
    "1e-320",
    "1e30",
    "-1e30",
    "nan",
    "inf",
    "-inf",
    "4294967296",
    "-4294967296",
    "0.5",
    "\"x\"",
    "[]",
    "[1e30, nan, 0]",
    "true",
];

struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
}

/// One mutation of `src`: a value replaced, scaled, or a line removed.
fn mutate(src: &str, rng: &mut Rng) -> String {
    let lines: Vec<&str> = src.lines().collect();
    let values: Vec<usize> = (0..lines.len())
        .filter(|&i| lines[i].contains(" = ") && !lines[i].trim_start().starts_with('#'))
        .collect();
    let mut out: Vec<String> = lines.iter().map(|l| l.to_string()).collect();
    if values.is_empty() {
        return src.to_string();
    }
    let at = values[rng.below(values.len())];
    let (key, value) = out[at].split_once(" = ").expect("a key line");
    let (key, value) = (key.to_string(), value.to_string());
    match rng.below(4) {
        0 => out[at] = String::new(),
        1 => {
            // Scale a number by a large or small power of ten.
            let scaled = value
                .trim()
                .parse::<f64>()
                .map(|v| v * [1e-12, 1e-6, 1e6, 1e12][rng.below(4)]);
            out[at] = match scaled {
                Ok(v) => format!("{key} = {v:e}"),
                Err(_) => format!("{key} = {}", EXTREMES[rng.below(EXTREMES.len())]),
            };
        }
        _ => out[at] = format!("{key} = {}", EXTREMES[rng.below(EXTREMES.len())]),
    }
    out.join("\n")
}

/// Loads, and when cheap plans and steps one frame; panics propagate to the caller.
fn exercise(text: &str, path: &std::path::Path) {
    let Ok(mut scene) = Scene::parse(text, path) else {
        return;
    };
    // Bodies bake an SDF per new resolution (seconds each): their loading is fuzzed, not
    // their runs. Large or many-substep scenes are refused by their own checks or skipped.
    if !scene.bodies.is_empty() {
        return;
    }
    scene.solver.frames = 1;
    scene.solver.max_substeps_per_frame = scene.solver.max_substeps_per_frame.min(400);
    scene.solver.max_memory_bytes = Some(64 << 20);
    let Ok(prep) = prepare(&scene) else {
        return;
    };
    let mut cpu = CpuSolver::new(&prep.model, prep.params, &prep.plan);
    let mut stats = RunStats::default();
    let _ = simulate(&prep, &mut cpu, &mut stats, |_, _| Ok(()));
}

#[test]
fn mutated_scenes_never_panic() {
    let inputs: usize = std::env::var("DRAPEKIT_FUZZ_INPUTS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(DEFAULT_INPUTS);
    let dir = common::fixture("scenes");
    let mut scenes: Vec<(std::path::PathBuf, String)> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .map(|p| {
            let text = std::fs::read_to_string(&p).unwrap();
            (p, text)
        })
        .collect();
    scenes.sort();
    // Quiet the panic hook: a panic is collected and reported with its input below.
    std::panic::set_hook(Box::new(|_| {}));
    let mut rng = Rng(0x5eed_d4a9_e000_0001);
    let mut panics = Vec::new();
    for k in 0..inputs {
        let (path, src) = &scenes[k % scenes.len()];
        let text = mutate(src, &mut rng);
        if catch_unwind(AssertUnwindSafe(|| exercise(&text, path))).is_err() {
            panics.push(format!("{}:\n{text}", path.display()));
        }
    }
    let _ = std::panic::take_hook();
    eprintln!("fuzzed {inputs} mutated scenes, {} panicked", panics.len());
    assert!(
        panics.is_empty(),
        "{} of {inputs} inputs panicked; the first:\n{}",
        panics.len(),
        panics[0]
    );
}
