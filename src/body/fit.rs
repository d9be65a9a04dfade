//! Rigid parts for a vertex cache, which has no skeleton: the body's vertices are split into
//! parts that each move (nearly) rigidly over the cache, each part gets its best rigid pose at
//! every frame, and the parts' labels are smoothed over the surface into skin weights. Collision
//! then treats the cache like a skinned body over these parts.
//!
//! The split alternates two steps (the initialisation of Le and Deng's skinning decomposition,
//! 2012): fit each part's rigid pose per frame to its vertices (Kabsch, through glam's SVD),
//! then move each vertex to the part whose poses follow its trajectory best.

use super::skin::Influence;
use glam::{Mat3, Quat, Vec3};
use glamx::Svd3;

/// Alternations of fitting poses and reassigning vertices.
const ROUNDS: usize = 8;

/// Most cache frames the split looks at (evenly spread); the final poses use every frame.
const SPLIT_FRAMES: usize = 40;

/// Smoothing passes of the labels over the surface (as the mannequin's rig smooths its weights).
const SMOOTHING_PASSES: usize = 6;

/// A cache's parts: each vertex's weights over the parts, and each part's rigid pose (rest to
/// frame) at every frame.
#[derive(Clone, Debug, PartialEq)]
pub struct PartFit {
    /// One per vertex, over part indices.
    pub influences: Vec<Influence>,
    /// `poses[part][frame]`: rotation and translation taking the rest position to the frame's.
    pub poses: Vec<Vec<(Quat, Vec3)>>,
    /// The farthest any vertex of any frame lies from its position blended from the parts'
    /// poses, in m: how far collision's picture of the body may be off.
    pub max_error: f32,
}

/// The rigid motion taking points `from` to `to` with the least squared error (Kabsch).
pub fn kabsch(from: &[Vec3], to: &[Vec3]) -> (Quat, Vec3) {
    let n = from.len().max(1) as f32;
    let (cf, ct) = (from.iter().sum::<Vec3>() / n, to.iter().sum::<Vec3>() / n);
    let mut h = Mat3::ZERO;
    for (a, b) in from.iter().zip(to) {
        let (a, b) = (*a - cf, *b - ct);
        h += Mat3::from_cols(a * b.x, a * b.y, a * b.z);
    }
    let svd = Svd3::from_matrix(h);
    let (u, v) = (svd.u, svd.vt.transpose());
    // A reflection is no rigid motion: flip the least significant axis.
    let d = (v * u.transpose()).determinant().signum();
    let r = v * Mat3::from_diagonal(Vec3::new(1.0, 1.0, d)) * u.transpose();
    let q = Quat::from_mat3(&r).normalize();
    (q, ct - q * cf)
}

/// Splits `rest` (with `triangles`, for smoothing) into `parts` parts moving rigidly over
/// `frames`.
pub fn fit_parts(
    rest: &[Vec3],
    triangles: &[[u32; 3]],
    frames: &[Vec<Vec3>],
    parts: usize,
) -> PartFit {
    let parts = parts.clamp(1, rest.len().max(1));
    let step = frames.len().div_ceil(SPLIT_FRAMES).max(1);
    let sample: Vec<&Vec<Vec3>> = frames.iter().step_by(step).collect();
    let mut label = seed_labels(rest, parts);
    for _ in 0..ROUNDS {
        let poses: Vec<Vec<(Quat, Vec3)>> = (0..parts)
            .map(|p| fit_poses(rest, &label, p, sample.iter().copied()))
            .collect();
        for (v, l) in label.iter_mut().enumerate() {
            let error = |p: usize| -> f32 {
                (poses[p].iter().zip(&sample))
                    .map(|((q, t), f)| (*q * rest[v] + *t - f[v]).length_squared())
                    .sum()
            };
            *l = (0..parts)
                .min_by(|a, b| error(*a).total_cmp(&error(*b)))
                .unwrap_or(0);
        }
        reseed_empty(&mut label, parts, rest);
    }
    let poses: Vec<Vec<(Quat, Vec3)>> = (0..parts)
        .map(|p| fit_poses(rest, &label, p, frames.iter()))
        .collect();
    let influences = smooth_labels(&label, parts, rest.len(), triangles);
    let max_error = (frames.iter().enumerate())
        .flat_map(|(f, frame)| {
            let poses = &poses;
            (influences.iter().zip(rest).zip(frame)).map(move |((inf, r), x)| {
                let blended: Vec3 = (inf.joints.iter().zip(inf.weights))
                    .map(|(&p, w)| w * (poses[p as usize][f].0 * *r + poses[p as usize][f].1))
                    .sum();
                blended.distance(*x)
            })
        })
        .fold(0.0, f32::max);
    PartFit {
        influences,
        poses,
        max_error,
    }
}

/// Part `p`'s best rigid pose at each of `frames` (the identity for an empty part).
fn fit_poses<'a>(
    rest: &[Vec3],
    label: &[usize],
    p: usize,
    frames: impl Iterator<Item = &'a Vec<Vec3>>,
) -> Vec<(Quat, Vec3)> {
    let members: Vec<usize> = (0..rest.len()).filter(|&v| label[v] == p).collect();
    let from: Vec<Vec3> = members.iter().map(|&v| rest[v]).collect();
    frames
        .map(|f| {
            if members.is_empty() {
                return (Quat::IDENTITY, Vec3::ZERO);
            }
            let to: Vec<Vec3> = members.iter().map(|&v| f[v]).collect();
            kabsch(&from, &to)
        })
        .collect()
}

/// `parts` seeds spread by farthest-point sampling, each vertex labelled by its nearest seed.
fn seed_labels(rest: &[Vec3], parts: usize) -> Vec<usize> {
    let mut seeds = vec![0usize];
    let mut nearest: Vec<f32> = rest.iter().map(|p| p.distance(rest[0])).collect();
    while seeds.len() < parts {
        let far = (0..rest.len())
            .max_by(|a, b| nearest[*a].total_cmp(&nearest[*b]))
            .unwrap_or(0);
        seeds.push(far);
        for (d, p) in nearest.iter_mut().zip(rest) {
            *d = d.min(p.distance(rest[far]));
        }
    }
    rest.iter()
        .map(|p| {
            (0..seeds.len())
                .min_by(|a, b| {
                    p.distance(rest[seeds[*a]])
                        .total_cmp(&p.distance(rest[seeds[*b]]))
                })
                .unwrap_or(0)
        })
        .collect()
}

/// Gives each empty part the vertex farthest from the centre of the largest part.
fn reseed_empty(label: &mut [usize], parts: usize, rest: &[Vec3]) {
    for p in 0..parts {
        if label.contains(&p) {
            continue;
        }
        let mut count = vec![0usize; parts];
        for &l in label.iter() {
            count[l] += 1;
        }
        let big = (0..parts).max_by_key(|&q| count[q]).unwrap_or(0);
        let members: Vec<usize> = (0..rest.len()).filter(|&v| label[v] == big).collect();
        let centre = members.iter().map(|&v| rest[v]).sum::<Vec3>() / members.len().max(1) as f32;
        if let Some(&far) = members.iter().max_by(|a, b| {
            rest[**a]
                .distance(centre)
                .total_cmp(&rest[**b].distance(centre))
        }) {
            label[far] = p;
        }
    }
}

/// Labels as one-hot weights smoothed over the surface, the four largest kept per vertex.
fn smooth_labels(
    label: &[usize],
    parts: usize,
    n: usize,
    triangles: &[[u32; 3]],
) -> Vec<Influence> {
    let mut around = vec![Vec::new(); n];
    for t in triangles {
        for k in 0..3 {
            let (a, b) = (t[k] as usize, t[(k + 1) % 3] as usize);
            if !around[a].contains(&b) {
                around[a].push(b);
                around[b].push(a);
            }
        }
    }
    let mut w: Vec<Vec<f32>> = label
        .iter()
        .map(|&l| (0..parts).map(|p| if p == l { 1.0 } else { 0.0 }).collect())
        .collect();
    for _ in 0..SMOOTHING_PASSES {
        let before = w.clone();
        for (v, near) in around.iter().enumerate() {
            if near.is_empty() {
                continue;
            }
            for p in 0..parts {
                let mean = near.iter().map(|&k| before[k][p]).sum::<f32>() / near.len() as f32;
                w[v][p] = before[v][p] + (mean - before[v][p]) / 3.0;
            }
        }
    }
    w.into_iter()
        .map(|row| {
            let pairs = (row.into_iter().enumerate())
                .map(|(p, x)| (p as u16, x))
                .collect();
            Influence::strongest(pairs).expect("smoothing keeps each vertex's total at one")
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kabsch_recovers_a_rigid_motion() {
        let from = [Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::new(0.3, 0.2, 1.0)];
        let q = Quat::from_euler(glam::EulerRot::XYZ, 0.3, -0.7, 1.1);
        let t = Vec3::new(0.5, -2.0, 0.25);
        let to: Vec<Vec3> = from.iter().map(|p| q * *p + t).collect();
        let (q2, t2) = kabsch(&from, &to);
        for (a, b) in from.iter().zip(&to) {
            // f32 SVD of a small covariance: a few ulps of unit-sized coordinates.
            assert!((q2 * *a + t2 - *b).length() < 1e-5);
        }
    }
}
