//! The collision bodies as a run sees them: how fast their surfaces move (which bounds the
//! substep), and their SDF grids, contact response and poses as the kernels read them.

use super::SEWING_SLIP_SPEED;
use crate::body::motion::BodyState;
use crate::model::layout::{BodyParams, BodyPose, MAX_BODIES};
use crate::model::ClothModel;
use crate::scene::{BodySettings, Scene};

/// Tunnelling: no body surface point may move more than its body's thickness in one substep.
/// Returns the substeps (raised to what the fastest body needs when `auto`), the fastest
/// surface speed in m/s, and whether body speed raised the substeps; with a fixed count too
/// small, warns instead.
pub(super) fn body_speed_substeps(
    model: &ClothModel,
    scene: &Scene,
    frame_dt: f32,
    substeps: u32,
    auto: bool,
    warnings: &mut Vec<String>,
) -> (u32, f32, bool) {
    let (mut substeps, mut fastest, mut raised) = (substeps, 0.0f32, false);
    for (i, (c, settings)) in model.colliders.iter().zip(&scene.bodies).enumerate() {
        let speed = c.motion.max_surface_speed(&c.body.mesh.positions);
        fastest = fastest.max(speed);
        let thickness = settings.thickness;
        let needed = (speed * frame_dt / thickness).ceil() as u32;
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
    (substeps, fastest, raised)
}

/// Each body's SDF grid (its nodes one after another in the SDF texture, in scene order) and
/// contact response; friction's slip speed is `SEWING_SLIP_SPEED` while `sewing`.
pub(super) fn body_params(
    model: &ClothModel,
    bodies: &[BodySettings],
    sewing: bool,
) -> [BodyParams; MAX_BODIES] {
    let mut out = [BodyParams::default(); MAX_BODIES];
    let mut first_node = 0u32;
    for ((p, c), b) in out.iter_mut().zip(&model.colliders).zip(bodies) {
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
            ..Default::default()
        };
        first_node += g.values.len() as u32;
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
