//! A structural fuzzer over the shipped sewing patterns. Each input is a shipped pattern with
//! one to three mutations: a member or list entry deleted, a value swapped for another JSON
//! type, a number made extreme or non-finite (the bare `NaN` / `Infinity` tokens Python
//! writes) or scaled, an edge stitched to itself, two panels given one name, an outline made
//! to cross itself, names and labels in odd Unicode, the text truncated, or a value buried in
//! deep nesting. Every input goes through what `drapekit plan` does (load, warnings, model,
//! plan, output estimate) and, when that succeeds, a one-frame `drapekit run` on the CPU path.
//!
//! A defect is a panic, an exit code other than 0, 2 or 3, an input over its time budget, or a
//! non-finite number in a summary. `DRAPEKIT_FUZZ_PATTERNS=N` sets the count (CI runs the
//! default); the seed is fixed, so a run is repeatable.

mod common;

use drapekit::run::{run_scene, BackendChoice, RunOptions};
use drapekit::scene::Scene;
use drapekit::Error;
use serde_json::Value;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// Inputs CI runs (about 40 s on two cores); a longer run:
/// DRAPEKIT_FUZZ_PATTERNS=100000 cargo test --release --test fuzz_patterns.
const DEFAULT_INPUTS: usize = 3000;

/// The most one input may take. The fuzz scene meshes at 5 cm under a 64 MiB cap: at most
/// about 50,000 particles, whose load, plan and implicit frame take about a second here; ten
/// times that allows for a loaded machine. More is a stall (as a quadratic outline test was).
const TIME_BUDGET: Duration = Duration::from_secs(10);

struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
    fn pick<'a, T>(&mut self, items: &'a [T]) -> &'a T {
        &items[self.below(items.len())]
    }
}

/// Numbers that break patterns; the non-finite ones are bare tokens, as Python's json writes.
const NUMBERS: &[&str] = &[
    "0",
    "-0",
    "-1",
    "1e-320",
    "1e-30",
    "1e30",
    "1e300",
    "-1e300",
    "1e308",
    "4294967296",
    "18446744073709551616",
    "0.5",
    "NaN",
    "Infinity",
    "-Infinity",
];

/// Values of every JSON type, for type swaps.
const OTHER_TYPES: &[&str] = &[
    "\"x\"",
    "null",
    "[]",
    "{}",
    "[1, 2]",
    "true",
    "{\"a\": 1}",
    "7",
];

/// Names that test the readers' and writers' Unicode handling.
const NAMES: &[&str] = &[
    "",
    " ",
    "ärmel",
    "袖",
    "🧵 sleeve",
    "\u{202e}evéels",
    "e\u{301}",
    "a\u{0}b",
    "front",
    "back",
    "con",
    "../../etc",
    "a b\tc\nd",
];

/// Paths (keys and indices) to every value of `v`.
fn paths(v: &Value) -> Vec<Vec<String>> {
    fn walk(v: &Value, at: &mut Vec<String>, out: &mut Vec<Vec<String>>) {
        out.push(at.clone());
        match v {
            Value::Object(m) => m.iter().for_each(|(k, c)| {
                at.push(k.clone());
                walk(c, at, out);
                at.pop();
            }),
            Value::Array(a) => a.iter().enumerate().for_each(|(i, c)| {
                at.push(i.to_string());
                walk(c, at, out);
                at.pop();
            }),
            _ => {}
        }
    }
    let mut out = Vec::new();
    walk(v, &mut Vec::new(), &mut out);
    out
}

fn at_mut<'a>(v: &'a mut Value, path: &[String]) -> Option<&'a mut Value> {
    path.iter().try_fold(v, |v, key| match v {
        Value::Object(m) => m.get_mut(key),
        Value::Array(a) => a.get_mut(key.parse::<usize>().ok()?),
        _ => None,
    })
}

/// A placeholder replaced in the text after serialising: a number JSON cannot hold, or text
/// that is not a value at all.
const RAW: &str = "@@RAW@@";

/// The panels object of a pattern, if it has one.
fn panels(v: &mut Value) -> Option<&mut serde_json::Map<String, Value>> {
    v.get_mut("pattern")?.get_mut("panels")?.as_object_mut()
}

/// One structural mutation of the pattern tree; text-level ones are returned as
/// `(placeholder value, raw text)` to splice in after serialising.
fn mutate(v: &mut Value, rng: &mut Rng) -> Option<String> {
    let all = paths(v);
    if all.len() < 2 {
        // Nothing left below the root (earlier mutations emptied it).
        return None;
    }
    let path = all[1 + rng.below(all.len() - 1)].clone();
    // Number mutations pick among the numbers, so that the structure survives them.
    let numbers: Vec<&Vec<String>> = (all.iter())
        .filter(|p| {
            let mut v = v.clone();
            at_mut(&mut v, p).is_some_and(|x| x.is_number())
        })
        .collect();
    let number = numbers.get(rng.below(numbers.len())).map(|p| (*p).clone());
    // Weights: breaking the structure is easy; inputs that still run fuzz the run path.
    const KINDS: [usize; 10] = [2, 2, 3, 5, 1, 1, 2, 2, 1, 1];
    let mut pick = rng.below(KINDS.iter().sum());
    let kind = KINDS.iter().position(|&w| {
        let hit = pick < w;
        pick = pick.saturating_sub(w);
        hit
    });
    match kind.unwrap_or(0) {
        // Delete a member or list entry.
        0 => {
            let (last, parent) = path.split_last()?;
            match at_mut(v, parent)? {
                Value::Object(m) => {
                    m.remove(last);
                }
                Value::Array(a) => {
                    a.remove(last.parse::<usize>().ok()?);
                }
                _ => {}
            }
            None
        }
        // Swap the value for another type.
        1 => {
            let other = OTHER_TYPES[rng.below(OTHER_TYPES.len())];
            *at_mut(v, &path)? = serde_json::from_str(other).unwrap();
            None
        }
        // An extreme or non-finite number (as raw text).
        2 => {
            *at_mut(v, &number?)? = Value::String(RAW.into());
            Some(rng.pick(NUMBERS).to_string())
        }
        // Scale a number by a large or small power of ten.
        3 => {
            let slot = at_mut(v, &number?)?;
            if let Some(x) = slot.as_f64() {
                *slot = serde_json::json!(x * rng.pick(&[1e-9, 1e-3, 1e3, 1e6, 1e9, -1.0]));
            }
            None
        }
        // Stitch an edge to itself, or to its neighbour.
        4 => {
            let names: Vec<String> = panels(v)?.keys().cloned().collect();
            if names.is_empty() {
                return None;
            }
            let name = rng.pick(&names).clone();
            let e = rng.below(4);
            let other = if rng.below(2) == 0 { e } else { e + 1 };
            let stitch =
                serde_json::json!([{"panel": name, "edge": e}, {"panel": name, "edge": other}]);
            let stitches = v.get_mut("pattern")?.get_mut("stitches")?.as_array_mut()?;
            stitches.push(stitch);
            None
        }
        // Two panels with one name (JSON keeps both keys in the text).
        5 => {
            let names: Vec<String> = panels(v)?.keys().cloned().collect();
            if names.is_empty() {
                return None;
            }
            let (a, b) = (rng.pick(&names).clone(), rng.pick(&names).clone());
            let panel = panels(v)?.remove(&a)?;
            panels(v)?.insert(format!("{RAW}{b}"), panel);
            Some(format!("dup:{b}"))
        }
        // Make an outline cross itself: swap two corners, or throw one across the panel.
        6 => {
            let names: Vec<String> = panels(v)?.keys().cloned().collect();
            if names.is_empty() {
                return None;
            }
            let name = rng.pick(&names).clone();
            let verts = panels(v)?
                .get_mut(&name)?
                .get_mut("vertices")?
                .as_array_mut()?;
            let n = verts.len();
            if n >= 4 {
                let (i, j) = (rng.below(n), rng.below(n));
                if rng.below(2) == 0 {
                    verts.swap(i, j);
                } else {
                    let far = verts[j].clone();
                    let x = far.get(0).and_then(Value::as_f64).unwrap_or(0.0);
                    let y = far.get(1).and_then(Value::as_f64).unwrap_or(0.0);
                    verts[i] = serde_json::json!([-3.0 * x, -3.0 * y]);
                }
            }
            None
        }
        // Odd Unicode in a panel name, a label, or a string value.
        7 => {
            let name = rng.pick(NAMES).to_string();
            if rng.below(2) == 0 {
                let names: Vec<String> = panels(v)?.keys().cloned().collect();
                if names.is_empty() {
                    return None;
                }
                let old = rng.pick(&names).clone();
                let panel = panels(v)?.remove(&old)?;
                panels(v)?.insert(name, panel);
            } else {
                *at_mut(v, &path)? = Value::String(name);
            }
            None
        }
        // Bury a value in deep nesting (past the JSON reader's recursion limit, or not).
        8 => {
            let depth = *rng.pick(&[3usize, 100, 127, 129, 5000]);
            *at_mut(v, &path)? = Value::String(RAW.into());
            let open = if rng.below(2) == 0 { "[" } else { "{\"a\":" };
            let close = if open == "[" { "]" } else { "}" };
            Some(format!("{}1{}", open.repeat(depth), close.repeat(depth)))
        }
        // Truncate the text (marked here, cut after serialising).
        _ => Some("truncate".into()),
    }
}

/// A mutated pattern's text.
fn mutated_text(original: &Value, rng: &mut Rng) -> String {
    let mut v = original.clone();
    let mut raws = Vec::new();
    let mut truncate = false;
    // One mutation in most inputs, two or three in some.
    for _ in 0..*rng.pick(&[1, 1, 1, 2, 2, 3]) {
        match mutate(&mut v, rng) {
            Some(t) if t == "truncate" => truncate = true,
            Some(t) => raws.push(t),
            None => {}
        }
    }
    let mut text = serde_json::to_string(&v).unwrap();
    for raw in raws {
        text = match raw.strip_prefix("dup:") {
            // The renamed panel's key becomes the other panel's name: a duplicate key.
            Some(name) => text.replacen(&format!("\"{RAW}{name}\""), &format!("\"{name}\""), 1),
            None => text.replacen(&format!("\"{RAW}\""), &raw, 1),
        };
    }
    if truncate {
        let mut cut = rng.below(text.len());
        while !text.is_char_boundary(cut) {
            cut -= 1;
        }
        text.truncate(cut);
    }
    text
}

/// How one input ended; `Err` is a defect.
fn exercise(text: &str, work: &Path) -> Result<i32, String> {
    std::fs::write(work.join("pattern.json"), text).unwrap();
    let scene_path = work.join("scene.toml");
    let scene_text = "[cloth.pattern]\npath = \"pattern.json\"\nparticle_distance_m = 0.05\n\
                      [fabric]\npreset = \"cotton\"\n[solver]\nfps = 24\nframes = 1\n\
                      integrator = \"implicit\"\nmax_memory_mb = 64\n[output]\nobj = true\n";
    let code = |e: &Error| match e.exit_code() {
        c @ (2 | 3) => Ok(c),
        c => Err(format!("exit code {c}: {e}")),
    };
    // What `drapekit plan` does.
    let scene = match Scene::parse(scene_text, &scene_path) {
        Ok(s) => s,
        Err(e) => return code(&Error::Input(e)),
    };
    if std::env::var_os("DRAPEKIT_FUZZ_VERBOSE").is_some() {
        if let Err(e) = drapekit::pattern::Pattern::load(&work.join("pattern.json")) {
            eprintln!("refused: {}", e.problem);
        }
    }
    let _ = drapekit::model::budget::load_warnings(&scene);
    let out = work.join("out");
    let planned = drapekit::sim::prepare(&scene).and_then(|prep| {
        drapekit::export::disk::check_space(&scene, &prep, &out, 0)?;
        Ok(())
    });
    if let Err(e) = planned {
        return code(&e);
    }
    // One frame of `drapekit run`.
    let opts = RunOptions {
        backend: BackendChoice::Cpu,
        adapter: drapekit::gpu::AdapterChoice::Auto,
        out_dir: Some(out.clone()),
        frames: None,
        progress: false,
        checkpoint_every: None,
        overwrite: false,
    };
    let result = run_scene(&scene, &opts);
    let summary = std::fs::read_to_string(out.join("summary.json")).unwrap_or_default();
    let _ = std::fs::remove_dir_all(&out);
    if summary.contains("non-finite values in the summary") {
        return Err(format!("a non-finite number in summary.json:\n{summary}"));
    }
    match result {
        Ok(s) if !s.non_finite_fields().is_empty() => Err(format!(
            "non-finite summary fields {:?}",
            s.non_finite_fields()
        )),
        Ok(_) => Ok(0),
        Err(e) => code(&e),
    }
}

#[test]
fn mutated_patterns_have_no_defect() {
    let inputs: usize = std::env::var("DRAPEKIT_FUZZ_PATTERNS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(DEFAULT_INPUTS);
    let mut patterns: Vec<(PathBuf, Value)> = std::fs::read_dir(common::fixture("patterns"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "json"))
        .map(|p| {
            let v = serde_json::from_str(&std::fs::read_to_string(&p).unwrap()).unwrap();
            (p, v)
        })
        .collect();
    patterns.sort_by(|a, b| a.0.cmp(&b.0));
    // DRAPEKIT_FUZZ_ONLY=k1,k2 runs only those inputs (of the first N), to reproduce a defect.
    let only: Option<Vec<usize>> = std::env::var("DRAPEKIT_FUZZ_ONLY")
        .ok()
        .map(|v| v.split(',').filter_map(|k| k.trim().parse().ok()).collect());
    let only = &only;
    // Quiet the panic hook: a panic is collected and reported with its input below.
    std::panic::set_hook(Box::new(|_| {}));
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let started = Instant::now();
    let results: Vec<(Vec<String>, [usize; 4], Duration)> = std::thread::scope(|scope| {
        let handles: Vec<_> = (0..threads)
            .map(|t| {
                let patterns = &patterns;
                scope.spawn(move || {
                    let work = std::env::temp_dir()
                        .join(format!("drapekit-fuzzp-{}-{t}", std::process::id()));
                    std::fs::create_dir_all(&work).unwrap();
                    let (mut defects, mut codes, mut slowest) =
                        (Vec::new(), [0usize; 4], Duration::ZERO);
                    for k in (t..inputs).step_by(threads) {
                        if only.as_ref().is_some_and(|o| !o.contains(&k)) {
                            continue;
                        }
                        // Each input's own seed: the same input whatever the thread count.
                        let mut rng =
                            Rng(0x5eed_9a77_e400_0001
                                ^ (k as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15));
                        let (path, original) = &patterns[k % patterns.len()];
                        // A bug in the mutator fails the test with its input number (the
                        // panic hook is quiet here, so it is reported like a defect).
                        let mutated =
                            catch_unwind(AssertUnwindSafe(|| mutated_text(original, &mut rng)));
                        let text = match mutated {
                            Ok(text) => text,
                            Err(p) => {
                                let why = (p.downcast_ref::<String>().cloned())
                                    .or_else(|| p.downcast_ref::<&str>().map(|s| s.to_string()));
                                defects.push(format!(
                                    "the mutator panicked on input {k} (a test bug): {why:?}"
                                ));
                                continue;
                            }
                        };
                        if t == 0 && k % 10_000 < threads {
                            eprintln!("fuzzing input {k} of {inputs}");
                        }
                        let start = Instant::now();
                        let outcome = catch_unwind(AssertUnwindSafe(|| exercise(&text, &work)))
                            .unwrap_or_else(|_| Err("panicked".into()));
                        let took = start.elapsed();
                        slowest = slowest.max(took);
                        let shown = || format!("input {k} from {}:\n{text:.2000}", path.display());
                        match outcome {
                            Ok(c) => codes[c as usize] += 1,
                            Err(why) => defects.push(format!("{why}\n{}", shown())),
                        }
                        if took > TIME_BUDGET {
                            defects
                                .push(format!("took {took:?}, over {TIME_BUDGET:?}\n{}", shown()));
                        }
                    }
                    let _ = std::fs::remove_dir_all(&work);
                    (defects, codes, slowest)
                })
            })
            .collect();
        handles.into_iter().map(|h| h.join().unwrap()).collect()
    });
    let _ = std::panic::take_hook();
    let defects: Vec<&String> = results.iter().flat_map(|r| &r.0).collect();
    let codes = results.iter().fold([0usize; 4], |mut a, r| {
        (0..4).for_each(|i| a[i] += r.1[i]);
        a
    });
    let slowest = results.iter().map(|r| r.2).max().unwrap_or_default();
    eprintln!(
        "fuzzed {inputs} mutated patterns in {:.1} s on {threads} threads: {} ran (exit 0), {} \
         refused as bad input (2), {} stopped as unstable (3); slowest input {slowest:.2?}; {} \
         defect(s)",
        started.elapsed().as_secs_f64(),
        codes[0],
        codes[2],
        codes[3],
        defects.len()
    );
    let shown: Vec<&str> = defects.iter().take(20).map(|d| d.as_str()).collect();
    assert!(
        defects.is_empty(),
        "{} of {inputs} inputs are defects; the first {}:\n{}",
        defects.len(),
        shown.len(),
        shown.join("\n\n")
    );
    // The mutations must leave some inputs runnable, or the run path goes unfuzzed.
    if only.is_none() {
        assert!(
            codes[0] * 10 >= inputs,
            "only {} of {inputs} inputs ran",
            codes[0]
        );
    }
}
