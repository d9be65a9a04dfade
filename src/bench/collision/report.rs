//! `collision.csv`, `collision.md` and `collision.svg` from the rows of a collision benchmark.

use super::{CollisionOptions, CollisionRow, Contender, CSV_COLUMNS};
use crate::body::Strategy;
use crate::error::Error;
use crate::plot::{log_log_svg, Series};
use std::fmt::Write as _;
use std::path::Path;

fn cell(v: f64, digits: usize) -> String {
    if v.is_finite() {
        format!("{v:.digits$}")
    } else {
        String::new()
    }
}

fn percent(part: usize, whole: usize) -> f64 {
    if whole == 0 {
        0.0
    } else {
        100.0 * part as f64 / whole as f64
    }
}

pub(super) fn csv_text(rows: &[CollisionRow]) -> String {
    let mut csv = CSV_COLUMNS.join(",") + "\n";
    for r in rows {
        let _ = writeln!(
            csv,
            "{},{},{},{},{},\"{}\",{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},\"{}\"",
            r.scale,
            r.particles,
            r.body_triangles,
            r.contender.name(),
            r.contender.backend(),
            r.device,
            r.samples,
            r.repeats,
            r.window_substeps,
            cell(r.collision_us, 3),
            cell(r.in_run_us, 3),
            cell(r.substep_us, 3),
            cell(r.share_percent(), 2),
            r.contacts,
            r.exact_contacts,
            r.missed,
            r.extra,
            cell(percent(r.missed, r.exact_contacts), 2),
            cell(percent(r.extra, r.exact_contacts), 2),
            cell(1e3 * r.max_penetration as f64, 4),
            cell(1e3 * r.max_edge_penetration as f64, 4),
            cell(1e3 * r.build_s, 3),
            r.memory_bytes,
            r.note
        );
    }
    csv
}

/// The row of `c` at `scale`, if it ran.
fn find(rows: &[CollisionRow], scale: u32, c: Contender) -> Option<&CollisionRow> {
    rows.iter().find(|r| r.scale == scale && r.contender == c)
}

/// Sentences on who wins where, from the figures: the thesis's ranking checked at each size.
fn findings(rows: &[CollisionRow], scales: &[u32]) -> String {
    let mut md = String::new();
    let us = |s: u32, c: Contender| find(rows, s, c).map(|r| r.collision_us);
    for &s in scales {
        let Some(first) = rows.iter().find(|r| r.scale == s) else {
            continue;
        };
        let mut said = Vec::new();
        let cpu = (rows.iter())
            .filter(|r| r.scale == s && r.contender.backend() == "cpu")
            .min_by(|a, b| a.collision_us.total_cmp(&b.collision_us));
        if let Some(best) = cpu {
            said.push(format!(
                "the fastest CPU strategy is {} ({:.0} µs)",
                best.contender.name(),
                best.collision_us
            ));
        }
        let aabb = us(s, Contender::Cpu(Strategy::BvhAabb));
        if let (Some(a), Some(o)) = (aabb, us(s, Contender::Cpu(Strategy::BvhObb))) {
            said.push(format!("OBB takes {:.2}× AABB's time", o / a));
        }
        if let (Some(a), Some(sp)) = (aabb, us(s, Contender::Cpu(Strategy::BvhSphere))) {
            said.push(format!("spheres take {:.2}× AABB's", sp / a));
        }
        let bvhs = [Strategy::BvhAabb, Strategy::BvhObb, Strategy::BvhSphere];
        let best_bvh = (bvhs.iter())
            .filter_map(|&b| us(s, Contender::Cpu(b)))
            .fold(f64::INFINITY, f64::min);
        if let Some(e) = us(s, Contender::Cpu(Strategy::Exact)) {
            if best_bvh.is_finite() {
                said.push(format!(
                    "parry's exact takes {:.2}× our best BVH's",
                    e / best_bvh
                ));
            }
            if let Some(ee) = us(s, Contender::ExactEdges) {
                said.push(format!(
                    "edge-edge contacts add {:.0}% to exact",
                    100.0 * (ee / e - 1.0)
                ));
            }
        }
        if let (Some(g), Some(c)) = (
            us(s, Contender::GpuSdf),
            us(s, Contender::Cpu(Strategy::Sdf)),
        ) {
            said.push(format!(
                "the GPU's SDF pass takes {:.2}× the CPU twin's",
                g / c
            ));
        }
        let _ = writeln!(md, "- {} particles: {}.", first.particles, said.join("; "));
    }
    md
}

pub(super) fn md_text(
    rows: &[CollisionRow],
    opts: &CollisionOptions,
    (cpu, gpu): (&str, Option<&str>),
    deforming: bool,
) -> String {
    let first = rows.first();
    let body = match deforming {
        false => "The body is rigid: its structures are built once and never refitted.",
        true => {
            "The body deforms: `gpu-sdf` and `sdf` map each point back to the rest pose by \
             inverse skinning and read the rest pose's SDF (what the solver does); `bvh-aabb` \
             and `exact` are rebuilt over the deformed mesh at each substep, their stage being \
             the rebuild plus a query per particle (their contacts: the particles within the \
             thickness; their substep: the plan less collision plus that stage; the response \
             is not run, so no depth after it). `exact` against the deformed mesh is the \
             reference for contacts and depths. The other BVHs answer as `bvh-aabb` does, and \
             `exact+edges` and `brute` are rigid-body references: they do not apply."
        }
    };
    let mut md = format!(
        "Collision strategies on `{}` (body: {} triangles). One warm-up run per size (CPU, SDF) \
         records the state at {} frame(s) spread over the body's motion; every strategy then \
         starts from the same states. **Alone** is the collision stage by itself on the state \
         it receives in the next substep (per sample the fastest of the repeats, each after an \
         untimed stage on the same state; the GPU's a batch of {} of the same substep less an \
         empty batch). **Substep** is a whole substep with that strategy (the mean over the \
         window of substeps from the frame's state), and **in its run** that less the same \
         window without the collision stage: the stage's cost in the strategy's own run, whose \
         share of the substep the table gives. All are averaged over the samples. **Contacts** \
         are the particles the stage moved, summed over the samples; **missed** and **extra** \
         are against `exact`. **Deepest** is the largest depth inside the exact body of any \
         particle (or cloth-edge midpoint) after the stage and after each window. {body} Our three BVHs keep their \
         volume in one enum, so their nodes take the same memory whatever the volume.\n\n\
         - command: `{}`\n- CPU: {cpu}\n- GPU: {}\n",
        opts.scene.display(),
        first.map_or(0, |r| r.body_triangles),
        first.map_or(0, |r| r.samples),
        super::measure::GPU_STAGE_BATCH,
        opts.command,
        gpu.unwrap_or("none (no adapter)"),
    );
    let mut scales: Vec<u32> = rows.iter().map(|r| r.scale).collect();
    scales.dedup();
    for &s in &scales {
        let Some(first) = rows.iter().find(|r| r.scale == s) else {
            continue;
        };
        let _ = write!(
            md,
            "\n### {} particles ({s}× the scene's)\n\n\
             | strategy | backend | alone µs | in its run µs | substep µs | share | contacts | missed | extra | deepest particle mm | deepest edge mm | build ms | memory MiB | repeats × window | note |\n\
             |---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|---|\n",
            first.particles
        );
        for r in rows.iter().filter(|r| r.scale == s) {
            let _ = writeln!(
                md,
                "| {} | {} | {:.0} | {:.0} | {:.0} | {:.1}% | {} | {} ({:.1}%) | {} ({:.1}%) | {:.3} | {:.3} | {:.1} | {:.2} | {} × {} | {} |",
                r.contender.name(),
                r.contender.backend(),
                r.collision_us,
                r.in_run_us,
                r.substep_us,
                r.share_percent(),
                r.contacts,
                r.missed,
                percent(r.missed, r.exact_contacts),
                r.extra,
                percent(r.extra, r.exact_contacts),
                1e3 * r.max_penetration,
                1e3 * r.max_edge_penetration,
                1e3 * r.build_s,
                r.memory_bytes as f64 / 1048576.0,
                r.repeats,
                r.window_substeps,
                r.note
            );
        }
    }
    md.push_str("\n### Findings\n\n");
    md.push_str(&findings(rows, &scales));
    md
}

/// Collision time per substep against particles, one line per strategy, on log axes, titled
/// with the body's motion (`deformed`: a deforming body).
pub(super) fn plot(rows: &[CollisionRow], deformed: bool, path: &Path) -> Result<(), Error> {
    let body = match deformed {
        true => "the cloth on a deforming body",
        false => "the cloth on a rigid moving body",
    };
    let series: Vec<Series> = (Contender::ALL.iter())
        .map(|&c| Series {
            name: c.name().to_string(),
            points: (rows.iter())
                .filter(|r| r.contender == c && r.collision_us > 0.0)
                .map(|r| (r.particles as f64, r.collision_us))
                .collect(),
        })
        .filter(|s| !s.points.is_empty())
        .collect();
    log_log_svg(
        &series,
        &format!("Collision stage per substep: {body}"),
        "particles",
        "µs per substep (collision stage)",
        path,
    )
}
