//! The Cusick drape test (Cusick 1965/1968; BS 5058; ISO 9073-9): a 30 cm circular specimen
//! held between 18 cm discs drapes into folds; its drape coefficient is
//! DC = (shadow area − disc area) / (specimen area − disc area): 1 stays flat, 0 hangs straight.

use glam::Vec3;

/// Specimen radius, m (30 cm diameter).
pub const SPECIMEN_RADIUS_M: f64 = 0.15;
/// Support disc radius, m (18 cm diameter).
pub const DISC_RADIUS_M: f64 = 0.09;
/// Shadow raster cell, m: the shadow's outline is the only place a cell can be misjudged, so
/// the area error is at most its length times a cell (≈ 1 m × 0.5 mm, 1% of the annulus) and
/// in practice far less, since over- and under-counted cells along it cancel.
pub const SHADOW_CELL_M: f64 = 5e-4;

/// The area of the union of the triangles projected straight down (onto xz), in m², by
/// counting `cell`-sized raster cells whose centres some triangle covers (overlaps count once).
pub fn shadow_area(positions: &[Vec3], triangles: &[[u32; 3]], cell: f64) -> f64 {
    let p2 = |i: u32| {
        let p = positions[i as usize];
        (p.x as f64, p.z as f64)
    };
    let (mut lo, mut hi) = ((f64::MAX, f64::MAX), (f64::MIN, f64::MIN));
    for p in positions {
        lo = (lo.0.min(p.x as f64), lo.1.min(p.z as f64));
        hi = (hi.0.max(p.x as f64), hi.1.max(p.z as f64));
    }
    if positions.is_empty() {
        return 0.0;
    }
    let nx = ((hi.0 - lo.0) / cell).ceil() as usize + 1;
    let nz = ((hi.1 - lo.1) / cell).ceil() as usize + 1;
    let mut covered = vec![false; nx * nz];
    for t in triangles {
        let [a, b, c] = [p2(t[0]), p2(t[1]), p2(t[2])];
        let cross = |o: (f64, f64), p: (f64, f64), q: (f64, f64)| {
            (p.0 - o.0) * (q.1 - o.1) - (p.1 - o.1) * (q.0 - o.0)
        };
        let area2 = cross(a, b, c);
        if area2 == 0.0 {
            continue; // seen edge-on: it casts no area
        }
        let cell_range = |lo_t: f64, hi_t: f64, origin: f64, n: usize| {
            let first = ((lo_t - origin) / cell - 0.5).ceil().max(0.0) as usize;
            let last = (((hi_t - origin) / cell - 0.5).floor().max(-1.0) + 1.0) as usize;
            first..last.min(n)
        };
        let xs = cell_range(a.0.min(b.0).min(c.0), a.0.max(b.0).max(c.0), lo.0, nx);
        let zs = cell_range(a.1.min(b.1).min(c.1), a.1.max(b.1).max(c.1), lo.1, nz);
        for iz in zs {
            let z = lo.1 + (iz as f64 + 0.5) * cell;
            for ix in xs.clone() {
                let p = (lo.0 + (ix as f64 + 0.5) * cell, z);
                let (w0, w1, w2) = (cross(b, c, p), cross(c, a, p), cross(a, b, p));
                let inside = if area2 > 0.0 {
                    w0 >= 0.0 && w1 >= 0.0 && w2 >= 0.0
                } else {
                    w0 <= 0.0 && w1 <= 0.0 && w2 <= 0.0
                };
                if inside {
                    covered[iz * nx + ix] = true;
                }
            }
        }
    }
    covered.iter().filter(|&&c| c).count() as f64 * cell * cell
}

/// The drape coefficient of a settled specimen, with its specimen area taken from the same
/// raster of its flat rest shape, so that a specimen that stays flat scores exactly 1.
pub fn drape_coefficient(rest: &[Vec3], settled: &[Vec3], triangles: &[[u32; 3]]) -> f64 {
    let disc = std::f64::consts::PI * DISC_RADIUS_M * DISC_RADIUS_M;
    let specimen = shadow_area(rest, triangles, SHADOW_CELL_M);
    let shadow = shadow_area(settled, triangles, SHADOW_CELL_M);
    (shadow - disc) / (specimen - disc)
}

/// Folds ("nodes") around the hem: peaks of the hem's projected radius against its angle,
/// each rising at least `prominence` (m) above the troughs on either side. The hem is every
/// particle within one particle spacing of the specimen's rest edge.
pub fn nodes(rest: &[Vec3], settled: &[Vec3], spacing: f64, prominence: f64) -> usize {
    let rest_r = |p: Vec3| (p.x as f64).hypot(p.z as f64);
    let outer = rest.iter().map(|&p| rest_r(p)).fold(0.0, f64::max);
    let mut hem: Vec<(f64, f64)> = (0..rest.len())
        .filter(|&i| rest_r(rest[i]) > outer - spacing)
        .map(|i| {
            let p = settled[i];
            ((p.z as f64).atan2(p.x as f64), rest_r(p))
        })
        .collect();
    if hem.len() < 8 {
        return 0;
    }
    hem.sort_by(|a, b| a.0.total_cmp(&b.0));
    let r: Vec<f64> = hem.iter().map(|h| h.1).collect();
    count_peaks(&r, prominence)
}

/// Peaks of a closed (circular) profile, each standing at least `prominence` above the lowest
/// point between it and the next peak at least as high on both sides.
fn count_peaks(r: &[f64], prominence: f64) -> usize {
    let n = r.len();
    let at = |i: isize| r[i.rem_euclid(n as isize) as usize];
    // Walk the loop from its lowest point, alternating between rises and falls of at least
    // `prominence`: each completed rise-then-fall is one peak.
    let start = (0..n).min_by(|&a, &b| r[a].total_cmp(&r[b])).unwrap_or(0) as isize;
    let (mut peaks, mut rising, mut low, mut high) = (0, true, at(start), at(start));
    for k in 1..=n as isize {
        let v = at(start + k);
        if rising {
            high = high.max(v);
            if high - v >= prominence && high - low >= prominence {
                peaks += 1;
                rising = false;
                low = v;
            }
        } else {
            low = low.min(v);
            if v - low >= prominence {
                rising = true;
                high = v;
            }
        }
    }
    peaks
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square(side: f32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let h = side / 2.0;
        let p = vec![
            Vec3::new(-h, 0.0, -h),
            Vec3::new(h, 0.0, -h),
            Vec3::new(h, 0.0, h),
            Vec3::new(-h, 0.0, h),
        ];
        (p, vec![[0, 1, 2], [0, 2, 3]])
    }

    #[test]
    fn a_square_shadow_is_its_area_within_a_cell_row() {
        let (p, t) = square(0.1);
        let a = shadow_area(&p, &t, SHADOW_CELL_M);
        // The outline is 0.4 m long: at most one row of cells along it, 0.4 × 0.5 mm.
        assert!((a - 0.01).abs() <= 0.4 * SHADOW_CELL_M, "{a}");
    }

    #[test]
    fn overlapping_and_upright_triangles_count_once_or_not_at_all() {
        let (mut p, mut t) = square(0.1);
        // The same square again on top, and an upright triangle in the yz plane.
        p.extend(p.clone());
        t.extend([[4, 5, 6], [4, 6, 7]]);
        p.extend([
            Vec3::new(0.3, 0.0, 0.0),
            Vec3::new(0.3, 0.1, 0.0),
            Vec3::new(0.3, 0.0, 0.1),
        ]);
        t.push([8, 9, 10]);
        let one = shadow_area(&p[..4], &[[0, 1, 2], [0, 2, 3]], SHADOW_CELL_M);
        assert_eq!(shadow_area(&p, &t, SHADOW_CELL_M), one);
    }

    #[test]
    fn a_flat_specimen_scores_one_and_a_hanging_one_zero() {
        // A ring of 64 triangles from the disc edge to the specimen edge, plus the disc.
        let n = 64;
        let ring = |r: f64, k: usize| {
            let a = std::f64::consts::TAU * k as f64 / n as f64;
            Vec3::new((r * a.cos()) as f32, 0.0, (r * a.sin()) as f32)
        };
        let mut rest = vec![Vec3::ZERO];
        for k in 0..n {
            rest.push(ring(DISC_RADIUS_M, k));
            rest.push(ring(SPECIMEN_RADIUS_M, k));
        }
        let mut tris = Vec::new();
        for k in 0..n as u32 {
            let (a, b) = (1 + 2 * k, 1 + 2 * ((k + 1) % n as u32));
            tris.extend([[0, a, b], [a, a + 1, b + 1], [a, b + 1, b]]);
        }
        let dc = drape_coefficient(&rest, &rest, &tris);
        assert_eq!(dc, 1.0);
        // Hanging straight down: the outer ring sits under the disc edge, 6 cm lower.
        let mut hung = rest.clone();
        for k in 0..n {
            hung[2 + 2 * k] = ring(DISC_RADIUS_M, k) - Vec3::Y * 0.06;
        }
        let dc = drape_coefficient(&rest, &hung, &tris);
        // The 64-gon disc is 0.16% smaller than the circle; against the annulus that is
        // −0.16% × 0.0254 / 0.0452 ≈ −0.1%, and the raster adds at most ±1%.
        assert!(dc.abs() < 0.011, "{dc}");
    }

    #[test]
    fn peaks_are_counted_by_prominence() {
        let wave = |m: f64| {
            (0..360)
                .map(|i| 0.12 + 0.01 * (m * (i as f64).to_radians()).cos())
                .collect::<Vec<_>>()
        };
        // Seven folds 2 cm from crest to trough: seven peaks at 5 mm, none at 3 cm.
        assert_eq!(count_peaks(&wave(7.0), 0.005), 7);
        assert_eq!(count_peaks(&wave(7.0), 0.03), 0);
    }
}
