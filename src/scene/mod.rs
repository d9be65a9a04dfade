//! Scene files (TOML): parsing and validation with precise errors, into plain SI data. A scene
//! describes; building the cloth model from it is `model`'s job. One file per section; every
//! key, its unit and its default are documented in docs/src/scenes.md.

mod body;
mod cloth;
mod fabric;
pub mod limits;
mod pins;
mod presets;
mod preview;
mod raw;
mod self_collision;
mod solver;
mod world;

pub use body::{
    BodySettings, BodySource, DeformMotion, DeformSettings, MAX_BODIES, MAX_SDF_RESOLUTION_M,
};
pub use cloth::ClothSource;
pub use fabric::{Fabric, Grain, Orthotropic, BUCKLED_FRACTION, HINGE_PER_RIGIDITY};
pub use pins::{Corner, GridEdge, PinSelection};
pub use presets::{preset, FabricPreset, PRESETS};
pub use preview::{
    hex_color, CameraSetting, PreviewSettings, TextureSetting, CAMERA_PRESETS, DEFAULT_STRAIN_MAX,
    PREVIEW_MODES,
};
pub use self_collision::SelfCollision;
pub use solver::{
    OutputSettings, SolverSettings, INTEGRATOR_EXPLICIT, INTEGRATOR_IMPLICIT,
    INTEGRATOR_SYMPLECTIC, TOLERANCE_RANGE,
};
pub use world::Wind;

use crate::check::Checker;
use crate::error::InputError;
use glam::Vec3;
use raw::RawScene;
use std::path::{Path, PathBuf};

/// What a scene asks for beyond its mesh; the pass plan gives each effect its passes.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Effects {
    /// Bending stiffness is set.
    pub bending: bool,
    /// A wind section is present.
    pub wind: bool,
    /// A collision body is present.
    pub body: bool,
    /// Self-collision is on.
    pub self_collision: bool,
    /// Backward Euler (Vertex Block Descent) instead of an explicit force-then-integrate step.
    pub implicit: bool,
    /// Edge stretch is capped after each step.
    pub strain_limit: bool,
}

/// A validated scene in SI units.
#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    /// The scene file.
    pub path: PathBuf,
    /// The scene file's text, to locate errors found after parsing.
    pub source: String,
    /// The cloth geometry.
    pub cloth: ClothSource,
    /// The fabric.
    pub fabric: Fabric,
    /// Where the membrane's warp runs on each panel.
    pub grain: Grain,
    /// Pin selections, in file order.
    pub pins: Vec<PinSelection>,
    /// Gravity in m/s².
    pub gravity: Vec3,
    /// Gravity is off before this time (a zero-gravity sewing phase), in s.
    pub gravity_start: f32,
    /// Air damping in 1/s.
    pub air_damping: f32,
    /// Wind, if any.
    pub wind: Option<Wind>,
    /// Self-collision, if on.
    pub self_collision: Option<SelfCollision>,
    /// The collision bodies (`[body]`, or `[[body]]` for several), in file order.
    pub bodies: Vec<BodySettings>,
    /// Solver settings.
    pub solver: SolverSettings,
    /// Output settings.
    pub output: OutputSettings,
    /// What the previews look like and when they are rendered.
    pub preview: PreviewSettings,
}

impl Scene {
    /// Reads and validates a scene file.
    ///
    /// ```
    /// use drapekit::scene::Scene;
    /// use std::path::Path;
    ///
    /// let dir = Path::new(env!("CARGO_MANIFEST_DIR"));
    /// let scene = Scene::load(&dir.join("fixtures/scenes/tshirt_drape_cotton.toml"))?;
    /// assert_eq!(scene.bodies.len(), 1); // the mannequin
    /// assert_eq!(scene.solver.fps, 24.0);
    /// # Ok::<(), drapekit::InputError>(())
    /// ```
    pub fn load(path: &Path) -> Result<Scene, InputError> {
        let src = std::fs::read_to_string(path).map_err(|e| {
            InputError::new(
                path,
                "",
                format!("cannot read the scene file: {e}"),
                "check the path",
            )
        })?;
        Scene::parse(&src, path)
    }

    /// Parses and validates scene text; `path` locates errors and relative mesh paths.
    ///
    /// ```
    /// use drapekit::scene::Scene;
    /// use std::path::Path;
    ///
    /// let text = r#"
    ///     [cloth.grid]
    ///     width_m = 1.0
    ///     height_m = 1.0
    ///     columns = 16
    ///     rows = 16
    ///     [fabric]
    ///     preset = "denim"
    ///     [solver]
    ///     frames = 24
    /// "#;
    /// let scene = Scene::parse(text, Path::new("sheet.toml"))?;
    /// assert_eq!(scene.solver.frames, 24);
    /// assert_eq!(scene.fabric.density, 0.324); // kg/m², from the preset
    ///
    /// // Bad input names the file, line and key, and says what to do.
    /// let typo = text.replace("width_m", "width");
    /// let err = Scene::parse(&typo, Path::new("sheet.toml")).unwrap_err();
    /// assert_eq!(err.line, Some(3));
    /// assert_eq!(err.location, "cloth.grid.width");
    /// assert_eq!(err.fix, "rename it to `width_m`");
    /// # Ok::<(), drapekit::InputError>(())
    /// ```
    pub fn parse(src: &str, path: &Path) -> Result<Scene, InputError> {
        let raw: RawScene =
            toml::from_str(src).map_err(|e| crate::toml_message::describe(path, src, &e))?;
        let c = Checker { path, src };
        let base = path.parent().unwrap_or(Path::new("."));
        let fabric = fabric::parse(&c, &raw.fabric)?;
        let grain = fabric::parse_grain(&c, &raw.fabric)?;
        let cloth = cloth::parse(&c, base, raw.cloth, fabric.stiffest_stretch() as f64)?;
        let pins = pins::parse(&c, &raw.pins, &cloth)?;
        let world = world::parse_world(&c, &raw.world)?;
        let wind = world::parse_wind(&c, &raw.wind)?;
        let solver = solver::parse_solver(&c, &raw.solver)?;
        let output = solver::parse_output(&c, path, &raw.output)?;
        let preview = preview::parse(&c, &raw.output, raw.preview.as_ref(), output.obj)?;
        let coarse_start = matches!(
            cloth,
            ClothSource::Pattern {
                coarse_start: Some(_),
                ..
            }
        );
        if coarse_start && solver.settle_speed.is_none() {
            return Err(c.err(
                "cloth.pattern",
                "coarse_start_distance_m",
                "the coarse start runs until the coarse garment settles, and the scene has no \
                 settle rule",
                "add [solver] settle_speed_m_s (such as 0.005), or remove coarse_start_distance_m",
            ));
        }
        let scene = Scene {
            path: path.to_path_buf(),
            source: src.to_string(),
            cloth,
            fabric,
            grain,
            pins,
            gravity: world.gravity,
            gravity_start: world.gravity_start,
            air_damping: world.air_damping,
            wind,
            self_collision: self_collision::parse(&c, &raw.self_collision)?,
            bodies: body::parse_all(&c, base, &raw.body)?,
            solver,
            output,
            preview,
        };
        // Derived quantities (masses, stiffness, steps), in f64, before anything is f32.
        limits::check(&c, &scene)?;
        Ok(scene)
    }

    /// The validation context of this scene's file, to report errors found after parsing.
    pub fn checker(&self) -> Checker<'_> {
        Checker {
            path: &self.path,
            src: &self.source,
        }
    }

    /// An error about `table.key` of this scene, located at its line.
    pub fn error(
        &self,
        table: &str,
        key: &str,
        problem: impl Into<String>,
        fix: impl Into<String>,
    ) -> InputError {
        self.checker().err(table, key, problem, fix)
    }

    /// How errors name body `i`: `body` for the only one, `body[i]` among several.
    pub fn body_table(&self, i: usize) -> String {
        body::body_table(self.bodies.len(), i)
    }

    /// The effects this scene asks for, for the pass plan.
    pub fn effects(&self) -> Effects {
        Effects {
            bending: self.fabric.bending_stiffness.is_some(),
            wind: self.wind.is_some(),
            body: !self.bodies.is_empty(),
            self_collision: self.self_collision.is_some(),
            implicit: self.solver.integrator == INTEGRATOR_IMPLICIT,
            strain_limit: self.solver.strain_limit.is_some(),
        }
    }
}
