//! The mannequin's built-in motions, as clips over its rig (`rig::skeleton`): the thesis's turn
//! right then left, the arms lowering from the A-pose, walking in place with the arms lowered,
//! and the arms rising.
//!
//! Every joint of the rig is bound with its frame parallel to the world's (+y up, facing +z,
//! the model's left at +x), so a local rotation about x swings a limb forwards or backwards
//! and one about z opens or closes it sideways.

use super::skin::{Channel, Clip, Interpolation, Skeleton, Values};
use glam::Quat;
use std::f32::consts::TAU;

/// The motions' names, as scenes give them.
pub const NAMES: [&str; 4] = ["turn-right-left", "arms-down", "walk", "arms-up"];

/// How far "arms-down" lowers each upper arm from the A-pose's 45° to the vertical, in degrees:
/// 35° leaves the arms 10° out, where the wrists clear the hips by about 2.5 cm.
pub const ARMS_DOWN_DEG: f32 = 35.0;

/// Keys per second of the sampled (smooth) motions.
const KEY_RATE: f32 = 30.0;

/// One walking step's length in s (a step of each leg makes a cycle).
pub const WALK_CYCLE_S: f32 = 1.2;

/// Cycles in the walk clip.
const WALK_CYCLES: u32 = 2;

/// Every built-in motion over `skeleton` (the mannequin's rig).
pub fn built_in(skeleton: &Skeleton) -> Vec<Clip> {
    vec![
        turn_right_left(skeleton),
        arms_down(skeleton),
        walk(skeleton),
        arms_up(skeleton),
    ]
}

fn joint(s: &Skeleton, name: &str) -> usize {
    s.joint(name)
        .unwrap_or_else(|| panic!("the mannequin's rig has joint {name}"))
}

fn rotation_channel(joint: usize, times: Vec<f32>, rotations: Vec<Quat>) -> Channel {
    Channel {
        joint,
        times,
        values: Values::Rotation(rotations),
        interpolation: Interpolation::Linear,
    }
}

/// A channel keyed every 1/`KEY_RATE` s over `duration` s from `f(t)`.
fn sampled(joint: usize, duration: f32, f: impl Fn(f32) -> Quat) -> Channel {
    let keys = (duration * KEY_RATE).round() as usize;
    let times: Vec<f32> = (0..=keys)
        .map(|k| k as f32 / keys as f32 * duration)
        .collect();
    let rotations = times.iter().map(|&t| f(t)).collect();
    rotation_channel(joint, times, rotations)
}

/// Smooth from 0 to 1 over [0, 1] with zero slope at both ends.
fn ease(s: f32) -> f32 {
    let s = s.clamp(0.0, 1.0);
    s * s * (3.0 - 2.0 * s)
}

/// The thesis's turn: the whole body about the vertical through the hips, to 60° right over
/// 1 s, over to 60° left over 2 s and back over 1 s (as the rigid "turn-right-left").
fn turn_right_left(s: &Skeleton) -> Clip {
    let yaw = |deg: f32| Quat::from_rotation_y(deg.to_radians());
    let times = vec![0.0, 1.0, 2.0, 3.0, 4.0];
    let rotations = [0.0, -60.0, 0.0, 60.0, 0.0].map(yaw).to_vec();
    Clip {
        name: "turn-right-left".into(),
        channels: vec![rotation_channel(joint(s, "hips"), times, rotations)],
    }
}

/// Each upper arm's rotation that lowers it by `deg` from the A-pose (the left arm at +x turns
/// clockwise about +z, the right one counter-clockwise).
fn lower(side: f32, deg: f32) -> Quat {
    Quat::from_rotation_z(-side * deg.to_radians())
}

/// The arms from the A-pose down to 10° from the body over 1.5 s: what a garment sewn in the
/// A-pose needs before the body moves on.
fn arms_down(s: &Skeleton) -> Clip {
    let duration = 1.5;
    let arm = |name: &str, side: f32| {
        sampled(joint(s, name), duration, move |t| {
            lower(side, ARMS_DOWN_DEG * ease(t / duration))
        })
    };
    Clip {
        name: "arms-down".into(),
        channels: vec![arm("upper_arm.L", 1.0), arm("upper_arm.R", -1.0)],
    }
}

/// The arms from the A-pose up to 35° above the horizontal over 2 s.
fn arms_up(s: &Skeleton) -> Clip {
    let duration = 2.0;
    let raise = 80.0;
    let arm = |name: &str, side: f32| {
        sampled(joint(s, name), duration, move |t| {
            lower(side, -raise * ease(t / duration))
        })
    };
    Clip {
        name: "arms-up".into(),
        channels: vec![arm("upper_arm.L", 1.0), arm("upper_arm.R", -1.0)],
    }
}

/// Walking in place with the arms lowered: each leg in turn lifts (the thigh forward by up to
/// 40°, the knee bent by up to 70°) while the opposite arm swings forward by up to 18° and the
/// elbows bend a little with it; `WALK_CYCLES` cycles of `WALK_CYCLE_S`, ending as it starts so
/// that it can repeat.
fn walk(s: &Skeleton) -> Clip {
    let duration = WALK_CYCLE_S * WALK_CYCLES as f32;
    let phase = |t: f32| TAU * t / WALK_CYCLE_S;
    // Each leg's lift over the cycle: sin² over its half, 0 over the other (smooth at both ends).
    let lift = |t: f32, side: f32| (side * phase(t).sin()).max(0.0).powi(2);
    let about_x = |deg: f32| Quat::from_rotation_x(deg.to_radians());
    let mut channels = Vec::new();
    for (suffix, side) in [("L", 1.0f32), ("R", -1.0)] {
        let name = |part: &str| format!("{part}.{suffix}");
        // Forward is −x rotation (a limb hanging down swings towards +z).
        channels.push(sampled(joint(s, &name("thigh")), duration, move |t| {
            about_x(-40.0 * lift(t, side))
        }));
        channels.push(sampled(joint(s, &name("shin")), duration, move |t| {
            about_x(70.0 * lift(t, side))
        }));
        // The arm swings with the opposite leg.
        channels.push(sampled(joint(s, &name("upper_arm")), duration, move |t| {
            let swing = 18.0 * (lift(t, -side) - lift(t, side));
            about_x(-swing) * lower(side, ARMS_DOWN_DEG)
        }));
        channels.push(sampled(joint(s, &name("forearm")), duration, move |t| {
            about_x(-15.0 * lift(t, -side))
        }));
    }
    Clip {
        name: "walk".into(),
        channels,
    }
}
