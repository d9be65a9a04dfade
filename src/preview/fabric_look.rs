//! What each fabric preset looks like in previews and exports: a colour a designer would
//! recognise, and the strain range the fabric works in, which the strain preview's scale spans.

use crate::scene::{hex_color, Fabric, DEFAULT_STRAIN_MAX};
use glam::Vec3;

/// A preset's look.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FabricLook {
    /// The preset's name.
    pub preset: &'static str,
    /// Its colour, sRGB `#rrggbb`.
    pub color: &'static str,
    /// The strain shown in full red by default: the largest strain the fabric takes in use.
    pub strain_max: f32,
}

/// Wovens are stiff once their crimp is pulled out: denim reaches the KES tensile test's
/// maximum load (500 gf/cm) at 4.7–5.7% strain (EMT of six denims). Knits stretch far more:
/// a cotton interlock's weft stiffness entry grows twelvefold by 16.7% strain (Wang et al. 2011), so 20% is the end
/// of its working range. Garment leather breaks at about 15% elongation (ISO 3376, quoted
/// by ppf). The sources are the fabric presets' (docs/src/fabrics.md).
pub const LOOKS: [FabricLook; 7] = [
    FabricLook {
        preset: "cotton",
        color: "#a9c1dc",
        strain_max: 0.05,
    },
    FabricLook {
        preset: "denim",
        color: "#3b5a86",
        strain_max: 0.05,
    },
    FabricLook {
        preset: "silk",
        color: "#b03a48",
        strain_max: 0.05,
    },
    FabricLook {
        preset: "polyester",
        color: "#5f8f6a",
        strain_max: 0.05,
    },
    FabricLook {
        preset: "jersey",
        color: "#8a8f96",
        strain_max: 0.20,
    },
    FabricLook {
        preset: "wool",
        color: "#7a6a5a",
        strain_max: 0.05,
    },
    FabricLook {
        preset: "leather",
        color: "#6b4226",
        strain_max: 0.15,
    },
];

/// The colour of a fabric without a preset: a mid blue, sRGB.
pub const PLAIN: &str = "#5991ce";

/// The look of `fabric`'s preset, if it has one.
pub fn look(fabric: &Fabric) -> Option<&'static FabricLook> {
    LOOKS.iter().find(|l| Some(l.preset) == fabric.preset)
}

/// The fabric's colour in linear RGB.
pub fn fabric_color(fabric: &Fabric) -> Vec3 {
    hex_color(look(fabric).map_or(PLAIN, |l| l.color)).expect("the table's colours parse")
}

/// The strain the preview shows in full red for `fabric` when the scene gives none.
pub fn fabric_strain_max(fabric: &Fabric) -> f32 {
    look(fabric).map_or(DEFAULT_STRAIN_MAX, |l| l.strain_max)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_preset_has_a_look_and_every_look_a_preset() {
        let presets: Vec<&str> = crate::scene::PRESETS.iter().map(|p| p.name).collect();
        let looks: Vec<&str> = LOOKS.iter().map(|l| l.preset).collect();
        assert_eq!(presets, looks);
        for l in &LOOKS {
            assert!(hex_color(l.color).is_some(), "{}", l.preset);
        }
    }
}
