//! `summary.json`, the run's report (the frame files are `export`'s).

use crate::sim::Settled;
use crate::solver::AdapterReport;
use serde::Serialize;

/// `summary.json`. Field names are stable: later versions add fields, never rename them.
#[derive(Clone, Debug, Serialize)]
pub struct Summary {
    /// The scene file, as an absolute path (its text is `scene.toml` in the output folder).
    pub scene: String,
    /// SHA-256 of the scene's text as the run read it (`scene.toml`), so that a preview can
    /// tell when that copy was edited afterwards.
    pub scene_sha256: String,
    /// Every file the run read, as absolute paths.
    pub inputs: crate::run_folder::Inputs,
    /// "cpu" or "gpu".
    pub backend: String,
    /// Why the backend differs from the one asked for, if it does.
    pub backend_note: Option<String>,
    /// The GPU adapter (name, driver, backend, device_type), or null on the CPU.
    pub adapter: Option<AdapterReport>,
    /// The CPU backend's rayon threads (`--threads`), or null on the GPU.
    pub cpu_threads: Option<usize>,
    /// Particles.
    pub particles: usize,
    /// Triangles.
    pub triangles: usize,
    /// Stretch springs.
    pub springs: usize,
    /// Bending hinges.
    pub hinges: usize,
    /// Output frames simulated.
    pub frames: u32,
    /// Output frames asked for.
    pub frames_requested: u32,
    /// Output frames per simulated second.
    pub fps: f32,
    /// Substeps per output frame.
    pub substeps_per_frame: u32,
    /// "auto" (from the stability estimate) or "scene".
    pub substeps_source: &'static str,
    /// Estimated largest stable substep in s.
    pub stable_dt_estimate_s: Option<f32>,
    /// What set the substep: "scene", "stretch", "seam", "bending", "damping" or "body speed".
    pub dt_limited_by: &'static str,
    /// Substep length in s.
    pub dt: f32,
    /// "explicit", "symplectic" or "implicit".
    pub integrator: &'static str,
    /// Vertex Block Descent sweeps per substep, the most with a tolerance (implicit only).
    pub iterations: Option<u32>,
    /// `[solver] tolerance`, if any (implicit only).
    pub tolerance: Option<f32>,
    /// Vertex Block Descent sweeps the solve ran per substep, on average (implicit only).
    pub iterations_mean: Option<f64>,
    /// Newton steps the solve ran per substep, on average (implicit with coarse levels):
    /// `iterations` without a tolerance, fewer with one.
    pub newton_steps_mean: Option<f64>,
    /// The particles of each level of the multigrid solve, the cloth's own first (implicit with
    /// coarse levels; null for plain Vertex Block Descent).
    pub multigrid_levels: Option<Vec<usize>>,
    /// Vertex colours, i.e. dispatches per sweep (implicit only).
    pub colors: Option<usize>,
    /// Largest relative residual over the last substep of every output frame (implicit only):
    /// the largest Newton step of the last sweep over that of the first sweep (steps under
    /// 1 µm count as 1 µm), i.e. how much of the step's correction the sweeps left undone.
    pub max_residual: Option<f32>,
    /// The force residual |fᵢ|/(mᵢ·g) of the free particles at the end of the last frame's
    /// solve, largest over particles (implicit only): how far from balanced the solved step
    /// left the forces, in units of each particle's weight (at contacts the body's normal
    /// reaction is left out).
    pub force_residual_max: Option<f32>,
    /// Its root mean square over the free particles.
    pub force_residual_rms: Option<f32>,
    /// Simulated time in s (with a coarse start, its frames too).
    pub simulated_seconds: f64,
    /// Wall time of stepping and readback in s (setup and file writing excluded; with a
    /// coarse start, all of its time too).
    pub wall_seconds: f64,
    /// Particles × substeps / wall time, of the full mesh's frames only.
    pub particle_substeps_per_second: f64,
    /// The coarse start the full mesh continued from (`None`: none).
    pub coarse_start: Option<crate::sim::CoarseStart>,
    /// The pass plan, by stage name.
    pub passes: Vec<&'static str>,
    /// Largest spring strain at any output frame.
    pub max_edge_strain: f32,
    /// Largest spring strain at the last frame (the result; sewing can strain more on the way).
    pub last_frame_max_edge_strain: f32,
    /// The 99th percentile of the spring strains at the last frame: what the cloth as a whole
    /// rests at, apart from the few most pinched edges.
    pub last_frame_edge_strain_p99: f32,
    /// With a membrane fabric: its thread strain (largest and 99th percentile) and shear angle
    /// (99th percentile, degrees) at the last frame. Edge strain includes shear, which a woven
    /// takes easily; thread strain is what stretches the yarns.
    #[serde(default)]
    pub last_frame_thread_strain: Option<crate::metrics::ThreadStrain>,
    /// The strain-limiting stage's cap on edge stretch (0.1 = 10%), or null when it is off.
    pub strain_limit: Option<f32>,
    /// With the cap on: the edges at it in the last frame (stretched to within 0.1% of the cap
    /// or past it), which the cap holds rather than the solve.
    pub strain_limit_clamped_edges: Option<usize>,
    /// Largest particle speed at any output frame, in m/s (from the `monitor` stage).
    pub max_speed_m_s: f32,
    /// Kinetic energy at the last good frame, in J.
    pub kinetic_energy_j: f64,
    /// Seams (stitches) in the pattern; 0 without one.
    pub seams: usize,
    /// Seams whose every pair gap is below the scene's `seam_closed_gap_m` at the last frame.
    pub seams_closed: usize,
    /// Largest seam pair gap at the last frame, in m (`null` without seams).
    pub max_seam_gap_m: Option<f32>,
    /// Largest pair gap of each seam (stitch order) at the last frame, in m.
    pub seam_gaps_m: Vec<f32>,
    /// The first output frame at which every seam was closed (after a coarse start, the coarse
    /// garment's).
    pub seams_closed_frame: Option<u32>,
    /// Collision bodies in the scene.
    pub bodies: usize,
    /// CPU contact strategy against the bodies (`null` without a body; the GPU uses the SDF;
    /// `mixed` where bodies use different ones).
    pub collision_strategy: Option<&'static str>,
    /// Whether cloth edges were also tested against some body's edges (CPU only).
    pub edge_contacts: Option<bool>,
    /// Deepest particle inside any body at any output frame, measured against the exact mesh.
    pub max_penetration_m: Option<f32>,
    /// Particles resting on a body at the last frame: outside it and within the collision
    /// thickness plus 1 mm of its exact surface.
    pub body_contacts: Option<usize>,
    /// Where a body shows through the cloth at the last frame (`null` without a body, or when
    /// the run stopped on an error).
    pub body_show_through: Option<crate::metrics::ShowThrough>,
    /// The (first) body's SDF: grid, bake time, memory, cache.
    pub sdf: Option<crate::body::sdf::BakeReport>,
    /// Every body's SDF, in scene order (empty without a body).
    pub body_sdfs: Vec<crate::body::sdf::BakeReport>,
    /// Fastest surface point of any body in m/s.
    pub body_surface_speed_m_s: Option<f32>,
    /// Body surface travel per substep in m; at most the thickness unless a warning says so.
    pub body_surface_step_m: Option<f32>,
    /// The (first) deforming body's motion: its source, timing and the deepest particle inside
    /// its exact deformed mesh at each output frame; null without one.
    pub body_motion: Option<crate::body::deform::MotionReport>,
    /// Particles held by `attach_labels` at the start.
    pub attached_particles: usize,
    /// The frame after which they were released.
    pub released_after_frame: Option<u32>,
    /// Whether every frame was finite.
    pub finite: bool,
    /// Set when the settle rule stopped the run early.
    pub settled: Option<Settled>,
    /// The settle rule's speed at the last frame (the free particles' RMS displacement over
    /// the frame, per second), in m/s, whether or not the scene has the rule.
    pub last_frame_rms_speed_m_s: Option<f64>,
    /// Warnings about the setup.
    pub warnings: Vec<String>,
    /// The error that stopped the run, if any.
    pub error: Option<String>,
    /// Files written, relative to the output folder.
    pub outputs: Vec<String>,
}

impl Summary {
    /// The fields (dotted paths) holding a non-finite number: see [`non_finite_fields`]. A
    /// run checks this before writing the summary.
    pub fn non_finite_fields(&self) -> Vec<String> {
        non_finite_fields(self)
    }
}

/// The fields (dotted paths) of `value` holding a non-finite number. JSON has no NaN:
/// serde_json writes one as `null`, which reads as "not applicable". The value goes through a
/// TOML value instead, which keeps NaN and infinities, so that every field is covered, also
/// ones added later.
pub fn non_finite_fields<T: Serialize>(value: &T) -> Vec<String> {
    fn walk(v: &toml::Value, at: &str, out: &mut Vec<String>) {
        match v {
            toml::Value::Float(x) if !x.is_finite() => out.push(at.to_string()),
            toml::Value::Array(items) => (items.iter().enumerate())
                .for_each(|(i, item)| walk(item, &format!("{at}[{i}]"), out)),
            toml::Value::Table(t) => t.iter().for_each(|(k, item)| {
                let path = if at.is_empty() {
                    k.clone()
                } else {
                    format!("{at}.{k}")
                };
                walk(item, &path, out)
            }),
            _ => {}
        }
    }
    let mut out = Vec::new();
    match toml::Value::try_from(value) {
        Ok(v) => walk(&v, "", &mut out),
        Err(e) => out.push(format!("(the values could not be checked: {e})")),
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Serialize)]
    struct Inner {
        speed: f64,
        gaps: Vec<f32>,
    }

    #[derive(Serialize)]
    struct Report {
        name: &'static str,
        step: Option<f32>,
        absent: Option<f32>,
        inner: Inner,
        bodies: Vec<Inner>,
    }

    #[test]
    fn every_non_finite_number_is_named_wherever_it_sits() {
        let report = Report {
            name: "x",
            step: Some(f32::NAN),
            absent: None,
            inner: Inner {
                speed: 1.0,
                gaps: vec![0.0, f32::INFINITY],
            },
            bodies: vec![Inner {
                speed: f64::NEG_INFINITY,
                gaps: vec![],
            }],
        };
        let mut found = non_finite_fields(&report);
        found.sort();
        assert_eq!(found, ["bodies[0].speed", "inner.gaps[1]", "step"]);
        // serde_json would have hidden all three as null.
        let json = serde_json::to_string(&report).unwrap();
        assert_eq!(json.matches("null").count(), 4, "{json}");
    }
}
