//! `fabric.csv` and `fabric.md` from the rows of `drapekit bench fabric`.

use super::{FabricOptions, FabricRow, GRAVITY};
use std::fmt::Write as _;

/// The columns of `fabric.csv`, documented in docs/src/benchmarks/fabric.md.
pub const CSV_COLUMNS: &[&str] = &[
    "preset",
    "test",
    "simulated",
    "unit",
    "published_low",
    "published_high",
    "within_published",
    "source",
    "nodes",
    "preset_b_n_m",
    "overhang_m",
    "bracketed",
    "elastica_overhang_m",
    "g_over_b",
    "elastica_g_over_b",
    "angle_error_deg",
    "particles",
    "spacing_m",
    "substeps_per_frame",
    "frames",
    "settled",
    "wall_seconds",
    "force_residual_rms",
    "newton_steps_per_substep",
    "sweeps_per_substep",
];

fn num(v: Option<f64>) -> String {
    match v {
        // Shortest text that reads back as the same f64: G is of order 1e-5.
        Some(v) if v.is_finite() => format!("{v}"),
        _ => String::new(),
    }
}

/// The cantilever's G/B, and what the standard procedure gives a perfect strip: (l_e/2)³·W/B.
fn ratios(r: &FabricRow) -> (Option<f64>, Option<f64>) {
    let b = r.preset.bending_stiffness_n_m;
    if !r.test.starts_with("cantilever") {
        return (None, None);
    }
    let ideal = r
        .elastica_overhang
        .map(|l| super::cantilever::rigidity(l, r.weight()) / b);
    (Some(r.simulated / b), ideal)
}

fn within(r: &FabricRow) -> &'static str {
    match r.band {
        Some(b) if r.simulated.is_finite() => {
            if (b.low..=b.high).contains(&r.simulated) {
                "yes"
            } else {
                "no"
            }
        }
        _ => "",
    }
}

pub(super) fn csv_text(rows: &[FabricRow]) -> String {
    let mut csv = CSV_COLUMNS.join(",") + "\n";
    for r in rows {
        let (gb, ideal) = ratios(r);
        let work = r.solve_work.per_substep();
        let _ = writeln!(
            csv,
            "{},{},{},{},{},{},{},\"{}\",{},{},{},{},{},{},{},{},{},{},{},{},{},{:.3},{},{},{}",
            r.preset.name,
            r.test,
            num(Some(r.simulated)),
            if r.test == "cusick" { "%" } else { "N·m" },
            num(r.band.map(|b| b.low)),
            num(r.band.map(|b| b.high)),
            within(r),
            r.band.map_or("", |b| b.source),
            r.nodes.map_or(String::new(), |n| n.to_string()),
            num(Some(r.preset.bending_stiffness_n_m)),
            num(r.overhang.map(|o| o.0)),
            r.overhang.map_or("", |o| if o.1 { "yes" } else { "no" }),
            num(r.elastica_overhang),
            num(gb),
            num(ideal),
            num(r.angle_error_deg),
            r.particles,
            num(Some(r.spacing)),
            r.substeps,
            r.frames,
            if r.settled { "yes" } else { "no" },
            r.wall_seconds,
            num(r.force_residual_rms.map(f64::from)),
            num(work.map(|w| w.0)),
            num(work.map(|w| w.1)),
        );
    }
    csv
}

/// One line of progress for the terminal.
pub(super) fn line(r: &FabricRow) -> String {
    match r.test {
        "cusick" => format!(
            "{:<9} cusick      DC {:5.1}% (published {}) {} nodes, {} particles, {:.1} s",
            r.preset.name,
            r.simulated,
            r.band
                .map_or("none".to_string(), |b| format!("{}–{}%", b.low, b.high)),
            r.nodes.unwrap_or(0),
            r.particles,
            r.wall_seconds
        ),
        _ => {
            let (gb, ideal) = ratios(r);
            format!(
                "{:<9} {:<16} G {:.3e} N·m, G/B {:.3} (perfect strip {:.3}), angle error {:+.2}°, {:.1} s",
                r.preset.name,
                r.test,
                r.simulated,
                gb.unwrap_or(f64::NAN),
                ideal.unwrap_or(f64::NAN),
                r.angle_error_deg.unwrap_or(f64::NAN),
                r.wall_seconds
            )
        }
    }
}

fn stepping_text(s: &super::Stepping) -> String {
    let steps = s
        .substeps
        .map_or("the stability estimate's".to_string(), |n| n.to_string());
    let stepping = match s.integrator.as_str() {
        "implicit" => format!(
            "implicit Euler, {steps} steps a frame of {}",
            s.iterations.map_or(
                "the default iterations (1 Newton step with coarse levels, 10 \
                 sweeps without)"
                    .to_string(),
                |n| format!(
                    "{n} iterations (Newton steps with \
                 coarse levels, sweeps without)"
                )
            )
        ),
        other => format!("{other} Euler, {steps} substeps a frame"),
    };
    let stepping = match (s.integrator.as_str(), s.tolerance) {
        ("implicit", Some(t)) => format!(
            "{stepping} at most, each step's solve ending once its RMS force residual is at \
             most {t} of the weight"
        ),
        _ => stepping,
    };
    let model = match s.fabric_model.as_str() {
        "membrane" => ", the orthotropic membrane (warp, weft and shear)",
        _ => ", isotropic edge springs",
    };
    let bending = s.bending_scale.map_or(String::new(), |f| {
        format!(", every preset's bending rigidity times {f} (B here and `preset_b_n_m` in fabric.csv are the scaled values)")
    });
    let compression = if s.buckling {
        ", cloth that buckles in compression at its strip's Euler load"
    } else {
        ""
    };
    stepping + model + compression + &bending
}

pub(super) fn md_text(rows: &[FabricRow], opts: &FabricOptions, device: &str) -> String {
    let tests = match (opts.tests.cusick, opts.tests.cantilever) {
        (true, true) => "two virtual standard tests",
        (true, false) => "the virtual Cusick drape test",
        _ => "the virtual cantilever bending test",
    };
    let mut md = format!(
        "Fabric presets in {tests}, on {device}; {}, air damping \
         10/s, each specimen run until no particle moved more than 0.5 mm (Cusick) or 0.1 mm \
         (cantilever) over 0.25 s (at most {} frames at 24 fps). Command: `{}`.\n\n",
        stepping_text(&opts.stepping),
        opts.stepping.max_frames,
        opts.command
    );
    if opts.tests.cusick {
        md += &cusick_md(rows);
    }
    if opts.tests.cantilever {
        md += &cantilever_md(rows);
    }
    md
}

fn cusick_md(rows: &[FabricRow]) -> String {
    let mut md = String::new();
    md += "**Cusick drape test** (30 cm specimen held within an 18 cm disc; DC from the \
           shadow rasterised at 0.5 mm):\n\n\
           | preset | DC simulated | published | within | nodes | particles | spacing | frames | settled | force residual | Newton steps, sweeps a step | wall |\n\
           |---|---|---|---|---|---|---|---|---|---|---|---|\n";
    for r in rows.iter().filter(|r| r.test == "cusick") {
        let _ = writeln!(
            md,
            "| {} | {:.1}% | {} | {} | {} | {} | {:.2} mm | {} | {} | {} | {} | {:.1} s |",
            r.preset.name,
            r.simulated,
            r.band.map_or("not found".to_string(), |b| format!(
                "{}–{}% ({})",
                b.low, b.high, b.source
            )),
            match within(r) {
                "" => "–",
                w => w,
            },
            r.nodes.unwrap_or(0),
            r.particles,
            1e3 * r.spacing,
            r.frames,
            if r.settled { "yes" } else { "no" },
            r.force_residual_rms
                .map_or("–".to_string(), |f| format!("{f:.1e}")),
            r.solve_work
                .per_substep()
                .map_or("–".to_string(), |(n, s)| format!("{n:.2}, {s:.1}")),
            r.wall_seconds
        );
    }
    md
}

fn cantilever_md(rows: &[FabricRow]) -> String {
    let mut md = String::new();
    let _ = write!(
        md,
        "\n**Cantilever bending test** (25 mm strip held on the platform; the overhang at which \
         the tip reaches the 41.5° line, interpolated over the runs; G = ρ_A·g·(l/2)³ with \
         g = {GRAVITY} m/s²). \"Perfect strip\" is G/B for the exact elastica of rigidity B under \
         the same procedure (1 but for rounding: at 41.5° the elastica's overhang is twice its \
         bending length); the angle error is the \
         simulated chord angle less the elastica's at the same overhang, averaged over the runs:\n\n\
         | preset | cut | B (preset) | G simulated | G/B | perfect strip | angle error | overhang | particles | spacing | frames | settled | wall |\n\
         |---|---|---|---|---|---|---|---|---|---|---|---|---|\n"
    );
    for r in rows.iter().filter(|r| r.test.starts_with("cantilever")) {
        let (gb, ideal) = ratios(r);
        let cut = match r.test {
            "cantilever_weft" => "weft",
            "cantilever_bias" => "bias (45°)",
            _ => "warp",
        };
        let _ = writeln!(
            md,
            "| {} | {cut} | {:.3e} N·m | {:.3e} N·m | {:.3} | {:.3} | {:+.2}° | {:.1} mm{} | {} | {:.2} mm | {} | {} | {:.1} s |",
            r.preset.name,
            r.preset.bending_stiffness_n_m,
            r.simulated,
            gb.unwrap_or(f64::NAN),
            ideal.unwrap_or(f64::NAN),
            r.angle_error_deg.unwrap_or(f64::NAN),
            1e3 * r.overhang.map_or(f64::NAN, |o| o.0),
            if r.overhang.is_some_and(|o| !o.1) { " (extrapolated)" } else { "" },
            r.particles,
            1e3 * r.spacing,
            r.frames,
            if r.settled { "yes" } else { "no" },
            r.wall_seconds
        );
    }
    md
}
