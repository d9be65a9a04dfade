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
    #[serde(default, deserialize_with = "super::raw::exactly")]
    offset_m: [f64; 3],
    shape: Option<String>,
    #[serde(default, deserialize_with = "super::raw::exactly")]
    center_m: [f64; 3],
    radius_m: Option<f64>,
    #[serde(default, deserialize_with = "super::raw::exactly_if_given")]
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
    animation: Option<String>,
    cache: Option<String>,
    #[serde(default = "default_cache_fps")]
    cache_fps: f64,
    #[serde(default = "default_transition")]
    transition_s: f64,
    #[serde(default = "one")]
    plays: i64,
    #[serde(default = "default_parts")]
    parts: i64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawKeyframe {
    time_s: f64,
    #[serde(default, deserialize_with = "super::raw::exactly")]
    translation_m: [f64; 3],
    #[serde(default, deserialize_with = "super::raw::exactly")]
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
fn default_cache_fps() -> f64 {
    24.0
}
/// A second: long enough that the arms lowering from the A-pose (the usual first frame's
/// change) move at about 0.6 m/s at the hands, slow enough to keep a sewn garment in place.
fn default_transition() -> f64 {
    1.0
}
fn one() -> i64 {
    1
}
/// Parts fitted to a vertex cache: about a human's major segments (the shipped mannequin's rig
/// has 19 joints).
fn default_parts() -> i64 {
    16
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
    /// A skinned glTF body (`None`: the shipped rigged mannequin, feet at `offset`).
    Skinned {
        /// Resolved path of the `.glb` or `.gltf` file.
        path: Option<PathBuf>,
        /// Metres per file unit.
        scale: f32,
        /// Translation in m.
        offset: Vec3,
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
    /// How a deforming body moves (`None`: rigid).
    pub deform: Option<DeformSettings>,
}

/// What moves a deforming body, and when.
#[derive(Clone, Debug, PartialEq)]
pub struct DeformSettings {
    /// The motion's source.
    pub motion: DeformMotion,
    /// The rest pose holds until this time, in s.
    pub start: f32,
    /// Seconds over which the body blends from the rest pose into the motion's first frame.
    pub transition: f32,
    /// How many times the motion plays.
    pub plays: u32,
}

/// Where a deforming body's motion comes from.
#[derive(Clone, Debug, PartialEq)]
pub enum DeformMotion {
    /// A clip of the body's glTF skin (or a built-in motion of the mannequin), by name; `None`
    /// when the scene named none (the file's clips are listed in the error).
    Skin {
        /// The clip's name.
        animation: Option<String>,
    },
    /// A vertex cache over the OBJ body's vertices.
    Cache {
        /// A `.pc2` file, or an OBJ sequence named with `#` for the frame number.
        path: PathBuf,
        /// The cache's frames per second.
        fps: f32,
        /// How many rigid parts collision fits to it.
        parts: u32,
    },
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
    let gltf = |p: &str| {
        let lower = p.to_lowercase();
        lower.ends_with(".glb") || lower.ends_with(".gltf")
    };
    let source = match (&b.path, b.shape.as_deref()) {
        (Some(p), None) if gltf(p) => BodySource::Skinned {
            path: Some(base.join(p)),
            scale: c.units(t, "units", &b.units)?,
            offset: c.vec3(t, "offset_m", b.offset_m)?,
        },
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
                "mannequin" if b.animation.is_some() => BodySource::Skinned {
                    path: None,
                    scale: 1.0,
                    offset: center,
                },
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
    let resolution = c.within(
        t,
        "sdf_resolution_m",
        b.sdf_resolution_m,
        (1e-4, MAX_SDF_RESOLUTION_M),
        "m",
    )?;
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
        if let Some(before) = k.checked_sub(1).map(|j| b.keyframes[j].rotation_deg) {
            let turn = (0..3)
                .map(|a| (kf.rotation_deg[a] - before[a]).abs())
                .fold(0.0, f64::max);
            // Slerp goes the shorter way round: 360° would read as no turn at all, 270° as
            // 90° the other way.
            if turn >= 180.0 {
                return Err(c.err(
                    &table,
                    "rotation_deg",
                    format!(
                        "turns {turn}° from the keyframe before; the motion between two \
                         keyframes takes the shorter way round, so it would not turn as written"
                    ),
                    "add keyframes in between, each less than 180° from the last",
                ));
            }
        }
    }
    let motion = match (b.motion.as_deref(), keys.is_empty()) {
        (None, _) => Motion { keys },
        (Some("turn-right-left"), true) => Motion::turn_right_left(
            // Its middle leg turns twice the angle, and a leg takes the shorter way round.
            c.within(
                t,
                "turn_angle_deg",
                b.turn_angle_deg,
                (-89.0, 89.0),
                "degrees",
            )?,
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
    let deform = parse_deform(c, base, b, t, &source, &motion)?;
    if deform.is_some() && (strategy != Strategy::Sdf || b.edge_contacts) {
        return Err(c.err(
            t,
            if b.edge_contacts {
                "edge_contacts"
            } else {
                "collision_strategy"
            },
            "a deforming body collides through its rest pose's SDF and its parts' poses only",
            "remove collision_strategy and edge_contacts from this body",
        ));
    }
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
        deform,
    })
}

/// The deforming motion of body table `t`, if it has one: a glTF clip (`animation`), a built-in
/// motion of the mannequin, or a vertex cache (`cache`).
fn parse_deform(
    c: &Checker,
    base: &Path,
    b: &RawBody,
    t: &str,
    source: &BodySource,
    rigid: &Motion,
) -> Result<Option<DeformSettings>, InputError> {
    let motion =
        match (source, &b.animation, &b.cache) {
            (_, Some(_), Some(_)) => return Err(c.err(
                t,
                "cache",
                "give either animation (a skinned glTF body) or cache (a vertex cache), not both",
                "remove one",
            )),
            (BodySource::Skinned { .. }, animation, None) => DeformMotion::Skin {
                animation: animation.clone(),
            },
            (BodySource::Mesh { .. }, None, Some(cache)) => DeformMotion::Cache {
                path: base.join(cache),
                fps: c.within(t, "cache_fps", b.cache_fps, (1e-3, 1e4), "frames/s")?,
                parts: {
                    let parts = b.parts.clamp(0, u32::MAX as i64) as u32;
                    if parts == 0 || parts as usize > crate::body::deform::MAX_PARTS {
                        return Err(c.err(
                            t,
                            "parts",
                            format!("{} parts", b.parts),
                            format!(
                                "use 1 to {} (collision fits that many rigid parts to the cache)",
                                crate::body::deform::MAX_PARTS
                            ),
                        ));
                    }
                    parts
                },
            },
            (BodySource::Mesh { .. }, Some(_), None) => {
                return Err(c.err(
                    t,
                    "animation",
                    "an OBJ body has no skeleton to animate",
                    "give path = a skinned .glb or .gltf avatar, or give the OBJ's motion as \
                 cache = \"walk.pc2\" (or an OBJ sequence, walk_####.obj)",
                ))
            }
            (_, None, Some(_)) => {
                return Err(c.err(
                    t,
                    "cache",
                    "a vertex cache needs the body's own mesh, whose vertices it moves",
                    "give path = the OBJ the cache was exported from",
                ))
            }
            (_, Some(_), None) => {
                return Err(c.err(
                    t,
                    "animation",
                    "only a skinned glTF body or the mannequin can play an animation",
                    format!(
                        "give path = a .glb or .gltf avatar, or shape = \"mannequin\" with one of \
                     {:?}",
                        crate::body::motions::NAMES
                    ),
                ))
            }
            (_, None, None) => return Ok(None),
        };
    if !rigid.keys.is_empty() {
        return Err(c.err(
            t,
            "motion",
            "a deforming body moves by its animation or cache only",
            "remove motion and [[body.keyframes]], or the animation",
        ));
    }
    if !(1..=10_000).contains(&b.plays) {
        return Err(c.err(
            t,
            "plays",
            format!("{} plays", b.plays),
            "use a whole number from 1 (the motion plays once, then holds its last frame)",
        ));
    }
    Ok(Some(DeformSettings {
        motion,
        start: c.non_negative(t, "motion_start_s", b.motion_start_s, "s")?,
        transition: c.within(t, "transition_s", b.transition_s, (0.0, 600.0), "s")?,
        plays: b.plays as u32,
    }))
}

/// The coarsest `sdf_resolution_m` a scene may give, in m.
pub const MAX_SDF_RESOLUTION_M: f64 = 0.5;
