//! The levels of `bench convergence`'s FAS V-cycle (`fas`): the scene's cloth meshed coarser
//! and coarser, each level prepared as a run of its own at the fine level's step.

use super::fas::{CoarseLevel, Fas, FAS_COARSEST_PARTICLES};
use crate::cpu::CpuSolver;
use crate::error::Error;
use crate::mesh::Charted;
use crate::model::levels::MIN_REDUCTION;
use crate::scene::{ClothSource, Scene};
use crate::sim::{packed_at, phase_params, prepare, Prepared, RunStats};

/// The FAS V-cycle below the scene `scene` as `prep` prepared it: the scene meshed
/// `coarsening` times coarser, again and again, each level in its phase at `frame` of the run
/// `stats` describes, until a level has at most
/// `FAS_COARSEST_PARTICLES`, or has no coarse levels of its own (then it has no arrays for the
/// line search a coarser level's correction takes, and is the coarsest), or the cloth coarsens
/// no further (warned); `smoothing` sweeps around each level's correction and
/// `coarsest_sweeps` on the coarsest. `chart_of` gives a meshing's chart coordinates. `None`
/// with `coarsening` below 2 or no level built.
pub fn fas_levels(
    (fine_scene, prep): (&Scene, &Prepared),
    (frame, stats): (u32, &RunStats),
    (smoothing, coarsening, coarsest_sweeps): (u32, u32, u32),
    chart_of: fn(&Scene, &Prepared) -> Result<Charted, Error>,
) -> Result<Option<Fas>, Error> {
    if coarsening < 2 {
        return Ok(None);
    }
    let fine_chart = chart_of(fine_scene, prep)?;
    let dt = phase_params(prep, frame, stats).dt;
    let (mut levels, mut scene, mut particles) = (Vec::new(), fine_scene.clone(), prep.model.len());
    let mut sizes = vec![particles];
    while particles > FAS_COARSEST_PARTICLES {
        let coarse = match coarser_level(&scene, particles, coarsening) {
            Ok(coarse) => coarse,
            Err(why) => {
                crate::notice::warn(&if levels.is_empty() {
                    format!("no FAS curve for the cloth of {particles} particles: {why}")
                } else {
                    format!(
                        "the FAS V-cycle stops at {particles} particles (levels {sizes:?}): {why}"
                    )
                });
                break;
            }
        };
        let (coarse_scene, coarse) = coarse;
        let params = phase_params(&coarse, frame, stats);
        assert_eq!(params.dt, dt, "every level takes the same step");
        particles = coarse.model.len();
        sizes.push(particles);
        let has_levels = coarse.model.multigrid.is_some();
        levels.push(CoarseLevel {
            solver: CpuSolver::new(&coarse.model, params, &coarse.plan),
            packed: packed_at(&coarse, frame),
            chart: chart_of(&coarse_scene, &coarse)?,
        });
        scene = coarse_scene;
        if !has_levels {
            break;
        }
    }
    if !levels.is_empty() {
        crate::notice::note(&format!("FAS V-cycle levels (particles): {sizes:?}"));
    }
    Ok(Fas::new(
        &fine_chart,
        levels,
        (smoothing, coarsest_sweeps),
        dt,
    ))
}

/// `scene` (of `particles` particles) meshed `factor` times coarser and prepared, or why it
/// is no FAS level: a grid whose rows or columns less one do not divide by the factor, a
/// meshing that fails, or one that keeps more than `MIN_REDUCTION` of them, the multigrid
/// hierarchy's own rule (a pattern's outline keeps a particle at every corner however coarse
/// the spacing).
fn coarser_level(
    scene: &Scene,
    particles: usize,
    factor: u32,
) -> Result<(Scene, Prepared), String> {
    let coarse_scene = coarsened(scene, factor).ok_or_else(|| {
        format!(
            "the grid's rows or columns less one do not divide by --fas-coarsening {factor}; \
             give one that divides them"
        )
    })?;
    let coarse = prepare(&coarse_scene)
        .map_err(|e| format!("the cloth meshed {factor} times coarser does not build: {e}"))?;
    if coarse.model.len() as f64 > MIN_REDUCTION * particles as f64 {
        return Err(format!(
            "meshed {factor} times coarser it keeps {} particles",
            coarse.model.len()
        ));
    }
    Ok((coarse_scene, coarse))
}

/// The scene with its particle spacing multiplied by `factor` (`None` for a grid whose rows
/// or columns do not coarsen by it).
fn coarsened(scene: &Scene, factor: u32) -> Option<Scene> {
    let mut s = scene.clone();
    match &mut s.cloth {
        ClothSource::Pattern { options, .. } => options.particle_distance *= factor as f64,
        ClothSource::Grid { columns, rows, .. } => {
            if (*columns - 1) % factor != 0 || (*rows - 1) % factor != 0 {
                return None;
            }
            *columns = (*columns - 1) / factor + 1;
            *rows = (*rows - 1) / factor + 1;
        }
        ClothSource::Mesh { .. } => return None,
    }
    // Its coarse levels give it the Newton arrays that hold its correction and line search
    // when a coarser level corrects it.
    s.solver.multigrid = true;
    Some(s)
}
