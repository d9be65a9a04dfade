//! The state `bench convergence` measures from: the scene run on the CPU at its own spacing to
//! a representative frame, carried onto a finer meshing through the pattern (or grid)
//! coordinates, as the coarse start does, and run on there a few frames. Attached particles
//! are held, or let go, as the run itself holds them at that frame.

use crate::cpu::CpuSolver;
use crate::error::Error;
use crate::mesh::Charted;
use crate::pattern::transfer::Transfer;
use crate::scene::{ClothSource, Scene};
use crate::sim::{
    carried, packed_at, phase_params, prepare, release, simulate, substep_params, Prepared,
    RunStats,
};
use crate::solver::{ParticleState, Solver};

/// The scene with its particle spacing divided by `r`.
pub fn refined(scene: &Scene, r: u32) -> Scene {
    let mut s = scene.clone();
    match &mut s.cloth {
        ClothSource::Pattern { options, .. } => options.particle_distance /= r as f64,
        ClothSource::Grid { columns, rows, .. } => {
            *columns = (*columns - 1) * r + 1;
            *rows = (*rows - 1) * r + 1;
        }
        ClothSource::Mesh { .. } => {}
    }
    s.solver.multigrid = true;
    s.solver.strain_limit = None;
    s
}

/// The scene run on the CPU to its representative frame: its prepared run, the state, the run's
/// stats and the frame.
pub fn representative_state(
    scene: &Scene,
    frames: Option<u32>,
) -> Result<(Prepared, ParticleState, RunStats, u32), Error> {
    let mut prep = prepare(&refined(scene, 1))?;
    if let Some(f) = frames {
        prep.frames = f;
        prep.settle_speed = None;
    }
    let mut solver = CpuSolver::new(&prep.model, prep.params, &prep.plan);
    let mut stats = RunStats::default();
    let mut last = solver.state()?;
    simulate(&prep, &mut solver, &mut stats, |_, s| {
        last = s.clone();
        Ok(())
    })?;
    let frame = stats.frames_run;
    Ok((prep, last, stats, frame))
}

/// `frames` more frames of `prep` from `state` at the end of frame `frame`: the state then, and
/// the frame.
pub fn continue_run(
    prep: &Prepared,
    state: ParticleState,
    stats: &RunStats,
    frame: u32,
    frames: u32,
) -> Result<(ParticleState, u32), Error> {
    if frames == 0 {
        return Ok((state, frame));
    }
    let mut params = phase_params(prep, frame, stats);
    let mut solver = CpuSolver::new(&prep.model, params, &prep.plan);
    solver.set_state(&state);
    for f in frame + 1..=frame + frames {
        solver.advance(&substep_params(prep, f))?;
        // What the run does after each frame: attachments let go, gravity switched on.
        if f == prep.attach_frames && !prep.attached.is_empty() {
            let state = solver.state()?;
            release(prep, &mut solver, state);
        }
        let next = phase_params(prep, f, stats);
        if next != params {
            solver.set_params(&next);
            params = next;
        }
    }
    Ok((solver.state()?, frame + frames))
}

/// The cloth's chart coordinates (pattern panels or grid plane).
fn charted(scene: &Scene, prep: &Prepared) -> Option<Charted> {
    match &scene.cloth {
        ClothSource::Grid {
            width,
            height,
            columns,
            rows,
            ..
        } => Some(Charted::grid(*width, *height, *columns, *rows)),
        _ => prep.garment.as_ref().map(|g| g.charted()),
    }
}

/// `state` of the scene's own meshing at the end of output frame `frame` carried onto
/// `fine`'s particles through the charts, its particles held as they are then.
pub fn map_state(
    (scene, base): (&Scene, &Prepared),
    state: &ParticleState,
    (fine_scene, fine): (&Scene, &Prepared),
    frame: u32,
) -> Result<ParticleState, Error> {
    let transfer = Transfer::between(&chart_of(scene, base)?, &chart_of(fine_scene, fine)?);
    Ok(carried(&transfer, state, &packed_at(fine, frame)))
}

/// The cloth's chart coordinates, or the error that it has none.
pub fn chart_of(scene: &Scene, prep: &Prepared) -> Result<Charted, Error> {
    charted(scene, prep).ok_or_else(|| {
        Error::Input(scene.error(
            "solver",
            "multigrid",
            "the cloth has no chart coordinates to carry its state between meshings",
            "use a grid or pattern cloth",
        ))
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    /// A 20 cm square of cotton meshed at 2 cm in implicit Euler's 4 steps a frame, held by
    /// its top edge (labelled `lower_interface`) for its first two frames, then let go to fall,
    /// with the `[world]` keys `world`; and the folder of its files, for the test to remove.
    fn released_square(name: &str, world: &str) -> (Scene, PathBuf) {
        let dir = std::env::temp_dir().join(format!(
            "drapekit-measured-state-{}-{name}",
            std::process::id()
        ));
        std::fs::create_dir_all(&dir).unwrap();
        let pattern = r#"{"pattern": {"panels": {"a": {"translation": [0, 100, 0],
            "rotation": [0, 0, 0], "vertices": [[0, 0], [20, 0], [20, 20], [0, 20]],
            "edges": [{"endpoints": [0, 1]}, {"endpoints": [1, 2]},
                      {"endpoints": [2, 3], "label": "lower_interface"}, {"endpoints": [3, 0]}]}},
            "stitches": []}, "properties": {"units_in_meter": 100}}"#;
        std::fs::write(dir.join("square.json"), pattern).unwrap();
        let path = dir.join("square.toml");
        let text = format!(
            "[cloth.pattern]\npath = \"square.json\"\nparticle_distance_m = 0.02\n\
             attach_labels = [\"lower_interface\"]\nattach_frames = 2\n\
             [fabric]\npreset = \"cotton\"\n\
             [world]\ngravity_m_s2 = [0.0, -9.81, 0.0]\n{world}\n\
             [solver]\nfps = 24\nframes = 24\nsubsteps = 4\nintegrator = \"implicit\"\n"
        );
        std::fs::write(&path, text).unwrap();
        (Scene::load(&path).unwrap(), dir)
    }

    /// How far each attached particle of `prep` is below its place in the model, in m.
    fn drops(prep: &Prepared, state: &ParticleState) -> Vec<f32> {
        (prep.attached.iter())
            .map(|&i| prep.model.positions[i as usize].y - state.positions[i as usize].y)
            .collect()
    }

    #[test]
    fn carried_before_the_release_the_attached_particles_stay_where_the_model_holds_them() {
        let (scene, dir) = released_square("before", "");
        let (base, state, _, frame) = representative_state(&scene, Some(1)).unwrap();
        assert_eq!(frame, 1);
        assert_eq!(base.attached.len(), 11, "the top edge at 2 cm");
        let mapped = map_state((&scene, &base), &state, (&scene, &base), frame).unwrap();
        for &i in &base.attached {
            let p = mapped.positions[i as usize];
            assert_eq!(
                p,
                base.model.positions[i as usize].extend(0.0),
                "particle {i}"
            );
        }
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn carried_after_the_release_the_attached_particles_are_free_where_they_fell() {
        let (scene, dir) = released_square("after", "");
        let (base, state, _, frame) = representative_state(&scene, Some(4)).unwrap();
        assert_eq!(frame, 4);
        let mapped = map_state((&scene, &base), &state, (&scene, &base), frame).unwrap();
        // Let go after frame 2, the square falls for two frames (8 steps of h = 1/96 s): from
        // rest, backward Euler drops it h²·g·(1 + … + 8) = 3.8 cm. The stretched cloth below
        // pulls the top edge down faster still; only damping slows it, and not to a third.
        for (k, drop) in drops(&base, &state).into_iter().enumerate() {
            assert!(drop > 0.01, "attached particle {k} fell only {drop} m");
        }
        assert_let_go(&base, &mapped);
        for &i in &base.attached {
            let (p, s) = (mapped.positions[i as usize], state.positions[i as usize]);
            // The same meshing: each particle blends from a triangle of its own at weights
            // (1, 0, 0) up to their rounding, a few ulps of a metre-scale position.
            let moved = p.truncate().distance(s.truncate());
            assert!(
                moved < 1e-5,
                "particle {i} carried {moved} m from its place"
            );
        }
        std::fs::remove_dir_all(&dir).ok();
    }

    /// The square of `released_square(name, world)` run to frame 1 at 2 cm, carried onto its
    /// 1 cm meshing and run on there `frames` frames (`continue_run`).
    struct RunOn {
        /// The 2 cm run.
        base: Prepared,
        /// The 1 cm meshing.
        fine: Prepared,
        /// The carried state at frame 1.
        mapped: ParticleState,
        /// The state `frames` frames on, and its frame.
        relaxed: (ParticleState, u32),
    }

    fn run_on_finer(name: &str, world: &str, frames: u32) -> RunOn {
        let (scene, dir) = released_square(name, world);
        let (base, state, stats, frame) = representative_state(&scene, Some(1)).unwrap();
        let fine_scene = refined(&scene, 2);
        let fine = prepare(&fine_scene).unwrap();
        let mapped = map_state((&scene, &base), &state, (&fine_scene, &fine), frame).unwrap();
        let relaxed = continue_run(&fine, mapped.clone(), &stats, frame, frames).unwrap();
        std::fs::remove_dir_all(&dir).ok();
        RunOn {
            base,
            fine,
            mapped,
            relaxed,
        }
    }

    /// Asserts that every attached particle of `prep` has its inverse mass in `state`.
    fn assert_let_go(prep: &Prepared, state: &ParticleState) {
        for &i in &prep.attached {
            let w = state.positions[i as usize].w;
            assert_eq!(w, 1.0 / prep.model.masses[i as usize], "particle {i} held");
        }
    }

    #[test]
    fn a_finer_meshing_run_on_to_the_release_frame_lets_them_go_after_it() {
        // Frame 2 is stepped with them held; they are let go at its end.
        let RunOn { fine, relaxed, .. } = run_on_finer("at", "", 1);
        let (relaxed, at) = relaxed;
        assert_eq!(at, 2);
        for &i in &fine.attached {
            let (p, i) = (relaxed.positions[i as usize], i as usize);
            assert_eq!(
                p.truncate(),
                fine.model.positions[i],
                "particle {i} moved in frame 2"
            );
        }
        assert_let_go(&fine, &relaxed);
    }

    #[test]
    fn a_finer_meshing_run_on_switches_gravity_on_when_the_run_does() {
        // Gravity from 0.07 s: on after frame 2 (at 24 fps), when the top edge is let go too.
        // Run on from frame 1, frame 3 must fall as in the test below; with frame 1's
        // parameters kept, nothing pulls the square down.
        let RunOn {
            base,
            fine,
            relaxed,
            ..
        } = run_on_finer("gravity", "gravity_start_s = 0.07", 2);
        assert_eq!(base.gravity.1, 2, "gravity on after frame 2");
        // Frame 3's four steps from rest drop it h²·g·(1 + … + 4) = 1.1 cm; with gravity off
        // from the start, nothing moves it.
        for (k, drop) in drops(&fine, &relaxed.0).into_iter().enumerate() {
            assert!(drop > 0.0035, "attached particle {k} fell only {drop} m");
        }
    }

    #[test]
    fn a_finer_meshing_run_on_past_the_release_lets_the_attached_particles_go() {
        let RunOn {
            fine,
            mapped,
            relaxed,
            ..
        } = run_on_finer("finer", "", 2);
        assert!((fine.attached.iter()).all(|&i| mapped.positions[i as usize].w == 0.0));
        let (relaxed, at) = relaxed;
        assert_eq!(at, 3);
        // Let go after frame 2, frame 3's four steps drop the square h²·g·(1 + … + 4) = 1.1 cm
        // from rest. The stretched cloth below pulls the top edge down faster still; only
        // damping slows it, and not to a third.
        for (k, drop) in drops(&fine, &relaxed).into_iter().enumerate() {
            assert!(drop > 0.0035, "attached particle {k} fell only {drop} m");
        }
        assert_let_go(&fine, &relaxed);
    }
}
