//! A spring's law in its stretch s = |d| − L: linear, ½k·s², or buckling in compression
//! (`[fabric] compression = "buckling"`). CPU twin of `spring_tension`, `spring_axial` and
//! `spring_energy_change` in `kernels/common.wgsl`.
//!
//! Why buckling: an edge spring resists compression with its full stretch stiffness, but a
//! strip of cloth of length L and bending rigidity B buckles out of plane at the Euler load
//! π²B/L² per unit width (a thin strip, pinned ends), and beyond it carries little more. The
//! mesh can only buckle into folds a few edges long, so without the cap the fabric resists
//! the circumferential compression a drape needs: the Cusick drape coefficient then rises as
//! the fabric gets limper (compression locking). A spring of stiffness k = Y·A/L² (Y the
//! stretch stiffness, A its share of area, so its width is A/L) reaches its strip's Euler
//! load π²B·(A/L)/L² at compression s_b = π²B/(Y·L) = `euler_onset`/L. Beyond it the spring
//! keeps `buckled_fraction` of its stiffness: zero is a neutral direction that Newton steps
//! cannot resolve; a small fraction keeps each sweep's local problem well posed at a
//! documented cost in over-stiffness.
//!
//! The energy is C¹: ½k·s² down to −s_b, then ½k·s_b² − k·s_b·u + ½rk·u², u = s + s_b.

use crate::model::layout::SimParams;

/// The compression at which a spring of rest length `rest` buckles, in m, or `None` when
/// springs are linear.
fn onset(p: &SimParams, rest: f32) -> Option<f32> {
    (p.buckled_fraction > 0.0).then(|| p.euler_onset / rest)
}

/// The spring's tension (N, positive pulls its ends together) at stretch `s`.
pub fn tension(p: &SimParams, k: f32, rest: f32, s: f32) -> f32 {
    match onset(p, rest) {
        Some(o) if s < -o => -k * o + p.buckled_fraction * k * (s + o),
        _ => k * s,
    }
}

/// d(tension)/ds at stretch `s`: k, or the buckled fraction of it.
pub fn axial(p: &SimParams, k: f32, rest: f32, s: f32) -> f32 {
    match onset(p, rest) {
        Some(o) if s < -o => p.buckled_fraction * k,
        _ => k,
    }
}

/// The change of the spring's energy from length `len` to `len2` (`dl` = len2 − len, computed
/// without cancelling the two lengths). Where both lengths are on one branch the change is a
/// product with `dl`, not a difference of two energies.
pub fn energy_change(p: &SimParams, k: f32, rest: f32, len: f32, len2: f32, dl: f32) -> f32 {
    let sum = len + len2 - 2.0 * rest;
    let Some(o) = onset(p, rest) else {
        return 0.5 * k * dl * sum;
    };
    let (s1, s2) = (len - rest, len2 - rest);
    let r = p.buckled_fraction;
    if s1 >= -o && s2 >= -o {
        0.5 * k * dl * sum
    } else if s1 < -o && s2 < -o {
        k * dl * (0.5 * r * (sum + 2.0 * o) - o)
    } else {
        buckled_energy(k, o, r, s2) - buckled_energy(k, o, r, s1)
    }
}

/// The energy at stretch `s` with onset `o` and buckled fraction `r`.
fn buckled_energy(k: f32, o: f32, r: f32, s: f32) -> f32 {
    if s >= -o {
        0.5 * k * s * s
    } else {
        let u = s + o;
        0.5 * k * o * o - k * o * u + 0.5 * r * k * u * u
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn buckling(onset_area: f32, fraction: f32) -> SimParams {
        SimParams {
            euler_onset: onset_area,
            buckled_fraction: fraction,
            ..Default::default()
        }
    }

    #[test]
    fn linear_when_off() {
        let p = SimParams::default();
        assert_eq!(tension(&p, 100.0, 0.01, -0.002), 100.0 * -0.002);
        assert_eq!(axial(&p, 100.0, 0.01, -0.002), 100.0);
    }

    #[test]
    fn tension_is_continuous_and_is_the_derivative_of_the_energy() {
        // Onset 1e-7 m²/1 cm = 1e-5 m; fraction 0.03.
        let p = buckling(1e-7, 0.03);
        let (k, rest) = (1000.0, 0.01);
        let o = 1e-5;
        // Continuous at the onset, to f32 rounding of k·o (1e-2 N): 1e-8 N.
        let below = tension(&p, k, rest, -o * (1.0 + 1e-6));
        let above = tension(&p, k, rest, -o * (1.0 - 1e-6));
        assert!((below - above).abs() < 1e-7, "{below} {above}");
        // Beyond the onset the load grows at r·k.
        let t = tension(&p, k, rest, -3.0 * o);
        assert!((t - (-k * o - 0.03 * k * 2.0 * o)).abs() < 1e-8, "{t}");
        // Energy change over a small step ≈ tension × step (midpoint), on each branch and
        // across the onset: the midpoint rule's error is k·ds²-sized, below 1e-3 of it. Across
        // the onset the change is a difference of energies at two lengths, each rounded to
        // half an ulp of the length: |tension|·ulp(len) more.
        for s in [-5.0 * o, -1.01 * o, -0.5 * o, 0.5 * o] {
            let ds = 0.02 * o;
            let len = rest + s;
            let de = energy_change(&p, k, rest, len, len + ds, ds);
            let t = tension(&p, k, rest, s + 0.5 * ds);
            let bound = 1e-3 * (t * ds).abs() + t.abs() * len * f32::EPSILON;
            assert!((de - t * ds).abs() <= bound, "s {s}: {de} vs {}", t * ds);
        }
    }
}
