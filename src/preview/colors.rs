//! The colour modes of the cloth: one fabric colour, strain against the rest shape, or signed
//! distance to the body; each coloured mode with the legend that explains it.

use glam::Vec3;
use std::str::FromStr;

/// How the cloth is coloured.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ColorMode {
    /// One fabric colour.
    Fabric,
    /// Each triangle's largest principal stretch against frame 0, blue (0%) to red (at the
    /// preview's `strain_max`).
    Strain,
    /// Each vertex's signed distance to the body: red inside, yellow within the contact
    /// thickness, green beyond it.
    Penetration,
}

impl FromStr for ColorMode {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "fabric" => Ok(ColorMode::Fabric),
            "strain" => Ok(ColorMode::Strain),
            "penetration" => Ok(ColorMode::Penetration),
            _ => Err(format!(
                "unknown mode {s:?}; use fabric, strain or penetration"
            )),
        }
    }
}

impl ColorMode {
    /// The name used in file names and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            ColorMode::Fabric => "fabric",
            ColorMode::Strain => "strain",
            ColorMode::Penetration => "penetration",
        }
    }
}

/// Linear RGB of the cloth in fabric mode (also its colour in the glTF export).
pub const FABRIC: Vec3 = Vec3::new(0.10, 0.28, 0.62);
/// Linear RGB of the panels in fabric mode, in pattern order (repeating): the fabric blue
/// first, then hues far apart at similar lightness.
pub const PALETTE: [Vec3; 8] = [
    FABRIC,
    Vec3::new(0.70, 0.38, 0.05),
    Vec3::new(0.08, 0.40, 0.33),
    Vec3::new(0.58, 0.13, 0.20),
    Vec3::new(0.21, 0.42, 0.10),
    Vec3::new(0.28, 0.18, 0.56),
    Vec3::new(0.58, 0.23, 0.10),
    Vec3::new(0.15, 0.25, 0.36),
];

/// The colour of panel `k`: from `colors` when given (repeating), else from `PALETTE`.
pub fn panel_color(k: u32, colors: &[Vec3]) -> Vec3 {
    let list = if colors.is_empty() {
        &PALETTE[..]
    } else {
        colors
    };
    list[k as usize % list.len()]
}

/// Linear RGB of the body.
pub const BODY: Vec3 = Vec3::new(0.62, 0.60, 0.58);
/// Linear RGB of seam lines.
pub const SEAM: Vec3 = Vec3::new(0.015, 0.015, 0.015);

/// The largest principal stretch − 1 of each triangle from `rest` to `now` (the deformation
/// gradient's largest singular value, computed in each triangle's own plane).
pub fn triangle_strain(rest: &[Vec3], now: &[Vec3], triangles: &[[u32; 3]]) -> Vec<f32> {
    triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| rest[i as usize]);
            let [p, q, r] = t.map(|i| now[i as usize]);
            // An orthonormal frame of the rest triangle.
            let e1 = b - a;
            let u = e1.normalize_or_zero();
            let n = e1.cross(c - a);
            let v = n.cross(e1).normalize_or_zero();
            let (x1, x2, y2) = (e1.dot(u), (c - a).dot(u), (c - a).dot(v));
            if x1.abs() < 1e-12 || y2.abs() < 1e-12 {
                return 0.0;
            }
            // F maps rest edges (x1, 0), (x2, y2) to the current ones: F = D_now · D_rest⁻¹.
            let d1 = q - p;
            let d2 = r - p;
            let f1 = d1 / x1;
            let f2 = (d2 - f1 * x2) / y2;
            // Singular values of the 3×2 F from its 2×2 Gram matrix FᵀF.
            let (g11, g12, g22) = (f1.dot(f1), f1.dot(f2), f2.dot(f2));
            // The larger eigenvalue (g11 + g22)/2 + √(((g11 − g22)/2)² + g12²), written without
            // the cancellation of √(tr²/4 − det) near the identity.
            let half_diff = 0.5 * (g11 - g22);
            let disc = (half_diff * half_diff + g12 * g12).sqrt();
            (0.5 * (g11 + g22) + disc).sqrt() - 1.0
        })
        .collect()
}

/// The strain colour map: blue (0) through white (½) to red (1), clamped.
pub fn strain_ramp(t: f32) -> Vec3 {
    let t = t.clamp(0.0, 1.0);
    let blue = Vec3::new(0.05, 0.20, 0.80);
    let white = Vec3::new(0.85, 0.85, 0.85);
    let red = Vec3::new(0.80, 0.05, 0.03);
    if t < 0.5 {
        blue.lerp(white, 2.0 * t)
    } else {
        white.lerp(red, 2.0 * t - 1.0)
    }
}

/// The penetration colour scale: signed distances from −`range` to +`range`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PenetrationScale {
    /// The body's contact thickness in m.
    pub thickness: f32,
    /// Half the legend's span in m.
    pub range: f32,
}

impl PenetrationScale {
    /// A scale that shows the thickness band and as much again on both sides: ±max(4 ×
    /// thickness, 5 mm).
    pub fn for_thickness(thickness: f32) -> Self {
        PenetrationScale {
            thickness,
            range: (4.0 * thickness).max(0.005),
        }
    }

    /// The colour of signed distance `d` (m, negative inside): red inside, darker deeper;
    /// yellow within the thickness; green beyond it, paler further away.
    pub fn color(&self, d: f32) -> Vec3 {
        let red = Vec3::new(0.85, 0.04, 0.02);
        let deep = Vec3::new(0.25, 0.0, 0.0);
        let yellow = Vec3::new(0.90, 0.70, 0.02);
        let green = Vec3::new(0.04, 0.50, 0.06);
        let pale = Vec3::new(0.45, 0.62, 0.45);
        if d < 0.0 {
            red.lerp(deep, (-d / self.range).min(1.0))
        } else if d < self.thickness {
            yellow
        } else {
            let t = (d - self.thickness) / (self.range - self.thickness).max(1e-6);
            green.lerp(pale, t.min(1.0))
        }
    }
}

/// A colour bar with labelled ticks: `color(t)` for t from 0 (bottom) to 1 (top).
pub struct Legend {
    /// Printed above the bar.
    pub title: String,
    /// Tick positions in [0, 1] and their labels.
    pub ticks: Vec<(f32, String)>,
    /// Linear RGB along the bar.
    pub color: Box<dyn Fn(f32) -> Vec3>,
}

/// "12", "2.5", "0.25": a number with no trailing zeros (at most two decimals).
fn number(v: f32) -> String {
    let s = format!("{v:.2}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" {
        "0".into()
    } else {
        s.into()
    }
}

/// The strain legend: 0% to `max` in quarters.
pub fn strain_legend(max: f32) -> Legend {
    Legend {
        title: "STRAIN".into(),
        ticks: (0..=4)
            .map(|k| {
                let t = k as f32 / 4.0;
                (t, format!("{}%", number(100.0 * max * t)))
            })
            .collect(),
        color: Box::new(strain_ramp),
    }
}

/// The penetration legend: −range, 0, the thickness and +range, in mm.
pub fn penetration_legend(scale: PenetrationScale) -> Legend {
    let r = scale.range;
    let at = |d: f32| (d + r) / (2.0 * r);
    let mm = |d: f32| {
        let n = number(1000.0 * d);
        if d > 0.0 {
            format!("+{n} mm")
        } else {
            format!("{n} mm")
        }
    };
    Legend {
        title: "GAP TO BODY".into(),
        ticks: vec![
            (0.0, mm(-r)),
            (at(0.0), mm(0.0)),
            (at(scale.thickness), mm(scale.thickness)),
            (1.0, mm(r)),
        ],
        color: Box::new(move |t| scale.color(-r + 2.0 * r * t)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn labels_read_as_percent_and_millimetres() {
        let l = strain_legend(0.2);
        let labels: Vec<&str> = l.ticks.iter().map(|t| t.1.as_str()).collect();
        assert_eq!(labels, ["0%", "5%", "10%", "15%", "20%"]);
        assert_eq!(strain_legend(0.1).ticks[1].1, "2.5%");
        let p = penetration_legend(PenetrationScale::for_thickness(0.003));
        let labels: Vec<&str> = p.ticks.iter().map(|t| t.1.as_str()).collect();
        assert_eq!(labels, ["-12 mm", "0 mm", "+3 mm", "+12 mm"]);
        for (_, label) in l.ticks.iter().chain(&p.ticks) {
            assert!(super::super::font::covers(label), "{label}");
        }
        assert!(super::super::font::covers(&l.title) && super::super::font::covers(&p.title));
    }

    #[test]
    fn penetration_colours_by_band() {
        let s = PenetrationScale::for_thickness(0.003);
        let inside = s.color(-0.001);
        let within = s.color(0.001);
        let outside = s.color(0.005);
        assert!(inside.x > 0.5 && inside.y < 0.1, "red inside: {inside}");
        assert!(
            within.x > 0.5 && within.y > 0.5 && within.z < 0.1,
            "yellow: {within}"
        );
        assert!(
            outside.y > outside.x && outside.y > outside.z,
            "green: {outside}"
        );
    }
}
