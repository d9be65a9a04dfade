//! `drapekit bench fabric --out DIR`: every fabric preset in two virtual standard tests, against
//! published values: the Cusick drape test ([`cusick`]) against measured drape-coefficient
//! bands, and the cantilever bending test ([`cantilever`]) against the preset's rigidity and the
//! exact elastica. Each specimen ([`specimen`]) is a pattern panel, meshed as garments are, and
//! is kept as a scene under `DIR/specimens/`. Writes `fabric.csv` and `fabric.md`.

pub mod cantilever;
pub mod cusick;
mod report;
pub mod specimen;

pub use report::CSV_COLUMNS;
pub use specimen::Stepping;

use crate::atomic_file::write_atomic;
use crate::error::{Error, InputError};
use crate::gpu::{AdapterChoice, GpuContext};
use crate::run::BackendChoice;
use crate::scene::{preset, FabricPreset, PRESETS};
use specimen::{Outline, HEIGHT_M};
use std::path::{Path, PathBuf};

/// Gravity of the specimens' scenes, m/s².
const GRAVITY: f64 = 9.81;
/// A Cusick specimen has settled when no particle moved more than this (m) over the settle
/// window: a 0.5 mm move of the hem changes the shadow by under 0.5 mm × 1 m of outline,
/// 1% of the annulus, and less as the motion dies away.
const CUSICK_SETTLED_M: f32 = 5e-4;
/// A cantilever strip has settled when its tip moved no more than this (m) over the window:
/// 0.1 mm of a 5 cm strip's tip turns its chord by about 0.1°.
const CANTILEVER_SETTLED_M: f32 = 1e-4;

/// The options of `drapekit bench fabric`.
#[derive(Clone, Debug)]
pub struct FabricOptions {
    /// Output folder.
    pub out: PathBuf,
    /// Coarser specimens and fewer frames.
    pub quick: bool,
    /// The presets to test (empty: all).
    pub presets: Vec<String>,
    /// How every specimen is stepped.
    pub stepping: Stepping,
    /// The Cusick specimen's particle spacing, m (None: 7.5 mm, 1.5 cm with `quick`).
    pub cusick_spacing: Option<f64>,
    /// Which tests to run: the Cusick drape test, the cantilevers, or both.
    pub tests: Tests,
    /// Which path runs the specimens (the CPU twin gives the reference figures).
    pub backend: BackendChoice,
    /// The adapter, for the GPU path.
    pub adapter: AdapterChoice,
    /// The command line, for the report.
    pub command: String,
}

/// Which of the two tests a run makes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Tests {
    /// The Cusick drape test.
    pub cusick: bool,
    /// The cantilever bending test.
    pub cantilever: bool,
}

/// A published drape-coefficient band, in %.
#[derive(Clone, Copy, Debug)]
pub struct Band {
    /// Lowest published DC, %.
    pub low: f64,
    /// Highest published DC, %.
    pub high: f64,
    /// Where it comes from (docs/src/benchmarks/fabric.md).
    pub source: &'static str,
}

/// The published Cusick band of a preset, where one was found.
pub fn drape_band(preset: &str) -> Option<Band> {
    let band = |low, high, source| Some(Band { low, high, source });
    match preset {
        "cotton" => band(60.0, 76.0, "Gan et al. 1991 (68.4 measured) via ppf [2]"),
        "denim" => band(70.0, 90.0, "ppf calibration band [2, weak]"),
        "silk" => band(
            20.0,
            40.0,
            "Matsudaira & Yang 2003, Hu et al. 2020 via ppf [2]",
        ),
        "wool" => band(40.0, 70.0, "ppf, wool worsted drape studies [2, weak]"),
        "leather" => band(47.35, 69.9, "Memon et al. 2021, 4 sheep leathers [M]"),
        _ => None,
    }
}

/// One preset in one test.
#[derive(Clone, Debug)]
pub struct FabricRow {
    /// The preset (its bending rigidity scaled by `--bending-scale`).
    pub preset: FabricPreset,
    /// `"cusick"`, `"cantilever"` (along the warp), `"cantilever_weft"` or
    /// `"cantilever_bias"`.
    pub test: &'static str,
    /// DC in % (Cusick) or G in N·m (cantilever).
    pub simulated: f64,
    /// The published band (Cusick).
    pub band: Option<Band>,
    /// Folds around the hem (Cusick).
    pub nodes: Option<usize>,
    /// Cantilever: the overhang at the test angle, m, and whether the runs bracketed it.
    pub overhang: Option<(f64, bool)>,
    /// Cantilever: the overhang at which the exact elastica of rigidity B reaches the line, m.
    pub elastica_overhang: Option<f64>,
    /// Cantilever: the mean of simulated − elastica chord angle over the runs, degrees.
    pub angle_error_deg: Option<f64>,
    /// Particles of the (largest) specimen.
    pub particles: usize,
    /// Particle spacing, m.
    pub spacing: f64,
    /// Substeps per frame.
    pub substeps: u32,
    /// Frames simulated (summed over a cantilever's runs).
    pub frames: u32,
    /// Whether every run met the settle rule.
    pub settled: bool,
    /// Simulation seconds (summed over a cantilever's runs).
    pub wall_seconds: f64,
    /// Implicit Euler's RMS force residual at the end, relative to the weight (the largest
    /// over a cantilever's runs); `None` for explicit integrators.
    pub force_residual_rms: Option<f32>,
    /// Implicit Euler's Newton steps and sweeps (summed over a cantilever's runs).
    pub solve_work: specimen::SolveWork,
}

impl FabricRow {
    /// Weight per area, N/m².
    pub fn weight(&self) -> f64 {
        self.preset.density_kg_m2 * GRAVITY
    }
}

/// Drapes `p` in the Cusick rig: held within the disc radius, settled under gravity.
fn cusick_row(
    p: &FabricPreset,
    dir: &Path,
    spacing: f64,
    step: &Stepping,
    gpu: Option<&GpuContext>,
) -> Result<FabricRow, Error> {
    let disc = cusick::DISC_RADIUS_M as f32;
    let s = specimen::settle(
        &dir.join(format!("cusick-{}", p.name)),
        p.name,
        None,
        0.0,
        Outline::Circle {
            radius: cusick::SPECIMEN_RADIUS_M,
        },
        spacing,
        step,
        gpu,
        CUSICK_SETTLED_M,
        |x| x.x.hypot(x.z) <= disc,
    )?;
    let dc = 100.0 * cusick::drape_coefficient(&s.rest, &s.positions, &s.triangles);
    Ok(FabricRow {
        preset: *p,
        test: "cusick",
        simulated: dc,
        band: drape_band(p.name),
        // A fold stands out of the hem by at least a spacing.
        nodes: Some(cusick::nodes(&s.rest, &s.positions, spacing, spacing)),
        overhang: None,
        elastica_overhang: None,
        angle_error_deg: None,
        particles: s.particles,
        spacing,
        substeps: s.substeps,
        frames: s.frames,
        settled: s.settled_frame.is_some(),
        wall_seconds: s.wall_seconds,
        force_residual_rms: s.force_residual_rms,
        solve_work: s.solve_work,
    })
}

/// Strip width, m (ASTM D1388: 25 mm).
const STRIP_WIDTH_M: f64 = 0.025;
/// The strip's length on the platform, held, m.
const CLAMP_M: f64 = 0.01;
/// The cantilever strip's stretch stiffness is capped at this (N/m): the test measures bending
/// of a strip its own weight barely stretches (leather's 0.3 kg/m² over 5 cm pull its clamp
/// with 0.15 N/m, a strain of 3e-4 at this stiffness), and the explicit step shrinks as the
/// square root of the stiffness: leather's 5.8e4 N/m would take 11× the substeps.
const CANTILEVER_STRETCH_N_M: f64 = 500.0;

/// The cantilever strips a run cuts: along the warp only for springs (which have no grain);
/// along the warp, the weft and the bias for a membrane. (test name, grain from the strip's
/// length in degrees.)
fn cantilever_cuts(step: &Stepping) -> &'static [(&'static str, f64)] {
    if step.fabric_model == "membrane" {
        &[
            ("cantilever", 0.0),
            ("cantilever_weft", 90.0),
            ("cantilever_bias", 45.0),
        ]
    } else {
        &[("cantilever", 0.0)]
    }
}

/// Bends `p` cut `grain_deg` from the warp over the platform edge at overhangs around the
/// elastica's, and finds where its tip crosses the test line.
fn cantilever_row(
    p: &FabricPreset,
    dir: &Path,
    quick: bool,
    step: &Stepping,
    gpu: Option<&GpuContext>,
    (test, grain_deg): (&'static str, f64),
) -> Result<FabricRow, Error> {
    let b = specimen::strip_rigidity(p, step, grain_deg);
    // The row reports the rigidity this strip was given.
    let p = &FabricPreset {
        bending_stiffness_n_m: b,
        ..*p
    };
    let w = p.density_kg_m2 * GRAVITY;
    let expected = cantilever::elastica_overhang(b, w);
    // About 16 particles along the expected overhang (12 with --quick).
    let spacing = expected / if quick { 12.0 } else { 16.0 };
    let factors: &[f64] = if quick {
        &[0.9, 1.1]
    } else {
        &[0.85, 1.0, 1.15]
    };
    let (mut points, mut errors) = (Vec::new(), Vec::new());
    let mut row = FabricRow {
        preset: *p,
        test,
        simulated: f64::NAN,
        band: None,
        nodes: None,
        overhang: None,
        elastica_overhang: Some(expected),
        angle_error_deg: None,
        particles: 0,
        spacing,
        substeps: 0,
        frames: 0,
        settled: true,
        wall_seconds: 0.0,
        force_residual_rms: None,
        solve_work: specimen::SolveWork::default(),
    };
    for (k, f) in factors.iter().enumerate() {
        let overhang = f * expected;
        let s = specimen::settle(
            &dir.join(format!("{test}-{}-{}", p.name, k + 1)),
            p.name,
            Some(p.stretch_stiffness_n_m.min(CANTILEVER_STRETCH_N_M)),
            grain_deg,
            Outline::Strip {
                x0: -CLAMP_M,
                x1: overhang,
                width: STRIP_WIDTH_M,
            },
            spacing,
            step,
            gpu,
            CANTILEVER_SETTLED_M,
            |x| x.x <= 0.0,
        )?;
        let (clamp_x, end_x) = clamp_and_end(&s);
        let length = (end_x - clamp_x) as f64;
        let chord = tip_now(&s, end_x) - glam::Vec2::new(clamp_x, HEIGHT_M as f32);
        let angle_now = (-chord.y as f64).atan2(chord.x as f64).to_degrees();
        points.push((length, angle_now));
        errors.push(angle_now - cantilever::elastica_angle(length, b, w));
        row.particles = row.particles.max(s.particles);
        row.substeps = s.substeps;
        row.frames += s.frames;
        row.settled &= s.settled_frame.is_some();
        row.wall_seconds += s.wall_seconds;
        row.solve_work.add(s.solve_work);
        row.force_residual_rms = match (row.force_residual_rms, s.force_residual_rms) {
            (Some(a), Some(b)) => Some(a.max(b)),
            (a, b) => a.or(b),
        };
    }
    row.overhang = cantilever::crossing(&points);
    row.simulated = row
        .overhang
        .map_or(f64::NAN, |(l, _)| cantilever::rigidity(l, w));
    row.angle_error_deg = Some(errors.iter().sum::<f64>() / errors.len() as f64);
    Ok(row)
}

/// The clamp line (the mean rest x of the held particles that share a triangle with a free
/// one: the strip turns about them) and the rest x of the strip's free end.
fn clamp_and_end(s: &specimen::Settled) -> (f32, f32) {
    let held = |i: u32| s.rest[i as usize].x <= 0.0;
    let mut edge = vec![false; s.rest.len()];
    for t in &s.triangles {
        if t.iter().any(|&i| !held(i)) {
            for &i in t.iter().filter(|&&i| held(i)) {
                edge[i as usize] = true;
            }
        }
    }
    let xs: Vec<f32> = (0..s.rest.len())
        .filter(|&i| edge[i])
        .map(|i| s.rest[i].x)
        .collect();
    let clamp_x = xs.iter().sum::<f32>() / xs.len().max(1) as f32;
    let end_x = s.rest.iter().map(|p| p.x).fold(f32::MIN, f32::max);
    (clamp_x, end_x)
}

/// The settled free end: the mean (x, y) of the particles on the strip's end edge.
fn tip_now(s: &specimen::Settled, end_x: f32) -> glam::Vec2 {
    let tip: Vec<usize> = (0..s.rest.len())
        .filter(|&i| s.rest[i].x >= end_x - 1e-6)
        .collect();
    let sum: glam::Vec2 = tip
        .iter()
        .map(|&i| glam::Vec2::new(s.positions[i].x, s.positions[i].y))
        .sum();
    sum / tip.len().max(1) as f32
}

/// Runs `drapekit bench fabric`.
pub fn run_cli(opts: &FabricOptions) -> Result<Vec<FabricRow>, Error> {
    if opts.stepping.tolerance.is_some() && opts.stepping.integrator != "implicit" {
        return Err(InputError::new(
            Path::new("drapekit bench fabric"),
            "--tolerance",
            "a tolerance ends implicit Euler's solves; the explicit integrators have none",
            "remove --tolerance, or add --integrator implicit",
        )
        .into());
    }
    if opts.cusick_spacing.is_some() && !opts.tests.cusick {
        return Err(InputError::new(
            Path::new("drapekit bench fabric"),
            "--cusick-spacing-mm",
            "the Cusick specimen's spacing, but --tests leaves the Cusick test out",
            "remove --cusick-spacing-mm, or add cusick to --tests",
        )
        .into());
    }
    let presets: Vec<&'static FabricPreset> = if opts.presets.is_empty() {
        PRESETS.iter().collect()
    } else {
        let mut list = Vec::new();
        for name in &opts.presets {
            list.push(preset(name).ok_or_else(|| {
                let names: Vec<&str> = PRESETS.iter().map(|p| p.name).collect();
                InputError::new(
                    Path::new("drapekit bench fabric"),
                    "--presets",
                    format!("there is no preset {name:?}"),
                    format!("use some of {}", names.join(", ")),
                )
            })?);
        }
        list
    };
    let (gpu, device) = super::choose_device(opts.backend, &opts.adapter)?;
    println!("specimens run on {device}");
    let dir = opts.out.join("specimens");
    let mut rows = Vec::new();
    let cusick_spacing = opts
        .cusick_spacing
        .unwrap_or(if opts.quick { 0.015 } else { 0.0075 });
    let cuts = if opts.tests.cantilever {
        cantilever_cuts(&opts.stepping)
    } else {
        &[]
    };
    for p in presets {
        let p = &FabricPreset {
            bending_stiffness_n_m: specimen::bending_rigidity(p, &opts.stepping),
            ..*p
        };
        if opts.tests.cusick {
            let row = cusick_row(p, &dir, cusick_spacing, &opts.stepping, gpu.as_ref())?;
            println!("{}", report::line(&row));
            rows.push(row);
        }
        for &cut in cuts {
            let row = cantilever_row(p, &dir, opts.quick, &opts.stepping, gpu.as_ref(), cut)?;
            println!("{}", report::line(&row));
            rows.push(row);
        }
    }
    std::fs::create_dir_all(&opts.out).map_err(|e| Error::io(&opts.out, e))?;
    let (csv, md) = (opts.out.join("fabric.csv"), opts.out.join("fabric.md"));
    write_atomic(&csv, report::csv_text(&rows).as_bytes())?;
    write_atomic(&md, report::md_text(&rows, opts, &device).as_bytes())?;
    println!("wrote {} and {}", csv.display(), md.display());
    Ok(rows)
}
