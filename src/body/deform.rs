//! A deforming body over time: its rest pose (where garments are sewn), the transition from the
//! rest pose into the motion's first frame, and the motion itself (a skinned clip or a vertex
//! cache), repeated as the scene asks. It gives the exact deformed mesh at any time, and the
//! rigid poses of the parts that collision bends the body with.

use super::cache::VertexCache;
use super::fit::PartFit;
use super::motion::{BodyState, Keyframe, Motion};
use super::skin::{Clip, Influence, Skeleton, SkinnedMesh, Trs};
use glam::{Mat4, Quat, Vec3};
use rayon::prelude::*;

/// Most parts a deforming body's collision may use (`MAX_PARTS` in common.wgsl): every
/// substep's uniform carries each part's pose.
pub const MAX_PARTS: usize = 24;

/// Keys per second of the parts' rigid motions: between keys a part turns at a constant rate,
/// so a joint 1 m from the origin turning at 6 rad/s strays 1 m × (6/120)²/8 = 0.3 mm from its
/// path, a tenth of the usual collision thickness.
const PART_KEY_RATE: f32 = 120.0;

/// Samples per second of the exact mesh for the fastest surface point's speed.
const SPEED_SAMPLE_RATE: f32 = 60.0;

/// When the motion plays.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Timeline {
    /// The rest pose holds until this time, in s (garments are sewn meanwhile).
    pub start: f32,
    /// Seconds over which the body blends from the rest pose into the motion's first frame.
    pub transition: f32,
    /// How many times the motion plays (its last frame holds afterwards).
    pub plays: u32,
}

/// Where the motion comes from.
#[derive(Clone, Debug, PartialEq)]
pub enum Source {
    /// A skinned mesh and one of its clips.
    Skin {
        /// The mesh, skeleton and clips.
        mesh: SkinnedMesh,
        /// Which clip plays.
        clip: usize,
    },
    /// A vertex cache over the rest mesh's vertices, and the parts fitted to it.
    Cache {
        /// The frames, in welded vertex order.
        cache: VertexCache,
        /// The parts collision uses.
        fit: PartFit,
    },
}

/// A deforming body.
#[derive(Clone, Debug, PartialEq)]
pub struct Deformation {
    /// The rest pose's vertices, m (the body mesh's positions).
    pub rest: Vec<Vec3>,
    /// The motion.
    pub source: Source,
    /// When it plays.
    pub timeline: Timeline,
    /// What the summary calls the motion's source (a file and animation, or a built-in motion).
    pub description: String,
    /// Each vertex's weights over the collision parts.
    pub part_influences: Vec<Influence>,
    /// Each collision part's rigid motion (rest to world), keyed at `PART_KEY_RATE`.
    pub part_motions: Vec<Motion>,
    /// The skin's joint behind each part (empty for a cache).
    pub part_joints: Vec<usize>,
}

/// The longest timeline (transition and every play) a deforming body may have, in s: collision
/// keys each part's motion `PART_KEY_RATE` times a second over all of it, and no garment run
/// simulates an hour.
pub const MAX_MOTION_S: f32 = 3600.0;

impl Timeline {
    /// Whether the transition and `plays` plays of a motion `length` s long fit in
    /// `MAX_MOTION_S`: `Err` with their total otherwise.
    pub fn fits(&self, length: f32) -> Result<(), f32> {
        let total = self.transition + length * self.plays as f32;
        if total <= MAX_MOTION_S {
            Ok(())
        } else {
            Err(total)
        }
    }
}

/// Smooth from 0 to 1 over [0, 1] with zero slope at both ends: the transition's blend.
fn ease(s: f32) -> f32 {
    let s = s.clamp(0.0, 1.0);
    s * s * (3.0 - 2.0 * s)
}

impl Deformation {
    /// A skinned body playing `clip` of `mesh` on `timeline`.
    pub fn skinned(
        mesh: SkinnedMesh,
        clip: usize,
        timeline: Timeline,
        description: String,
    ) -> Self {
        let (part_joints, part_influences) = joint_parts(&mesh);
        let mut d = Deformation {
            rest: mesh.mesh.positions.clone(),
            source: Source::Skin { mesh, clip },
            timeline,
            description,
            part_influences,
            part_motions: Vec::new(),
            part_joints,
        };
        d.part_motions = d.key_parts();
        d
    }

    /// A body moved by `cache` (frames over the `rest` vertices), its parts fitted already.
    pub fn cached(
        rest: Vec<Vec3>,
        cache: VertexCache,
        fit: PartFit,
        timeline: Timeline,
        description: String,
    ) -> Self {
        let part_influences = fit.influences.clone();
        let mut d = Deformation {
            rest,
            source: Source::Cache { cache, fit },
            timeline,
            description,
            part_influences,
            part_motions: Vec::new(),
            part_joints: Vec::new(),
        };
        d.part_motions = d.key_parts();
        d
    }

    /// One play of the motion, in s.
    pub fn motion_length(&self) -> f32 {
        match &self.source {
            Source::Skin { mesh, clip } => {
                let c = &mesh.clips[*clip];
                c.duration() - c.start()
            }
            Source::Cache { cache, .. } => cache.duration(),
        }
    }

    /// When the last play ends, in s.
    pub fn end(&self) -> f32 {
        let t = &self.timeline;
        t.start + t.transition + self.motion_length() * t.plays as f32
    }

    /// Where on the timeline `t` falls: `Err(s)` in the rest pose or the transition (s from 0
    /// to 1), `Ok(τ)` at τ s into one play of the motion.
    fn phase(&self, t: f32) -> Result<f32, f32> {
        let tl = &self.timeline;
        if t < tl.start + tl.transition {
            let s = if tl.transition > 0.0 {
                (t - tl.start) / tl.transition
            } else {
                0.0
            };
            return Err(ease(s));
        }
        let length = self.motion_length();
        let tau = t - tl.start - tl.transition;
        if length <= 0.0 || tau >= length * tl.plays as f32 {
            return Ok(length);
        }
        Ok(tau % length)
    }

    /// The skin's joints' local transforms at `t`.
    fn locals(&self, mesh: &SkinnedMesh, clip: &Clip, t: f32) -> Vec<Trs> {
        let bind = mesh.skeleton.bind_locals();
        match self.phase(t) {
            Err(s) => {
                let first = clip.pose(&mesh.skeleton, clip.start());
                (bind.iter().zip(&first))
                    .map(|(a, b)| a.lerp(b, s))
                    .collect()
            }
            Ok(tau) => clip.pose(&mesh.skeleton, clip.start() + tau),
        }
    }

    /// The exact deformed mesh's vertices at time `t`.
    pub fn positions_at(&self, t: f32) -> Vec<Vec3> {
        match &self.source {
            Source::Skin { mesh, clip } => mesh.posed(&self.locals(mesh, &mesh.clips[*clip], t)),
            Source::Cache { cache, .. } => match self.phase(t) {
                Err(s) => (self.rest.iter().zip(&cache.frames[0]))
                    .map(|(a, b)| a.lerp(*b, s))
                    .collect(),
                Ok(tau) => cache.at(tau),
            },
        }
    }

    /// Each part's rigid pose (rest to world) at `t`, straight from the source.
    fn part_poses(&self, t: f32) -> Vec<(Quat, Vec3)> {
        match &self.source {
            Source::Skin { mesh, clip } => {
                let m = mesh
                    .skeleton
                    .skinning(&self.locals(mesh, &mesh.clips[*clip], t));
                self.part_joints.iter().map(|&j| rigid(m[j])).collect()
            }
            Source::Cache { cache, fit } => {
                let at = |poses: &[(Quat, Vec3)], tau: f32| {
                    let times = &cache.times;
                    let last = times.len() - 1;
                    if tau >= times[last] {
                        return poses[last];
                    }
                    let k = times.partition_point(|&s| s <= tau).max(1) - 1;
                    let s = ((tau - times[k]) / (times[k + 1] - times[k])).clamp(0.0, 1.0);
                    (
                        poses[k].0.slerp(poses[k + 1].0, s),
                        poses[k].1.lerp(poses[k + 1].1, s),
                    )
                };
                (fit.poses.iter())
                    .map(|p| match self.phase(t) {
                        Err(s) => (Quat::IDENTITY.slerp(p[0].0, s), p[0].1 * s),
                        Ok(tau) => at(p, tau),
                    })
                    .collect()
            }
        }
    }

    /// Each part's rigid motion over the whole timeline, keyed at `PART_KEY_RATE` (and at the
    /// start and end of the transition and of the motion).
    fn key_parts(&self) -> Vec<Motion> {
        let tl = &self.timeline;
        let (from, to) = (tl.start, self.end());
        let keys = ((to - from) * PART_KEY_RATE).ceil().max(1.0) as usize;
        let mut times: Vec<f32> = (0..=keys)
            .map(|k| from + (to - from) * k as f32 / keys as f32)
            .collect();
        times.push(tl.start + tl.transition);
        times.sort_by(f32::total_cmp);
        times.dedup_by(|a, b| (*a - *b).abs() < 1e-6);
        let poses: Vec<Vec<(Quat, Vec3)>> = times.iter().map(|&t| self.part_poses(t)).collect();
        (0..self.part_influences_parts())
            .map(|p| {
                let mut keys: Vec<Keyframe> = (times.iter().zip(&poses))
                    .map(|(&time, pose)| Keyframe {
                        time,
                        rotation: pose[p].0,
                        translation: pose[p].1,
                    })
                    .collect();
                // Keep consecutive keys on the same side so that slerp takes the short way.
                for k in 1..keys.len() {
                    if keys[k].rotation.dot(keys[k - 1].rotation) < 0.0 {
                        keys[k].rotation = -keys[k].rotation;
                    }
                }
                Motion { keys }
            })
            .collect()
    }

    /// Where the speed estimates stop: the end of the second play (later plays repeat it, the
    /// step from one play's end to the next's start included), or of the timeline if sooner.
    fn speed_scan_end(&self) -> f32 {
        let tl = &self.timeline;
        self.end()
            .min(tl.start + tl.transition + 2.0 * self.motion_length())
    }

    /// How many collision parts.
    pub fn part_count(&self) -> usize {
        self.part_influences_parts()
    }

    fn part_influences_parts(&self) -> usize {
        match &self.source {
            Source::Skin { .. } => self.part_joints.len(),
            Source::Cache { fit, .. } => fit.poses.len(),
        }
    }

    /// Each part's pose and velocity at `t`, as the substeps see them.
    pub fn part_states(&self, t: f32) -> Vec<BodyState> {
        self.part_motions.iter().map(|m| m.at(t)).collect()
    }

    /// The fastest any vertex of the exact mesh moves, in m/s, from positions sampled at
    /// `SPEED_SAMPLE_RATE` over the transition and the motion's first two plays
    /// (`speed_scan_end`).
    pub fn max_vertex_speed(&self) -> f32 {
        let (from, to) = (self.timeline.start, self.speed_scan_end());
        let samples = ((to - from) * SPEED_SAMPLE_RATE).ceil().max(1.0) as usize;
        let dt = (to - from) / samples as f32;
        if dt <= 0.0 {
            return 0.0;
        }
        let mut before = self.positions_at(from);
        let mut fastest = 0.0f32;
        for k in 1..=samples {
            let now = self.positions_at(from + k as f32 * dt);
            let moved = (now.iter().zip(&before))
                .map(|(a, b)| a.distance(*b))
                .fold(0.0, f32::max);
            fastest = fastest.max(moved / dt);
            before = now;
        }
        fastest
    }

    /// The fastest any point of the surface moves as collision sees it, in m/s, over the
    /// transition and the first two plays (as `max_vertex_speed`). Collision places a rest
    /// point q at Σₚ wₚ(Rₚq + tₚ), the parts' poses blended with the point's weights
    /// (`part_influences`), so q moves at Σₚ wₚ(vₚ + ωₚ × Rₚq). Between keys each part turns at
    /// a constant rate while its translation runs straight, so that speed drifts across a key
    /// interval (by about |ω|²·|c|·Δt/2 for a joint at c from the origin: ±2% for a thigh at
    /// 5 rad/s): it is taken at both keys and the middle of each interval. (Points between
    /// vertices blend the weights too, so one may move a little faster than its triangle's
    /// corners: by up to about an edge's length times |ω|, a few cm/s.) Taking each part's
    /// own rigid speed at every point it weighs at all read the walk's knees and feet
    /// (1.7 m/s) as 3.4 m/s, which doubled the substeps of every walking scene: a foot's turn
    /// swung shin points that follow the foot by a few percent.
    pub fn max_part_speed(&self) -> f32 {
        let two_plays = self.speed_scan_end();
        let Some(first) = self.part_motions.first() else {
            return 0.0;
        };
        let intervals: Vec<usize> = (0..first.keys.len().saturating_sub(1))
            .take_while(|&k| first.keys[k].time < two_plays)
            .collect();
        (intervals.par_iter())
            .map(|&k| {
                let middle = 0.5 * (first.keys[k].time + first.keys[k + 1].time);
                let states: Vec<BodyState> =
                    self.part_motions.iter().map(|m| m.at(middle)).collect();
                [Some(k), None, Some(k + 1)]
                    .map(|key| {
                        // The interval's velocities with each part turned as at `key`.
                        let turned: Vec<BodyState> = (states.iter().zip(&self.part_motions))
                            .map(|(s, m)| BodyState {
                                rotation: key.map_or(s.rotation, |i| m.keys[i].rotation),
                                ..*s
                            })
                            .collect();
                        (self.rest.iter().zip(&self.part_influences))
                            .map(|(q, inf)| blended_velocity(&turned, inf, *q).length())
                            .fold(0.0, f32::max)
                    })
                    .into_iter()
                    .fold(0.0, f32::max)
            })
            .reduce(|| 0.0, f32::max)
    }
}

/// The velocity of rest point `q` under the parts' poses blended with its weights `inf`,
/// each part in `states` (all keyed at the same times, so their segments line up).
fn blended_velocity(states: &[BodyState], inf: &Influence, q: Vec3) -> Vec3 {
    (inf.joints.iter().zip(inf.weights))
        .filter(|(_, w)| *w > 0.0)
        .map(|(&p, w)| {
            let s = &states[p as usize];
            w * (s.linear_velocity + s.angular_velocity.cross(s.rotation * q))
        })
        .sum()
}

/// The rotation and translation of a skinning matrix (its scale, if any, dropped).
fn rigid(m: Mat4) -> (Quat, Vec3) {
    let (_, r, t) = m.to_scale_rotation_translation();
    (r.normalize(), t)
}

/// Collision parts for a skin: the joints that some vertex follows most, at most `MAX_PARTS`
/// of them (the smallest merged into the nearest part above it), and each vertex's weights
/// summed over the parts.
fn joint_parts(mesh: &SkinnedMesh) -> (Vec<usize>, Vec<Influence>) {
    let s = &mesh.skeleton;
    let mut dominant = vec![0usize; s.len()];
    for inf in &mesh.influences {
        dominant[inf.joints[0] as usize] += 1;
    }
    // Each joint's part: itself while it leads some vertex, else the nearest such joint above.
    let mut part_of: Vec<usize> = (0..s.len()).collect();
    let mut live: Vec<bool> = dominant.iter().map(|&c| c > 0).collect();
    if !live.iter().any(|&l| l) {
        live[0] = true;
    }
    loop {
        let count = live.iter().filter(|&&l| l).count();
        if count <= MAX_PARTS {
            break;
        }
        // The live joint with the fewest vertices (that has a live joint above it) joins it.
        let smallest = (0..s.len())
            .filter(|&j| live[j] && live_above(s, &live, j).is_some())
            .min_by_key(|&j| (dominant[j], j));
        let Some(j) = smallest else { break };
        let above = live_above(s, &live, j).expect("filtered");
        dominant[above] += dominant[j];
        live[j] = false;
    }
    for (j, p) in part_of.iter_mut().enumerate() {
        *p = if live[j] {
            j
        } else {
            live_above(s, &live, j).unwrap_or_else(|| live.iter().position(|&l| l).unwrap_or(0))
        };
    }
    let joints: Vec<usize> = (0..s.len()).filter(|&j| live[j]).collect();
    let index_of = |j: usize| joints.iter().position(|&k| k == part_of[j]).unwrap_or(0);
    let influences = (mesh.influences.iter())
        .map(|inf| {
            let mut sums: Vec<(u16, f32)> = Vec::new();
            for (&j, w) in inf.joints.iter().zip(inf.weights) {
                let p = index_of(j as usize) as u16;
                match sums.iter_mut().find(|(q, _)| *q == p) {
                    Some(e) => e.1 += w,
                    None => sums.push((p, w)),
                }
            }
            Influence::strongest(sums).unwrap_or(Influence {
                joints: [0; 4],
                weights: [1.0, 0.0, 0.0, 0.0],
            })
        })
        .collect();
    (joints, influences)
}

/// The nearest live joint above joint `j`.
fn live_above(s: &Skeleton, live: &[bool], j: usize) -> Option<usize> {
    let mut up = s.parents[j];
    while let Some(p) = up {
        if live[p] {
            return Some(p);
        }
        up = s.parents[p];
    }
    None
}

/// What `summary.json` says about a deforming body's motion.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct MotionReport {
    /// The motion's source: a file and animation, a built-in motion or a vertex cache.
    pub source: String,
    /// When the rest pose starts blending into the motion, in s.
    pub start_s: f32,
    /// How long the blend from the rest pose into the motion's first frame takes, in s.
    pub transition_s: f32,
    /// One play of the motion, in s.
    pub duration_s: f32,
    /// How many times it plays.
    pub plays: u32,
    /// When the last play ends (the last frame holds afterwards), in s.
    pub end_s: f32,
    /// The rigid parts collision bends the body with.
    pub collision_parts: usize,
    /// At each output frame (frame number, m): the deepest particle inside the exact deformed
    /// mesh.
    pub penetration_by_frame_m: Vec<(u32, f32)>,
}

impl Deformation {
    /// The summary's report of this motion, with the measured `penetration` per output frame.
    pub fn report(&self, penetration: Vec<(u32, f32)>) -> MotionReport {
        MotionReport {
            source: self.description.clone(),
            start_s: self.timeline.start,
            transition_s: self.timeline.transition,
            duration_s: self.motion_length(),
            plays: self.timeline.plays,
            end_s: self.end(),
            collision_parts: self.part_count(),
            penetration_by_frame_m: penetration,
        }
    }
}
