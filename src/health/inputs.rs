//! Inputs that parse but make no physical sense: fabric values outside what real fabrics
//! measure, and body meshes of no plausible size. Each is a warning (the run goes on), naming
//! the key, the measured range and the likely slip.
//!
//! The ranges are the measured extremes of the data behind the fabric presets
//! (docs/src/fabrics.md), widened by a factor of 2 on each side: finite samples do not hold the
//! true extremes, while the slips these warnings are for (g/m² for kg/m², kN/m for N/m, a lost
//! exponent) are factors of 10 to 1000.

use crate::body::size::{largest_extent, size_problem};
use crate::body::Body;
use crate::scene::{BodySource, Fabric, FabricPreset, Scene, PRESETS};

/// A quantity's measured range over real garment fabrics, and where it comes from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MeasuredRange {
    /// The `[fabric]` key.
    pub key: &'static str,
    /// Smallest and largest measured value, in the key's unit.
    pub measured: (f64, f64),
    /// The key's unit.
    pub unit: &'static str,
    /// Which fabrics gave the extremes.
    pub source: &'static str,
}

/// Widening of the measured range before a value is called implausible.
pub const MARGIN: f64 = 2.0;

/// Areal density: Feng et al. 2022's 618 garment fabrics, 15 to 870 g/m².
pub const DENSITY: MeasuredRange = MeasuredRange {
    key: "density_kg_m2",
    measured: (0.015, 0.870),
    unit: "kg/m²",
    source: "over 618 garment fabrics (Feng et al. 2022)",
};

/// Stretch stiffness: from a cotton interlock knit's softer axis (21 N/m, lateral edges free,
/// Wang et al. 2011) to garment leather's E·t (77 MPa × 0.75 mm = 5.8e4 N/m).
pub const STRETCH: MeasuredRange = MeasuredRange {
    key: "stretch_stiffness_n_m",
    measured: (21.0, 5.8e4),
    unit: "N/m",
    source: "from a cotton interlock knit to garment leather (Wang et al. 2011; ISO 3376)",
};

/// The membrane's warp and weft: the same measured range as the springs' stretch.
pub const WARP: MeasuredRange = MeasuredRange {
    key: "warp_stiffness_n_m",
    ..STRETCH
};

/// See [`WARP`].
pub const WEFT: MeasuredRange = MeasuredRange {
    key: "weft_stiffness_n_m",
    ..STRETCH
};

/// A stiffening membrane's large-strain tangents along the warp and the weft: the same
/// measured range (the knit's weft at 1/6 strain, 1,717 N/m, lies inside it).
pub const WARP_LARGE: MeasuredRange = MeasuredRange {
    key: "warp_large_strain_stiffness_n_m",
    ..STRETCH
};

/// See [`WARP_LARGE`].
pub const WEFT_LARGE: MeasuredRange = MeasuredRange {
    key: "weft_large_strain_stiffness_n_m",
    ..STRETCH
};

/// In-plane shear: from a polyester jacket fabric's 7.2 N/m (Wang et al. 2011, k3/4) to
/// garment leather's isotropic E·t/3 = 1.9e4 N/m (the leather preset's proxy).
pub const SHEAR: MeasuredRange = MeasuredRange {
    key: "shear_stiffness_n_m",
    measured: (7.2, 1.93e4),
    unit: "N/m",
    source: "from a polyester woven to garment leather (Wang et al. 2011; ISO 3376)",
};

/// Bending: the scene's hinge coefficient is 4 × the bending rigidity (`HINGE_PER_RIGIDITY`);
/// Feng et al. 2022's 618 fabrics span rigidities of 3.4e-7 to 2.7e-4 N·m.
pub const BENDING: MeasuredRange = MeasuredRange {
    key: "bending_stiffness_n_m",
    measured: (4.0 * 3.4e-7, 4.0 * 2.7e-4),
    unit: "N·m",
    source: "4 × the bending rigidity of 618 garment fabrics (Feng et al. 2022)",
};

/// The membrane's hinge coefficients of warp and weft strips, against the same range.
pub const WARP_BENDING: MeasuredRange = MeasuredRange {
    key: "warp_bending_n_m",
    ..BENDING
};

/// See [`WARP_BENDING`].
pub const WEFT_BENDING: MeasuredRange = MeasuredRange {
    key: "weft_bending_n_m",
    ..BENDING
};

/// Every warning about `scene`'s inputs. Loads its body meshes (not their distance fields) to
/// measure them: a body in the wrong unit is named before its distance field's size is refused.
pub fn scene_warnings(scene: &Scene) -> Result<Vec<String>, crate::InputError> {
    let c = scene.checker();
    let bodies = (scene.bodies.iter().enumerate())
        .map(|(i, b)| crate::model::build_body(b, &c, &scene.body_table(i)))
        .collect::<Result<Vec<_>, _>>()?;
    Ok(input_warnings(scene, &bodies))
}

/// Every warning about `scene`'s inputs; `bodies` are its bodies as loaded (in scene order),
/// for their size.
pub fn input_warnings(scene: &Scene, bodies: &[Body]) -> Vec<String> {
    let mut out = fabric_warnings(scene, &scene.fabric);
    for (i, (body, settings)) in bodies.iter().zip(&scene.bodies).enumerate() {
        if let Some((key, size)) = thinnest_shape(&settings.source) {
            if size < settings.sdf_resolution {
                let problem = format!(
                    "the shape is {size:.3e} m thick at its thinnest, less than its \
                     sdf_resolution_m = {} m: its distance field cannot resolve it, and the \
                     cloth may pass through",
                    settings.sdf_resolution
                );
                let fix = "check its size, or use an sdf_resolution_m of a fifth of it";
                out.push(
                    scene
                        .error(&scene.body_table(i), key, problem, fix)
                        .one_line(),
                );
            }
        }
        // Shapes are given in metres by their keys; only a mesh file has a unit to get wrong.
        let BodySource::Mesh { scale, .. } = &settings.source else {
            continue;
        };
        if let Some((problem, fix)) = size_problem(largest_extent(&body.mesh.positions), *scale) {
            let e = scene.error(&scene.body_table(i), "units", problem, fix);
            out.push(e.one_line());
        }
    }
    out
}

/// A shape body's key for its thinnest size and that size (a diameter or a box's side), in m.
fn thinnest_shape(source: &BodySource) -> Option<(&'static str, f32)> {
    match source {
        BodySource::Sphere { radius, .. } | BodySource::Capsule { radius, .. } => {
            Some(("radius_m", 2.0 * radius))
        }
        BodySource::Cuboid { half, .. } => Some(("half_extents_m", 2.0 * half.min_element())),
        _ => None,
    }
}

/// A stiffening membrane whose large-strain stiffness is below its small-strain one softens as
/// it stretches: the law runs it, but every measured fabric stiffens (Wang et al. 2011).
fn softening_warnings(scene: &Scene, m: &crate::scene::Orthotropic) -> Vec<String> {
    let Some(large) = m.large_strain else {
        return Vec::new();
    };
    let axes = [
        ("warp", m.warp, large[0], "warp_large_strain_stiffness_n_m"),
        ("weft", m.weft, large[1], "weft_large_strain_stiffness_n_m"),
    ];
    (axes.into_iter())
        .filter(|a| a.2 < a.1)
        .map(|(axis, small, large, key)| {
            let problem = format!(
                "the {axis}'s large-strain stiffness {} N/m is below its small-strain {} N/m: \
                 the membrane softens as it stretches, where measured fabrics stiffen",
                short(large as f64),
                short(small as f64)
            );
            let fix = format!(
                "give {key} at least {} N/m, or tension = \"linear\"",
                short(small as f64)
            );
            scene.error("fabric", key, problem, fix).one_line()
        })
        .collect()
}

/// The fabric's values outside `MARGIN` × the measured ranges, a stiffening membrane that
/// softens, and buckling without bending.
pub fn fabric_warnings(scene: &Scene, fabric: &Fabric) -> Vec<String> {
    let m = fabric.membrane;
    let values = [
        (DENSITY, Some(fabric.density as f64)),
        (STRETCH, Some(fabric.stretch_stiffness as f64)),
        (BENDING, fabric.bending_stiffness.map(f64::from)),
        (WARP, m.map(|m| m.warp as f64)),
        (WEFT, m.map(|m| m.weft as f64)),
        (SHEAR, m.map(|m| m.shear as f64)),
        (
            WARP_LARGE,
            m.and_then(|m| m.large_strain).map(|l| l[0] as f64),
        ),
        (
            WEFT_LARGE,
            m.and_then(|m| m.large_strain).map(|l| l[1] as f64),
        ),
        (WARP_BENDING, m.and_then(|m| m.bending).map(|b| b[0] as f64)),
        (WEFT_BENDING, m.and_then(|m| m.bending).map(|b| b[1] as f64)),
    ];
    let mut out = Vec::new();
    for (range, value) in values {
        let Some(v) = value else { continue };
        let (lo, hi) = (range.measured.0 / MARGIN, range.measured.1 * MARGIN);
        if (lo..=hi).contains(&v) {
            continue;
        }
        let side = if v < lo { "below" } else { "above" };
        let problem = format!(
            "{} {} is {side} any real garment fabric's ({} to {} {}, {}): the run goes on, but \
             it drapes no real cloth",
            short(v),
            range.unit,
            short(range.measured.0),
            short(range.measured.1),
            range.unit,
            range.source
        );
        let e = scene.error("fabric", range.key, problem, fix(&range, v));
        out.push(e.one_line());
    }
    if let Some(m) = m {
        out.extend(softening_warnings(scene, &m));
    }
    if fabric.buckling && fabric.bending_stiffness.is_none() {
        let e = scene.error(
            "fabric",
            "compression",
            format!(
                "compression = \"buckling\" without bending: with no bending rigidity to hold \
                 it flat, every compressed edge buckles at once and keeps {:.0}% of its stiffness",
                100.0 * crate::scene::BUCKLED_FRACTION
            ),
            "give bending_stiffness_n_m (or a preset), or remove compression",
        );
        out.push(e.one_line());
    }
    out
}

/// The fix for an implausible `v`: the scaled value a common unit slip would have meant, if one
/// brings it into the measured range, and a preset as an example of real values.
fn fix(range: &MeasuredRange, v: f64) -> String {
    let slips: [(f64, &str); 4] = match range.key {
        "density_kg_m2" => [
            (1e-3, "it was written in g/m² (220 g/m² is 0.220 kg/m²)"),
            (1e-2, "a decimal point slipped"),
            (1e2, "a decimal point slipped"),
            (1e3, "it was written in kg per 1000 m²"),
        ],
        _ => [
            (1e3, "it was written in kN/m (or N/mm)"),
            (1e-3, "it was written in mN/m"),
            (1e-2, "a decimal point slipped"),
            (1e2, "a decimal point slipped"),
        ],
    };
    let cotton: &FabricPreset = &PRESETS[0];
    let example = match range.key {
        "density_kg_m2" => cotton.density_kg_m2,
        "stretch_stiffness_n_m" => cotton.stretch_stiffness_n_m,
        "warp_stiffness_n_m" => cotton.warp_stiffness_n_m,
        "weft_stiffness_n_m" => cotton.weft_stiffness_n_m,
        "shear_stiffness_n_m" => cotton.shear_stiffness_n_m,
        _ => crate::scene::HINGE_PER_RIGIDITY * cotton.bending_stiffness_n_m,
    };
    let meant = (slips.iter())
        .find(|(f, _)| (range.measured.0..=range.measured.1).contains(&(v * f)))
        .map(|(f, why)| format!("if {why}, write {}; ", short(v * f)));
    format!(
        "{}check the unit, {} (woven cotton has {}), or use a preset (preset = \"cotton\")",
        meant.unwrap_or_default(),
        range.unit,
        short(example)
    )
}

/// A value in at most 3 significant digits: "220", "0.22", "4.05e3", "2e-5".
fn short(v: f64) -> String {
    if v != 0.0 && !(1e-2..1e4).contains(&v.abs()) {
        let s = format!("{v:.2e}");
        let (m, e) = s.split_once('e').unwrap_or((&s, "0"));
        let m = m.trim_end_matches('0').trim_end_matches('.');
        return format!("{m}e{e}");
    }
    let s = format!("{v:.3}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    s.to_string()
}

/// `--frames N` for `scene`: at least one frame (frame 0 is the start, not a simulated frame).
pub fn check_frames(scene: &Scene, frames: u32) -> Result<u32, crate::error::Error> {
    if frames == 0 {
        return Err(crate::error::Error::Input(crate::error::InputError::new(
            &scene.path,
            "--frames",
            "0 output frames simulate nothing (frame 0 is the starting state)",
            "give --frames 1 or more, or leave it out to run the scene's solver.frames",
        )));
    }
    Ok(frames)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    fn scene(fabric: &str) -> Scene {
        let text = format!(
            "[cloth.grid]\nwidth_m = 1.0\nheight_m = 1.0\ncolumns = 4\nrows = 4\n\n[fabric]\n{fabric}\n\n[solver]\nfps = 24\nframes = 1\n"
        );
        Scene::parse(&text, Path::new("scene.toml")).unwrap()
    }

    #[test]
    fn unit_slips_in_the_fabric_are_named_with_the_value_meant() {
        // The slips a new user made: grams for kilograms, a lost "000".
        let s =
            scene("density_kg_m2 = 220\nstretch_stiffness_n_m = 3\nbending_stiffness_n_m = 2e-5");
        let w = fabric_warnings(&s, &s.fabric);
        assert_eq!(w.len(), 2, "{w:?}");
        assert!(
            w[0].starts_with("scene.toml:8: fabric.density_kg_m2: 220 kg/m² is above"),
            "{}",
            w[0]
        );
        assert!(w[0].contains("write 0.22"), "{}", w[0]);
        assert!(
            w[1].contains("fabric.stretch_stiffness_n_m: 3 N/m is below"),
            "{}",
            w[1]
        );
        assert!(w[1].contains("write 3000"), "{}", w[1]);
        // Bending a thousand times too stiff.
        let s = scene("preset = \"cotton\"\nbending_stiffness_n_m = 0.1");
        let w = fabric_warnings(&s, &s.fabric);
        assert_eq!(w.len(), 1, "{w:?}");
        assert!(
            w[0].contains("bending_stiffness_n_m: 0.1 N·m is above"),
            "{}",
            w[0]
        );
    }

    #[test]
    fn every_preset_and_the_range_edges_are_plausible() {
        for p in PRESETS {
            for model in ["springs", "membrane"] {
                let s = scene(&format!("preset = \"{}\"\nmodel = \"{model}\"", p.name));
                assert!(fabric_warnings(&s, &s.fabric).is_empty(), "{}", p.name);
            }
        }
        // A shear given in kN/m.
        let s = scene("preset = \"cotton\"\nmodel = \"membrane\"\nshear_stiffness_n_m = 0.052");
        let w = fabric_warnings(&s, &s.fabric);
        assert_eq!(w.len(), 1, "{w:?}");
        assert!(
            w[0].contains("shear_stiffness_n_m: 0.052 N/m is below"),
            "{}",
            w[0]
        );
        assert!(w[0].contains("write 52"), "{}", w[0]);
        // Just inside the widened range, and just outside it.
        let s = scene("density_kg_m2 = 1.7\nstretch_stiffness_n_m = 11");
        assert!(fabric_warnings(&s, &s.fabric).is_empty());
        let s = scene("density_kg_m2 = 1.8\nstretch_stiffness_n_m = 10");
        assert_eq!(fabric_warnings(&s, &s.fabric).len(), 2);
    }

    #[test]
    fn buckling_without_bending_is_warned() {
        let plain = "density_kg_m2 = 0.2\nstretch_stiffness_n_m = 500\ncompression = \"buckling\"";
        let s = scene(plain);
        let w = fabric_warnings(&s, &s.fabric);
        assert_eq!(w.len(), 1, "{w:?}");
        assert!(
            w[0].starts_with(
                "scene.toml:10: fabric.compression: compression = \"buckling\" without bending"
            ),
            "{}",
            w[0]
        );
        let s = scene(&format!("{plain}\nbending_stiffness_n_m = 2e-5"));
        assert!(fabric_warnings(&s, &s.fabric).is_empty());
    }

    #[test]
    fn measured_stiffening_is_plausible_and_softening_is_warned() {
        for p in PRESETS.iter().filter(|p| p.large_strain_n_m.is_some()) {
            let text = format!(
                "preset = \"{}\"\nmodel = \"membrane\"\ntension = \"stiffening\"",
                p.name
            );
            let s = scene(&text);
            assert!(fabric_warnings(&s, &s.fabric).is_empty(), "{}", p.name);
        }
        let s = scene(
            "preset = \"jersey\"\nmodel = \"membrane\"\ntension = \"stiffening\"\n\
             weft_large_strain_stiffness_n_m = 30",
        );
        let w = fabric_warnings(&s, &s.fabric);
        assert_eq!(w.len(), 1, "{w:?}");
        assert!(
            w[0].contains("fabric.weft_large_strain_stiffness_n_m: the weft's large-strain stiffness 30 N/m is below its small-strain 42.9"),
            "{}",
            w[0]
        );
        // A large-strain tangent a million times the jersey's: past any fabric's stretch.
        let s = scene(
            "preset = \"jersey\"\nmodel = \"membrane\"\ntension = \"stiffening\"\n\
             warp_large_strain_stiffness_n_m = 157900000",
        );
        let w = fabric_warnings(&s, &s.fabric);
        assert_eq!(w.len(), 1, "{w:?}");
        assert!(
            w[0].contains("fabric.warp_large_strain_stiffness_n_m: 1.58e8 N/m is above"),
            "{}",
            w[0]
        );
    }

    #[test]
    fn short_numbers() {
        assert_eq!(short(220.0), "220");
        assert_eq!(short(0.22), "0.22");
        assert_eq!(short(4050.0), "4050");
        assert_eq!(short(58000.0), "5.8e4");
        assert_eq!(short(2e-5), "2e-5");
        assert_eq!(short(1.36e-6), "1.36e-6");
    }
}
