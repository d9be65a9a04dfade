//! The `[self_collision]` table.

use super::raw::RawSelfCollision;
use crate::check::Checker;
use crate::error::InputError;

/// The `[self_collision]` table.
#[derive(Clone, Debug, PartialEq)]
pub struct SelfCollision {
    /// Particles keep this far apart, in m (`None`: 0.75 × the mean rest edge length).
    pub thickness: Option<f32>,
    /// Hash table size (`None`: the power of two at or above twice the particle count).
    pub buckets: Option<u32>,
    /// On the CPU backend, use point–triangle impulses (the reference) instead of the particle
    /// repulsion the GPU runs.
    pub cpu_point_triangle: bool,
}

/// Validates `[self_collision]`.
pub(super) fn parse(
    c: &Checker,
    raw: &Option<RawSelfCollision>,
) -> Result<Option<SelfCollision>, InputError> {
    Ok(match raw {
        Some(sc) => {
            Some(SelfCollision {
                thickness: match sc.thickness_m {
                    Some(t) => Some(c.positive("self_collision", "thickness_m", t, "m")?),
                    None => None,
                },
                buckets: match sc.hash_buckets {
                    Some(b) => Some(buckets(c, b)?),
                    None => None,
                },
                cpu_point_triangle: match sc.cpu_method.as_str() {
                    "particles" => false,
                    "point-triangle" => true,
                    other => return Err(c.err(
                        "self_collision",
                        "cpu_method",
                        format!("unknown method {other:?}"),
                        "use \"particles\" (as the GPU) or \"point-triangle\" (the CPU reference)",
                    )),
                },
            })
        }
        None => None,
    })
}

/// The most hash buckets a scene may ask for: 2²⁴, eight times the default for two million
/// particles. Each bucket is two u32 counters on both paths, cleared every substep, so 2³⁰
/// took 12 GB and minutes for a cloth of 1,600 particles.
pub const MAX_HASH_BUCKETS: i64 = 1 << 24;

/// `hash_buckets`, at least 64 and at most `MAX_HASH_BUCKETS`.
fn buckets(c: &Checker, b: i64) -> Result<u32, InputError> {
    if b > MAX_HASH_BUCKETS {
        return Err(c.err(
            "self_collision",
            "hash_buckets",
            format!(
                "{b} buckets is more than {MAX_HASH_BUCKETS}, which is more than any cloth needs"
            ),
            "leave it out (a power of two at least twice the particle count), or give at most \
             16777216",
        ));
    }
    c.count("self_collision", "hash_buckets", b, 64)
}
