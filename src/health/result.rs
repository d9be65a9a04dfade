//! What a finished run says about its result: seams left open, a body showing through the
//! cloth, cloth torn apart by a diverged step or thrown off the body, cloth that never came to
//! rest. Each is a warning in the summary and on the terminal.

use crate::metrics::{body_distances, deformed_distances, ShowThrough};
use crate::sim::{Prepared, RunStats};
use glam::Vec4;

/// The checks of a run's last frame, output frame `frame` at `positions` (`None` when the run
/// stopped on an error: nothing is checked): where a body shows through, and the result's
/// warnings, each printed on stderr as found.
pub fn last_frame(
    prep: &Prepared,
    stats: &RunStats,
    positions: Option<&[Vec4]>,
    frame: u32,
) -> (Option<ShowThrough>, Vec<String>) {
    let Some(positions) = positions else {
        return (None, Vec::new());
    };
    let inside = show_through(prep, positions, frame);
    let found = result_warnings(prep, stats, inside.as_ref(), true);
    for w in &found {
        crate::notice::warn(w);
    }
    (inside, found)
}

/// The body shows through wherever the cloth's surface lies inside it, however shallow: the
/// body's surface is then in front of the cloth's in any render. Particles rest at the
/// collision thickness, so it is the flat triangles between them that cut in. Measured at the
/// triangles' centres: the shipped cotton shirt at rest has every centre at least 0.9 mm
/// outside the body; the same shirt on a body 25% wider, 4 centres up to 0.65 mm inside, which
/// its preview shows as grey specks on the chest and a shoulder.
/// The last frame's `ShowThrough` for `positions` (at output frame `frame`), or `None` without
/// a body.
pub fn show_through(prep: &Prepared, positions: &[Vec4], frame: u32) -> Option<ShowThrough> {
    if prep.model.colliders.is_empty() {
        return None;
    }
    let triangles = &prep.model.triangles;
    let centres: Vec<Vec4> = (triangles.iter())
        .map(|t| t.iter().map(|&i| positions[i as usize]).sum::<Vec4>() / 3.0)
        .collect();
    let mut particle_depth = vec![0.0f32; positions.len()];
    let mut centre_depth = vec![0.0f32; centres.len()];
    let t = frame as f32 * prep.frame_dt;
    for (b, c) in prep.model.colliders.iter().enumerate() {
        let pose = prep.body_state(b, t);
        for (depth, points) in [
            (&mut particle_depth, positions),
            (&mut centre_depth, &centres[..]),
        ] {
            // A deforming body is measured as it stands at the frame, not in its rest pose; a
            // deformed mesh that cannot be built (degenerate) is left out of this check.
            let distances = match &c.deformed {
                Some(_) => deformed_distances(c, t, points).unwrap_or_default(),
                None => body_distances(c, &pose, points),
            };
            for (d, phi) in depth.iter_mut().zip(distances) {
                *d = d.max(-phi);
            }
        }
    }
    let deep = |d: &&f32| **d > 0.0;
    Some(ShowThrough {
        particles: particle_depth.iter().filter(deep).count(),
        triangles: centre_depth.iter().filter(deep).count(),
        of_triangles: triangles.len(),
        deepest_m: (particle_depth.iter().chain(&centre_depth)).fold(0.0, |a, &d| a.max(d)),
    })
}

/// The warnings a finished run earns (`finished`: it ran every frame or settled, rather than
/// stopping on an error).
pub fn result_warnings(
    prep: &Prepared,
    stats: &RunStats,
    inside: Option<&ShowThrough>,
    finished: bool,
) -> Vec<String> {
    let mut out = Vec::new();
    let open: Vec<usize> = (stats.seam_gaps.iter().enumerate())
        .filter(|(_, &g)| g >= prep.seam_closed_gap || g.is_nan())
        .map(|(k, _)| k)
        .collect();
    if !open.is_empty() {
        let widest = stats.seam_gaps.iter().copied().fold(0.0, f32::max);
        out.push(format!(
            "{} of {} seams are still open at the last frame ({} in the pattern's stitch \
             order; widest gap {:.1} mm, closed below seam_closed_gap_m = {:.1} mm): the garment \
             is not sewn (fix: run more frames or a longer seam_sewing_time_s; if the panels \
             cannot meet, check that the pattern fits the body)",
            open.len(),
            stats.seam_gaps.len(),
            list("seam", &open),
            1000.0 * widest,
            1000.0 * prep.seam_closed_gap
        ));
    }
    if let Some(s) = inside.filter(|s| s.particles + s.triangles > 0) {
        out.push(format!(
            "the body shows through the cloth at the last frame: {} of {} triangles have their \
             centre and {} particles lie inside a body, {} \
             (fix: check that the garment fits the body; a finer sdf_resolution_m, a larger \
             thickness_m or more substeps hold the cloth outside it)",
            s.triangles,
            s.of_triangles,
            s.particles,
            how_deep(s.deepest_m)
        ));
    }
    if let Some(w) = torn_warning(stats) {
        out.push(w);
    }
    if let Some(w) = fell_off_warning(prep, stats, finished) {
        out.push(w);
    }
    if let Some(w) = unbalanced_warning(stats) {
        out.push(w);
    }
    if let (Some(limit), None, true) = (prep.settle_speed, &stats.settled, finished) {
        let speed = stats.frame_speed_m_s.unwrap_or(f64::NAN);
        let residual = match (prep.settle_force_residual, stats.force_residual) {
            (Some(l), Some((_, rms))) => format!(
                ", force residual {rms:.2e} of the weight (settle_force_residual = {l:.2e})"
            ),
            _ => String::new(),
        };
        out.push(format!(
            "the cloth did not settle within the run's {} frames: at the last frame it moved at \
             {speed:.2e} m/s RMS (settle_speed_m_s = {limit:.2e}){residual} (fix: run more \
             frames with --frames, or damp it more with air_damping_per_s)",
            stats.frames_run
        ));
    }
    out
}

/// The largest strain of any output frame past which a result is not cloth: half its length
/// again. Wovens stretch about 5% at the KES tensile test's largest load, garment leather breaks
/// at about 15%, and a cotton knit is twelve times as stiff by 17% (docs/src/fabrics.md, the
/// presets' strain scales); the soft 300 N/m thesis skirt stretched over the hips reached 22%.
const TORN_STRAIN: f32 = 0.5;

/// What holds a step that diverged, as the torn and thrown-off warnings advise it.
const DIVERGED_FIX: &str = "more substeps, or with implicit Euler more Newton steps, [solver] \
                            iterations";

/// A frame whose cloth stretched past `TORN_STRAIN` somewhere: the step diverged there (or the
/// seams were pulled shut at once), even if the cloth came back together later.
fn torn_warning(stats: &RunStats) -> Option<String> {
    (stats.max_edge_strain > TORN_STRAIN).then(|| {
        format!(
            "an edge stretched {:.0}% at some frame (largest strain of the run; {:.0}% is past \
             what fabric survives): the step diverged there, or the seams were drawn shut at \
             once, and the frames after it may show the cloth thrown about (fix: \
             {DIVERGED_FIX}; for seams, a seam_sewing_time_s)",
            100.0 * stats.max_edge_strain,
            100.0 * TORN_STRAIN
        )
    })
}

/// A sewn garment that touches no body at the last frame, a second or more after its seams
/// closed and gravity came on: it was sewn around the body and has had time to settle on it,
/// so it has slid or been thrown off.
fn fell_off_warning(prep: &Prepared, stats: &RunStats, finished: bool) -> Option<String> {
    let second = (1.0 / prep.frame_dt).round() as u32;
    let sewn = stats.seams_closed_frame.map(|f| f.max(prep.gravity.1));
    let loaded = prep.gravity.0 != glam::Vec3::ZERO
        && sewn.is_some_and(|from| stats.frames_run >= from + second);
    let on_a_body = prep.garment.is_some() && !prep.model.colliders.is_empty();
    (finished && loaded && on_a_body && stats.body_contacts == 0).then(|| {
        format!(
            "the garment touches no body at the last frame: it has slid or been thrown off \
             (fix: check that the pattern fits the body, and that the run did not diverge: \
             {DIVERGED_FIX})"
        )
    })
}

/// The RMS force residual at the last frame, as a fraction of a particle's weight, from which
/// implicit Euler's steps are not solved: on average each particle's unbalanced force then
/// matches the whole load it carries, so its place is not where its forces put it. Solved
/// steps end far below it (the shipped garments at rest 0.01–0.05, the hanging sheet 3e-6),
/// and a sheet stepped by one plain sweep a substep ends its first frame at 1.57.
const UNBALANCED_RMS: f32 = 1.0;

/// With implicit Euler, a last frame whose forces are unbalanced by `UNBALANCED_RMS` of the
/// weight or more: the solve did not keep up with the step, settled or not.
fn unbalanced_warning(stats: &RunStats) -> Option<String> {
    let (largest, rms) = stats.force_residual?;
    (rms >= UNBALANCED_RMS).then(|| {
        format!(
            "the implicit solve left the forces unbalanced at the last frame: RMS {rms:.2} times \
             a particle's weight, the largest {largest:.1} times; at 1 or more the cloth is not \
             where its forces put it (fix: more Newton steps a substep, [solver] iterations or \
             a tolerance, or more substeps)"
        )
    })
}

/// "seam 3", "seams 1, 4 and 7" (1-based), at most 8 named.
fn list(what: &str, ids: &[usize]) -> String {
    let names: Vec<String> = ids.iter().take(8).map(|k| (k + 1).to_string()).collect();
    let more = ids.len().saturating_sub(8);
    match names.as_slice() {
        [one] => format!("{what} {one}"),
        _ if more > 0 => format!("{what}s {} and {more} more", names.join(", ")),
        [init @ .., last] => format!("{what}s {} and {last}", init.join(", ")),
        [] => String::new(),
    }
}

/// How deep the cloth lies inside the body, in words: to a hundredth of a millimetre, and a
/// depth that would print as 0.00 mm said as under a hundredth (it is there, however shallow).
fn how_deep(depth_m: f32) -> String {
    let mm = 1000.0 * depth_m;
    if mm < 0.005 {
        "by under 0.01 mm".into()
    } else {
        format!("up to {mm:.2} mm deep")
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn a_show_through_s_depth_never_reads_as_zero() {
        assert_eq!(super::how_deep(0.00065), "up to 0.65 mm deep");
        assert_eq!(super::how_deep(0.000006), "up to 0.01 mm deep");
        assert_eq!(super::how_deep(0.000004), "by under 0.01 mm");
    }

    #[test]
    fn seam_lists_read_as_english() {
        assert_eq!(super::list("seam", &[2]), "seam 3");
        assert_eq!(super::list("seam", &[0, 3, 6]), "seams 1, 4 and 7");
        let many: Vec<usize> = (0..10).collect();
        assert_eq!(
            super::list("seam", &many),
            "seams 1, 2, 3, 4, 5, 6, 7, 8 and 2 more"
        );
    }
}
