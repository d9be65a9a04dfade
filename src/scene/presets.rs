//! Named fabric presets for `[fabric] preset = "..."`: areal density, stretch and bending
//! stiffness, and damping for seven garment fabrics, from published measurements where they
//! exist. The book's "Fabrics" chapter (docs/src/fabrics.md) lists the sources and says which
//! values are proxies. A key written next to `preset` in `[fabric]` overrides that preset's value.
//!
//! The revisions of the repositories read for the sources: wxhaooo/lyra 5158f74 (the W11
//! material files), zhou13/arcsim 16f970e (the W11 units and hinge energy),
//! DrapeTester/ClothDrapeTester 24a980c (Feng et al. 2022's dataset), st-tech/ppf-contact-solver
//! f23b356 (the secondhand stretch quotes).
//!
//! Conventions, shared by every row:
//! - Stretch is the small-strain (zero-strain sample) uniaxial stiffness with the lateral edges
//!   free, k = k0 − k1²/k2: the quantity the model's Y is (edge springs Y·ΣA/L² on an
//!   equilateral mesh give a uniaxial stiffness of Y). The model is isotropic, so the two
//!   material axes are combined by their geometric mean √(k_u·k_v), which is the same factor from
//!   each axis; the weaker axis alone would make denim 2.2× softer than this. The Wang et al.
//!   2011 ("W11") files store half the stiffness: k0 = 2·json[0][0], k1 = 2·json[0][1],
//!   k2 = 2·json[0][2].
//! - Bending is the continuum rigidity B (moment per unit width per unit curvature). For W11 it
//!   is B = ke/4 from the lowest-curvature hinge sample, and the geometric mean of the 0° and 90°
//!   hinge rows. For the Feng et al. 2022 class medians it is the geometric mean of warp and weft.
//! - Damping has no measured source: 0.05 of critical everywhere, a modelling choice.
//!
//! Tags in the comments: [M] measured, [D] derived from [M], [2] secondhand, [P] proxy (real
//! data, not this fabric), [low] engine or vendor page.

/// A named fabric with values from published measurements (see docs/src/fabrics.md).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FabricPreset {
    /// The name used in `[fabric] preset`.
    pub name: &'static str,
    /// Areal density in kg/m².
    pub density_kg_m2: f64,
    /// Membrane stretch stiffness in N/m.
    pub stretch_stiffness_n_m: f64,
    /// Bending rigidity in N·m.
    pub bending_stiffness_n_m: f64,
    /// The membrane's small-strain stiffness along the warp, lateral edges free, in N/m.
    pub warp_stiffness_n_m: f64,
    /// Along the weft, in N/m.
    pub weft_stiffness_n_m: f64,
    /// In-plane shear, in N/m per radian (τ/γ).
    pub shear_stiffness_n_m: f64,
    /// The membrane's bending rigidity B of a strip cut along the warp, on the bias (45°) and
    /// along the weft, in N·m (`bending_stiffness_n_m` is the isotropic springs' value).
    pub strip_bending_n_m: [f64; 3],
    /// The membrane's tangent stiffness along the warp and the weft at `LARGE_STRAIN` (1/6),
    /// lateral edges free, in N/m, where measured: `tension = "stiffening"` rises to them.
    pub large_strain_n_m: Option<[f64; 2]>,
    /// Spring damping as a fraction of critical.
    pub damping_ratio: f64,
    /// Where the values come from, in one line.
    pub source: &'static str,
}

/// Every preset, in the order the book lists them.
pub const PRESETS: &[FabricPreset] = &[
    FabricPreset {
        name: "cotton",
        // 220 g/m² / 1000 = 0.220 kg/m². W11 royal-target, a 65/35 cotton/PES pants woven [M];
        // used as a proxy for shirting, which no source measured (shirting is lighter).
        density_kg_m2: 0.220,
        // u: 2·2016.55 = 4033.1, v: 2·2034.98 = 4069.9, k1 = 18.3; lateral-free 4033.0 / 4069.9;
        // √(4033.0·4069.9) = 4051 N/m [D]. Probably the W11 rig's ceiling: a lower bound.
        stretch_stiffness_n_m: 4.05e3,
        // ke 0° = 90° = 125.41e-6; √(125.41e-6·125.41e-6) / 4 = 3.135e-5 N·m [D].
        bending_stiffness_n_m: 3.14e-5,
        // Membrane: u = warp 4033.0, v = weft 4069.9 (lateral-free, above; the W11 files do not
        // say which axis is the warp: drapekit takes u) [D]. Shear k3/4 = 52 N/m [D].
        warp_stiffness_n_m: 4033.0,
        weft_stiffness_n_m: 4069.9,
        shear_stiffness_n_m: 52.0,
        // Strips along u, on the bias, along v: the 90°, 45° and 0° hinge rows (a hinge's angle
        // is its edge's, and a strip along u bends across edges at 90°), /4: 125.41e-6,
        // 107.998e-6, 125.41e-6 → 3.135e-5, 2.700e-5, 3.135e-5 N·m [D].
        strip_bending_n_m: [3.135e-5, 2.700e-5, 3.135e-5],
        large_strain_n_m: None,
        // Modelling choice: no measured source.
        damping_ratio: 0.05,
        source: "W11 royal-target (65/35 cotton/PES woven), proxy for shirting [M/D]",
    },
    FabricPreset {
        name: "denim",
        // 324 g/m² / 1000 = 0.324 kg/m². W11 11oz-black-denim, 99/1 cotton/spandex [M].
        density_kg_m2: 0.324,
        // u: 2·205.35 = 410.7, v: 2·1013.89 = 2027.8, k1 = 20.5; lateral-free 410.5 / 2026.8;
        // √(410.5·2026.8) = 912.1 N/m [D]. Crimp region; a KES secant at Fm is 4–25× stiffer.
        stretch_stiffness_n_m: 912.0,
        // ke 0° 64.196e-6, 90° 96.952e-6; √(64.196e-6·96.952e-6) / 4 = 1.972e-5 N·m [D].
        // Cross-check: KES B 0.144–0.227 gf·cm²/cm × 9.80665e-5 = 1.41–2.23e-5 N·m [M→D].
        bending_stiffness_n_m: 1.97e-5,
        // Membrane: u = warp 410.5, v = weft 2026.8 (lateral-free) [D]. Shear k3/4 = 27 N/m [D]
        // (KES G of regenerated-cellulose denims: 84–191 N/m/rad [M→D], at larger shear).
        warp_stiffness_n_m: 410.5,
        weft_stiffness_n_m: 2026.8,
        shear_stiffness_n_m: 27.0,
        // Strips along u, on the bias, along v: the 90°, 45° and 0° hinge rows /4: 96.952e-6,
        // 73.385e-6, 64.196e-6 → 2.424e-5, 1.835e-5, 1.605e-5 N·m [D].
        strip_bending_n_m: [2.424e-5, 1.835e-5, 1.605e-5],
        // Tangent stiffness at 1/6 strain (the W11 large-strain sample, lateral edges free),
        // chosen so that the tension there is W11's: its rows at 0° and 90° give
        // u: 2·232.03 − (2·40.65)²/(2·1052.84) = 460.92, v: 2·1051.56 − (2·40.92)²/(2·225.77)
        // = 2088.3 N/m; its uniaxial tension (1 + e)·k·(e + e²/2) at e = 1/6 is 97.09 and
        // 439.89 N/m; the law's, e·(k_small + k_large)/2, matches at k_large = 2T/e − k_small
        // = 754.6 and 3,252 N/m [D]: 1.8× and 1.6× the small-strain values.
        large_strain_n_m: Some([754.6, 3252.0]),
        // Modelling choice: no measured source.
        damping_ratio: 0.05,
        source: "W11 11oz-black-denim [M/D]; bending agrees with KES denim [M→D]",
    },
    FabricPreset {
        name: "silk",
        // ≈60 g/m² / 1000 = 0.060 kg/m²: 14-momme crêpe de chine, 14 × 4.34 = 60.8 g/m² [low].
        density_kg_m2: 0.060,
        // "E·t ≈ 500 N/m", a solver-calibration note [2, weak]; no silk measurement found.
        stretch_stiffness_n_m: 500.0,
        // Median of Feng 2022 fabrics under 0.1 kg/m², 2.6e-6 N·m (IQR 1.3–5.1e-6) [P].
        bending_stiffness_n_m: 2.6e-6,
        // Membrane: no silk measurement; both axes take the stretch note above [2], and shear
        // takes cotton's measured shear-to-stretch ratio, 52/4051 = 0.0128: 500 × 0.0128 = 6.4
        // N/m [P].
        warp_stiffness_n_m: 500.0,
        weft_stiffness_n_m: 500.0,
        shear_stiffness_n_m: 6.4,
        // One class median, no direction [P].
        strip_bending_n_m: [2.6e-6, 2.6e-6, 2.6e-6],
        large_strain_n_m: None,
        // Modelling choice: no measured source.
        damping_ratio: 0.05,
        source: "density vendor [low]; stretch ppf note [2]; bending Feng 2022 < 0.1 kg/m² [P]",
    },
    FabricPreset {
        name: "polyester",
        // 128 g/m² / 1000 = 0.128 kg/m². W11 white-dots-on-blk, 100 % PES tablecloth [M].
        density_kg_m2: 0.128,
        // u: 2·2002.09 = 4004.2, v: 2·2027.49 = 4055.0, k1 = 0.69; lateral-free the same;
        // √(4004.2·4055.0) = 4029 N/m [D]. Probably the W11 rig's ceiling: a lower bound.
        stretch_stiffness_n_m: 4.03e3,
        // ke 0° 51.714e-6, 90° 31.283e-6; √(51.714e-6·31.283e-6) / 4 = 1.006e-5 N·m [D].
        bending_stiffness_n_m: 1.01e-5,
        // Membrane: u = warp 4004.2, v = weft 4055.0 [D]. Shear k3/4 = 9.6 N/m [D].
        warp_stiffness_n_m: 4004.2,
        weft_stiffness_n_m: 4055.0,
        shear_stiffness_n_m: 9.6,
        // Strips along u, on the bias, along v: the 90°, 45° and 0° hinge rows /4: 31.283e-6,
        // 40.659e-6, 51.714e-6 → 7.82e-6, 1.016e-5, 1.293e-5 N·m [D].
        strip_bending_n_m: [7.82e-6, 1.016e-5, 1.293e-5],
        large_strain_n_m: None,
        // Modelling choice: no measured source.
        damping_ratio: 0.05,
        source: "W11 white-dots-on-blk (100 % polyester tablecloth) [M/D]",
    },
    FabricPreset {
        name: "jersey",
        // 187 g/m² / 1000 = 0.187 kg/m². W11 gray-interlock, 60/40 cotton/PES T-shirt [M].
        density_kg_m2: 0.187,
        // u: 2·16.59 = 33.19, v: 2·34.48 = 68.95, k1 = −29.39; lateral-free
        // 33.19 − 29.39²/68.95 = 20.66, 68.95 − 29.39²/33.19 = 42.92; √(20.66·42.92) = 29.8 [D].
        // Stiffens steeply: 93 / 812 N/m at ≈17 % strain.
        stretch_stiffness_n_m: 29.8,
        // ke 0° 23.192e-6, 90° 14.268e-6; √(23.192e-6·14.268e-6) / 4 = 4.548e-6 N·m [D].
        bending_stiffness_n_m: 4.55e-6,
        // Membrane: u = 20.66, v = 42.92 (lateral-free, above) [D]; a knit's wales and courses
        // stand in for warp and weft. Shear k3/4 = 18 N/m [D].
        warp_stiffness_n_m: 20.66,
        weft_stiffness_n_m: 42.92,
        shear_stiffness_n_m: 18.0,
        // Strips along u, on the bias, along v: the 90°, 45° and 0° hinge rows /4: 14.268e-6,
        // 24.750e-6, 23.192e-6 → 3.57e-6, 6.19e-6, 5.80e-6 N·m [D].
        strip_bending_n_m: [3.57e-6, 6.19e-6, 5.80e-6],
        // Tangent stiffness at 1/6 strain, as for denim: W11 rows at 0° and 90° give u:
        // 2·46.365 − (2·53.695)²/(2·261.014) = 70.64, v: 2·405.873 − (2·85.849)²/(2·127.444)
        // = 696.1 N/m; tension at 1/6: 14.88 and 146.6 N/m; k_large = 2T/e − k_small =
        // 157.9 and 1,717 N/m [D]: 7.6× and 40× the small-strain values.
        large_strain_n_m: Some([157.9, 1716.6]),
        // Modelling choice: no measured source.
        damping_ratio: 0.05,
        source: "W11 gray-interlock (60/40 cotton/PES knit) [M/D]",
    },
    FabricPreset {
        name: "wool",
        // No suiting weight in any source: 0.25 kg/m² is assumed, the centre of the Feng 2022
        // 0.2–0.3 kg/m² class whose bending is used below. Melton coat cloth: 0.7 [low].
        density_kg_m2: 0.25,
        // "FAST/SiroFAST secant ≈3 000 N/m", a solver note; no primary table seen [2].
        stretch_stiffness_n_m: 3.0e3,
        // Feng 2022 fabrics of 0.2–0.3 kg/m²: medians warp 2.0e-5, weft 1.5e-5;
        // √(2.0e-5·1.5e-5) = 1.732e-5 N·m [P].
        bending_stiffness_n_m: 1.73e-5,
        // Membrane: both axes take the FAST note above [2]; shear takes cotton's measured
        // shear-to-stretch ratio 0.0128: 3000 × 0.0128 = 38.5 N/m [P].
        warp_stiffness_n_m: 3.0e3,
        weft_stiffness_n_m: 3.0e3,
        shear_stiffness_n_m: 38.5,
        // Strips: the class medians warp 2.0e-5 and weft 1.5e-5; no bias value was measured, so
        // the bias takes their geometric mean, 1.73e-5 N·m [P].
        strip_bending_n_m: [2.0e-5, 1.73e-5, 1.5e-5],
        large_strain_n_m: None,
        // Modelling choice: no measured source.
        damping_ratio: 0.05,
        source: "density assumed; stretch FAST note [2]; bending Feng 2022 0.2–0.3 kg/m² [P]",
    },
    FabricPreset {
        name: "leather",
        // Unreal Chaos Cloth "light leather 0.3" kg/m² [low]; garment sheep leather is
        // 0.64–0.96 mm thick [M], but no measured areal density was found.
        density_kg_m2: 0.30,
        // E ≈ 77 MPa × t ≈ 0.75 mm: 77e6 Pa × 0.75e-3 m = 57 750 N/m [2] (ISO 3376, via ppf).
        stretch_stiffness_n_m: 5.78e4,
        // The measured rigidity (9.2–22) has no unit in the abstract, so it is unusable; the
        // Feng 2022 0.2–0.3 kg/m² class is used: √(2.0e-5·1.5e-5) = 1.732e-5 N·m [P].
        bending_stiffness_n_m: 1.73e-5,
        // Membrane: leather has no weave; isotropic E·t both ways [2], and the isotropic shear
        // E·t/(2(1 + ν)) with ν = 0.5 (no measured Poisson ratio found; 0.5 is the
        // incompressible bound, the softest shear): 57 750 / 3 = 19 250 N/m [P].
        warp_stiffness_n_m: 5.78e4,
        weft_stiffness_n_m: 5.78e4,
        shear_stiffness_n_m: 1.925e4,
        // Leather has no weave: the same rigidity every way [P].
        strip_bending_n_m: [1.73e-5, 1.73e-5, 1.73e-5],
        large_strain_n_m: None,
        // Modelling choice: no measured source.
        damping_ratio: 0.05,
        source: "density Unreal [low]; stretch Efendioglu via ppf [2]; bending Feng 2022 [P]",
    },
];

/// The preset of this name, if any.
pub fn preset(name: &str) -> Option<&'static FabricPreset> {
    PRESETS.iter().find(|p| p.name == name)
}

#[cfg(test)]
mod tests {
    use super::*;

    const GRAVITY: f64 = 9.80665;

    fn get(name: &str) -> &'static FabricPreset {
        preset(name).unwrap_or_else(|| panic!("no preset {name}"))
    }

    fn close(a: f64, b: f64, rel: f64) -> bool {
        (a - b).abs() <= rel * b.abs()
    }

    #[test]
    fn names_are_unique_in_readme_order_and_found() {
        let names: Vec<_> = PRESETS.iter().map(|p| p.name).collect();
        let order = [
            "cotton",
            "denim",
            "silk",
            "polyester",
            "jersey",
            "wool",
            "leather",
        ];
        assert_eq!(names, order);
        for p in PRESETS {
            assert_eq!(preset(p.name), Some(p));
        }
        assert_eq!(preset("linen"), None);
        assert_eq!(preset("Denim"), None);
    }

    #[test]
    fn every_value_is_finite_and_positive_and_sourced() {
        for p in PRESETS {
            for v in [
                p.density_kg_m2,
                p.stretch_stiffness_n_m,
                p.warp_stiffness_n_m,
                p.weft_stiffness_n_m,
                p.shear_stiffness_n_m,
                p.bending_stiffness_n_m,
                p.damping_ratio,
            ] {
                assert!(v.is_finite() && v > 0.0, "{}: {v}", p.name);
            }
            assert!(p.damping_ratio < 1.0, "{}", p.name);
            assert!(!p.source.is_empty(), "{}", p.name);
            assert!(!p.source.contains('\n'), "{}", p.name);
        }
    }

    #[test]
    fn damping_is_the_modelling_default_everywhere() {
        assert!(PRESETS.iter().all(|p| p.damping_ratio == 0.05));
    }

    #[test]
    fn wovens_are_at_least_ten_times_stiffer_than_the_knit() {
        let knit = get("jersey").stretch_stiffness_n_m;
        for name in ["cotton", "denim", "polyester"] {
            let k = get(name).stretch_stiffness_n_m;
            assert!(k >= 10.0 * knit, "{name}: {k} vs jersey {knit}");
        }
        // Woven cotton in the thousands of N/m, the knit in the tens to hundreds.
        assert!(get("cotton").stretch_stiffness_n_m >= 1.0e3);
        assert!((10.0..1.0e3).contains(&knit));
    }

    #[test]
    fn w11_conversions_reproduce_the_presets() {
        // Zero-strain stretching row [k0, k1, k2, k3] / 2 and the first bending column for the
        // 0°, 45° and 90° hinges, as printed in the W11 material files.
        let rows: [(&str, [f64; 3], [f64; 3]); 4] = [
            (
                "cotton",
                [2016.55456, 9.170511, 2034.97644],
                [125.409805e-6, 107.997696e-6, 125.409805e-6],
            ),
            (
                "denim",
                [205.352005, 10.234077, 1013.88629],
                [64.196457e-6, 73.384567e-6, 96.951576e-6],
            ),
            (
                "polyester",
                [2002.08618, 0.345588, 2027.48559],
                [51.713814e-6, 40.659470e-6, 31.282822e-6],
            ),
            (
                "jersey",
                [16.593832, -14.695990, 34.477123],
                [23.191698e-6, 24.749964e-6, 14.267624e-6],
            ),
        ];
        for (name, [h0, h1, h2], [ke0, ke45, ke90]) in rows {
            let (k0, k1, k2) = (2.0 * h0, 2.0 * h1, 2.0 * h2);
            let free_u = k0 - k1 * k1 / k2;
            let free_v = k2 - k1 * k1 / k0;
            let p = get(name);
            // The membrane takes the axes themselves (u as the warp).
            assert!(
                close(p.warp_stiffness_n_m, free_u, 0.005),
                "{name}: {free_u}"
            );
            assert!(
                close(p.weft_stiffness_n_m, free_v, 0.005),
                "{name}: {free_v}"
            );
            let k = (free_u * free_v).sqrt();
            assert!(close(p.stretch_stiffness_n_m, k, 0.005), "{name}: {k}");
            let b = (ke0 * ke90).sqrt() / 4.0;
            assert!(close(p.bending_stiffness_n_m, b, 0.005), "{name}: {b}");
            // A hinge's angle is its edge's: a strip along the warp (u) bends across the 90°
            // hinges, a strip along the weft across the 0° ones.
            for (got, ke) in p.strip_bending_n_m.iter().zip([ke90, ke45, ke0]) {
                assert!(
                    close(*got, ke / 4.0, 0.005),
                    "{name}: {got} vs {}",
                    ke / 4.0
                );
            }
        }
        // The W11 files give areal density in kg/m²: 220, 324, 128 and 187 g/m² / 1000.
        let densities = [
            ("cotton", 220.0),
            ("denim", 324.0),
            ("polyester", 128.0),
            ("jersey", 187.0),
        ];
        for (name, g_m2) in densities {
            assert_eq!(get(name).density_kg_m2, g_m2 / 1000.0, "{name}");
        }
    }

    #[test]
    fn membrane_proxies_follow_their_stated_arithmetic() {
        // Silk and wool: both axes the quoted stretch, shear at cotton's measured ratio.
        let ratio = get("cotton").shear_stiffness_n_m
            / (get("cotton").warp_stiffness_n_m * get("cotton").weft_stiffness_n_m).sqrt();
        for name in ["silk", "wool"] {
            let p = get(name);
            assert_eq!(p.warp_stiffness_n_m, p.stretch_stiffness_n_m, "{name}");
            assert_eq!(p.weft_stiffness_n_m, p.stretch_stiffness_n_m, "{name}");
            let shear = ratio * p.stretch_stiffness_n_m;
            assert!(close(p.shear_stiffness_n_m, shear, 0.01), "{name}: {shear}");
        }
        // Leather: isotropic, G = E·t / (2(1 + ν)) with ν = 0.5.
        let p = get("leather");
        assert!(close(
            p.shear_stiffness_n_m,
            p.warp_stiffness_n_m / 3.0,
            0.005
        ));
        // Every woven shears far more easily than it stretches (W11: 1.3% for cotton, 3% for
        // denim's geometric mean, 0.24% for the polyester tablecloth).
        for name in ["cotton", "denim", "silk", "polyester", "wool"] {
            let p = get(name);
            let stiffer = p.warp_stiffness_n_m.max(p.weft_stiffness_n_m);
            assert!(p.shear_stiffness_n_m < 0.05 * stiffer, "{name}");
        }
    }

    #[test]
    fn large_strain_stiffness_reproduces_w11_s_tension_at_one_sixth() {
        // The W11 large-strain rows at principal directions 0° (along u) and 90° (along v),
        // [k0, k1, k2] / 2 as printed; the lateral-free stiffness of each, the fitted model's
        // uniaxial tension (1 + e)·k·(e + e²/2) at e = 1/6 (second Piola–Kirchhoff stress on
        // the Green strain, times the stretch), and the tangent the law's trapezoid needs to
        // reach it: k_large = 2T/e − k_small.
        let e = 1.0 / 6.0;
        let free_u = |r: [f64; 3]| 2.0 * (r[0] - r[1] * r[1] / r[2]);
        let free_v = |r: [f64; 3]| 2.0 * (r[2] - r[1] * r[1] / r[0]);
        let large = |k_free: f64, small: f64| {
            let tension = (1.0 + e) * k_free * (e + 0.5 * e * e);
            2.0 * tension / e - small
        };
        let rows = [
            (
                "denim",
                [232.027634, 40.646339, 1052.84289],
                [225.767487, 40.917892, 1051.55712],
            ),
            (
                "jersey",
                [46.364765, 53.694656, 261.013855],
                [127.443810, 85.848587, 405.872833],
            ),
        ];
        for (name, along_u, along_v) in rows {
            let p = get(name);
            let [warp, weft] = p.large_strain_n_m.expect("measured");
            let u = large(free_u(along_u), p.warp_stiffness_n_m);
            let v = large(free_v(along_v), p.weft_stiffness_n_m);
            // The presets carry four or five digits.
            assert!(close(warp, u, 1e-3), "{name} warp: {warp} vs {u}");
            assert!(close(weft, v, 1e-3), "{name} weft: {weft} vs {v}");
        }
        // Only the W11 fabrics whose large-strain samples are not at the rig's ceiling.
        let measured: Vec<_> = (PRESETS.iter())
            .filter(|p| p.large_strain_n_m.is_some())
            .map(|p| p.name)
            .collect();
        assert_eq!(measured, ["denim", "jersey"]);
    }

    #[test]
    fn gf_cm_conversion_and_the_kes_denim_cross_check() {
        // 1 gf·cm²/cm: 9.80665e-3 N × 1e-4 m² / 1e-2 m.
        let gf = GRAVITY * 1e-3;
        let gf_cm = gf * 1e-4 / 1e-2;
        assert!(close(gf_cm, 9.80665e-5, 1e-12), "{gf_cm}");
        // The W11 denim bending lies inside the KES range of six denims, 0.144–0.227 gf·cm.
        let b = get("denim").bending_stiffness_n_m;
        assert!((0.144 * gf_cm..=0.227 * gf_cm).contains(&b), "{b}");
    }

    #[test]
    fn other_unit_conversions() {
        // 14 momme × 4.34 g/m² per momme = 60.76 g/m², quoted as about 60 g/m².
        assert!(close(get("silk").density_kg_m2, 14.0 * 4.34 / 1000.0, 0.02));
        // E·t: 77 MPa × 0.75 mm = 57 750 N/m.
        let e_t = 77e6 * 0.75e-3;
        assert!(close(get("leather").stretch_stiffness_n_m, e_t, 0.005));
    }

    #[test]
    fn bending_lengths_are_in_the_measured_range() {
        // Bending length c = (B / (ρ_A g))^(1/3); Feng 2022's 618 fabrics span 0.7–3.9 cm.
        for p in PRESETS {
            let c = (p.bending_stiffness_n_m / (p.density_kg_m2 * GRAVITY)).cbrt();
            assert!((0.007..=0.039).contains(&c), "{}: c = {c} m", p.name);
        }
    }
}
