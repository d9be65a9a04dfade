//! `peer.csv` and `peer.md`: the tables of `drapekit bench peer`.

use super::peer::{PeerOptions, PeerReport, PeerRow};
use super::python_peer::PINNED;
use crate::atomic_file::write_atomic;
use crate::error::Error;
use std::fmt::Write as _;

/// The CSV header; the first six columns are the documented ones.
pub const CSV_HEADER: &str = "system,backend,grid,particles,springs,particle_substeps_per_s,\
    integrator,substeps_per_frame,iterations,frames,median_frame_s,wall_s_per_simulated_s,\
    max_distance_to_warp_m,device";

fn csv(report: &PeerReport) -> String {
    let mut out = format!("{CSV_HEADER}\n");
    for r in &report.rows {
        let _ = writeln!(
            out,
            "{},{},{},{},{},{:.1},{},{},{},{},{:.6e},{:.6e},{},\"{}\"",
            r.system,
            r.backend,
            r.grid,
            r.particles,
            r.springs,
            r.particle_substeps_per_s(),
            r.integrator,
            r.substeps_per_frame,
            r.iterations,
            r.frames,
            r.median_frame_seconds,
            r.wall_s_per_simulated_s(),
            r.max_distance_to_warp_m
                .map(|d| format!("{d:.3e}"))
                .unwrap_or_default(),
            r.device.replace('"', "'")
        );
    }
    out
}

fn find<'a>(
    rows: &'a [PeerRow],
    grid: u32,
    system: &str,
    backend: &str,
    integrator: &str,
) -> Option<&'a PeerRow> {
    rows.iter().find(|r| {
        r.grid == grid && r.system == system && r.backend == backend && r.integrator == integrator
    })
}

/// Warp's row at `grid` under `integrator`, on whichever device it ran (one per run).
fn find_warp<'a>(rows: &'a [PeerRow], grid: u32, integrator: &str) -> Option<&'a PeerRow> {
    find(rows, grid, "warp", "cpu", integrator)
        .or_else(|| find(rows, grid, "warp", "gpu", integrator))
}

/// Where the peers ran, from their rows' devices, e.g. "WpIntegrator on Warp's cuda:0 (…)".
fn peer_devices(rows: &[PeerRow]) -> String {
    let mut devices: Vec<&str> = Vec::new();
    for r in rows.iter().filter(|r| r.system != "drapekit") {
        if !devices.contains(&r.device.as_str()) {
            devices.push(&r.device);
        }
    }
    devices.join("; ")
}

fn rate(r: Option<&PeerRow>) -> String {
    r.map(|r| format!("{:.3e}", r.particle_substeps_per_s()))
        .unwrap_or_else(|| "–".into())
}

fn ratio(a: Option<&PeerRow>, b: Option<&PeerRow>) -> Option<f64> {
    Some(a?.particle_substeps_per_s() / b?.particle_substeps_per_s())
}

fn distance(r: Option<&PeerRow>) -> String {
    match r.and_then(|r| r.max_distance_to_warp_m) {
        Some(d) => format!("{d:.2e} m"),
        None => "–".into(),
    }
}

/// The issue-14 target: drapekit's CPU path at least 2× Warp-CPU at 128² and 256².
fn target_line(rows: &[PeerRow]) -> String {
    let ratios: Vec<(u32, Option<f64>)> = [128, 256]
        .iter()
        .map(|&g| {
            (
                g,
                ratio(
                    find(rows, g, "drapekit", "cpu", "symplectic"),
                    find(rows, g, "warp", "cpu", "symplectic"),
                ),
            )
        })
        .collect();
    let shown: Vec<String> = ratios
        .iter()
        .map(|(g, r)| match r {
            Some(r) => format!("{r:.2}× at {g}²"),
            None => format!("not measured at {g}²"),
        })
        .collect();
    let verdict = if ratios.iter().any(|(_, r)| r.is_none()) {
        "not measured in this run"
    } else if ratios.iter().all(|(_, r)| r.unwrap() >= 2.0) {
        "**met**"
    } else {
        "**not met**"
    };
    format!(
        "Target: drapekit's CPU path at least 2× Warp-CPU at 128² and 256², in one \
         run: {verdict} ({}).\n",
        shown.join(", ")
    )
}

fn markdown(opts: &PeerOptions, report: &PeerReport) -> String {
    let mut md = String::from("# drapekit beside NVIDIA Warp and Newton\n\n");
    let _ = writeln!(md, "Command: `{}`\n", opts.command);
    let _ = writeln!(md, "- Machine: {} (drapekit's CPU path).", report.machine);
    if report.rows.iter().any(|r| r.system != "drapekit") {
        let _ = writeln!(
            md,
            "- Peers' devices: {}. Warp's CPU device, under Warp and Newton, runs each \
             kernel's threads one after another on one core.",
            peer_devices(&report.rows)
        );
    }
    let _ = writeln!(
        md,
        "- Adapter (drapekit's GPU path): {}",
        match &report.adapter {
            Some(a) => a.describe(),
            None => "none".into(),
        }
    );
    match &report.versions {
        Some(v) => {
            let _ = writeln!(
                md,
                "- Peers: warp-lang {}, newton {}, numpy {}, Python {} (pinned: {}; environment \
                 `{}`).",
                v.warp,
                v.newton,
                v.numpy,
                v.python,
                PINNED
                    .iter()
                    .map(|(p, v)| format!("{p}=={v}"))
                    .collect::<Vec<_>>()
                    .join(" "),
                opts.venv.display()
            );
        }
        None => md.push_str("- Peers: not run (`--systems` named drapekit only).\n"),
    }
    let _ = writeln!(
        md,
        "- Each point: {} frames of 1/60 s from rest, each frame timed (its substeps plus \
         reading the positions back, as Warp's benchmark returns them); the median frame is \
         reported; before them, untimed frames for half a second warm caches and clocks, and \
         the cloth starts again from rest. Kernel compilation is excluded. The cloth is Warp's benchmark cloth \
         (`bench::warp_cloth`): springs only, k = 1000 N/m, damping 10 N·s/m, 0.1 kg \
         particles 0.1 m apart, two corners pinned.\n",
        opts.frames
    );
    md.push_str(
        "## Warp's cloth benchmark\n\nSemi-implicit Euler, 16 substeps per frame; \
         particle-substeps/s. \"Distance\" is the largest distance between drapekit's CPU \
         state and Warp's after the same frames: a check that the cloth and the integrator \
         are the same (float rounding differs: Warp multiplies by 1/l, drapekit divides by l).\n\n\
         | grid | particles | springs | Warp | drapekit CPU | drapekit GPU | CPU ÷ Warp | GPU ÷ Warp | distance |\n\
         |---|---|---|---|---|---|---|---|---|\n",
    );
    let sym = "symplectic";
    for &g in &opts.sizes {
        let warp = find_warp(&report.rows, g, sym);
        let cpu = find(&report.rows, g, "drapekit", "cpu", sym);
        let gpu = find(&report.rows, g, "drapekit", "gpu", sym);
        let Some(any) = warp.or(cpu).or(gpu) else {
            continue;
        };
        let times = |r: Option<f64>| r.map(|r| format!("{r:.2}×")).unwrap_or("–".into());
        let _ = writeln!(
            md,
            "| {g}² | {} | {} | {} | {} | {} | {} | {} | {} |",
            any.particles,
            any.springs,
            rate(warp),
            rate(cpu),
            rate(gpu),
            times(ratio(cpu, warp)),
            times(ratio(gpu, warp)),
            distance(cpu)
        );
    }
    md.push('\n');
    md.push_str(&target_line(&report.rows));
    let newton_rows: Vec<&PeerRow> = report
        .rows
        .iter()
        .filter(|r| opts.newton_sizes.contains(&r.grid) && r.system != "warp")
        .collect();
    if !newton_rows.is_empty() {
        let _ = writeln!(
            md,
            "\n## Newton on the same cloth\n\n\
             Newton's `SolverSemiImplicit` (16 substeps per frame) and `SolverVBD` ({} substeps \
             per frame, {} iterations) on the peers' device, without particle grid or triangle contacts \
             (the cloth has springs only), replayed from a captured graph as Newton's examples \
             do; drapekit's symplectic and implicit Euler at the same settings. Equal \
             stiffness: every system runs the same springs. \"Distance\" is from Warp's \
             final state at the same simulated time (for implicit rows: the larger step's \
             error and its numerical damping).\n\n\
             | grid | system | backend | integrator | substeps/frame | iterations | wall s per simulated s | particle-substeps/s | distance |\n\
             |---|---|---|---|---|---|---|---|---|",
            opts.implicit_substeps, opts.iterations
        );
        for r in newton_rows {
            let _ = writeln!(
                md,
                "| {}² | {} | {} | {} | {} | {} | {:.3} | {:.3e} | {} |",
                r.grid,
                r.system,
                r.backend,
                r.integrator,
                r.substeps_per_frame,
                r.iterations,
                r.wall_s_per_simulated_s(),
                r.particle_substeps_per_s(),
                distance(Some(r))
            );
        }
    }
    if !report.failures.is_empty() {
        md.push_str("\n## Did not run\n\n");
        for f in &report.failures {
            let _ = writeln!(md, "- {}", f.replace('\n', " "));
        }
    }
    md
}

/// Writes `peer.csv` and `peer.md` into `opts.out`.
pub fn write(opts: &PeerOptions, report: &PeerReport) -> Result<(), Error> {
    std::fs::create_dir_all(&opts.out).map_err(|e| Error::io(&opts.out, e))?;
    let (csv_path, md_path) = (opts.out.join("peer.csv"), opts.out.join("peer.md"));
    write_atomic(&csv_path, csv(report).as_bytes())?;
    write_atomic(&md_path, markdown(opts, report).as_bytes())?;
    println!("wrote {} and {}", csv_path.display(), md_path.display());
    Ok(())
}
