//! The scene file as TOML gives it: serde structs with defaults, before validation.

use serde::{Deserialize, Deserializer};

/// A TOML array of exactly `N` numbers. serde's fixed-size arrays stop reading after `N` and
/// ignore the rest, so `center_m = [0.0, 1.5, 0.0, 1.0]` would pass as a position.
pub(super) fn exactly<'de, D: Deserializer<'de>, const N: usize>(
    d: D,
) -> Result<[f64; N], D::Error> {
    let values = Vec::<f64>::deserialize(d)?;
    let found = values.len();
    values.try_into().map_err(|_| {
        // Worded as serde's own, which `toml_message` turns into the key's error.
        serde::de::Error::invalid_length(found, &format!("an array of length {N}").as_str())
    })
}

/// `exactly`, for a key that may be left out (with `#[serde(default)]`).
pub(super) fn exactly_if_given<'de, D: Deserializer<'de>, const N: usize>(
    d: D,
) -> Result<Option<[f64; N]>, D::Error> {
    exactly(d).map(Some)
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawScene {
    pub(super) cloth: RawCloth,
    pub(super) fabric: RawFabric,
    #[serde(default)]
    pub(super) pins: Vec<RawPin>,
    #[serde(default)]
    pub(super) world: RawWorld,
    pub(super) wind: Option<RawWind>,
    pub(super) body: Option<super::body::RawBodies>,
    pub(super) self_collision: Option<RawSelfCollision>,
    pub(super) solver: RawSolver,
    #[serde(default)]
    pub(super) output: RawOutput,
    pub(super) preview: Option<RawPreview>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawSelfCollision {
    pub(super) thickness_m: Option<f64>,
    pub(super) hash_buckets: Option<i64>,
    #[serde(default = "default_cpu_reference")]
    pub(super) cpu_method: String,
}

fn default_cpu_reference() -> String {
    "particles".into()
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawCloth {
    pub(super) grid: Option<RawGrid>,
    pub(super) mesh: Option<RawMesh>,
    pub(super) pattern: Option<RawPattern>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawPattern {
    pub(super) path: String,
    #[serde(default = "default_particle_distance")]
    pub(super) particle_distance_m: f64,
    pub(super) coarse_start_distance_m: Option<f64>,
    pub(super) seam_stiffness_n_m: Option<f64>,
    pub(super) seam_sewing_time_s: Option<f64>,
    #[serde(default = "default_closed_gap")]
    pub(super) seam_closed_gap_m: f64,
    #[serde(default)]
    pub(super) placement: std::collections::BTreeMap<String, RawPlacement>,
    #[serde(default)]
    pub(super) seams: Vec<RawSeam>,
    #[serde(default)]
    pub(super) attach_labels: Vec<String>,
    #[serde(default)]
    pub(super) attach_frames: i64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawSeam {
    pub(super) stitch: i64,
    #[serde(default)]
    pub(super) fold_deg: f64,
}

fn default_particle_distance() -> f64 {
    0.01
}

fn default_closed_gap() -> f64 {
    0.001
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawPlacement {
    #[serde(deserialize_with = "exactly")]
    pub(super) translation: [f64; 3],
    #[serde(default, deserialize_with = "exactly")]
    pub(super) rotation_deg: [f64; 3],
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawGrid {
    pub(super) width_m: f64,
    pub(super) height_m: f64,
    pub(super) columns: u32,
    pub(super) rows: u32,
    #[serde(default, deserialize_with = "exactly")]
    pub(super) center_m: [f64; 3],
    #[serde(default = "default_plane")]
    pub(super) plane: String,
}

fn default_plane() -> String {
    "xy".into()
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawMesh {
    pub(super) path: String,
    #[serde(default = "crate::check::default_units")]
    pub(super) units: String,
    #[serde(default, deserialize_with = "exactly")]
    pub(super) offset_m: [f64; 3],
}
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawFabric {
    pub(super) preset: Option<String>,
    pub(super) density_kg_m2: Option<f64>,
    pub(super) stretch_stiffness_n_m: Option<f64>,
    pub(super) bending_stiffness_n_m: Option<f64>,
    pub(super) damping_ratio: Option<f64>,
    pub(super) model: Option<String>,
    pub(super) compression: Option<String>,
    pub(super) tension: Option<String>,
    pub(super) warp_large_strain_stiffness_n_m: Option<f64>,
    pub(super) weft_large_strain_stiffness_n_m: Option<f64>,
    pub(super) warp_stiffness_n_m: Option<f64>,
    pub(super) weft_stiffness_n_m: Option<f64>,
    pub(super) shear_stiffness_n_m: Option<f64>,
    pub(super) warp_bending_n_m: Option<f64>,
    pub(super) weft_bending_n_m: Option<f64>,
    pub(super) grain_deg: Option<f64>,
    #[serde(default)]
    pub(super) panel_grain_deg: std::collections::BTreeMap<String, f64>,
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub(super) struct RawPin {
    pub(super) corners: Option<Vec<String>>,
    pub(super) edge: Option<String>,
    pub(super) indices: Option<Vec<i64>>,
    #[serde(default, deserialize_with = "exactly_if_given")]
    pub(super) box_min_m: Option<[f64; 3]>,
    #[serde(default, deserialize_with = "exactly_if_given")]
    pub(super) box_max_m: Option<[f64; 3]>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawWorld {
    #[serde(default = "default_gravity", deserialize_with = "exactly")]
    pub(super) gravity_m_s2: [f64; 3],
    #[serde(default)]
    pub(super) air_damping_per_s: f64,
    #[serde(default)]
    pub(super) gravity_start_s: f64,
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
pub(super) struct RawWind {
    #[serde(deserialize_with = "exactly")]
    pub(super) velocity_m_s: [f64; 3],
    #[serde(default = "default_air_density")]
    pub(super) air_density_kg_m3: f64,
    #[serde(default = "default_drag")]
    pub(super) drag_coefficient: f64,
    #[serde(default)]
    pub(super) gust_amplitude: f64,
    #[serde(default)]
    pub(super) gust_frequency_hz: f64,
}

fn default_air_density() -> f64 {
    1.225
}
fn default_drag() -> f64 {
    1.0
}

#[derive(Deserialize)]
#[serde(untagged)]
pub(super) enum RawSubsteps {
    Count(i64),
    Word(String),
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawSolver {
    #[serde(default = "default_fps")]
    pub(super) fps: f64,
    pub(super) frames: i64,
    pub(super) substeps: Option<RawSubsteps>,
    #[serde(default = "default_integrator")]
    pub(super) integrator: String,
    pub(super) iterations: Option<i64>,
    pub(super) tolerance: Option<f64>,
    pub(super) multigrid: Option<bool>,
    pub(super) smoothing_sweeps: Option<i64>,
    pub(super) settle_speed_m_s: Option<f64>,
    pub(super) settle_force_residual: Option<f64>,
    /// Replaced by `settle_speed_m_s`; read only to say so.
    pub(super) settle_ke_per_particle_j: Option<f64>,
    #[serde(default = "default_max_substeps")]
    pub(super) max_substeps_per_frame: i64,
    #[serde(default = "default_max_strain")]
    pub(super) max_strain: f64,
    pub(super) max_memory_mb: Option<f64>,
    pub(super) strain_limit: Option<RawStrainLimit>,
    #[serde(default = "default_max_energy_growth")]
    pub(super) max_energy_growth: f64,
    #[serde(default = "default_max_speed")]
    pub(super) max_speed_m_s: f64,
    #[serde(default = "default_strain_limit_iterations")]
    pub(super) strain_limit_iterations: i64,
}

/// Between two frames with no work done on the cloth, its energy may rise by half its kinetic
/// plus elastic energy before the run counts as diverging (docs/src/stability.md).
fn default_max_energy_growth() -> f64 {
    0.5
}

/// No garment moves at 100 m/s: a whipped cloth tip reaches tens of m/s, a swung arm a few.
fn default_max_speed() -> f64 {
    100.0
}

/// `strain_limit = 0.1`, or `true` (the default limit) / `false` (off).
#[derive(Deserialize)]
#[serde(
    untagged,
    expecting = "strain_limit takes a strain such as 0.1 (10%), true (the default) or false (off)"
)]
pub(super) enum RawStrainLimit {
    Switch(bool),
    Limit(f64),
}

/// Jacobi sweeps of the strain limit per substep: enough to fix an isolated over-stretched edge
/// and its neighbours; a long chain takes several substeps (docs/src/stability.md, "Strain limiting").
fn default_strain_limit_iterations() -> i64 {
    4
}

fn default_fps() -> f64 {
    24.0
}

/// A frame with a spring stretched past 500% is an exploded frame.
fn default_max_strain() -> f64 {
    5.0
}

fn default_integrator() -> String {
    "symplectic".into()
}
fn default_max_substeps() -> i64 {
    20_000
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawOutput {
    pub(super) dir: Option<String>,
    /// `None`: not given (true unless `formats` leaves it out).
    pub(super) obj: Option<bool>,
    #[serde(default = "default_every")]
    pub(super) every: i64,
    #[serde(default)]
    pub(super) previews: Vec<String>,
    pub(super) preview_camera: Option<String>,
    pub(super) preview_every: Option<i64>,
    #[serde(default)]
    pub(super) preview_modes: Vec<String>,
    pub(super) pc2: Option<bool>,
    pub(super) gltf: Option<bool>,
    pub(super) formats: Option<Vec<String>>,
    pub(super) weld_seams: Option<bool>,
}

fn default_every() -> i64 {
    1
}

impl Default for RawOutput {
    fn default() -> Self {
        RawOutput {
            dir: None,
            obj: None,
            every: default_every(),
            previews: Vec::new(),
            preview_camera: None,
            preview_every: None,
            preview_modes: Vec::new(),
            pc2: None,
            gltf: None,
            formats: None,
            weld_seams: None,
        }
    }
}

/// `camera = "front"` or `camera = { eye = [..], target = [..], fov_deg = 30 }`.
#[derive(Deserialize)]
#[serde(
    untagged,
    expecting = "camera takes a preset (\"front\", \"back\", \"side\", \"three-quarter\") or \
                 { eye = [x, y, z], target = [x, y, z], fov_deg = 30 } in m and degrees"
)]
pub(super) enum RawCamera {
    Preset(String),
    Custom {
        #[serde(deserialize_with = "exactly")]
        eye: [f64; 3],
        #[serde(deserialize_with = "exactly")]
        target: [f64; 3],
        #[serde(default = "default_fov")]
        fov_deg: f64,
    },
}

fn default_fov() -> f64 {
    30.0
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawPreview {
    pub(super) camera: Option<RawCamera>,
    pub(super) strain_max: Option<f64>,
    #[serde(default)]
    pub(super) seams: bool,
    #[serde(default = "default_preview_size")]
    pub(super) size: [i64; 2],
    pub(super) animation: Option<String>,
    #[serde(default = "default_animation_size")]
    pub(super) animation_size: [i64; 2],
    #[serde(default)]
    pub(super) colors: Vec<String>,
    pub(super) checker_m: Option<f64>,
    pub(super) texture: Option<String>,
    #[serde(default, deserialize_with = "exactly_if_given")]
    pub(super) texture_size_m: Option<[f64; 2]>,
}

impl Default for RawPreview {
    fn default() -> Self {
        RawPreview {
            camera: None,
            strain_max: None,
            seams: false,
            size: default_preview_size(),
            animation: None,
            animation_size: default_animation_size(),
            colors: Vec::new(),
            checker_m: None,
            texture: None,
            texture_size_m: None,
        }
    }
}

fn default_preview_size() -> [i64; 2] {
    [1280, 960]
}
/// Small enough that a GIF of a few dozen frames stays a few MB.
fn default_animation_size() -> [i64; 2] {
    [480, 360]
}
