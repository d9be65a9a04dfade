//! The coarse start: the garment sewn and draped on a coarser mesh first, then carried onto
//! the full mesh, where the run continues.

use super::build_solver;
use crate::error::Error;
use crate::gpu::GpuContext;
use crate::scene::Scene;
use crate::sim::{map_state, prepare, simulate, CoarseStart, Prepared, ResumeFrom, RunStats};

/// Sews and drapes `scene`'s garment at `distance` spacing until it settles (or its frames
/// end) and maps the result onto `fine`'s mesh: where the full-resolution run continues from,
/// and its stats so far (what the coarse start did, the seams' state, its time).
pub(super) fn coarse_start(
    scene: &Scene,
    distance: f64,
    device: Option<&GpuContext>,
    fine: &Prepared,
) -> Result<(ResumeFrom, RunStats), Error> {
    let started = std::time::Instant::now();
    let mut coarse = scene.clone();
    if let crate::scene::ClothSource::Pattern {
        options,
        coarse_start,
        ..
    } = &mut coarse.cloth
    {
        options.particle_distance = distance;
        *coarse_start = None;
    }
    let prep = prepare(&coarse)?;
    crate::notice::note(&format!(
        "coarse start: sewing and draping {} particles at {distance:.3} m until they settle \
         (a second Ctrl-C stops it at once)",
        prep.model.len()
    ));
    let mut solver = build_solver(&prep, device)?;
    let mut stats = RunStats::default();
    simulate(&prep, solver.as_mut(), &mut stats, |_, _| Ok(())).map_err(|e| match e {
        Error::Unstable(m) => Error::Unstable(format!(
            "the coarse start (coarse_start_distance_m = {distance:.3}): {m}"
        )),
        e => e,
    })?;
    let frame = stats.frames_run;
    if stats.settled.is_none() || frame >= fine.frames {
        return Err(scene
            .error(
                "cloth.pattern",
                "coarse_start_distance_m",
                format!(
                    "the coarse start ({} particles at {distance:.3} m) {} within the run's {} \
                     frames (its speed at frame {frame}: {:.2e} m/s, against settle_speed_m_s), \
                     so no frame is left for the full mesh",
                    prep.model.len(),
                    if stats.settled.is_none() {
                        "did not settle"
                    } else {
                        "settled only at the last frame"
                    },
                    fine.frames,
                    stats.frame_speed_m_s.unwrap_or(f64::NAN),
                ),
                "raise solver.frames (or --frames), use a finer coarse_start_distance_m, or \
                 remove it",
            )
            .into());
    }
    let (state, gap) = map_state(&prep, &solver.state()?, fine, frame).ok_or_else(|| {
        scene.error(
            "cloth.pattern",
            "coarse_start_distance_m",
            "a coarse start needs a sewing pattern",
            "remove coarse_start_distance_m",
        )
    })?;
    let wall_seconds = started.elapsed().as_secs_f64();
    let record = CoarseStart {
        particle_distance_m: distance as f32,
        particles: prep.model.len(),
        frame,
        settled_frame: stats.settled.as_ref().map(|s| s.frame),
        seams_closed_frame: stats.seams_closed_frame,
        max_edge_strain: stats.max_edge_strain,
        wall_seconds,
        max_pattern_gap_m: gap,
    };
    let continued = RunStats {
        frames: stats.frames,
        frames_run: frame,
        wall_seconds,
        finite: true,
        seams_closed_frame: stats.seams_closed_frame,
        released_after_frame: stats.released_after_frame,
        coarse_start: Some(record),
        ..RunStats::default()
    };
    Ok((ResumeFrom { frame, state }, continued))
}
