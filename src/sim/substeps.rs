//! How many substeps a frame takes before the bodies have their say: the scene's count, or
//! `auto`'s from the stable step of the cloth's springs, hinges and damping and of the wind's
//! drag (`bodies::body_speed_substeps` may raise it for a fast body).

use super::AUTO_DT_SAFETY;
use crate::error::Error;
use crate::model::layout::INTEGRATOR_IMPLICIT;
use crate::model::ClothModel;
use crate::scene::Scene;

/// The substep count and what set it.
pub(super) struct StepChoice {
    /// Substeps per frame.
    pub substeps: u32,
    /// Whether `auto` chose them.
    pub auto: bool,
    /// The estimated stable step, in s (`None` for implicit Euler, which has no bound).
    pub stable_dt: Option<f32>,
    /// What set the substep: `"scene"`, or the stable step's binding term.
    pub limited_by: &'static str,
}

/// The substeps of `scene`'s frames of `frame_dt` s on `model`; a scene substep above the
/// stable estimate is a warning, an `auto` count above the scene's limit an error.
pub(super) fn choose(
    scene: &Scene,
    model: &ClothModel,
    frame_dt: f32,
    warnings: &mut Vec<String>,
) -> Result<StepChoice, Error> {
    let s = &scene.solver;
    let implicit = s.integrator == INTEGRATOR_IMPLICIT;
    // Backward Euler is stable at any step: it has no bound to report or to obey.
    let stable_step = if implicit {
        None
    } else {
        let cloth = model.stable_step(
            s.integrator,
            scene.air_damping,
            scene.fabric.tangent_ratio(),
        );
        // The drag's explicit update is stable for γ·dt < 2, like the damping bound.
        let drag = crate::scene::limits::wind_drag_rate(scene);
        let wind = (drag > 0.0).then(|| ((2.0 / drag) as f32, "wind drag"));
        match (cloth, wind) {
            (Some(c), Some(w)) if w.0 < c.0 => Some(w),
            (None, _) => None,
            (c, _) => c,
        }
    };
    let stable_dt = stable_step.map(|(dt, _)| dt);
    // What sets the substep: the scene, or the stability bound's binding term (body speed
    // below, if it asks for more).
    let dt_limited_by = match (s.substeps, stable_step) {
        (None, Some((_, term))) if !implicit => term,
        _ => "scene",
    };
    let (substeps, auto_substeps) =
        match s.substeps {
            Some(n) if implicit => (n, false),
            None if implicit => (1, true),
            Some(n) => {
                let dt = frame_dt / n as f32;
                match stable_dt {
                    Some(bound) if dt > bound => warnings.push(format!(
                        "substep {dt:.3e} s exceeds the estimated stable step {bound:.3e} s; \
                     the run may blow up (use substeps = \"auto\")"
                    )),
                    None => warnings.push(
                        "explicit Euler without damping has no stable step; energy will grow"
                            .into(),
                    ),
                    _ => {}
                }
                (n, false)
            }
            None => {
                let Some(bound) = stable_dt else {
                    return Err(scene
                        .error(
                            "fabric",
                            "damping_ratio",
                            "explicit Euler has no stable substep without damping",
                            "set fabric.damping_ratio above 0, or use integrator = \"symplectic\"",
                        )
                        .into());
                };
                let n = (frame_dt / (AUTO_DT_SAFETY * bound)).ceil().max(1.0);
                if n > s.max_substeps_per_frame as f32 {
                    return Err(scene
                        .error(
                            "solver",
                            "substeps",
                            format!(
                            "the {} needs {n:.0} substeps per frame (stable step {bound:.2e} s, \
                             frames of {frame_dt:.3e} s), above max_substeps_per_frame = {}",
                            if dt_limited_by == "wind drag" { "wind's drag" } else { "fabric" },
                            s.max_substeps_per_frame
                        ),
                            too_many_substeps_fix(scene, dt_limited_by, frame_dt),
                        )
                        .into());
                }
                (n as u32, true)
            }
        };
    Ok(StepChoice {
        substeps,
        auto: auto_substeps,
        stable_dt,
        limited_by: dt_limited_by,
    })
}

/// What to change when `auto` would need more substeps than allowed: the term that binds, and
/// the slips that make a step tiny or a frame long (a mesh in the wrong units, a low fps).
fn too_many_substeps_fix(scene: &Scene, limited_by: &str, frame_dt: f32) -> String {
    let mut fix = match limited_by {
        "wind drag" => "lower wind.drag_coefficient (cloth: 1 to 2) or wind.air_density_kg_m3",
        _ => "lower stretch_stiffness_n_m or coarsen the cloth",
    }
    .to_string();
    if matches!(scene.cloth, crate::scene::ClothSource::Mesh { .. }) {
        fix += "; check [cloth.mesh] units (a mesh read in the wrong unit has edges far too \
                short)";
    }
    if frame_dt > 0.1 {
        fix += &format!(
            "; raise solver.fps (fps = {} makes each frame {frame_dt} s)",
            scene.solver.fps
        );
    }
    fix + "; or raise solver.max_substeps_per_frame"
}
