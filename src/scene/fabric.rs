//! The `[fabric]` table: areal density, stretch and bending stiffness, damping.

use super::presets::{preset, FabricPreset, PRESETS};
use super::raw::RawFabric;
use crate::check::Checker;
use crate::error::InputError;

/// Fabric parameters in SI units.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fabric {
    /// Areal density in kg/m².
    pub density: f32,
    /// Membrane stretch stiffness in N/m (force per unit width per unit strain).
    pub stretch_stiffness: f32,
    /// Bending rigidity in N·m; `None` disables bending.
    pub bending_stiffness: Option<f32>,
    /// Spring damping as a fraction of each spring's critical damping.
    pub damping_ratio: f32,
    /// The preset the values start from, if any (its look in previews and exports).
    pub preset: Option<&'static str>,
    /// The orthotropic membrane that replaces the isotropic edge springs (`model =
    /// "membrane"`); `None`: springs of `stretch_stiffness`.
    pub membrane: Option<Orthotropic>,
    /// The cloth buckles in compression (`compression = "buckling"`,
    /// `cpu::stretch_law`) rather than resist it linearly.
    pub buckling: bool,
}

/// An orthotropic membrane's small-strain stiffness, in N/m: uniaxial along the warp and the
/// weft (lateral edges free) and in-plane shear (shear force per width per radian of
/// engineering shear strain).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Orthotropic {
    /// Along the warp (the grain).
    pub warp: f32,
    /// Along the weft (across the grain).
    pub weft: f32,
    /// In-plane shear.
    pub shear: f32,
    /// The hinge coefficient (N·m, `HINGE_PER_RIGIDITY` times the rigidity) of strips cut along
    /// the warp and along the weft (`warp_bending_n_m`, `weft_bending_n_m`, else the preset's
    /// measurements); `None`: the fabric's one bending stiffness every way (`model::bending`).
    pub bending: Option<[f32; 2]>,
    /// With `tension = "stiffening"`: the tangent stiffness along the warp and along the weft
    /// at `LARGE_STRAIN` (N/m), to which each rises linearly from its small-strain value and
    /// then stays (`cpu::stretch_law`); `None`: linear in tension.
    pub large_strain: Option<[f32; 2]>,
}

/// The strain at which a stiffening membrane's tangent stiffness reaches its large-strain
/// value: 1/6, the strain of Wang et al. 2011's large-strain samples, where the presets' values
/// come from.
pub const LARGE_STRAIN: f32 = 1.0 / 6.0;

impl Orthotropic {
    /// The uniaxial stiffness of a strip cut at `angle` radians from the warp, lateral edges
    /// free: 1/k(θ) = cos⁴θ/k_warp + sin⁴θ/k_weft + sin²θ·cos²θ/k_shear (the classical
    /// laminate result with no Poisson coupling, which the membrane model has none of).
    pub fn uniaxial(&self, angle: f32) -> f32 {
        let (s, c) = angle.sin_cos();
        let (s2, c2) = (s * s, c * c);
        1.0 / (c2 * c2 / self.warp + s2 * s2 / self.weft + s2 * c2 / self.shear)
    }
}

/// The share of its stiffness a buckled spring keeps (`compression = "buckling"`): a
/// numerical choice, not a measurement. Zero leaves the sweeps a direction without stiffness
/// (measured: the solve diverged on the Cusick specimen); 0.1 still locked the drape of a limp
/// fabric; 0.03 let the drape coefficient fall with bending down to a sixteenth of cotton's.
pub const BUCKLED_FRACTION: f32 = 0.03;

impl Fabric {
    /// A plain woven-like sheet of `stretch_stiffness` N/m on linear springs: 0.2 kg/m², bending
    /// 1e-5 N·m, 5% of critical damping, no preset. The benchmark cloth's fabric, and the tests'.
    pub fn linear(stretch_stiffness: f32) -> Fabric {
        Fabric {
            density: 0.2,
            stretch_stiffness,
            bending_stiffness: Some(1e-5),
            damping_ratio: 0.05,
            preset: None,
            membrane: None,
            buckling: false,
        }
    }

    /// The cloth's law in compression as (`SimParams::euler_onset`,
    /// `SimParams::membrane_onset`, `SimParams::buckled_fraction`): with buckling, π²B/Y,
    /// (√3/4)·π²B (B = the hinge coefficient over `HINGE_PER_RIGIDITY`, 0 without bending) and
    /// `BUCKLED_FRACTION`; zeros when linear (`cpu::stretch_law` says why).
    pub fn compression_law(&self) -> [f32; 3] {
        if !self.buckling {
            return [0.0; 3];
        }
        let rigidity = self.bending_stiffness.unwrap_or(0.0) / HINGE_PER_RIGIDITY as f32;
        let euler = std::f32::consts::PI.powi(2) * rigidity;
        [
            euler / self.stretch_stiffness,
            3f32.sqrt() / 4.0 * euler,
            BUCKLED_FRACTION,
        ]
    }

    /// The membrane's law in tension as `SimParams::stiffening`: the warp's and the weft's
    /// tangent growth per unit strain g = (k_large/k − 1)/e and the end strain e =
    /// `LARGE_STRAIN`; zeros when linear.
    pub fn stiffening(&self) -> [f32; 4] {
        match self.membrane {
            Some(
                m @ Orthotropic {
                    large_strain: Some([warp, weft]),
                    ..
                },
            ) => {
                let growth = |large: f32, small: f32| (large / small - 1.0) / LARGE_STRAIN;
                [
                    growth(warp, m.warp),
                    growth(weft, m.weft),
                    LARGE_STRAIN,
                    0.0,
                ]
            }
            _ => [0.0; 4],
        }
    }

    /// The membrane's largest tangent stiffness over its small-strain one, along the warp and
    /// the weft: k_e/k where it stiffens, else 1 (the stable-step estimate's factor).
    pub fn tangent_ratio(&self) -> [f32; 2] {
        match self.membrane {
            Some(Orthotropic {
                warp,
                weft,
                large_strain: Some([large_warp, large_weft]),
                ..
            }) => [(large_warp / warp).max(1.0), (large_weft / weft).max(1.0)],
            _ => [1.0; 2],
        }
    }

    /// The stiffest small-strain stretch the cloth has, in N/m (the springs', or the membrane's
    /// stiffer axis): what the seams' default stiffness and the scale checks take (the
    /// stable-step estimate adds a stiffening membrane's `tangent_ratio`).
    pub fn stiffest_stretch(&self) -> f32 {
        match self.membrane {
            Some(m) => m.warp.max(m.weft).max(self.stretch_stiffness),
            None => self.stretch_stiffness,
        }
    }
}

/// Where the membrane's warp runs, in radians from each panel's x axis (a grid's width, an
/// OBJ mesh's world x turned about world z): `default` everywhere, `panels` per panel name.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Grain {
    /// The angle of every panel not listed.
    pub default: f32,
    /// Per-panel angles (`[fabric.panel_grain_deg]`), checked against the pattern's panels
    /// when the cloth is built.
    pub panels: std::collections::BTreeMap<String, f32>,
}

/// `[fabric] grain_deg` and `[fabric.panel_grain_deg]`.
pub(super) fn parse_grain(c: &Checker, f: &RawFabric) -> Result<Grain, InputError> {
    let angle = |key: &str, deg: f64| {
        if deg.is_finite() {
            Ok(deg.to_radians() as f32)
        } else {
            Err(c.err(
                "fabric",
                key,
                "the grain angle is not finite",
                "give degrees, such as 45",
            ))
        }
    };
    let mut panels = std::collections::BTreeMap::new();
    for (name, &deg) in &f.panel_grain_deg {
        panels.insert(name.clone(), angle("panel_grain_deg", deg)?);
    }
    Ok(Grain {
        default: angle("grain_deg", f.grain_deg.unwrap_or(0.0))?,
        panels,
    })
}

/// Damping ratio when neither the scene nor a preset gives one.
const DEFAULT_DAMPING_RATIO: f64 = 0.05;

/// The model's hinge coefficient per unit of continuum bending rigidity: the dihedral hinge
/// (Bridson et al. 2003) with coefficient k stores the energy of a sheet of rigidity k/4
/// (measured on a bent equilateral mesh: 0.98–0.99 of k/4 from 0° to 90°), so a preset of
/// rigidity B sets `bending_stiffness_n_m` = 4·B.
pub const HINGE_PER_RIGIDITY: f64 = 4.0;

/// Validates `[fabric]`: a preset's values, overridden by any key given beside it.
pub(super) fn parse(c: &Checker, f: &RawFabric) -> Result<Fabric, InputError> {
    let preset = match &f.preset {
        None => None,
        Some(name) => Some(preset(name).ok_or_else(|| {
            let names: Vec<&str> = PRESETS.iter().map(|p| p.name).collect();
            c.err(
                "fabric",
                "preset",
                format!(
                    "unknown fabric preset {name:?}{}",
                    crate::suggest::did_you_mean(name, names.iter().copied())
                ),
                format!("use one of {names:?}, or give density_kg_m2 and stretch_stiffness_n_m"),
            )
        })?),
    };
    let required = |key: &str, given: Option<f64>, from_preset: Option<f64>| {
        given.or(from_preset).ok_or_else(|| {
            c.err(
                "fabric",
                key,
                format!("missing {key}"),
                format!("give {key}, or a preset (e.g. preset = \"cotton\")"),
            )
        })
    };
    let density = required(
        "density_kg_m2",
        f.density_kg_m2,
        preset.map(|p| p.density_kg_m2),
    )?;
    let stretch = required(
        "stretch_stiffness_n_m",
        f.stretch_stiffness_n_m,
        preset.map(|p| p.stretch_stiffness_n_m),
    )?;
    // Bending by direction alone still bends: the springs' and the buckling law's one value is
    // then the geometric mean of the two, as a preset's is.
    let by_direction = (f.warp_bending_n_m.zip(f.weft_bending_n_m)).map(|(w, v)| (w * v).sqrt());
    let bending = f
        .bending_stiffness_n_m
        .or(by_direction.filter(|b| b.is_finite() && *b > 0.0))
        .or(preset.map(|p| HINGE_PER_RIGIDITY * p.bending_stiffness_n_m));
    let damping = f
        .damping_ratio
        .or(preset.map(|p| p.damping_ratio))
        .unwrap_or(DEFAULT_DAMPING_RATIO);
    Ok(Fabric {
        density: c.positive("fabric", "density_kg_m2", density, "kg/m²")?,
        stretch_stiffness: c.positive("fabric", "stretch_stiffness_n_m", stretch, "N/m")?,
        bending_stiffness: match bending {
            None => None,
            Some(v) => Some(c.positive(
                "fabric",
                "bending_stiffness_n_m",
                v,
                "N·m (omit the key to disable bending)",
            )?),
        },
        damping_ratio: c.non_negative(
            "fabric",
            "damping_ratio",
            damping,
            "fractions of critical damping",
        )?,
        preset: preset.map(|p| p.name),
        membrane: parse_membrane(c, f, preset)?,
        buckling: parse_compression(c, f)?,
    })
}

/// `compression = "buckling"` (springs and membrane conditions carry at most their strip's
/// Euler load in compression) or `"linear"` (the default).
fn parse_compression(c: &Checker, f: &RawFabric) -> Result<bool, InputError> {
    match f.compression.as_deref() {
        None | Some("linear") => Ok(false),
        Some("buckling") => Ok(true),
        Some(other) => Err(c.err(
            "fabric",
            "compression",
            format!(
                "unknown compression {other:?}{}",
                crate::suggest::did_you_mean(other, ["buckling", "linear"].into_iter())
            ),
            "use compression = \"buckling\" (compressed edges buckle at the Euler load) or \"linear\"",
        )),
    }
}

/// `tension = "stiffening"` (the membrane's warp and weft tangent stiffness rises to its
/// large-strain value: the scene's `warp_large_strain_stiffness_n_m` and
/// `weft_large_strain_stiffness_n_m`, else the preset's measurements) or `"linear"` (the
/// default). The large-strain keys without stiffening are refused, as is stiffening with
/// neither keys nor measurements.
fn parse_tension(
    c: &Checker,
    f: &RawFabric,
    preset: Option<&FabricPreset>,
) -> Result<Option<[f32; 2]>, InputError> {
    // Each axis: its large-strain key and value, and its small-strain key and value.
    let axes = [
        (
            "warp_large_strain_stiffness_n_m",
            f.warp_large_strain_stiffness_n_m,
            "warp_stiffness_n_m",
            f.warp_stiffness_n_m,
        ),
        (
            "weft_large_strain_stiffness_n_m",
            f.weft_large_strain_stiffness_n_m,
            "weft_stiffness_n_m",
            f.weft_stiffness_n_m,
        ),
    ];
    match f.tension.as_deref() {
        None | Some("linear") => match axes.iter().find(|a| a.1.is_some()) {
            Some((key, ..)) => Err(c.err(
                "fabric",
                key,
                format!(
                    "{key} is the stiffness a stiffening membrane rises to, but tension is linear"
                ),
                "add tension = \"stiffening\" to [fabric], or remove the key",
            )),
            None => Ok(None),
        },
        Some("stiffening") => {
            let measured = preset.and_then(|p| p.large_strain_n_m);
            let mut v = [0.0f32; 2];
            for (i, (out, (key, given, small_key, small))) in v.iter_mut().zip(axes).enumerate() {
                // A preset's large-strain value belongs to its own small-strain one.
                if given.is_none() && small.is_some() && measured.is_some() {
                    return Err(c.err(
                        "fabric",
                        small_key,
                        format!(
                            "{small_key} is given, but the preset's {key} was measured with the \
                             preset's own {small_key}"
                        ),
                        format!(
                            "give {key} too (the tangent at 1/6 strain), or remove {small_key}"
                        ),
                    ));
                }
                let value = given.or(measured.map(|m| m[i])).ok_or_else(|| {
                    let fix = match preset {
                        Some(p) => format!(
                            "give {key}: the {} preset has no measured large-strain stiffness \
                             (the jersey and denim presets do)",
                            p.name
                        ),
                        None => format!("give {key}, or a preset that has it (jersey, denim)"),
                    };
                    c.err(
                        "fabric",
                        key,
                        format!("missing {key} (tension = \"stiffening\")"),
                        fix,
                    )
                })?;
                *out = c.positive("fabric", key, value, "N/m")?;
            }
            Ok(Some(v))
        }
        Some(other) => Err(c.err(
            "fabric",
            "tension",
            format!(
                "unknown tension {other:?}{}",
                crate::suggest::did_you_mean(other, ["stiffening", "linear"].into_iter())
            ),
            "use tension = \"stiffening\" (the membrane stiffens as it stretches) or \"linear\"",
        )),
    }
}

/// The membrane's bending by direction, as hinge coefficients of warp and weft strips: the
/// scene's `warp_bending_n_m` and `weft_bending_n_m` (both or neither); else the preset's
/// measured strips, unless the scene writes its own `bending_stiffness_n_m` (one value every
/// way); else none.
fn parse_directional_bending(
    c: &Checker,
    f: &RawFabric,
    preset: Option<&FabricPreset>,
) -> Result<Option<[f32; 2]>, InputError> {
    match (f.warp_bending_n_m, f.weft_bending_n_m) {
        (Some(warp), Some(weft)) => Ok(Some([
            c.positive("fabric", "warp_bending_n_m", warp, "N·m")?,
            c.positive("fabric", "weft_bending_n_m", weft, "N·m")?,
        ])),
        (Some(_), None) | (None, Some(_)) => {
            let (given, missing) = match f.warp_bending_n_m {
                Some(_) => ("warp_bending_n_m", "weft_bending_n_m"),
                None => ("weft_bending_n_m", "warp_bending_n_m"),
            };
            Err(c.err(
                "fabric",
                given,
                format!("{given} without {missing}: bending by direction needs both"),
                format!("add {missing} (the same value bends alike every way)"),
            ))
        }
        (None, None) => Ok(match (f.bending_stiffness_n_m, preset) {
            (None, Some(p)) => {
                let [warp, _, weft] = p.strip_bending_n_m;
                Some([warp, weft].map(|b| (HINGE_PER_RIGIDITY * b) as f32))
            }
            _ => None,
        }),
    }
}

/// `model = "membrane"` (the orthotropic membrane, its warp, weft and shear stiffness from the
/// keys or the preset) or `"springs"` (the default: isotropic edge springs).
fn parse_membrane(
    c: &Checker,
    f: &RawFabric,
    preset: Option<&FabricPreset>,
) -> Result<Option<Orthotropic>, InputError> {
    let keys = [
        (
            "warp_stiffness_n_m",
            f.warp_stiffness_n_m,
            preset.map(|p| p.warp_stiffness_n_m),
        ),
        (
            "weft_stiffness_n_m",
            f.weft_stiffness_n_m,
            preset.map(|p| p.weft_stiffness_n_m),
        ),
        (
            "shear_stiffness_n_m",
            f.shear_stiffness_n_m,
            preset.map(|p| p.shear_stiffness_n_m),
        ),
    ];
    let bending_keys = [
        ("warp_bending_n_m", f.warp_bending_n_m, None),
        ("weft_bending_n_m", f.weft_bending_n_m, None),
    ];
    let tension_keys = [
        (
            "warp_large_strain_stiffness_n_m",
            f.warp_large_strain_stiffness_n_m,
            None,
        ),
        (
            "weft_large_strain_stiffness_n_m",
            f.weft_large_strain_stiffness_n_m,
            None,
        ),
    ];
    match f.model.as_deref() {
        None | Some("springs") => {
            match f.tension.as_deref() {
                None | Some("linear") => {}
                Some("stiffening") => return Err(c.err(
                    "fabric",
                    "tension",
                    "tension = \"stiffening\" is a law of the membrane, but the fabric is springs",
                    "add model = \"membrane\" to [fabric], or remove the key",
                )),
                // An unknown value: its own error, with the values there are.
                Some(_) => return parse_tension(c, f, preset).map(|_| None),
            }
            let mut membrane_keys = keys.iter().chain(&bending_keys).chain(&tension_keys);
            if let Some((key, _, _)) = membrane_keys.find(|k| k.1.is_some()) {
                return Err(c.err(
                    "fabric",
                    key,
                    format!("{key} is a membrane stiffness, but the fabric is springs"),
                    "add model = \"membrane\" to [fabric], or remove the key",
                ));
            }
            Ok(None)
        }
        Some("membrane") => {
            let mut v = [0.0f32; 3];
            for (out, (key, given, from_preset)) in v.iter_mut().zip(keys) {
                let value = given.or(from_preset).ok_or_else(|| {
                    c.err(
                        "fabric",
                        key,
                        format!("missing {key} (model = \"membrane\")"),
                        format!("give {key}, or a preset that has it (e.g. preset = \"cotton\")"),
                    )
                })?;
                *out = c.positive("fabric", key, value, "N/m")?;
            }
            let bending = parse_directional_bending(c, f, preset)?;
            Ok(Some(Orthotropic {
                warp: v[0],
                weft: v[1],
                shear: v[2],
                bending,
                large_strain: parse_tension(c, f, preset)?,
            }))
        }
        Some(other) => Err(c.err(
            "fabric",
            "model",
            format!(
                "unknown fabric model {other:?}{}",
                crate::suggest::did_you_mean(other, ["membrane", "springs"].into_iter())
            ),
            "use model = \"membrane\" (warp, weft and shear stiffness) or \"springs\"",
        )),
    }
}
