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
                    Some(b) => Some(c.count("self_collision", "hash_buckets", b, 64)?),
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
