//! The `[world]` and `[wind]` tables: gravity, air damping and wind.

use super::raw::{RawWind, RawWorld};
use crate::check::Checker;
use crate::error::InputError;
use glam::Vec3;

/// Wind in SI units.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Wind {
    /// Mean wind velocity in m/s.
    pub velocity: Vec3,
    /// Air density in kg/m³.
    pub air_density: f32,
    /// Normal drag coefficient.
    pub drag_coefficient: f32,
    /// Gust amplitude as a fraction of the mean.
    pub gust_amplitude: f32,
    /// Gust frequency in Hz.
    pub gust_frequency: f32,
}

impl Wind {
    /// Wind velocity at time `t`: v·(1 + a·sin(2πft)).
    pub fn at(&self, t: f32) -> Vec3 {
        let phase = 2.0 * std::f32::consts::PI * self.gust_frequency * t;
        self.velocity * (1.0 + self.gust_amplitude * phase.sin())
    }
}

/// The validated `[world]` table.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct World {
    pub(super) gravity: Vec3,
    pub(super) gravity_start: f32,
    pub(super) air_damping: f32,
}

/// Validates `[world]`.
pub(super) fn parse_world(c: &Checker, world: &RawWorld) -> Result<World, InputError> {
    let gravity = c.vec3("world", "gravity_m_s2", world.gravity_m_s2)?;
    let gravity_start = c.non_negative("world", "gravity_start_s", world.gravity_start_s, "s")?;
    let air_damping =
        c.non_negative("world", "air_damping_per_s", world.air_damping_per_s, "1/s")?;
    Ok(World {
        gravity,
        gravity_start,
        air_damping,
    })
}

/// Validates `[wind]`.
pub(super) fn parse_wind(c: &Checker, raw: &Option<RawWind>) -> Result<Option<Wind>, InputError> {
    let wind = match raw {
        None => None,
        Some(w) => Some(Wind {
            velocity: c.vec3("wind", "velocity_m_s", w.velocity_m_s)?,
            air_density: c.positive("wind", "air_density_kg_m3", w.air_density_kg_m3, "kg/m³")?,
            drag_coefficient: c.positive(
                "wind",
                "drag_coefficient",
                w.drag_coefficient,
                "(dimensionless)",
            )?,
            gust_amplitude: c.non_negative(
                "wind",
                "gust_amplitude",
                w.gust_amplitude,
                "fractions of the mean wind",
            )?,
            gust_frequency: c.non_negative(
                "wind",
                "gust_frequency_hz",
                w.gust_frequency_hz,
                "Hz",
            )?,
        }),
    };
    Ok(wind)
}
