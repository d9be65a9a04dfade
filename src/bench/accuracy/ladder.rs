//! The points of an accuracy sweep: one setting of every knob, the ladders that vary one knob at
//! a time from the scene's own settings, and the reference (the finest rung of every ladder).

use crate::model::layout::{INTEGRATOR_EXPLICIT, INTEGRATOR_IMPLICIT, INTEGRATOR_SYMPLECTIC};
use crate::scene::{ClothSource, PinSelection, Scene};

/// How many substeps per output frame a point takes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Step {
    /// This multiple of what the stability bound asks for (`substeps = "auto"`), rounded up.
    Auto(f32),
    /// A fixed count.
    Fixed(u32),
}

/// One setting of every knob.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Setting {
    /// `INTEGRATOR_EXPLICIT`, `INTEGRATOR_SYMPLECTIC` or `INTEGRATOR_IMPLICIT`.
    pub integrator: u32,
    /// Substeps per frame.
    pub step: Step,
    /// Vertex Block Descent sweeps per substep (implicit only).
    pub iterations: u32,
    /// Particle distance as a multiple of the scene's (0.5: half the distance, 4× the particles).
    pub spacing: f32,
    /// SDF node spacing as a multiple of the scene's.
    pub sdf: f32,
    /// Fraction of the body's triangles kept by simplification (1: the body as given).
    pub body: f32,
}

/// Which knob a point varies.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Knob {
    /// The scene's own settings.
    Scene,
    /// Integrator, substeps and (implicit) iterations.
    Step,
    /// Particle distance (mesh resolution).
    Spacing,
    /// SDF resolution.
    Sdf,
    /// Body simplification before the bake.
    Body,
    /// The finest rung of every ladder.
    Reference,
    /// Every knob at the rung with the smallest error in its ladder.
    Best,
    /// Every knob at the rung with the lowest cost in its ladder.
    Cheapest,
    /// The scene's settings with every free particle nudged at the start: the noise floor.
    Nudged,
}

impl Knob {
    /// The name in the CSV.
    pub fn name(self) -> &'static str {
        match self {
            Knob::Scene => "scene",
            Knob::Step => "step",
            Knob::Spacing => "particle_distance",
            Knob::Sdf => "sdf_resolution",
            Knob::Body => "body_simplification",
            Knob::Reference => "reference",
            Knob::Best => "combined_best",
            Knob::Cheapest => "combined_cheapest",
            Knob::Nudged => "nudged_scene",
        }
    }
}

/// A point of the sweep.
#[derive(Clone, Debug, PartialEq)]
pub struct Point {
    /// A short label for tables and the plot.
    pub label: String,
    /// The knob it varies.
    pub knob: Knob,
    /// Its settings.
    pub setting: Setting,
}

/// The integrator's name in scene files.
pub fn integrator_name(integrator: u32) -> &'static str {
    match integrator {
        INTEGRATOR_EXPLICIT => "explicit",
        INTEGRATOR_SYMPLECTIC => "symplectic",
        _ => "implicit",
    }
}

impl Setting {
    /// The scene's own settings.
    pub fn of_scene(scene: &Scene) -> Setting {
        Setting {
            integrator: scene.solver.integrator,
            step: scene.solver.substeps.map_or(Step::Auto(1.0), Step::Fixed),
            // The ladder scales a count it can see, so a scene without one starts from plain
            // sweeps' default (with coarse levels, that many Newton steps).
            iterations: scene.solver.iterations_for(false),
            spacing: 1.0,
            sdf: 1.0,
            body: 1.0,
        }
    }

    /// "symplectic auto×2", "implicit 4×10 it", …
    pub fn step_label(&self) -> String {
        let name = integrator_name(self.integrator);
        let steps = match self.step {
            Step::Auto(1.0) => "auto".to_string(),
            Step::Auto(f) => format!("auto×{f}"),
            Step::Fixed(n) => format!("{n}/frame"),
        };
        if self.integrator == INTEGRATOR_IMPLICIT {
            format!("{name} {steps} {} it", self.iterations)
        } else {
            format!("{name} {steps}")
        }
    }
}

/// Which knobs a scene has, and why one is missing.
pub struct Knobs {
    /// The cloth is a pattern or a grid (whose 2D coordinates map one resolution onto another).
    pub spacing: Result<(), String>,
    /// The scene has a body.
    pub body: bool,
}

impl Knobs {
    /// What `scene` lets the sweep vary.
    pub fn of(scene: &Scene) -> Knobs {
        let spacing = match &scene.cloth {
            ClothSource::Pattern { .. } => Ok(()),
            ClothSource::Grid { .. }
                if scene
                    .pins
                    .iter()
                    .any(|p| matches!(p, PinSelection::Indices(_))) =>
            {
                Err("pins by particle index select other particles at another resolution".into())
            }
            ClothSource::Grid { .. } => Ok(()),
            ClothSource::Mesh { .. } => {
                Err("an OBJ cloth has one resolution (no pattern or grid to remesh)".into())
            }
        };
        Knobs {
            spacing,
            body: !scene.bodies.is_empty(),
        }
    }
}

/// The one-knob-at-a-time ladders (without the scene's own point, which every ladder shares) and
/// the reference. `quick` shortens every ladder to its scene rung and one or two others.
pub fn ladders(scene: &Scene, quick: bool) -> (Vec<Point>, Point) {
    let base = Setting::of_scene(scene);
    let knobs = Knobs::of(scene);
    let mut points = Vec::new();
    let mut push = |knob: Knob, setting: Setting, label: String| {
        if setting != base {
            points.push(Point {
                label,
                knob,
                setting,
            });
        }
    };
    // Integrators and their steps. The explicit integrators step relative to their stability
    // bound (the scene's fixed count, if any, is kept for its own integrator); implicit Euler
    // has no bound and steps in multiples of the scene's count (1 when the scene's is "auto").
    let implicit_base = match (base.integrator, base.step) {
        (INTEGRATOR_IMPLICIT, Step::Fixed(n)) => n,
        _ => 1,
    };
    let auto_factors: &[f32] = if quick { &[1.0, 2.0] } else { &[0.5, 1.0, 2.0] };
    let mut finest_step = base;
    for integrator in [INTEGRATOR_EXPLICIT, INTEGRATOR_SYMPLECTIC] {
        // The finest rung (the reference's) only for the scene's own integrator; quick sweeps
        // give forward Euler one rung.
        let factors = match (quick, integrator == base.integrator) {
            (true, _) if integrator == INTEGRATOR_EXPLICIT => &auto_factors[..1],
            (_, false) => &auto_factors[..auto_factors.len() - 1],
            _ => auto_factors,
        };
        for &f in factors {
            let step = match (base.integrator == integrator, base.step) {
                (true, Step::Fixed(n)) => Step::Fixed(((n as f32 * f).ceil() as u32).max(1)),
                _ => Step::Auto(f),
            };
            let s = Setting {
                integrator,
                step,
                ..base
            };
            push(Knob::Step, s, s.step_label());
            if integrator == base.integrator {
                finest_step = s;
            }
        }
    }
    let substep_factors: &[u32] = match (quick, base.integrator == INTEGRATOR_IMPLICIT) {
        (true, _) => &[1, 2],
        (false, true) => &[1, 2, 4],
        (false, false) => &[1, 2],
    };
    for &f in substep_factors {
        let s = Setting {
            integrator: INTEGRATOR_IMPLICIT,
            step: Step::Fixed(implicit_base * f),
            ..base
        };
        push(Knob::Step, s, s.step_label());
    }
    let iteration_factors: &[f32] = if quick { &[2.0] } else { &[0.5, 2.0] };
    for &f in iteration_factors {
        let s = Setting {
            integrator: INTEGRATOR_IMPLICIT,
            step: Step::Fixed(implicit_base),
            iterations: ((base.iterations as f32 * f).round() as u32).max(1),
            ..base
        };
        push(Knob::Step, s, s.step_label());
    }
    if base.integrator == INTEGRATOR_IMPLICIT {
        let most = |v: &[f32]| v.iter().copied().fold(1.0f32, f32::max);
        finest_step = Setting {
            step: Step::Fixed(implicit_base * substep_factors.iter().max().unwrap_or(&1)),
            iterations: ((base.iterations as f32 * most(iteration_factors)).round() as u32).max(1),
            ..base
        };
    }
    let mut reference = Setting {
        integrator: finest_step.integrator,
        step: finest_step.step,
        iterations: finest_step.iterations,
        ..base
    };
    if knobs.spacing.is_ok() {
        let factors: &[f32] = if quick {
            &[1.5, 1.0]
        } else {
            &[2.0, 1.5, 1.0, 0.7, 0.5]
        };
        for &f in factors {
            push(
                Knob::Spacing,
                Setting { spacing: f, ..base },
                format!("spacing ×{f}"),
            );
        }
        reference.spacing = factors.iter().copied().fold(f32::INFINITY, f32::min);
    }
    if knobs.body {
        let sdf: &[f32] = if quick {
            &[2.0, 1.0]
        } else {
            &[4.0, 2.0, 1.0, 0.5]
        };
        for &f in sdf {
            push(Knob::Sdf, Setting { sdf: f, ..base }, format!("sdf ×{f}"));
        }
        reference.sdf = sdf.iter().copied().fold(f32::INFINITY, f32::min);
        let kept: &[f32] = if quick {
            &[0.2]
        } else {
            &[0.5, 0.2, 0.1, 0.05]
        };
        for &f in kept {
            push(
                Knob::Body,
                Setting { body: f, ..base },
                format!("body {:.0}%", 100.0 * f),
            );
        }
    }
    (
        points,
        Point {
            label: "reference".into(),
            knob: Knob::Reference,
            setting: reference,
        },
    )
}
