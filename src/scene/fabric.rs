//! The `[fabric]` table: areal density, stretch and bending stiffness, damping.

use super::presets::{preset, PRESETS};
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
    let bending = f
        .bending_stiffness_n_m
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
    })
}
