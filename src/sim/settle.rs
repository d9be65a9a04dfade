//! The settle rule: a run stops once its cloth has come to rest, judged by how far the free
//! particles moved over the last frame.

use super::{Prepared, RunStats};
use glam::Vec4;
use serde::{Deserialize, Serialize};

/// Why a run ended early.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Settled {
    /// The frame at which the rule fired.
    pub frame: u32,
    /// Which rule fired.
    pub rule: String,
    /// The free particles' RMS speed then, in m/s.
    pub rms_speed_m_s: f64,
    /// With implicit Euler, the RMS force residual |f|/(m·g) then.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub force_residual_rms: Option<f32>,
}

/// The free particles' mass-weighted RMS displacement over the frame, per second:
/// √(Σ mᵢ|Δxᵢ|² / Σ mᵢ) / frame length. Over a whole frame, not the last substep's velocity:
/// on cloth at rest that velocity is mostly the sweeps' jitter (a 3 cm shirt at rest: 7.8 mm/s
/// from the velocities, 4.1 mm/s over a frame, 1.1 mm/s over a second).
pub(super) fn frame_speed(prep: &Prepared, before: &[Vec4], after: &[Vec4]) -> f64 {
    let model = &prep.model;
    let sum: f64 = (before.iter().zip(after))
        .zip(model.masses.iter().zip(&model.pinned))
        .filter(|(_, (_, pinned))| !**pinned)
        .map(|((a, b), (m, _))| *m as f64 * (b.truncate() - a.truncate()).length_squared() as f64)
        .sum();
    (sum / prep.free_mass.max(f64::MIN_POSITIVE)).sqrt() / prep.frame_dt as f64
}

/// Whether frame `frame` settles the run: the scene has the rule, gravity is on, attachments
/// are released (a cloth at rest while still being sewn or held has not settled), the frame's
/// speed is under the threshold and, with implicit Euler, so is its solve's force residual: a
/// cloth that stopped moving because the solve stopped carrying load to where it belongs has
/// not settled. A run continued from a coarse start has no speed until the full mesh has run a
/// frame.
pub(super) fn check(prep: &Prepared, stats: &RunStats, frame: u32) -> Option<Settled> {
    let loaded = frame > prep.gravity.1 && frame > prep.attach_frames;
    let threshold = prep.settle_speed? as f64;
    let rms_speed = stats.frame_speed_m_s?;
    let balanced = match (prep.settle_force_residual, stats.force_residual) {
        (Some(limit), Some((_, rms))) => rms <= limit,
        (Some(_), None) => false,
        (None, _) => true,
    };
    (loaded && rms_speed < threshold && balanced).then(|| Settled {
        frame,
        rule: match prep.settle_force_residual {
            Some(_) => "rms_speed and force_residual".into(),
            None => "rms_speed".into(),
        },
        rms_speed_m_s: rms_speed,
        force_residual_rms: prep
            .settle_force_residual
            .and(stats.force_residual.map(|r| r.1)),
    })
}
