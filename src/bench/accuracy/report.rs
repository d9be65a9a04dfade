//! `accuracy.csv`, `accuracy.md` and `accuracy.svg` from the rows of a sweep.

use super::ladder::{integrator_name, Knob, Step};
use super::point::Status;
use super::{AccuracyOptions, Row};
use crate::atomic_file::write_atomic;
use crate::error::Error;
use crate::plot::{Group, Labelled, TradeOff};
use crate::scene::Scene;
use std::fmt::Write as _;

/// Where and how the sweep ran.
pub struct Environment {
    /// How far a 1 µm nudge at the start carries, if both runs finished.
    pub floor: Option<super::compare::PositionError>,
    /// The device the points ran on.
    pub device: String,
    /// The CPU and its threads.
    pub machine: String,
    /// Frames per point.
    pub frames: u32,
    /// The command's options.
    pub opts: AccuracyOptions,
    /// The scene as given.
    pub scene: Scene,
}

/// The CSV's columns, in order (documented in docs/src/benchmarks/accuracy.md).
pub const CSV_COLUMNS: [&str; 30] = [
    "label",
    "knob",
    "status",
    "integrator",
    "substeps_per_frame",
    "iterations",
    "spacing_factor",
    "particle_distance_m",
    "particles",
    "sdf_factor",
    "sdf_resolution_m",
    "body_fraction",
    "body_triangles",
    "body_simplify_error_m",
    "sdf_bake_s",
    "frames",
    "simulated_s",
    "wall_s",
    "wall_s_per_simulated_s",
    "particle_substeps_per_s",
    "rms_error_m",
    "max_error_m",
    "mean_shift_m",
    "max_penetration_m",
    "max_seam_gap_m",
    "max_strain",
    "final_strain",
    "final_ke_per_particle_j",
    "energy_drift",
    "pareto",
];

/// A number, or an empty cell when it is not finite.
fn cell(v: f64) -> String {
    if v.is_finite() {
        format!("{v}")
    } else {
        String::new()
    }
}

/// A number for a person, or "–".
fn show(v: f64, scale: f64, digits: usize) -> String {
    if v.is_finite() {
        format!("{:.*}", digits, v * scale)
    } else {
        "–".into()
    }
}

fn sci(v: f64) -> String {
    if v.is_finite() {
        format!("{v:.2e}")
    } else {
        "–".into()
    }
}

fn csv_text(rows: &[Row]) -> String {
    let mut csv = CSV_COLUMNS.join(",") + ",error\n";
    for r in rows {
        let (s, o) = (&r.point.setting, &r.outcome);
        let ran = o.status != Status::Failed;
        let fields = [
            format!("\"{}\"", r.point.label),
            r.point.knob.name().into(),
            o.status.name().into(),
            integrator_name(s.integrator).into(),
            if ran {
                o.substeps.to_string()
            } else {
                step_text(s.step)
            },
            s.iterations.to_string(),
            s.spacing.to_string(),
            cell(o.particle_distance_m),
            if ran {
                o.particles.to_string()
            } else {
                String::new()
            },
            s.sdf.to_string(),
            cell(o.sdf_resolution_m),
            s.body.to_string(),
            if ran {
                o.body_triangles.to_string()
            } else {
                String::new()
            },
            cell(o.body_error_m),
            cell(o.bake_s),
            o.frames.to_string(),
            cell(o.simulated_s),
            cell(o.wall_s),
            cell(o.wall_per_simulated_s()),
            cell(o.particle_substeps_per_s()),
            cell(r.error_m.rms),
            cell(r.error_m.max),
            cell(r.error_m.shift),
            cell(o.max_penetration_m),
            cell(o.max_seam_gap_m),
            cell(o.max_strain),
            cell(o.final_strain),
            cell(o.final_ke_per_particle_j),
            cell(r.energy_drift),
            (if r.pareto { "yes" } else { "no" }).into(),
        ];
        let why = o.error.as_deref().or(r.error_note.as_deref()).unwrap_or("");
        let _ = writeln!(
            csv,
            "{},\"{}\"",
            fields.join(","),
            why.replace('"', "'").replace('\n', " ")
        );
    }
    csv
}

fn step_text(step: Step) -> String {
    match step {
        Step::Auto(f) => format!("auto×{f}"),
        Step::Fixed(n) => n.to_string(),
    }
}

fn md_text(rows: &[Row], env: &Environment) -> String {
    let o = &env.opts;
    let reference = rows.iter().find(|r| r.point.knob == Knob::Reference);
    let mut md = format!(
        "Accuracy against cost for `{}`: every point runs {} frames ({:.2} s simulated) with the \
         settle rule off, on {}; machine: {}. Errors are against the reference (every knob at \
         its finest rung: {}) at the last frame, particles matched through their 2D pattern or \
         grid coordinates across resolutions. Penetration is against the exact body as given, \
         at every frame.\n\nReproduce: `drapekit bench accuracy {} --out {}{}{}{} --backend {} --adapter {}`\n\n",
        o.scene.display(),
        env.frames,
        env.frames as f64 / env.scene.solver.fps as f64,
        env.device,
        env.machine,
        reference.map_or(String::new(), describe),
        o.scene.display(),
        o.out.display(),
        if o.quick { " --quick" } else { "" },
        o.frames.map_or(String::new(), |f| format!(" --frames {f}")),
        o.max_substeps.map_or(String::new(), |n| format!(" --max-substeps {n}")),
        o.backend.name(),
        o.adapter,
    );
    if let Some(f) = env.floor {
        let _ = write!(
            md,
            "Noise floor: nudging every free particle by up to {:.0} µm at the start moves the \
             scene's last frame by {:.2} mm RMS ({:.2} mm at most; the cloth as a whole by \
             {:.2} mm). Folds that form elsewhere after a tiny change make differences of that \
             size; errors closer together than that do not rank the points.\n\n",
            super::NUDGE_M * 1e6,
            f.rms * 1e3,
            f.max * 1e3,
            f.shift * 1e3
        );
    }
    md.push_str(
        "| point | knob | status | substeps/frame | particles | wall s per simulated s | \
         particle-substeps/s | RMS error (mm) | largest error (mm) | mean shift (mm) | \
         penetration (mm) | seam gap (mm) | largest strain | KE per particle at the end (J) | \
         energy drift | Pareto |\n\
         |---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        let o = &r.outcome;
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
            r.point.label,
            r.point.knob.name(),
            o.status.name(),
            if o.status == Status::Failed {
                "–".into()
            } else {
                o.substeps.to_string()
            },
            if o.status == Status::Failed {
                "–".into()
            } else {
                o.particles.to_string()
            },
            show(o.wall_per_simulated_s(), 1.0, 3),
            sci(o.particle_substeps_per_s()),
            show(r.error_m.rms, 1e3, 2),
            show(r.error_m.max, 1e3, 2),
            show(r.error_m.shift, 1e3, 2),
            show(o.max_penetration_m, 1e3, 2),
            show(o.max_seam_gap_m, 1e3, 2),
            show(o.max_strain, 1.0, 3),
            sci(o.final_ke_per_particle_j),
            show(r.energy_drift, 1.0, 3),
            if r.pareto { "yes" } else { "" },
        );
    }
    let bodies: Vec<&Row> = rows
        .iter()
        .filter(|r| {
            matches!(
                r.point.knob,
                Knob::Scene | Knob::Sdf | Knob::Body | Knob::Reference
            )
        })
        .filter(|r| r.outcome.sdf_resolution_m.is_finite() || r.point.knob == Knob::Body)
        .collect();
    if !bodies.is_empty() {
        md.push_str(
            "\nThe body: what the SDF's resolution and the body's simplification cost to bake \
             (from scratch, measured even where the cache held the grid) and what they do to the \
             drape.\n\n| point | body triangles | simplifier's error bound (mm) | SDF cell (mm) | \
             bake s | RMS error (mm) | penetration (mm) |\n|---|---|---|---|---|---|---|\n",
        );
        for r in bodies {
            let o = &r.outcome;
            let _ = writeln!(
                md,
                "| {} | {} | {} | {} | {} | {} | {} |",
                r.point.label,
                if o.status == Status::Failed {
                    "–".into()
                } else {
                    o.body_triangles.to_string()
                },
                show(o.body_error_m, 1e3, 2),
                show(o.sdf_resolution_m, 1e3, 1),
                show(o.bake_s, 1.0, 2),
                show(r.error_m.rms, 1e3, 2),
                show(o.max_penetration_m, 1e3, 2),
            );
        }
    }
    md.push_str("\nPoints in full:\n\n");
    for r in rows {
        let _ = writeln!(md, "- {}: {}", r.point.label, describe(r));
    }
    let notes: Vec<&Row> = rows
        .iter()
        .filter(|r| r.outcome.error.is_some() || r.error_note.is_some())
        .collect();
    if !notes.is_empty() {
        md.push_str("\nWhy some points have no figures:\n\n");
        for r in notes {
            let why = r
                .outcome
                .error
                .as_deref()
                .or(r.error_note.as_deref())
                .unwrap_or("");
            let _ = writeln!(
                md,
                "- {} ({}): {}",
                r.point.label,
                r.outcome.status.name(),
                why.replace('\n', " ")
            );
        }
    }
    md.push_str(
        "\nEnergy drift is the mechanical energy a point gains (+) or loses (−) from the frame \
         after which nothing does work on the cloth to the last frame, minus what the reference \
         gains or loses, over the reference's largest kinetic plus elastic energy in that time; \
         it is blank where the solver's energy sum is incomplete (bending, seams) or something \
         does work (wind, a moving body, self-collision). A diverged point keeps its timing up \
         to the frame that failed and has no error; a failed point has only its settings.\n",
    );
    md
}

/// "symplectic, 504 substeps/frame, 1600 particles at 25.0 mm, SDF 5.0 mm, body 4512 triangles".
fn describe(r: &Row) -> String {
    let (s, o) = (&r.point.setting, &r.outcome);
    let mut d = integrator_name(s.integrator).to_string();
    if o.status == Status::Failed {
        let _ = write!(d, ", substeps {}", step_text(s.step));
    } else {
        let _ = write!(d, ", {} substeps/frame", o.substeps);
    }
    if s.integrator == crate::model::layout::INTEGRATOR_IMPLICIT {
        let _ = write!(d, ", {} iterations", s.iterations);
    }
    if o.status != Status::Failed {
        let _ = write!(d, ", {} particles", o.particles);
    }
    if o.particle_distance_m.is_finite() {
        let _ = write!(d, " {:.1} mm apart", 1e3 * o.particle_distance_m);
    }
    if o.sdf_resolution_m.is_finite() {
        let _ = write!(d, ", SDF cells {:.1} mm", 1e3 * o.sdf_resolution_m);
    }
    if o.body_triangles > 0 {
        let _ = write!(d, ", body {} triangles", o.body_triangles);
    }
    d
}

/// Draws `accuracy.svg`: error against cost, the Pareto front, the noise floor.
pub fn svg(rows: &[Row], env: &Environment, path: &std::path::Path) -> Result<(), Error> {
    let mut groups: Vec<Group> = Vec::new();
    let mut extra = TradeOff {
        front_name: "Pareto front".into(),
        ..Default::default()
    };
    for r in rows {
        let o = &r.outcome;
        let t = o.wall_per_simulated_s();
        if o.status == Status::Diverged && t.is_finite() {
            extra.top.push(Labelled {
                at: (t, f64::NAN),
                label: format!("{} (diverged)", r.point.label),
            });
            continue;
        }
        let (e, name) = (r.error_m.rms, r.point.knob.name());
        if !(t.is_finite() && e.is_finite()) {
            continue;
        }
        if e <= 0.0 {
            // The reference (and any point with its settings) has no error to plot on log axes.
            let label = match &extra.vertical {
                Some(v) => format!("{}, {}", v.label, r.point.label),
                None => format!("{} (error 0)", r.point.label),
            };
            extra.vertical = Some(Labelled {
                at: (t, f64::NAN),
                label,
            });
            continue;
        }
        let p = Labelled {
            at: (t, e),
            label: r.point.label.clone(),
        };
        match groups.iter_mut().find(|g| g.name == name) {
            Some(g) => g.points.push(p),
            None => groups.push(Group {
                name: name.into(),
                points: vec![p],
            }),
        }
    }
    let mut front: Vec<(f64, f64)> = rows
        .iter()
        .filter(|r| r.pareto && r.error_m.rms > 0.0)
        .map(|r| (r.outcome.wall_per_simulated_s(), r.error_m.rms))
        .collect();
    front.sort_by(|a, b| a.0.total_cmp(&b.0));
    extra.front = front;
    extra.horizontal = env.floor.filter(|f| f.rms > 0.0).map(|f| Labelled {
        at: (f64::NAN, f.rms),
        label: format!(
            "noise floor: the scene nudged {:.0} µm",
            super::NUDGE_M * 1e6
        ),
    });
    let name = env
        .opts
        .scene
        .file_name()
        .map_or("scene".into(), |n| n.to_string_lossy().into_owned());
    crate::plot::trade_off_svg(
        &groups,
        &extra,
        &format!(
            "{name}: RMS position error against cost ({} frames)",
            env.frames
        ),
        "wall s per simulated s",
        "RMS position error against the reference (m)",
        path,
    )
}

/// Writes the three files into the sweep's output folder and says where.
pub fn write(rows: &[Row], env: &Environment) -> Result<(), Error> {
    let out = &env.opts.out;
    std::fs::create_dir_all(out).map_err(|e| Error::io(out, e))?;
    let (csv, md, plot) = (
        out.join("accuracy.csv"),
        out.join("accuracy.md"),
        out.join("accuracy.svg"),
    );
    write_atomic(&csv, csv_text(rows).as_bytes())?;
    write_atomic(&md, md_text(rows, env).as_bytes())?;
    svg(rows, env, &plot)?;
    println!(
        "wrote {}, {} and {}",
        csv.display(),
        md.display(),
        plot.display()
    );
    Ok(())
}
