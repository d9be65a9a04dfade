//! Builds a scene in code and runs it on the CPU backend: a 60 cm square of each fabric preset
//! falls onto a 20 cm sphere (its top at y = 0.2 m), and the program prints, one simulated
//! second later, the cloth's lowest point and its largest strain.
//!
//!     cargo run --release --example drape_presets

use drapekit::cpu::CpuSolver;
use drapekit::scene::Scene;
use drapekit::sim::{prepare, simulate, RunStats};
use drapekit::solver::{ParticleState, Solver};
use std::path::Path;

/// The scene as TOML text, with the fabric preset filled in: a 25 × 25 particle square 5 cm
/// above a 20 cm sphere, implicit Euler at 4 steps of 10 sweeps per frame, one simulated second.
fn scene_text(preset: &str) -> String {
    format!(
        r#"
        [cloth.grid]
        width_m = 0.6
        height_m = 0.6
        columns = 25
        rows = 25
        center_m = [0.0, 0.25, 0.0]
        plane = "xz"

        [fabric]
        preset = "{preset}"

        [body]
        shape = "sphere"
        radius_m = 0.2

        [solver]
        frames = 24
        integrator = "implicit"
        substeps = 4
        iterations = 10

        [output]
        formats = []
        "#
    )
}

fn main() -> Result<(), drapekit::Error> {
    println!("preset     lowest point (m)  largest strain");
    for preset in ["silk", "jersey", "cotton", "denim", "leather"] {
        // The path only labels errors (and would anchor relative file paths).
        let scene = Scene::parse(&scene_text(preset), Path::new("drape_presets.toml"))?;
        let prep = prepare(&scene)?;
        let mut solver = CpuSolver::new(&prep.model, prep.params, &prep.plan);
        let mut last = ParticleState::default();
        simulate(
            &prep,
            &mut solver,
            &mut RunStats::default(),
            |_frame, state| {
                last = state.clone();
                Ok(())
            },
        )?;
        let lowest = last
            .positions
            .iter()
            .map(|p| p.y)
            .fold(f32::INFINITY, f32::min);
        let strain = solver.health()?.max_strain;
        println!("{preset:<10} {lowest:>16.3}  {:>13.1}%", strain * 100.0);
    }
    Ok(())
}
