//! The collision bodies as a run sees them: how fast their surfaces move (which bounds the
//! substep), and their SDF grids, contact response and poses as the kernels read them.

use super::SEWING_SLIP_SPEED;
use crate::body::motion::BodyState;
use crate::body::Collider;
use crate::error::InputError;
use crate::model::layout::{BodyParams, BodyPose, MAX_BODIES, MAX_PARTS};
use crate::model::ClothModel;
use crate::scene::{BodySettings, DeformMotion, Scene};

/// Tunnelling: no body surface point may move more than its body's thickness in one substep.
/// Returns the substeps (raised to what the fastest body needs when `auto`), the fastest
/// surface speed in m/s, and whether body speed raised the substeps; with a fixed count too
/// small, warns instead. A body that would need more than `max_substeps_per_frame` is refused.
pub(super) fn body_speed_substeps(
    model: &ClothModel,
    scene: &Scene,
    frame_dt: f32,
    substeps: u32,
    auto: bool,
    warnings: &mut Vec<String>,
) -> Result<(u32, f32, bool), InputError> {
    let (mut substeps, mut fastest, mut raised) = (substeps, 0.0f32, false);
    for (i, (c, settings)) in model.colliders.iter().zip(&scene.bodies).enumerate() {
        let speed = surface_speed(c);
        fastest = fastest.max(speed);
        let thickness = settings.thickness;
        let needed = (speed * frame_dt / thickness).ceil();
        let most = scene.solver.max_substeps_per_frame;
        if auto && (needed.is_nan() || needed > most as f32) {
            return Err(scene.error(
                &scene.body_table(i),
                motion_key(settings),
                format!(
                    "its surface moves up to {speed:.3e} m/s: to move at most its thickness \
                     ({thickness:.2e} m) a substep it needs {needed:.3e} substeps a frame, above \
                     solver.max_substeps_per_frame = {most}"
                ),
                "check the motion's units and timing (a cache's fps, keyframe times), or raise \
                 thickness_m or solver.max_substeps_per_frame",
            ));
        }
        let needed = needed as u32;
        if needed > substeps {
            if auto {
                substeps = needed;
                raised = true;
            } else {
                warnings.push(format!(
                    "{}: its surface moves up to {:.2e} m per substep, more than the \
                     thickness {thickness:.2e} m: particles may tunnel (use substeps = {needed} \
                     or \"auto\")",
                    scene.body_table(i),
                    speed * frame_dt / substeps as f32
                ));
            }
        }
    }
    Ok((substeps, fastest, raised))
}

/// The scene key that moves body `settings`, for errors about its motion: a rigid body's
/// comes from `motion` or from `[[body.keyframes]]`, which the settings do not tell apart, so
/// the error names its table alone.
fn motion_key(settings: &BodySettings) -> &'static str {
    match settings.deform.as_ref().map(|d| &d.motion) {
        Some(DeformMotion::Cache { .. }) => "cache",
        Some(DeformMotion::Skin { .. }) => "animation",
        None => "",
    }
}

/// The fastest any point of the body's surface moves, in m/s: for a deforming body, the faster
/// of its vertices (sampled from the skin or the cache) and of its collision parts' surfaces
/// (what collision sees).
pub(super) fn surface_speed(c: &Collider) -> f32 {
    match &c.deformed {
        Some(d) => {
            let d = &d.deformation;
            d.max_vertex_speed().max(d.max_part_speed())
        }
        None => c.motion.max_surface_speed(&c.body.mesh.positions),
    }
}

/// Each body's SDF grid (its nodes one after another in the SDF texture, in scene order) and
/// contact response; friction's slip speed is `SEWING_SLIP_SPEED` while `sewing`. A deforming
/// body's parts follow the earlier deforming bodies' in `SubstepParams::parts`.
pub(super) fn body_params(
    model: &ClothModel,
    bodies: &[BodySettings],
    sewing: bool,
) -> [BodyParams; MAX_BODIES] {
    let mut out = [BodyParams::default(); MAX_BODIES];
    let mut first_node = 0u32;
    let mut first_part = 0u32;
    for ((p, c), b) in out.iter_mut().zip(&model.colliders).zip(bodies) {
        let parts = c.deformed.as_ref().map_or(0, |d| d.parts as u32);
        let g = &c.sdf;
        *p = BodyParams {
            sdf_origin: g.origin.extend(g.cell).to_array(),
            sdf_dims: [g.dims[0], g.dims[1], g.dims[2], first_node],
            thickness: b.thickness,
            friction: b.friction,
            normal_loss: b.normal_loss,
            tangential_loss: b.tangential_loss,
            friction_slip_speed: if sewing {
                SEWING_SLIP_SPEED
            } else {
                b.friction_slip_speed
            },
            parts,
            first_part,
            ..Default::default()
        };
        first_node += g.values.len() as u32;
        first_part += parts;
    }
    out
}

/// The deforming bodies' collision parts' poses at time `t`, body after body.
pub fn part_poses(model: &ClothModel, t: f32) -> [BodyPose; MAX_PARTS] {
    let mut out = [BodyPose::default(); MAX_PARTS];
    let states = (model.colliders.iter())
        .filter_map(|c| c.deformed.as_ref())
        .flat_map(|d| d.deformation.part_states(t));
    for (pose, state) in out.iter_mut().zip(states) {
        *pose = body_pose(&state);
    }
    out
}

/// A body's pose as the kernels read it.
pub fn body_pose(body: &BodyState) -> BodyPose {
    let r = glam::Mat3::from_quat(body.rotation);
    BodyPose {
        x: r.x_axis.extend(0.0).to_array(),
        y: r.y_axis.extend(0.0).to_array(),
        z: r.z_axis.extend(0.0).to_array(),
        translation: body.translation.extend(0.0).to_array(),
        velocity: body.linear_velocity.extend(0.0).to_array(),
        angular_velocity: body.angular_velocity.extend(0.0).to_array(),
    }
}
