//! Rigid body motion from keyframes: translation interpolated linearly, rotation by slerp.
//! Velocities are those of the interpolation (constant within a segment).

use glam::{Quat, Vec3};

/// A body pose at a time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Keyframe {
    /// Time in s.
    pub time: f32,
    /// Translation of the body frame in m.
    pub translation: Vec3,
    /// Rotation of the body frame.
    pub rotation: Quat,
}

/// Where the body is and how it moves at one instant.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BodyState {
    /// Rotation, body to world.
    pub rotation: Quat,
    /// Translation, body to world, in m.
    pub translation: Vec3,
    /// Velocity of the body frame's origin in m/s.
    pub linear_velocity: Vec3,
    /// Angular velocity in rad/s (world frame).
    pub angular_velocity: Vec3,
}

impl BodyState {
    /// The body at rest at the origin.
    pub const REST: BodyState = BodyState {
        rotation: Quat::IDENTITY,
        translation: Vec3::ZERO,
        linear_velocity: Vec3::ZERO,
        angular_velocity: Vec3::ZERO,
    };
}

/// Keyframed rigid motion; before the first and after the last keyframe the body holds still.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Motion {
    /// Keyframes sorted by time.
    pub keys: Vec<Keyframe>,
}

impl Motion {
    /// "Turn right, then left": rotate about the vertical axis to −`angle_deg` (right, seen from
    /// above) over `period` s, over to +`angle_deg` over 2·`period`, and back over `period`.
    pub fn turn_right_left(angle_deg: f32, period: f32, start: f32) -> Motion {
        let yaw = |deg: f32| Quat::from_rotation_y(deg.to_radians());
        let key = |time: f32, deg: f32| Keyframe {
            time,
            translation: Vec3::ZERO,
            rotation: yaw(deg),
        };
        Motion {
            keys: vec![
                key(start, 0.0),
                key(start + period, -angle_deg),
                key(start + 2.0 * period, 0.0),
                key(start + 3.0 * period, angle_deg),
                key(start + 4.0 * period, 0.0),
            ],
        }
    }

    /// Whether the body ever changes pose (keyframes that all agree hold it still).
    pub fn moves(&self) -> bool {
        (self.keys.windows(2))
            .any(|w| w[0].rotation != w[1].rotation || w[0].translation != w[1].translation)
    }

    /// The body's pose and velocity at time `t`.
    pub fn at(&self, t: f32) -> BodyState {
        let Some(first) = self.keys.first() else {
            return BodyState::REST;
        };
        let hold = |k: &Keyframe| BodyState {
            rotation: k.rotation,
            translation: k.translation,
            linear_velocity: Vec3::ZERO,
            angular_velocity: Vec3::ZERO,
        };
        if t <= first.time {
            return hold(first);
        }
        // The first key after t (keys are sorted): t lies in the segment that ends there.
        let next = self.keys.partition_point(|k| k.time <= t);
        let (Some(a), Some(b)) = (self.keys.get(next.wrapping_sub(1)), self.keys.get(next)) else {
            return hold(self.keys.last().unwrap_or(first));
        };
        let span = b.time - a.time;
        let f = (t - a.time) / span;
        // Shortest-arc rotation from a to b, as an angular velocity over the segment.
        let mut delta = b.rotation * a.rotation.inverse();
        if delta.w < 0.0 {
            delta = -delta;
        }
        let (axis, angle) = delta.to_axis_angle();
        BodyState {
            rotation: a.rotation.slerp(b.rotation, f),
            translation: a.translation.lerp(b.translation, f),
            linear_velocity: (b.translation - a.translation) / span,
            angular_velocity: axis * angle / span,
        }
    }

    /// The fastest speed of any of `points` (body frame) over all segments, at most |v| + |ω|·r
    /// with r a point's distance from the rotation axis through the body origin. Within a
    /// segment the axis is fixed in the world and the body turns about it, so each point's
    /// distance from it is that of the segment's midpoint pose (a turning mannequin's head,
    /// on the axis, does not move; its hands do).
    pub fn max_surface_speed(&self, points: &[Vec3]) -> f32 {
        self.keys
            .windows(2)
            .map(|w| {
                let s = self.at(0.5 * (w[0].time + w[1].time));
                let axis = s.angular_velocity.normalize_or_zero();
                let reach = (points.iter())
                    .map(|p| axis.cross(s.rotation * *p).length())
                    .fold(0.0, f32::max);
                s.linear_velocity.length() + s.angular_velocity.length() * reach
            })
            .fold(0.0, f32::max)
    }
}
