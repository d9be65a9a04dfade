//! Why a run exploded, when the scene rather than the substep is the likely cause: the advice
//! an exploded frame's error gives first.

use super::Prepared;

/// What in the scene, rather than the substep, most likely tore the cloth apart, with its fix:
/// seams far stiffer than the fabric, a self-collision layer far thicker than the edges, or a
/// wind whose drag already set the substep.
pub(super) fn cause(prep: &Prepared) -> Option<String> {
    if let Some(r) = prep
        .seam_stiffness_ratio
        .filter(|&r| r > crate::scene::limits::MAX_SEAM_STIFFNESS_RATIO)
    {
        return Some(format!(
            "the seams pulled the panels together at once: cloth.pattern.seam_stiffness_n_m \
             is {r:.0} times the fabric's stretch stiffness; leave it out (twice the fabric's)"
        ));
    }
    let springs = &prep.model.springs;
    let mean_edge =
        springs.iter().map(|s| s.rest_length).sum::<f32>() / springs.len().max(1) as f32;
    let thickness = prep.params.self_thickness;
    if prep.plan.contains(crate::plan::Pass::SelfCollide) && thickness > 2.0 * mean_edge {
        return Some(format!(
            "self-collision pushed the cloth apart: self_collision.thickness_m ({thickness} m) \
             is {:.0} times the mean edge; leave it out (0.75 times the edge)",
            thickness / mean_edge
        ));
    }
    let wind = prep.wind.as_ref()?;
    if prep.dt_limited_by != "wind drag" {
        return None;
    }
    let gust = wind.velocity.length() * (1.0 + wind.gust_amplitude);
    Some(if gust > STORM_WIND_SPEED {
        format!(
            "chosen for the wind's drag, the wind tore the cloth: its gusts ({gust:.0} m/s) are \
             past what cloth survives; give at most a storm's (about {STORM_WIND_SPEED:.0} m/s)"
        )
    } else {
        "chosen for the wind's drag, the drag tore the cloth: check wind.drag_coefficient and \
         air_density_kg_m3 (about 1 and 1.2), and the fabric's density_kg_m2"
            .to_string()
    })
}

/// A storm's wind, in m/s (force 10 to 11): faster gusts tear cloth apart.
const STORM_WIND_SPEED: f32 = 30.0;
