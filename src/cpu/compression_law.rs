//! How cloth takes compression: linearly, ½k·s², or buckling (`[fabric] compression =
//! "buckling"`), for an edge spring's stretch s = |d| − L and for the membrane's warp and weft
//! conditions' strain s = |w| − 1 alike. CPU twin of `law_tension`, `law_axial` and
//! `law_energy_change` in `kernels/common.wgsl`.
//!
//! Why buckling: an edge spring (or a membrane condition) resists compression with its full
//! stretch stiffness, but a strip of cloth of length ℓ and bending rigidity B buckles out of
//! plane at the Euler load π²B/ℓ² per unit width (a thin strip, pinned ends), and beyond it
//! carries little more. The mesh can only buckle into folds a few edges long, so without the
//! cap the fabric resists the circumferential compression a drape needs: the Cusick drape
//! coefficient then rises as the fabric gets limper (compression locking).
//! - A spring of stiffness k = Y·A/L² (Y the stretch stiffness, A its share of area, so its
//!   width is A/L) reaches its strip's Euler load π²B·(A/L)/L² at compression
//!   s_b = π²B/(Y·L) = `SimParams::euler_onset`/L.
//! - A membrane condition of stiffness K = k·A (k its stiffness in N/m, A the triangle's rest
//!   area) takes a strip as long as the side ℓ of the equilateral triangle of the same area
//!   (ℓ² = 4A/√3, the spacing of an equilateral mesh): it buckles at strain
//!   π²B/(k·ℓ²) = (√3/4)·π²B/K = `SimParams::membrane_onset`/K, the area cancelling.
//!
//! Beyond the onset the element keeps `buckled_fraction` of its stiffness: zero is a neutral
//! direction that Newton steps cannot resolve; a small fraction keeps each sweep's local
//! problem well posed at a documented cost in over-stiffness. The energy is C¹: ½k·s² down to
//! −s_b, then ½k·s_b² − k·s_b·u + ½rk·u², u = s + s_b. The solves' Hessian takes the buckled
//! element's secant stiffness (`CompressionLaw::axial`).

use crate::model::layout::SimParams;

/// An element's law in compression: where it buckles and what it keeps beyond.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CompressionLaw {
    /// The compression (in the element's stretch units: m for a spring, strain for a membrane
    /// condition) at which it buckles.
    pub onset: f32,
    /// The share of its stiffness it keeps beyond; 0: linear in compression.
    pub fraction: f32,
}

impl CompressionLaw {
    /// A spring of rest length `rest`.
    pub fn spring(p: &SimParams, rest: f32) -> CompressionLaw {
        CompressionLaw {
            onset: p.euler_onset / rest,
            fraction: p.buckled_fraction,
        }
    }

    /// A membrane condition of stiffness `stiffness` (k·A, N·m).
    pub fn membrane(p: &SimParams, stiffness: f32) -> CompressionLaw {
        CompressionLaw {
            onset: p.membrane_onset / stiffness,
            fraction: p.buckled_fraction,
        }
    }

    fn buckled(self, s: f32) -> bool {
        self.fraction > 0.0 && s < -self.onset
    }

    /// The element's tension at stretch `s` for stiffness `k` (positive pulls).
    pub fn tension(self, k: f32, s: f32) -> f32 {
        if self.buckled(s) {
            -k * self.onset + self.fraction * k * (s + self.onset)
        } else {
            k * s
        }
    }

    /// The axial stiffness the solves take at stretch `s`: k, and buckled the secant
    /// tension/s, which falls from k at the onset towards the buckled fraction of k. Not the
    /// tangent (r·k): a Newton step with a stiffness that jumps 33-fold at the onset
    /// overshoots an element that crosses it, and one Newton step a substep then never settled
    /// leather's Cusick specimen (a residual of 1,245 times the weight after 480 frames). On
    /// the compressed side the secant's quadratic lies above the energy (its tension over
    /// stretch falls with |s|: the iteratively reweighted least-squares bound), so a local step
    /// that stays compressed does not overshoot; and the stiffness is continuous across the
    /// onset.
    pub fn axial(self, k: f32, s: f32) -> f32 {
        if self.buckled(s) {
            self.tension(k, s) / s
        } else {
            k
        }
    }

    /// The change of the element's energy from stretch `s1` to `s2` = s1 + `ds`, with `sum` =
    /// s1 + s2 as the caller computes it without cancellation. Where both are on one branch
    /// the change is a product with `ds`, not a difference of two energies.
    pub fn energy_change(self, k: f32, s1: f32, s2: f32, sum: f32, ds: f32) -> f32 {
        let (o, r) = (self.onset, self.fraction);
        match (self.buckled(s1), self.buckled(s2)) {
            (false, false) => 0.5 * k * ds * sum,
            (true, true) => k * ds * (0.5 * r * (sum + 2.0 * o) - o),
            _ => self.energy(k, s2) - self.energy(k, s1),
        }
    }

    /// The energy at stretch `s`.
    fn energy(self, k: f32, s: f32) -> f32 {
        if self.buckled(s) {
            let (o, u) = (self.onset, s + self.onset);
            0.5 * k * o * o - k * o * u + 0.5 * self.fraction * k * u * u
        } else {
            0.5 * k * s * s
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn linear_when_off() {
        let law = CompressionLaw::spring(&SimParams::default(), 0.01);
        assert_eq!(law.tension(100.0, -0.002), 100.0 * -0.002);
        assert_eq!(law.axial(100.0, -0.002), 100.0);
    }

    #[test]
    fn tension_is_continuous_and_is_the_derivative_of_the_energy() {
        // Onset 1e-7 m² over 1 cm = 1e-5 m; fraction 0.03.
        let p = SimParams {
            euler_onset: 1e-7,
            buckled_fraction: 0.03,
            ..Default::default()
        };
        let (k, rest) = (1000.0, 0.01);
        let law = CompressionLaw::spring(&p, rest);
        let o = 1e-5;
        // Continuous at the onset: the two sides, ±1e-6·o apart, differ by k·1e-6·o = 1e-8 N,
        // plus f32 rounding of k·o (1e-2 N): 1e-9 N.
        let below = law.tension(k, -o * (1.0 + 1e-6));
        let above = law.tension(k, -o * (1.0 - 1e-6));
        assert!((below - above).abs() < 1e-7, "{below} {above}");
        // Beyond the onset the load grows at r·k.
        let t = law.tension(k, -3.0 * o);
        assert!((t - (-k * o - 0.03 * k * 2.0 * o)).abs() < 1e-8, "{t}");
        // The solves' stiffness is the secant there: k at the onset, (1 + 2r)/3·k at 3×.
        let secant = law.axial(k, -3.0 * o);
        assert!((secant - k * (1.0 + 0.06) / 3.0).abs() < 1e-3, "{secant}");
        assert!((law.axial(k, -o * (1.0 + 1e-6)) - k).abs() < 1e-2);
        // Energy change over a small step ≈ tension × step (midpoint). On one branch the
        // tension is linear in s and the midpoint rule exact, up to f32 rounding (1e-3 of it is
        // far more). Across the onset the stiffness jumps by (1 − r)·k and the rule errs by up
        // to (1 − r)·k·(ds/2)²/2 (5e-12 J here); the stretches come from lengths rounded to
        // half an ulp each, and the change is a difference of two energies: |tension|·ulp(len)
        // more (1.2e-11 J), which covers both.
        for s in [-5.0 * o, -1.01 * o, -0.5 * o, 0.5 * o] {
            let ds = 0.02 * o;
            let (len, len2) = (rest + s, rest + s + ds);
            let sum = len + len2 - 2.0 * rest;
            let de = law.energy_change(k, len - rest, len2 - rest, sum, ds);
            let t = law.tension(k, s + 0.5 * ds);
            let bound = 1e-3 * (t * ds).abs() + t.abs() * len * f32::EPSILON;
            assert!((de - t * ds).abs() <= bound, "s {s}: {de} vs {}", t * ds);
        }
    }

    #[test]
    fn a_membrane_condition_buckles_at_its_strips_euler_strain() {
        // Cotton: B = 3.14e-5 N·m, k = 4050 N/m, on an equilateral triangle of side 7.5 mm
        // (A = √3/4·ℓ²): the strip's Euler strain π²B/(k·ℓ²) = 0.136%, whatever the area.
        let (b, k, side) = (3.14e-5f32, 4050.0f32, 7.5e-3f32);
        let area = 3f32.sqrt() / 4.0 * side * side;
        let p = SimParams {
            membrane_onset: 3f32.sqrt() / 4.0 * std::f32::consts::PI.powi(2) * b,
            buckled_fraction: 0.03,
            ..Default::default()
        };
        let law = CompressionLaw::membrane(&p, k * area);
        let expected = std::f32::consts::PI.powi(2) * b / (k * side * side);
        // Four f32 roundings apart: 1e-6 relative.
        assert!((law.onset / expected - 1.0).abs() < 1e-6, "{}", law.onset);
        assert!((expected - 1.36e-3).abs() < 1e-5, "{expected}");
    }
}
