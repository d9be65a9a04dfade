//! Panel edge geometry: straight lines, quadratic and cubic Béziers and circular arcs, all in
//! absolute panel coordinates, with arc-length sampling.

use glam::DVec2;
use std::f64::consts::TAU;

/// One edge's shape from `start` to `end`. Fields are the defining points, in panel units.
#[allow(missing_docs)]
#[derive(Clone, Debug, PartialEq)]
pub enum Curve {
    /// A straight segment.
    Line { start: DVec2, end: DVec2 },
    /// A quadratic Bézier with control point `c`.
    Quadratic { start: DVec2, c: DVec2, end: DVec2 },
    /// A cubic Bézier with control points `c1`, `c2`.
    Cubic {
        start: DVec2,
        c1: DVec2,
        c2: DVec2,
        end: DVec2,
    },
    /// A circular arc about `center` of `radius`, from angle `a0` sweeping `sweep` radians
    /// (positive: counter-clockwise).
    Arc {
        center: DVec2,
        radius: f64,
        a0: f64,
        sweep: f64,
    },
}

/// The chord rotated by +90°: GarmentCode's relative `v` axis (v > 0 bulges to the left).
pub fn perp(start: DVec2, end: DVec2) -> DVec2 {
    let d = end - start;
    DVec2::new(-d.y, d.x)
}

/// A point given relative to the chord: start + u·(end − start) + v·perp.
pub fn relative_point(start: DVec2, end: DVec2, u: f64, v: f64) -> DVec2 {
    start + u * (end - start) + v * perp(start, end)
}

impl Curve {
    /// The SVG-style arc through `start` and `end` with `radius`: `large_arc` takes the longer
    /// way round, `right` bulges to the right of start→end (as GarmentCode's circle edges).
    /// `None` when the radius is shorter than half the chord or the points coincide.
    pub fn arc(
        start: DVec2,
        end: DVec2,
        radius: f64,
        large_arc: bool,
        right: bool,
    ) -> Option<Self> {
        let chord = (end - start).length();
        if chord <= 0.0
            || !chord.is_finite()
            || !radius.is_finite()
            || radius < 0.5 * chord * (1.0 - 1e-9)
        {
            return None;
        }
        let left = perp(start, end) / chord; // unit normal, left of start→end
        let center_offset = (radius * radius - 0.25 * chord * chord).max(0.0).sqrt();
        let side = if right { -1.0 } else { 1.0 }; // which side the bulge is on
        let height = if large_arc {
            radius + center_offset
        } else {
            radius - center_offset
        };
        let mid = 0.5 * (start + end);
        let bulge = mid + side * height * left;
        let center = bulge - side * radius * left;
        let angle = |p: DVec2| (p - center).y.atan2((p - center).x);
        let (a0, a1, am) = (angle(start), angle(end), angle(bulge));
        let ccw = (a1 - a0).rem_euclid(TAU);
        let through = (am - a0).rem_euclid(TAU);
        let sweep = if through <= ccw { ccw } else { ccw - TAU };
        Some(Curve::Arc {
            center,
            radius,
            a0,
            sweep,
        })
    }

    /// Corners of a box holding the whole curve: a Bézier curve lies in the hull of its
    /// control points, an arc within its radius of its centre.
    pub fn bounds(&self) -> (DVec2, DVec2) {
        let hull = |pts: &[DVec2]| {
            (pts.iter()).fold((DVec2::INFINITY, DVec2::NEG_INFINITY), |(lo, hi), p| {
                (lo.min(*p), hi.max(*p))
            })
        };
        match *self {
            Curve::Line { start, end } => hull(&[start, end]),
            Curve::Quadratic { start, c, end } => hull(&[start, c, end]),
            Curve::Cubic { start, c1, c2, end } => hull(&[start, c1, c2, end]),
            Curve::Arc { center, radius, .. } => (center - radius.abs(), center + radius.abs()),
        }
    }

    /// The point at parameter `t` in [0, 1].
    pub fn point(&self, t: f64) -> DVec2 {
        let s = 1.0 - t;
        match *self {
            Curve::Line { start, end } => start.lerp(end, t),
            Curve::Quadratic { start, c, end } => s * s * start + 2.0 * s * t * c + t * t * end,
            Curve::Cubic { start, c1, c2, end } => {
                s * s * s * start + 3.0 * s * s * t * c1 + 3.0 * s * t * t * c2 + t * t * t * end
            }
            Curve::Arc {
                center,
                radius,
                a0,
                sweep,
            } => {
                let a = a0 + t * sweep;
                center + radius * DVec2::new(a.cos(), a.sin())
            }
        }
    }

    /// Parameters of a fine polyline, dense enough that its length matches the curve's to
    /// ~1e-6 relative (chord error falls as 1/segments²).
    fn dense_params(&self) -> Vec<f64> {
        let segments = match self {
            Curve::Line { .. } => 1,
            _ => 2048,
        };
        (0..=segments).map(|k| k as f64 / segments as f64).collect()
    }

    /// Arc length, from the dense polyline (exact for lines and arcs up to ~1e-7).
    pub fn length(&self) -> f64 {
        if let Curve::Arc { radius, sweep, .. } = self {
            return radius * sweep.abs();
        }
        let ts = self.dense_params();
        ts.windows(2)
            .map(|w| self.point(w[0]).distance(self.point(w[1])))
            .sum()
    }

    /// `segments + 1` points at equal arc-length spacing, both ends included exactly.
    pub fn sample(&self, segments: usize) -> Vec<DVec2> {
        let segments = segments.max(1);
        let ts = self.dense_params();
        let mut cumulative = vec![0.0];
        for w in ts.windows(2) {
            let l = self.point(w[0]).distance(self.point(w[1]));
            cumulative.push(cumulative.last().unwrap() + l);
        }
        let total = *cumulative.last().unwrap();
        let mut out = Vec::with_capacity(segments + 1);
        let mut k = 0;
        for i in 0..=segments {
            if i == 0 || i == segments {
                out.push(self.point(if i == 0 { 0.0 } else { 1.0 }));
                continue;
            }
            let target = total * i as f64 / segments as f64;
            while k + 1 < cumulative.len() - 1 && cumulative[k + 1] < target {
                k += 1;
            }
            let span = cumulative[k + 1] - cumulative[k];
            let f = if span > 0.0 {
                (target - cumulative[k]) / span
            } else {
                0.0
            };
            out.push(self.point(ts[k] + f * (ts[k + 1] - ts[k])));
        }
        out
    }
}
