//! Whether a body mesh has the size of something a garment is draped on, and, when it does
//! not, which length unit would give it one: a body modelled in centimetres but read as metres
//! is 100 times too large, and its distance field asks for millions of times the memory.

use glam::Vec3;

/// The largest extent a body may have before drapekit suspects its unit, in m: taller than
/// anyone (the tallest people measured are under 2.8 m).
pub const MAX_EXTENT_M: f32 = 3.0;
/// The smallest, in m: smaller than a toddler or a dress form's torso.
pub const MIN_EXTENT_M: f32 = 0.3;
/// The size the unit suggestion aims at, in m: an adult's height.
const TYPICAL_EXTENT_M: f32 = 1.7;

/// The length units a `units` key accepts, with metres per unit (as `Checker::units`).
const UNITS: [(&str, f32); 4] = [("m", 1.0), ("dm", 0.1), ("cm", 0.01), ("mm", 0.001)];

/// The largest side of the bounding box of `positions`, in their unit (0 without any).
pub fn largest_extent(positions: &[Vec3]) -> f32 {
    let Some(first) = positions.first() else {
        return 0.0;
    };
    let (lo, hi) =
        (positions.iter()).fold((*first, *first), |(lo, hi), p| (lo.min(*p), hi.max(*p)));
    (hi - lo).max_element()
}

/// The name of a unit given as metres per file unit, if it is one `units` accepts.
pub fn unit_name(scale: f32) -> Option<&'static str> {
    let close = |m: f32| (scale / m - 1.0).abs() < 1e-6;
    UNITS.iter().find(|(_, m)| close(*m)).map(|(n, _)| *n)
}

/// When a body `extent_m` across (read with `scale` metres per file unit) is outside
/// `MIN_EXTENT_M..=MAX_EXTENT_M`: what is wrong and what to do, naming the unit that would make
/// it closest to an adult's height (if one brings it into the range).
pub fn size_problem(extent_m: f32, scale: f32) -> Option<(String, String)> {
    if !extent_m.is_finite() || (MIN_EXTENT_M..=MAX_EXTENT_M).contains(&extent_m) {
        return None;
    }
    let current = unit_name(scale).map_or(String::new(), |u| format!(" with units = \"{u}\""));
    let problem = format!(
        "the body mesh is {} across{current}: {} any body a garment is draped on ({} to {} m)",
        metres(extent_m),
        if extent_m > MAX_EXTENT_M {
            "larger than"
        } else {
            "smaller than"
        },
        MIN_EXTENT_M,
        MAX_EXTENT_M
    );
    let in_file = extent_m / scale;
    let best = (UNITS.iter())
        .map(|&(name, m)| (name, in_file * m))
        .filter(|&(name, e)| {
            Some(name) != unit_name(scale) && (MIN_EXTENT_M..=MAX_EXTENT_M).contains(&e)
        })
        .min_by(|a, b| {
            let off = |e: f32| (e / TYPICAL_EXTENT_M).ln().abs();
            off(a.1).total_cmp(&off(b.1))
        });
    let fix = match best {
        Some((name, e)) => format!(
            "if the mesh was modelled in {name}, write units = \"{name}\" in its [body] table \
             (it is then {} across)",
            metres(e)
        ),
        None => "check the mesh's length unit and its units key (m, dm, cm or mm)".to_string(),
    };
    Some((problem, fix))
}

/// "170 m", "1.70 m", "0.017 m": three significant digits.
fn metres(v: f32) -> String {
    if v >= 100.0 {
        format!("{v:.0} m")
    } else if v >= 1.0 {
        format!("{v:.2} m")
    } else {
        format!("{v:.3} m")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_body_in_the_wrong_unit_gets_the_right_one() {
        // A 1.7 m figure modelled in cm and read as m is 170 m across.
        let (problem, fix) = size_problem(170.0, 1.0).unwrap();
        assert!(
            problem.contains("170 m across with units = \"m\""),
            "{problem}"
        );
        assert!(
            fix.contains("units = \"cm\"") && fix.contains("1.70 m"),
            "{fix}"
        );
        // In mm: 1700 m.
        assert!(size_problem(1700.0, 1.0).unwrap().1.contains("\"mm\""));
        // A metre model read as mm: 1.7 mm across.
        let (p, fix) = size_problem(0.0017, 0.001).unwrap();
        assert!(p.contains("smaller than"), "{p}");
        assert!(fix.contains("units = \"m\""), "{fix}");
        // Within the range: nothing to say.
        assert!(size_problem(1.7, 1.0).is_none() && size_problem(0.5, 0.01).is_none());
        // 10 km in m: no unit helps.
        assert!(size_problem(1.0e4, 0.001).unwrap().1.starts_with("check"));
    }

    #[test]
    fn extents_and_unit_names() {
        let box_ = [Vec3::ZERO, Vec3::new(0.4, 1.8, 0.3)];
        assert_eq!(largest_extent(&box_), 1.8);
        assert_eq!(largest_extent(&[]), 0.0);
        assert_eq!(unit_name(0.01), Some("cm"));
        assert_eq!(unit_name(0.0254), None);
    }
}
