//! What a run measured, frame by frame: the statistics a summary and a checkpoint hold.

use super::{CoarseStart, Settled};
use serde::{Deserialize, Serialize};
use std::fmt::Write;

/// What a run measured, filled in frame by frame (so it is complete up to a failure). A
/// checkpoint stores it, so a resumed run reports what the uninterrupted one would.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct RunStats {
    /// Frames simulated.
    pub frames_run: u32,
    /// Seconds spent in `advance` and readback (not in writing files).
    pub wall_seconds: f64,
    /// Largest spring strain seen at any output frame.
    pub max_edge_strain: f32,
    /// Kinetic energy at the last good frame, in J.
    pub kinetic_energy_j: f64,
    /// Whether every frame was finite.
    pub finite: bool,
    /// Set when the settle rule stopped the run.
    pub settled: Option<Settled>,
    /// Largest pair gap per seam at the last good frame, in m (empty without seams).
    pub seam_gaps: Vec<f32>,
    /// The first output frame at which every seam was closed.
    pub seams_closed_frame: Option<u32>,
    /// The frame after which attached particles were released.
    pub released_after_frame: Option<u32>,
    /// Deepest particle inside the body at any output frame, against the exact mesh, in m.
    pub max_penetration_m: f32,
    /// Particles resting on the body at the last good frame (see `CONTACT_SLACK`).
    pub body_contacts: usize,
    /// Largest relative residual of the implicit solve at any output frame.
    pub max_residual: Option<f32>,
    /// Iterations the implicit solve ran, over every substep.
    #[serde(default)]
    pub iterations_run: u64,
    /// Newton steps the implicit solve ran, over every substep.
    #[serde(default)]
    pub newton_steps_run: u64,
    /// With the strain-limiting stage on: the edges at its cap (stretched to within 0.1% of it
    /// or past it) at the last frame, which the cap, not the solve, holds.
    #[serde(default)]
    pub strain_limit_clamped_edges: Option<usize>,
    /// The implicit solve's force residual |f|/(m·g) at the end of the last frame's last
    /// substep: largest and RMS over the free particles.
    #[serde(default)]
    pub force_residual: Option<(f32, f32)>,
    /// Largest spring strain at the last good frame.
    pub last_edge_strain: f32,
    /// The 99th percentile of the springs' strain at the last good frame.
    #[serde(default)]
    pub last_edge_strain_p99: f32,
    /// A membrane's thread strain and shear at the last good frame.
    #[serde(default)]
    pub last_thread_strain: Option<crate::metrics::ThreadStrain>,
    /// Largest particle speed at any output frame, in m/s.
    pub max_speed: f32,
    /// The last frame's mechanical energy (kinetic + gravitational + elastic) and its kinetic
    /// plus elastic part, in J, for the energy-growth check.
    #[serde(default)]
    pub energy: Option<(f64, f64)>,
    /// The settle rule's speed at the last frame (see `frame_speed`), in m/s; `None` before
    /// the first simulated frame.
    #[serde(default)]
    pub frame_speed_m_s: Option<f64>,
    /// The coarse start this run continued from, if any.
    #[serde(default)]
    pub coarse_start: Option<CoarseStart>,
    /// With a deforming body: at each output frame (its number), the deepest particle inside
    /// the exact deformed mesh, in m.
    #[serde(default)]
    pub deformed_penetration_m: Vec<(u32, f32)>,
    /// Each simulated frame's settle figures, a coarse start's first (`frames.csv`).
    #[serde(default)]
    pub frames: Vec<FrameRecord>,
}

/// One simulated frame's figures: what the settle rule reads, and what holds the cloth.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FrameRecord {
    /// The output frame.
    pub frame: u32,
    /// The mesh's particles (a coarse start's frames have fewer).
    pub particles: usize,
    /// The free particles' RMS speed over the frame (`frame_speed`), in m/s.
    pub rms_speed_m_s: f64,
    /// With implicit Euler, the force residual |f|/(m·g) at the frame's end: largest and RMS.
    pub force_residual: Option<(f32, f32)>,
    /// The largest spring strain.
    pub max_edge_strain: f32,
    /// The widest seam gap, in m (0 without seams).
    pub max_seam_gap_m: f32,
    /// Particles resting on a body.
    pub body_contacts: usize,
}

impl RunStats {
    /// The widest seam gap at the last good frame, in m (`None` without seams).
    pub fn widest_seam_gap(&self) -> Option<f32> {
        self.seam_gaps.iter().copied().reduce(f32::max)
    }

    /// Records frame `frame` of a mesh of `particles`, with the frame's RMS speed and largest
    /// strain and the figures this frame has set (`frames.csv`'s row).
    pub fn record_frame(&mut self, frame: u32, particles: usize, speed: f64, strain: f32) {
        self.frames.push(FrameRecord {
            frame,
            particles,
            rms_speed_m_s: speed,
            force_residual: self.force_residual,
            max_edge_strain: strain,
            max_seam_gap_m: self.widest_seam_gap().unwrap_or(0.0),
            body_contacts: self.body_contacts,
        });
    }

    /// `frames` as CSV, a header first; a figure the run does not have is left empty.
    pub fn frames_csv(&self) -> String {
        let mut csv = String::from(
            "frame,particles,rms_speed_m_s,force_residual_max,force_residual_rms,\
             max_edge_strain,max_seam_gap_m,body_contacts\n",
        );
        for r in &self.frames {
            let (largest, rms) = match r.force_residual {
                Some((largest, rms)) => (largest.to_string(), rms.to_string()),
                None => (String::new(), String::new()),
            };
            // Writing to a String cannot fail.
            let _ = writeln!(
                csv,
                "{},{},{},{largest},{rms},{},{},{}",
                r.frame,
                r.particles,
                r.rms_speed_m_s,
                r.max_edge_strain,
                r.max_seam_gap_m,
                r.body_contacts
            );
        }
        csv
    }
}
