//! `effects.csv` and `effects.md` from the rows of an effects comparison.

use super::{EffectRow, EffectsOptions, CSV_COLUMNS};
use crate::sim::Prepared;
use std::fmt::Write as _;

fn cell(v: f64) -> String {
    if v.is_finite() {
        format!("{v:.3}")
    } else {
        String::new()
    }
}

pub(super) fn csv_text(rows: &[EffectRow]) -> String {
    let mut csv = CSV_COLUMNS.join(",") + "\n";
    for r in rows {
        let _ = writeln!(
            csv,
            "{},{},{},\"{}\",\"{}\",{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},\"{}\",\"{}\"",
            r.effect.name(),
            r.in_scene,
            r.backend,
            r.device,
            r.passes.join(" "),
            r.particles,
            r.batch,
            cell(r.with),
            cell(r.without),
            cell(r.cost()),
            cell(100.0 * r.cost() / r.with),
            cell(r.own),
            cell(r.idle),
            cell(r.residue()),
            cell(100.0 * r.residue() / r.with),
            cell(r.spread_percent),
            r.stages.0,
            r.stages.1,
            r.resources.0,
            r.resources.1,
            r.resources_added.join(" "),
            r.note
        );
    }
    csv
}

pub(super) fn md_text(
    rows: &[EffectRow],
    opts: &EffectsOptions,
    base: &Prepared,
    cpu: &str,
    gpu: Option<&str>,
) -> String {
    let mut md = format!(
        "What each optional effect costs per substep in `{}` ({} particles; the scene's plan: {}). \
         Each effect is added to or removed from the scene (seams: from the model; the membrane \
         replaces the edge springs, so \"without\" is the springs) and both \
         plans are timed from the scene's first frame; \"own passes\" runs only the passes the \
         effect adds, less what a plan with no pass costs (the fixed cost of a batch). Residue = without − (with − own passes): what is left of an effect once \
         it is removed, zero when removing it takes exactly its passes away. Times are µs per \
         substep, the fastest of {} timed batches (the one least disturbed by other work on \
         the machine), after one untimed batch; the plans take turns, one batch each per \
         round, so that a change in load falls on all alike; spread is the largest \
         (slowest − fastest)/fastest of those batches. Stages: CPU passes or GPU pipelines \
         (the monitor included); resources: GPU buffers and textures.\n\n\
         CPU: {cpu}. GPU: {}.\n\nReproduce: `drapekit --threads {} bench effects {} --out {}{} --adapter {}`\n\n",
        opts.scene.display(),
        base.model.len(),
        base.plan.names().join(", "),
        if opts.quick { 3 } else { 15 },
        gpu.unwrap_or("none (no adapter)"),
        rayon::current_num_threads(),
        opts.scene.display(),
        opts.out.display(),
        if opts.quick { " --quick" } else { "" },
        opts.adapter,
    );
    md.push_str(
        "| effect | in scene | backend | passes it adds | with | without | cost | own passes | \
         residue | spread | stages with → without | resources with → without |\n\
         |---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    let pct = |v: f64, of: f64| {
        if v.is_finite() && of.is_finite() {
            format!("{v:.1} ({:+.1}%)", 100.0 * v / of)
        } else {
            "–".into()
        }
    };
    for r in rows {
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} → {} | {} |",
            r.effect.name(),
            if r.in_scene { "yes" } else { "no" },
            r.backend,
            if r.passes.is_empty() {
                "–".into()
            } else {
                r.passes.join(", ")
            },
            if r.with.is_finite() {
                format!("{:.1}", r.with)
            } else {
                "–".into()
            },
            if r.without.is_finite() {
                format!("{:.1}", r.without)
            } else {
                "–".into()
            },
            pct(r.cost(), r.with),
            if r.own.is_finite() {
                format!("{:.1}", r.own)
            } else {
                "–".into()
            },
            pct(r.residue(), r.with),
            if r.spread_percent.is_finite() {
                format!("{:.0}%", r.spread_percent)
            } else {
                "–".into()
            },
            r.stages.0,
            r.stages.1,
            if r.backend == "gpu" {
                format!("{} → {}", r.resources.0, r.resources.1)
            } else {
                "–".into()
            },
        );
    }
    let gpu_rows: Vec<&EffectRow> = rows
        .iter()
        .filter(|r| r.backend == "gpu" && r.with.is_finite())
        .collect();
    if !gpu_rows.is_empty() {
        md.push_str(
            "\nWhat the GPU path creates only when the effect is there (the plan without it \
             builds none of these):\n\n",
        );
        for r in gpu_rows {
            let _ = writeln!(
                md,
                "- {}: pipelines {}; buffers and textures {}",
                r.effect.name(),
                if r.passes.is_empty() {
                    "none".into()
                } else {
                    r.passes.join(", ")
                },
                if r.resources_added.is_empty() {
                    "none".into()
                } else {
                    r.resources_added.join(", ")
                }
            );
        }
    }
    let notes: Vec<&EffectRow> = rows.iter().filter(|r| !r.note.is_empty()).collect();
    if !notes.is_empty() {
        md.push('\n');
        for r in notes {
            let _ = writeln!(md, "- {} ({}): {}", r.effect.name(), r.backend, r.note);
        }
    }
    md
}
