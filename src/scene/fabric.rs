//! The `[fabric]` table: areal density, stretch and bending stiffness, damping.

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
}

/// Validates `[fabric]`.
pub(super) fn parse(c: &Checker, f: &RawFabric) -> Result<Fabric, InputError> {
    Ok(Fabric {
        density: c.positive("fabric", "density_kg_m2", f.density_kg_m2, "kg/m²")?,
        stretch_stiffness: c.positive(
            "fabric",
            "stretch_stiffness_n_m",
            f.stretch_stiffness_n_m,
            "N/m",
        )?,
        bending_stiffness: match f.bending_stiffness_n_m {
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
            f.damping_ratio,
            "fractions of critical damping",
        )?,
    })
}
