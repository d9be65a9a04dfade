//! The `[body]` table (or `[[body]]` tables, one per body): which body, its SDF, its collision response and its motion.

use crate::body::motion::{Keyframe, Motion};
use crate::body::Strategy;
use crate::check::Checker;
use crate::error::InputError;
use glam::{EulerRot, Quat, Vec3};
use serde::Deserialize;
use std::path::{Path, PathBuf};

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawBody {
    path: Option<String>,
    #[serde(default = "crate::check::default_units")]
    units: String,
    #[serde(default)]
    offset_m: [f64; 3],
    shape: Option<String>,
    #[serde(default)]
    center_m: [f64; 3],
    radius_m: Option<f64>,
    half_extents_m: Option<[f64; 3]>,
    half_height_m: Option<f64>,
    #[serde(default = "default_resolution")]
    sdf_resolution_m: f64,
    sdf_margin_m: Option<f64>,
    #[serde(default = "default_max_mb")]
    sdf_max_mb: f64,
    #[serde(default = "yes")]
    sdf_cache: bool,
    #[serde(default = "default_thickness")]
    thickness_m: f64,
    #[serde(default = "default_friction")]
    friction: f64,
    #[serde(default = "default_friction_slip_speed")]
    friction_slip_speed_m_s: f64,
    #[serde(default)]
    normal_loss: f64,
    #[serde(default)]
    tangential_loss: f64,
    #[serde(default = "default_strategy")]
    collision_strategy: String,
    #[serde(default)]
    edge_contacts: bool,
    motion: Option<String>,
    #[serde(default = "default_turn_angle")]
    turn_angle_deg: f64,
    #[serde(default = "default_turn_period")]
    turn_period_s: f64,
    #[serde(default)]
    motion_start_s: f64,
    #[serde(default)]
    keyframes: Vec<RawKeyframe>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawKeyframe {
    time_s: f64,
    #[serde(default)]
    translation_m: [f64; 3],
    #[serde(default)]
    rotation_deg: [f64; 3],
}

fn default_resolution() -> f64 {
    0.01
}
fn default_max_mb() -> f64 {
    1024.0
}
fn yes() -> bool {
    true
}
fn default_thickness() -> f64 {
    0.003
}
fn default_friction() -> f64 {
    0.3
}
/// Implicit Euler's friction holds (creeps at most this speed times the ratio of the pull to
/// the Coulomb bound) below 1 cm/s of slip.
fn default_friction_slip_speed() -> f64 {
    0.01
}
fn default_strategy() -> String {
    "sdf".into()
}
fn default_turn_angle() -> f64 {
    60.0
}
fn default_turn_period() -> f64 {
    1.0
}

/// Where the body's triangles come from.
#[derive(Clone, Debug, PartialEq)]
pub enum BodySource {
    /// An OBJ file, scaled to metres and shifted.
    Mesh {
        /// Resolved path.
        path: PathBuf,
        /// Metres per file unit.
        scale: f32,
        /// Translation in m.
        offset: Vec3,
    },
    /// A UV sphere.
    Sphere {
        /// Centre in m.
        center: Vec3,
        /// Radius in m.
        radius: f32,
    },
    /// An axis-aligned box.
    Cuboid {
        /// Centre in m.
        center: Vec3,
        /// Half extents in m.
        half: Vec3,
    },
    /// The shipped mannequin, feet at this point.
    Mannequin {
        /// Where it stands, in m.
        feet: Vec3,
    },
    /// A capsule along y.
    Capsule {
        /// Centre in m.
        center: Vec3,
        /// Radius in m.
        radius: f32,
        /// Half length of the cylinder in m.
        half_height: f32,
    },
}

/// The validated `[body]` table.
#[derive(Clone, Debug, PartialEq)]
pub struct BodySettings {
    /// The body's triangles.
    pub source: BodySource,
    /// SDF node spacing in m.
    pub sdf_resolution: f32,
    /// Space around the body's bounding box in m.
    pub sdf_margin: f32,
    /// Largest SDF allowed, in bytes.
    pub sdf_max_bytes: u64,
    /// Whether to cache baked grids on disk.
    pub sdf_cache: bool,
    /// Collision thickness in m.
    pub thickness: f32,
    /// Coulomb coefficient.
    pub friction: f32,
    /// Implicit Euler's friction: the slip speed relative to the body below which friction
    /// grows in proportion to the slip (smoothed static friction), in m/s.
    pub friction_slip_speed: f32,
    /// Fraction of outward normal relative speed lost in contact.
    pub normal_loss: f32,
    /// Fraction of tangential relative speed lost in contact.
    pub tangential_loss: f32,
    /// CPU contact strategy.
    pub strategy: Strategy,
    /// Whether the CPU path also tests cloth edges against body edges.
    pub edge_contacts: bool,
    /// Rigid motion.
    pub motion: Motion,
}

/// Most collision bodies a scene may have (`MAX_BODIES` in common.wgsl): each body's pose
/// travels in every substep's uniform.
pub const MAX_BODIES: usize = 4;

/// `[body]` (one body) or `[[body]]` (several), as the file gives them: the bodies in order.
pub(super) struct RawBodies(Vec<RawBody>);

/// Either form, keeping serde's message (and line) for a bad key inside a body: an untagged enum
/// would replace it with "did not match any variant".
impl<'de> Deserialize<'de> for RawBodies {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct Visitor;
        impl<'de> serde::de::Visitor<'de> for Visitor {
            type Value = RawBodies;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a [body] table or [[body]] tables")
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(
                self,
                map: A,
            ) -> Result<RawBodies, A::Error> {
                RawBody::deserialize(serde::de::value::MapAccessDeserializer::new(map))
                    .map(|b| RawBodies(vec![b]))
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(
                self,
                seq: A,
            ) -> Result<RawBodies, A::Error> {
                Vec::<RawBody>::deserialize(serde::de::value::SeqAccessDeserializer::new(seq))
                    .map(RawBodies)
            }
        }
        d.deserialize_any(Visitor)
    }
}

/// How messages name body `i` of `count`: `body` for the only one, `body[i]` among several.
pub fn body_table(count: usize, i: usize) -> String {
    if count == 1 {
        "body".into()
    } else {
        format!("body[{i}]")
    }
}

/// Validates `[body]` or every `[[body]]`, at most `MAX_BODIES` of them.
pub(super) fn parse_all(
    c: &Checker,
    base: &Path,
    raw: &Option<RawBodies>,
) -> Result<Vec<BodySettings>, InputError> {
    let list = raw.as_ref().map_or(&[][..], |r| &r.0[..]);
    if list.len() > MAX_BODIES {
        return Err(c.err(
            &format!("body[{MAX_BODIES}]"),
            "",
            format!(
                "{} bodies, and a scene may have at most {MAX_BODIES} (each one's pose travels \
                 with every substep)",
                list.len()
            ),
            "merge bodies that move together into one OBJ mesh (a body may have several \
             closed pieces)",
        ));
    }
    (list.iter().enumerate())
        .map(|(i, b)| parse(c, base, b, &body_table(list.len(), i)))
        .collect()
}

/// Validates one body table, named `t` in messages.
fn parse(c: &Checker, base: &Path, b: &RawBody, t: &str) -> Result<BodySettings, InputError> {
    let source = match (&b.path, b.shape.as_deref()) {
        (Some(p), None) => BodySource::Mesh {
            path: base.join(p),
            scale: c.units(t, "units", &b.units)?,
            offset: c.vec3(t, "offset_m", b.offset_m)?,
        },
        (None, Some(shape)) => {
            let center = c.vec3(t, "center_m", b.center_m)?;
            let need = |key: &str, v: Option<f64>| {
                v.ok_or_else(|| {
                    c.err(
                        t,
                        key,
                        format!("a {shape} needs {key}"),
                        format!("add {key}"),
                    )
                })
            };
            match shape {
                "sphere" => BodySource::Sphere {
                    center,
                    radius: c.positive(t, "radius_m", need("radius_m", b.radius_m)?, "m")?,
                },
                "box" => {
                    let h = b.half_extents_m.ok_or_else(|| {
                        c.err(
                            t,
                            "half_extents_m",
                            "a box needs half_extents_m",
                            "add half_extents_m = [x, y, z]",
                        )
                    })?;
                    BodySource::Cuboid {
                        center,
                        half: Vec3::new(
                            c.positive(t, "half_extents_m", h[0], "m")?,
                            c.positive(t, "half_extents_m", h[1], "m")?,
                            c.positive(t, "half_extents_m", h[2], "m")?,
                        ),
                    }
                }
                "mannequin" => BodySource::Mannequin { feet: center },
                "capsule" => BodySource::Capsule {
                    center,
                    radius: c.positive(t, "radius_m", need("radius_m", b.radius_m)?, "m")?,
                    half_height: c.positive(
                        t,
                        "half_height_m",
                        need("half_height_m", b.half_height_m)?,
                        "m",
                    )?,
                },
                other => {
                    return Err(c.err(
                        t,
                        "shape",
                        format!("unknown shape {other:?}"),
                        "use \"mannequin\", \"sphere\", \"box\" or \"capsule\", or give path = an OBJ body",
                    ))
                }
            }
        }
        _ => {
            return Err(c.err(
                t,
                "",
                "needs exactly one of path (an OBJ body) or shape",
                "give path = \"...obj\" or shape = \"sphere\"",
            ))
        }
    };
    let strategy = Strategy::ALL
        .iter()
        .find(|(_, name)| *name == b.collision_strategy)
        .map(|(s, _)| *s)
        .ok_or_else(|| {
            let names: Vec<&str> = Strategy::ALL.iter().map(|(_, n)| *n).collect();
            c.err(
                t,
                "collision_strategy",
                format!("unknown strategy {:?}", b.collision_strategy),
                format!("use one of {names:?}"),
            )
        })?;
    let fraction = |key: &str, v: f64| -> Result<f32, InputError> {
        let x = c.non_negative(t, key, v, "fraction")?;
        if x > 1.0 {
            return Err(c.err(
                t,
                key,
                format!("{x} is above 1"),
                "use a fraction between 0 and 1",
            ));
        }
        Ok(x)
    };
    // A collision shell thinner than 10 µm is below f32 resolution at body scale; thicker than
    // 10 cm is no longer cloth touching a body. SDF cells finer than 0.1 mm cost gigabytes for
    // a body; coarser than 0.5 m cannot resolve one.
    let thickness = c.within(t, "thickness_m", b.thickness_m, (1e-5, 0.1), "m")?;
    let resolution = c.within(t, "sdf_resolution_m", b.sdf_resolution_m, (1e-4, 0.5), "m")?;
    let mut keys = Vec::new();
    for (k, kf) in b.keyframes.iter().enumerate() {
        let table = format!("{t}.keyframes[{k}]");
        let r = c.vec3(&table, "rotation_deg", kf.rotation_deg)?;
        keys.push(Keyframe {
            time: c.non_negative(&table, "time_s", kf.time_s, "s")?,
            translation: c.vec3(&table, "translation_m", kf.translation_m)?,
            rotation: Quat::from_euler(
                EulerRot::ZYX,
                r.z.to_radians(),
                r.y.to_radians(),
                r.x.to_radians(),
            ),
        });
        if k > 0 && keys[k].time <= keys[k - 1].time {
            return Err(c.err(
                &table,
                "time_s",
                "keyframe times must increase",
                "sort the keyframes by time",
            ));
        }
    }
    let motion = match (b.motion.as_deref(), keys.is_empty()) {
        (None, _) => Motion { keys },
        (Some("turn-right-left"), true) => Motion::turn_right_left(
            c.finite(t, "turn_angle_deg", b.turn_angle_deg)?,
            c.positive(t, "turn_period_s", b.turn_period_s, "s")?,
            c.non_negative(t, "motion_start_s", b.motion_start_s, "s")?,
        ),
        (Some("turn-right-left"), false) => {
            return Err(c.err(
                t,
                "motion",
                "give either motion or keyframes, not both",
                "remove one",
            ))
        }
        (Some(other), _) => {
            return Err(c.err(
                t,
                "motion",
                format!("unknown motion {other:?}"),
                "use \"turn-right-left\" or [[body.keyframes]]",
            ))
        }
    };
    Ok(BodySettings {
        source,
        sdf_resolution: resolution,
        sdf_margin: match b.sdf_margin_m {
            Some(m) => c.within(t, "sdf_margin_m", m, (1e-5, 1.0), "m")?,
            // Room for the thickness and the trilinear stencil around the surface.
            None => (2.0 * thickness).max(3.0 * resolution),
        },
        sdf_max_bytes: (c.positive(t, "sdf_max_mb", b.sdf_max_mb, "MiB")? as f64 * 1048576.0)
            as u64,
        sdf_cache: b.sdf_cache,
        thickness,
        friction: c.non_negative(t, "friction", b.friction, "1")?,
        friction_slip_speed: c.within(
            t,
            "friction_slip_speed_m_s",
            b.friction_slip_speed_m_s,
            (1e-4, 10.0),
            "m/s",
        )?,
        normal_loss: fraction("normal_loss", b.normal_loss)?,
        tangential_loss: fraction("tangential_loss", b.tangential_loss)?,
        strategy,
        edge_contacts: b.edge_contacts,
        motion,
    })
}
