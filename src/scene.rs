//! Scene files (TOML): parsing, validation with precise errors, and conversion to SI values.
//! Every key, its unit and its default are documented in README.md ("Scene format").

use crate::error::InputError;
use crate::gpu::layout::{Hinge, Seam};
use crate::gpu::layout::{INTEGRATOR_EXPLICIT, INTEGRATOR_SYMPLECTIC};
use crate::mesh::{GridPlane, TriMesh};
use crate::model::{ClothModel, Fabric};
use crate::pattern::garment::{Garment, GarmentOptions, Placement};
use crate::pattern::Pattern;
use crate::plan::Effects;
use glam::Vec3;
use serde::Deserialize;
use std::path::{Path, PathBuf};

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawScene {
    cloth: RawCloth,
    fabric: RawFabric,
    #[serde(default)]
    pins: Vec<RawPin>,
    #[serde(default)]
    world: RawWorld,
    wind: Option<RawWind>,
    body: Option<crate::body::settings::RawBody>,
    self_collision: Option<RawSelfCollision>,
    solver: RawSolver,
    #[serde(default)]
    output: RawOutput,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawSelfCollision {
    thickness_m: Option<f64>,
    hash_buckets: Option<i64>,
    #[serde(default = "default_cpu_reference")]
    cpu_method: String,
}

fn default_cpu_reference() -> String {
    "particles".into()
}

/// The `[self_collision]` table.
#[derive(Clone, Debug, PartialEq)]
pub struct SelfCollision {
    /// Particles keep this far apart, in m (`None`: 0.75 × the mean rest edge length).
    pub thickness: Option<f32>,
    /// Hash table size (`None`: the power of two at or above twice the particle count).
    pub buckets: Option<u32>,
    /// On the CPU backend, use point–triangle impulses (the reference) instead of the particle
    /// repulsion the GPU runs.
    pub cpu_point_triangle: bool,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawCloth {
    grid: Option<RawGrid>,
    mesh: Option<RawMesh>,
    pattern: Option<RawPattern>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawPattern {
    path: String,
    #[serde(default = "default_particle_distance")]
    particle_distance_m: f64,
    seam_stiffness_n_m: Option<f64>,
    seam_sewing_time_s: Option<f64>,
    #[serde(default = "default_closed_gap")]
    seam_closed_gap_m: f64,
    #[serde(default)]
    placement: std::collections::BTreeMap<String, RawPlacement>,
    #[serde(default)]
    seams: Vec<RawSeam>,
    #[serde(default)]
    attach_labels: Vec<String>,
    #[serde(default)]
    attach_frames: i64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawSeam {
    stitch: i64,
    #[serde(default)]
    fold_deg: f64,
}

fn default_particle_distance() -> f64 {
    0.01
}

fn default_closed_gap() -> f64 {
    0.001
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawPlacement {
    translation: [f64; 3],
    #[serde(default)]
    rotation_deg: [f64; 3],
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawGrid {
    width_m: f64,
    height_m: f64,
    columns: u32,
    rows: u32,
    #[serde(default)]
    center_m: [f64; 3],
    #[serde(default = "default_plane")]
    plane: String,
}

fn default_plane() -> String {
    "xy".into()
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawMesh {
    path: String,
    #[serde(default = "default_units")]
    units: String,
    #[serde(default)]
    offset_m: [f64; 3],
}

pub(crate) fn default_units() -> String {
    "m".into()
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawFabric {
    density_kg_m2: f64,
    stretch_stiffness_n_m: f64,
    bending_stiffness_n_m: Option<f64>,
    #[serde(default = "default_damping_ratio")]
    damping_ratio: f64,
}

fn default_damping_ratio() -> f64 {
    0.05
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct RawPin {
    corners: Option<Vec<String>>,
    edge: Option<String>,
    indices: Option<Vec<i64>>,
    box_min_m: Option<[f64; 3]>,
    box_max_m: Option<[f64; 3]>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawWorld {
    #[serde(default = "default_gravity")]
    gravity_m_s2: [f64; 3],
    #[serde(default)]
    air_damping_per_s: f64,
    #[serde(default)]
    gravity_start_s: f64,
}

impl Default for RawWorld {
    fn default() -> Self {
        RawWorld {
            gravity_m_s2: default_gravity(),
            air_damping_per_s: 0.0,
            gravity_start_s: 0.0,
        }
    }
}

fn default_gravity() -> [f64; 3] {
    [0.0, -9.81, 0.0]
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawWind {
    velocity_m_s: [f64; 3],
    #[serde(default = "default_air_density")]
    air_density_kg_m3: f64,
    #[serde(default = "default_drag")]
    drag_coefficient: f64,
    #[serde(default)]
    gust_amplitude: f64,
    #[serde(default)]
    gust_frequency_hz: f64,
}

fn default_air_density() -> f64 {
    1.225
}
fn default_drag() -> f64 {
    1.0
}

#[derive(Deserialize)]
#[serde(untagged)]
enum RawSubsteps {
    Count(i64),
    Word(String),
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawSolver {
    #[serde(default = "default_fps")]
    fps: f64,
    frames: i64,
    substeps: Option<RawSubsteps>,
    #[serde(default = "default_integrator")]
    integrator: String,
    settle_ke_per_particle_j: Option<f64>,
    #[serde(default = "default_max_substeps")]
    max_substeps_per_frame: i64,
}

fn default_fps() -> f64 {
    24.0
}
fn default_integrator() -> String {
    "symplectic".into()
}
fn default_max_substeps() -> i64 {
    20_000
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawOutput {
    dir: Option<String>,
    #[serde(default = "default_true")]
    obj: bool,
    #[serde(default = "default_every")]
    every: i64,
}

impl Default for RawOutput {
    fn default() -> Self {
        RawOutput {
            dir: None,
            obj: true,
            every: 1,
        }
    }
}

fn default_true() -> bool {
    true
}
fn default_every() -> i64 {
    1
}

/// What `Scene::build_model` makes.
pub struct BuiltCloth {
    /// The model, attached particles pinned.
    pub model: ClothModel,
    /// The sewn pattern, for `[cloth.pattern]` scenes.
    pub garment: Option<Garment>,
    /// Particles the scene's `[[pins]]` hold for the whole run.
    pub scene_pins: Vec<u32>,
    /// Particles held by `attach_labels` until they are released.
    pub attached: Vec<u32>,
}

/// Where the cloth's triangles come from.
#[derive(Clone, Debug, PartialEq)]
pub enum ClothSource {
    /// A generated rectangular grid.
    Grid {
        /// Width in m (along columns).
        width: f32,
        /// Height in m (along rows).
        height: f32,
        /// Particles along the width.
        columns: u32,
        /// Particles along the height.
        rows: u32,
        /// Centre in m.
        center: Vec3,
        /// The world plane the grid lies in.
        plane: GridPlane,
    },
    /// A GarmentCode sewing pattern, sewn by seam forces.
    Pattern {
        /// Absolute or scene-relative path, resolved.
        path: PathBuf,
        /// Meshing and placement options.
        options: GarmentOptions,
        /// Seam pair stiffness in N/m.
        seam_stiffness: f32,
        /// Time over which seam rest gaps shrink from the placed gap to 0, in s; 0: seams pull
        /// with their full stiffness from the start.
        sewing_time: f32,
        /// A seam counts as closed when every pair's gap is below this, in m.
        closed_gap: f32,
        /// Fold angles θ0 in radians by stitch index (others fold to 0: flat).
        folds: Vec<(usize, f32)>,
        /// Edges with these labels are held in place for the first `attach_frames` frames.
        attach_labels: Vec<String>,
        /// Output frames during which labelled edges stay attached.
        attach_frames: u32,
    },
    /// A triangle mesh from an OBJ file.
    Mesh {
        /// Absolute or scene-relative path, resolved.
        path: PathBuf,
        /// Metres per file unit.
        scale: f32,
        /// Translation in m after scaling.
        offset: Vec3,
    },
}

/// A grid corner.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Corner {
    /// Highest row, first column.
    TopLeft,
    /// Highest row, last column.
    TopRight,
    /// Row 0, first column.
    BottomLeft,
    /// Row 0, last column.
    BottomRight,
}

/// A grid edge.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GridEdge {
    /// The highest row.
    Top,
    /// Row 0.
    Bottom,
    /// The first column.
    Left,
    /// The last column.
    Right,
}

/// Which particles one `[[pins]]` entry holds fixed.
#[derive(Clone, Debug, PartialEq)]
pub enum PinSelection {
    /// Named grid corners.
    Corners(Vec<Corner>),
    /// A whole grid edge.
    Edge(GridEdge),
    /// Particle indices.
    Indices(Vec<u32>),
    /// Every particle whose initial position lies in the box (m).
    Box {
        /// Minimum corner.
        min: Vec3,
        /// Maximum corner.
        max: Vec3,
    },
}

/// Wind in SI units.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Wind {
    /// Mean wind velocity in m/s.
    pub velocity: Vec3,
    /// Air density in kg/m³.
    pub air_density: f32,
    /// Normal drag coefficient.
    pub drag_coefficient: f32,
    /// Gust amplitude as a fraction of the mean.
    pub gust_amplitude: f32,
    /// Gust frequency in Hz.
    pub gust_frequency: f32,
}

impl Wind {
    /// Wind velocity at time `t`: v·(1 + a·sin(2πft)).
    pub fn at(&self, t: f32) -> Vec3 {
        let phase = 2.0 * std::f32::consts::PI * self.gust_frequency * t;
        self.velocity * (1.0 + self.gust_amplitude * phase.sin())
    }
}

/// Solver settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SolverSettings {
    /// Output frames per simulated second.
    pub fps: f32,
    /// Number of output frames.
    pub frames: u32,
    /// Substeps per frame, or `None` for automatic from the stability bound.
    pub substeps: Option<u32>,
    /// `INTEGRATOR_EXPLICIT` or `INTEGRATOR_SYMPLECTIC`.
    pub integrator: u32,
    /// Stop once kinetic energy per free particle falls below this (J).
    pub settle_ke_per_particle: Option<f32>,
    /// The most substeps per frame `auto` may choose before the scene is refused.
    pub max_substeps_per_frame: u32,
}

/// Output settings.
#[derive(Clone, Debug, PartialEq)]
pub struct OutputSettings {
    /// Output folder.
    pub dir: PathBuf,
    /// Write one OBJ per output frame.
    pub obj: bool,
    /// Write every n-th frame.
    pub every: u32,
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
    /// The collision body, if any.
    pub body: Option<crate::body::settings::BodySettings>,
    /// Solver settings.
    pub solver: SolverSettings,
    /// Output settings.
    pub output: OutputSettings,
}

/// Finds the 1-based line of `key` inside `table` ("fabric", "cloth.grid", "pins[1]"), falling
/// back to the table's header line.
fn key_line(src: &str, table: &str, key: &str) -> Option<usize> {
    let (name, index) = match table.split_once('[') {
        Some((n, rest)) => (n, rest.trim_end_matches(']').parse::<usize>().unwrap_or(0)),
        None => (table, 0),
    };
    let mut current = String::new();
    let mut current_index = 0usize;
    let mut array_counts = std::collections::HashMap::<String, usize>::new();
    let mut header_line = None;
    for (n, line) in src.lines().enumerate() {
        let t = line.trim();
        if let Some(h) = t.strip_prefix("[[") {
            current = h.split("]]").next().unwrap_or("").trim().to_string();
            let count = array_counts.entry(current.clone()).or_insert(0);
            current_index = *count;
            *count += 1;
        } else if let Some(h) = t.strip_prefix('[') {
            current = h.split(']').next().unwrap_or("").trim().to_string();
            current_index = 0;
        } else if current == name && current_index == index {
            if let Some(rest) = t.strip_prefix(key) {
                if rest.trim_start().starts_with('=') {
                    return Some(n + 1);
                }
            }
            continue;
        } else {
            continue;
        }
        if current == name && current_index == index {
            header_line = Some(n + 1);
        }
    }
    header_line
}

/// Validation context: the file and its text, for locations.
pub(crate) struct Checker<'a> {
    pub(crate) path: &'a Path,
    pub(crate) src: &'a str,
}

impl Checker<'_> {
    pub(crate) fn err(
        &self,
        table: &str,
        key: &str,
        problem: impl Into<String>,
        fix: impl Into<String>,
    ) -> InputError {
        let location = if key.is_empty() {
            table.to_string()
        } else {
            format!("{table}.{key}")
        };
        InputError::new(self.path, location, problem, fix).at_line(key_line(self.src, table, key))
    }

    /// Metres per file unit for a unit name (`m`, `dm`, `cm`, `mm`).
    pub(crate) fn units(&self, table: &str, key: &str, name: &str) -> Result<f32, InputError> {
        match name {
            "m" => Ok(1.0),
            "dm" => Ok(0.1),
            "cm" => Ok(0.01),
            "mm" => Ok(0.001),
            other => Err(self.err(
                table,
                key,
                format!("unknown unit {other:?}"),
                "use one of \"m\", \"dm\", \"cm\", \"mm\"",
            )),
        }
    }

    pub(crate) fn finite(&self, table: &str, key: &str, v: f64) -> Result<f32, InputError> {
        if !v.is_finite() {
            return Err(self.err(
                table,
                key,
                format!("{v} is not a finite number"),
                "write a finite decimal number",
            ));
        }
        Ok(v as f32)
    }

    pub(crate) fn positive(
        &self,
        table: &str,
        key: &str,
        v: f64,
        unit: &str,
    ) -> Result<f32, InputError> {
        let x = self.finite(table, key, v)?;
        if v <= 0.0 {
            return Err(self.err(
                table,
                key,
                format!("must be greater than zero, got {v}"),
                format!("give a positive value in {unit}"),
            ));
        }
        Ok(x)
    }

    pub(crate) fn non_negative(
        &self,
        table: &str,
        key: &str,
        v: f64,
        unit: &str,
    ) -> Result<f32, InputError> {
        let x = self.finite(table, key, v)?;
        if v < 0.0 {
            return Err(self.err(
                table,
                key,
                format!("must not be negative, got {v}"),
                format!("give zero or a positive value in {unit}"),
            ));
        }
        Ok(x)
    }

    pub(crate) fn vec3(&self, table: &str, key: &str, v: [f64; 3]) -> Result<Vec3, InputError> {
        let mut out = [0.0f32; 3];
        for (o, x) in out.iter_mut().zip(v) {
            *o = self.finite(table, key, x)?;
        }
        Ok(Vec3::from(out))
    }

    pub(crate) fn count(
        &self,
        table: &str,
        key: &str,
        v: i64,
        min: i64,
    ) -> Result<u32, InputError> {
        if v < min || v > u32::MAX as i64 {
            return Err(self.err(
                table,
                key,
                format!("must be an integer of at least {min}, got {v}"),
                format!("give a whole number ≥ {min}"),
            ));
        }
        Ok(v as u32)
    }
}

impl Scene {
    /// Reads and validates a scene file.
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
    pub fn parse(src: &str, path: &Path) -> Result<Scene, InputError> {
        let raw: RawScene = toml::from_str(src).map_err(|e| {
            let line = e
                .span()
                .map(|s| src[..s.start.min(src.len())].matches('\n').count() + 1);
            InputError::new(
                path,
                "",
                e.message().trim().to_string(),
                "see the scene format in README.md: every key, its unit and default",
            )
            .at_line(line)
        })?;
        let c = Checker { path, src };
        let base = path.parent().unwrap_or(Path::new("."));

        let cloth = match (raw.cloth.grid, raw.cloth.mesh, raw.cloth.pattern) {
            (Some(g), None, None) => {
                let plane = match g.plane.as_str() {
                    "xy" => GridPlane::Xy,
                    "xz" => GridPlane::Xz,
                    other => {
                        return Err(c.err(
                            "cloth.grid",
                            "plane",
                            format!("unknown plane {other:?}"),
                            "use \"xy\" (hanging) or \"xz\" (lying flat)",
                        ))
                    }
                };
                ClothSource::Grid {
                    width: c.positive("cloth.grid", "width_m", g.width_m, "m")?,
                    height: c.positive("cloth.grid", "height_m", g.height_m, "m")?,
                    columns: c.count("cloth.grid", "columns", g.columns as i64, 2)?,
                    rows: c.count("cloth.grid", "rows", g.rows as i64, 2)?,
                    center: c.vec3("cloth.grid", "center_m", g.center_m)?,
                    plane,
                }
            }
            (None, Some(m), None) => ClothSource::Mesh {
                path: base.join(&m.path),
                scale: c.units("cloth.mesh", "units", &m.units)?,
                offset: c.vec3("cloth.mesh", "offset_m", m.offset_m)?,
            },
            (None, None, Some(p)) => {
                let t = "cloth.pattern";
                let stretch = raw.fabric.stretch_stiffness_n_m;
                let mut placement = std::collections::HashMap::new();
                for (name, pl) in &p.placement {
                    let table = format!("cloth.pattern.placement.{name}");
                    placement.insert(
                        name.clone(),
                        Placement {
                            translation: c.vec3(&table, "translation", pl.translation)?.as_dvec3(),
                            rotation_deg: c
                                .vec3(&table, "rotation_deg", pl.rotation_deg)?
                                .as_dvec3(),
                        },
                    );
                }
                ClothSource::Pattern {
                    path: base.join(&p.path),
                    options: GarmentOptions {
                        particle_distance: c.positive(
                            t,
                            "particle_distance_m",
                            p.particle_distance_m,
                            "m",
                        )? as f64,
                        placement,
                    },
                    seam_stiffness: match p.seam_stiffness_n_m {
                        Some(k) => c.positive(t, "seam_stiffness_n_m", k, "N/m")?,
                        // Twice the fabric's stretch stiffness (validated with the fabric).
                        None => (2.0 * stretch) as f32,
                    },
                    sewing_time: match p.seam_sewing_time_s {
                        Some(v) => c.positive(t, "seam_sewing_time_s", v, "s")?,
                        None => 0.0,
                    },
                    closed_gap: c.positive(t, "seam_closed_gap_m", p.seam_closed_gap_m, "m")?,
                    folds: {
                        let mut folds = Vec::new();
                        for (k, seam) in p.seams.iter().enumerate() {
                            let table = format!("cloth.pattern.seams[{k}]");
                            let stitch = c.count(&table, "stitch", seam.stitch, 0)? as usize;
                            let fold = c.finite(&table, "fold_deg", seam.fold_deg)?;
                            if fold.abs() >= 180.0 {
                                return Err(c.err(
                                    &table,
                                    "fold_deg",
                                    format!("{fold}° is not a fold angle"),
                                    "use an angle between -180 and 180 degrees",
                                ));
                            }
                            folds.push((stitch, fold.to_radians()));
                        }
                        folds
                    },
                    attach_labels: p.attach_labels.clone(),
                    attach_frames: c.count(t, "attach_frames", p.attach_frames, 0)?,
                }
            }
            _ => {
                return Err(c.err(
                    "cloth",
                    "",
                    "needs exactly one of [cloth.grid], [cloth.mesh] or [cloth.pattern]",
                    "keep one of the two sections",
                ))
            }
        };

        let f = &raw.fabric;
        let fabric = Fabric {
            density: c.positive("fabric", "density_kg_m2", f.density_kg_m2, "kg/m²")?,
            stretch_stiffness: c.positive(
                "fabric",
                "stretch_stiffness_n_m",
                f.stretch_stiffness_n_m,
                "N/m",
            )?,
            bending_stiffness: match f.bending_stiffness_n_m {
                None => None,
                Some(v) => Some(c.positive(
                    "fabric",
                    "bending_stiffness_n_m",
                    v,
                    "N·m (omit the key to disable bending)",
                )?),
            },
            damping_ratio: c.non_negative(
                "fabric",
                "damping_ratio",
                f.damping_ratio,
                "fractions of critical damping",
            )?,
        };

        let mut pins = Vec::new();
        for (k, p) in raw.pins.iter().enumerate() {
            let table = format!("pins[{k}]");
            let given = [
                p.corners.is_some(),
                p.edge.is_some(),
                p.indices.is_some(),
                p.box_min_m.is_some() || p.box_max_m.is_some(),
            ];
            if given.iter().filter(|&&g| g).count() != 1 {
                return Err(c.err(
                    &table,
                    "",
                    "needs exactly one selector",
                    "give one of corners, edge, indices, or box_min_m with box_max_m",
                ));
            }
            let is_grid = matches!(cloth, ClothSource::Grid { .. });
            let selection = if let Some(names) = &p.corners {
                if !is_grid {
                    return Err(c.err(
                        &table,
                        "corners",
                        "named corners exist only for [cloth.grid]",
                        "select mesh particles with indices or box_min_m/box_max_m",
                    ));
                }
                let mut corners = Vec::new();
                for name in names {
                    corners.push(match name.as_str() {
                        "top-left" => Corner::TopLeft,
                        "top-right" => Corner::TopRight,
                        "bottom-left" => Corner::BottomLeft,
                        "bottom-right" => Corner::BottomRight,
                        other => {
                            return Err(c.err(
                                &table,
                                "corners",
                                format!("unknown corner {other:?}"),
                                "use top-left, top-right, bottom-left or bottom-right",
                            ))
                        }
                    });
                }
                PinSelection::Corners(corners)
            } else if let Some(name) = &p.edge {
                if !is_grid {
                    return Err(c.err(
                        &table,
                        "edge",
                        "named edges exist only for [cloth.grid]",
                        "select mesh particles with indices or box_min_m/box_max_m",
                    ));
                }
                PinSelection::Edge(match name.as_str() {
                    "top" => GridEdge::Top,
                    "bottom" => GridEdge::Bottom,
                    "left" => GridEdge::Left,
                    "right" => GridEdge::Right,
                    other => {
                        return Err(c.err(
                            &table,
                            "edge",
                            format!("unknown edge {other:?}"),
                            "use top, bottom, left or right",
                        ))
                    }
                })
            } else if let Some(ids) = &p.indices {
                let mut out = Vec::new();
                for &i in ids {
                    if i < 0 || i > u32::MAX as i64 {
                        return Err(c.err(
                            &table,
                            "indices",
                            format!("{i} is not a particle index"),
                            "use 0-based particle indices",
                        ));
                    }
                    out.push(i as u32);
                }
                PinSelection::Indices(out)
            } else {
                let (Some(min), Some(max)) = (p.box_min_m, p.box_max_m) else {
                    return Err(c.err(
                        &table,
                        "",
                        "a box needs both box_min_m and box_max_m",
                        "add the missing corner",
                    ));
                };
                PinSelection::Box {
                    min: c.vec3(&table, "box_min_m", min)?,
                    max: c.vec3(&table, "box_max_m", max)?,
                }
            };
            pins.push(selection);
        }

        let gravity = c.vec3("world", "gravity_m_s2", raw.world.gravity_m_s2)?;
        let gravity_start =
            c.non_negative("world", "gravity_start_s", raw.world.gravity_start_s, "s")?;
        let air_damping = c.non_negative(
            "world",
            "air_damping_per_s",
            raw.world.air_damping_per_s,
            "1/s",
        )?;

        let wind = match &raw.wind {
            None => None,
            Some(w) => Some(Wind {
                velocity: c.vec3("wind", "velocity_m_s", w.velocity_m_s)?,
                air_density: c.positive(
                    "wind",
                    "air_density_kg_m3",
                    w.air_density_kg_m3,
                    "kg/m³",
                )?,
                drag_coefficient: c.positive(
                    "wind",
                    "drag_coefficient",
                    w.drag_coefficient,
                    "(dimensionless)",
                )?,
                gust_amplitude: c.non_negative(
                    "wind",
                    "gust_amplitude",
                    w.gust_amplitude,
                    "fractions of the mean wind",
                )?,
                gust_frequency: c.non_negative(
                    "wind",
                    "gust_frequency_hz",
                    w.gust_frequency_hz,
                    "Hz",
                )?,
            }),
        };

        let s = &raw.solver;
        let substeps = match &s.substeps {
            None => None,
            Some(RawSubsteps::Word(w)) if w == "auto" => None,
            Some(RawSubsteps::Word(w)) => {
                return Err(c.err(
                    "solver",
                    "substeps",
                    format!("{w:?} is not a substep count"),
                    "write \"auto\" or a whole number ≥ 1",
                ))
            }
            Some(RawSubsteps::Count(n)) => Some(c.count("solver", "substeps", *n, 1)?),
        };
        let integrator = match s.integrator.as_str() {
            "explicit" => INTEGRATOR_EXPLICIT,
            "symplectic" | "semi-implicit" => INTEGRATOR_SYMPLECTIC,
            other => {
                return Err(c.err(
                    "solver",
                    "integrator",
                    format!("unknown integrator {other:?}"),
                    "use \"explicit\" or \"symplectic\"",
                ))
            }
        };
        let solver = SolverSettings {
            fps: c.positive("solver", "fps", s.fps, "frames per second")?,
            frames: c.count("solver", "frames", s.frames, 1)?,
            substeps,
            integrator,
            settle_ke_per_particle: match s.settle_ke_per_particle_j {
                None => None,
                Some(v) => Some(c.positive("solver", "settle_ke_per_particle_j", v, "J")?),
            },
            max_substeps_per_frame: c.count(
                "solver",
                "max_substeps_per_frame",
                s.max_substeps_per_frame,
                1,
            )?,
        };

        let stem = path.file_stem().and_then(|s| s.to_str()).unwrap_or("scene");
        let output = OutputSettings {
            dir: raw
                .output
                .dir
                .as_ref()
                .map(PathBuf::from)
                .unwrap_or_else(|| Path::new("out").join(stem)),
            obj: raw.output.obj,
            every: c.count("output", "every", raw.output.every, 1)?,
        };

        Ok(Scene {
            path: path.to_path_buf(),
            source: src.to_string(),
            cloth,
            fabric,
            pins,
            gravity,
            gravity_start,
            air_damping,
            wind,
            self_collision: match &raw.self_collision {
                Some(sc) => Some(SelfCollision {
                    thickness: match sc.thickness_m {
                        Some(t) => Some(c.positive("self_collision", "thickness_m", t, "m")?),
                        None => None,
                    },
                    buckets: match sc.hash_buckets {
                        Some(b) => Some(c.count("self_collision", "hash_buckets", b, 64)?),
                        None => None,
                    },
                    cpu_point_triangle: match sc.cpu_method.as_str() {
                        "particles" => false,
                        "point-triangle" => true,
                        other => {
                            return Err(c.err(
                                "self_collision",
                                "cpu_method",
                                format!("unknown method {other:?}"),
                                "use \"particles\" (as the GPU) or \"point-triangle\" (the CPU reference)",
                            ))
                        }
                    },
                }),
                None => None,
            },
            body: match &raw.body {
                Some(b) => Some(crate::body::settings::parse(&c, base, b)?),
                None => None,
            },
            solver,
            output,
        })
    }

    /// An error about `table.key` of this scene, located at its line.
    pub fn error(
        &self,
        table: &str,
        key: &str,
        problem: impl Into<String>,
        fix: impl Into<String>,
    ) -> InputError {
        Checker {
            path: &self.path,
            src: &self.source,
        }
        .err(table, key, problem, fix)
    }

    /// The effects this scene asks for, for the pass plan.
    pub fn effects(&self) -> Effects {
        Effects {
            bending: self.fabric.bending_stiffness.is_some(),
            wind: self.wind.is_some(),
            body: self.body.is_some(),
            self_collision: self.self_collision.is_some(),
        }
    }

    /// The cloth's triangle mesh in metres.
    pub fn build_mesh(&self) -> Result<TriMesh, InputError> {
        match &self.cloth {
            ClothSource::Grid {
                width,
                height,
                columns,
                rows,
                center,
                plane,
            } => Ok(TriMesh::grid(
                *width, *height, *columns, *rows, *center, *plane,
            )),
            ClothSource::Mesh {
                path,
                scale,
                offset,
            } => {
                let mut mesh = TriMesh::load_obj(path, *scale, "cloth.mesh.path").map_err(|e| {
                    self.error(
                        "cloth.mesh",
                        "path",
                        format!("{}: {}", path.display(), e.problem),
                        e.fix,
                    )
                })?;
                for p in &mut mesh.positions {
                    *p += *offset;
                }
                Ok(mesh)
            }
            ClothSource::Pattern { .. } => Ok(self.build_garment()?.expect("a pattern").mesh),
        }
    }

    /// The particles held by `attach_labels` for the first `attach_frames` frames.
    pub fn attached_particles(&self, garment: &Garment) -> Result<Vec<u32>, InputError> {
        let ClothSource::Pattern {
            attach_labels,
            attach_frames,
            ..
        } = &self.cloth
        else {
            return Ok(Vec::new());
        };
        if attach_labels.is_empty() || *attach_frames == 0 {
            return Ok(Vec::new());
        }
        let ids = garment.particles_on_labelled_edges(attach_labels);
        if ids.is_empty() {
            let mut found: Vec<&String> = garment.edge_labels.iter().flatten().flatten().collect();
            found.sort();
            found.dedup();
            return Err(self.error(
                "cloth.pattern",
                "attach_labels",
                format!("no edge of the pattern has a label in {attach_labels:?}"),
                format!("use labels the pattern has: {found:?}"),
            ));
        }
        Ok(ids)
    }

    /// The sewn cloth of a `[cloth.pattern]` scene (`None` for grids and meshes).
    pub fn build_garment(&self) -> Result<Option<Garment>, InputError> {
        let ClothSource::Pattern { path, options, .. } = &self.cloth else {
            return Ok(None);
        };
        let pattern = Pattern::load(path)?;
        Ok(Some(Garment::build(&pattern, options)?))
    }

    /// The particles each pin entry selects; an entry that selects nothing is an error.
    pub fn pinned_particles(&self, mesh: &TriMesh) -> Result<Vec<u32>, InputError> {
        let c = Checker {
            path: &self.path,
            src: &self.source,
        };
        let n = mesh.positions.len() as u32;
        let mut all = Vec::new();
        for (k, pin) in self.pins.iter().enumerate() {
            let table = format!("pins[{k}]");
            let ids: Vec<u32> = match (pin, &self.cloth) {
                (PinSelection::Corners(cs), ClothSource::Grid { columns, rows, .. }) => cs
                    .iter()
                    .map(|corner| match corner {
                        Corner::TopLeft => (rows - 1) * columns,
                        Corner::TopRight => rows * columns - 1,
                        Corner::BottomLeft => 0,
                        Corner::BottomRight => columns - 1,
                    })
                    .collect(),
                (PinSelection::Edge(e), ClothSource::Grid { columns, rows, .. }) => match e {
                    GridEdge::Top => ((rows - 1) * columns..rows * columns).collect(),
                    GridEdge::Bottom => (0..*columns).collect(),
                    GridEdge::Left => (0..*rows).map(|r| r * columns).collect(),
                    GridEdge::Right => (0..*rows).map(|r| r * columns + columns - 1).collect(),
                },
                (PinSelection::Indices(ids), _) => {
                    if let Some(&bad) = ids.iter().find(|&&i| i >= n) {
                        return Err(c.err(
                            &table,
                            "indices",
                            format!("particle {bad} does not exist; the cloth has {n} particles"),
                            format!("use indices from 0 to {}", n - 1),
                        ));
                    }
                    ids.clone()
                }
                (PinSelection::Box { min, max }, _) => (0..n)
                    .filter(|&i| {
                        let p = mesh.positions[i as usize];
                        p.cmpge(*min).all() && p.cmple(*max).all()
                    })
                    .collect(),
                _ => unreachable!("named corners and edges are refused for meshes at load time"),
            };
            if ids.is_empty() {
                let (lo, hi) = mesh.positions.iter().fold(
                    (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
                    |(lo, hi), p| (lo.min(*p), hi.max(*p)),
                );
                return Err(c.err(
                    &table,
                    "",
                    "selects no particle",
                    format!("the cloth spans {lo:?} to {hi:?} m; widen the selection"),
                ));
            }
            all.extend(ids);
        }
        all.sort_unstable();
        all.dedup();
        Ok(all)
    }

    /// Builds the cloth model (mesh, fabric, pins and seams) and, for patterns, the garment.
    pub fn build_model(&self) -> Result<BuiltCloth, InputError> {
        let garment = self.build_garment()?;
        let mesh = match &garment {
            Some(g) => g.mesh.clone(),
            None => self.build_mesh()?,
        };
        let scene_pins = self.pinned_particles(&mesh)?;
        let attached = match &garment {
            Some(g) => self.attached_particles(g)?,
            None => Vec::new(),
        };
        let pinned: Vec<u32> = scene_pins.iter().chain(&attached).copied().collect();
        let mut model = ClothModel::from_mesh(&mesh, &self.fabric, &pinned);
        if let Some(b) = &self.body {
            let c = Checker {
                path: &self.path,
                src: &self.source,
            };
            model.collider = Some(std::sync::Arc::new(b.collider(&c)?));
        }
        if let (
            Some(g),
            ClothSource::Pattern {
                seam_stiffness,
                sewing_time,
                folds,
                ..
            },
        ) = (&garment, &self.cloth)
        {
            let c = Checker {
                path: &self.path,
                src: &self.source,
            };
            let mut fold_of = vec![0.0f32; g.stitches];
            for (k, &(stitch, angle)) in folds.iter().enumerate() {
                if stitch >= g.stitches {
                    return Err(c.err(
                        &format!("cloth.pattern.seams[{k}]"),
                        "stitch",
                        format!(
                            "the pattern has {} stitches; there is no stitch {stitch}",
                            g.stitches
                        ),
                        format!("use a stitch index from 0 to {}", g.stitches.max(1) - 1),
                    ));
                }
                fold_of[stitch] = angle;
            }
            // Hinges across seams bend like the fabric and rest at the seam's fold angle.
            if let Some(kb) = self.fabric.bending_stiffness {
                model.hinges.extend(g.seam_hinges.iter().map(|h| Hinge {
                    v: h.v,
                    stiffness: kb,
                    rest_sin_half: (0.5 * fold_of[h.stitch as usize]).sin(),
                    _pad0: 0,
                    _pad1: 0,
                }));
            }
            model.seams = g
                .seam_pairs
                .iter()
                .map(|p| {
                    let m = |i: u32| model.masses[i as usize];
                    let partner_mass = (1.0 - p.w) * m(p.b[0]) + p.w * m(p.b[1]);
                    let reduced = m(p.a) * partner_mass / (m(p.a) + partner_mass);
                    let x = |i: u32| model.positions[i as usize];
                    let partner = x(p.b[0]).lerp(x(p.b[1]), p.w);
                    Seam {
                        v: [p.a, p.b[0], p.b[1], 0],
                        weight: p.w,
                        stiffness: *seam_stiffness,
                        damping: 2.0
                            * self.fabric.damping_ratio
                            * (*seam_stiffness * reduced).sqrt(),
                        // With a sewing time the pair starts at rest where it was placed.
                        open_gap: if *sewing_time > 0.0 {
                            x(p.a).distance(partner)
                        } else {
                            0.0
                        },
                    }
                })
                .collect();
        }
        Ok(BuiltCloth {
            model,
            garment,
            scene_pins,
            attached,
        })
    }
}
