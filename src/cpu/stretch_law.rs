//! How cloth's tension follows its stretch, for an edge spring's stretch s = |d| − L and for
//! the membrane's warp and weft conditions' strain s = |w| − 1 alike: linearly, ½k·s², unless
//! it buckles in compression (`[fabric] compression = "buckling"`) or stiffens in tension
//! (`[fabric] tension = "stiffening"`, membrane only). CPU twin of `law_tension`, `law_axial`
//! and `law_energy_change` in `kernels/common.wgsl`.
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
//! element's secant stiffness (`StretchLaw::axial`).
//!
//! Why stiffening: measured fabric stiffens as it stretches (Wang et al. 2011's knit carries 20
//! times a linear membrane's tension across its weft at 17% strain). In tension the law's
//! tangent stiffness rises linearly with the strain, k·(1 + g·s), from k at no strain to
//! k·(1 + g·e) at the end strain e, and stays there: tension
//! k·(s + g·t·(s − t/2)) and energy k·(½s² + g·t·(s²/2 − t·s/2 + t²/6)), t = min(s, e). Both
//! are C² up to e and C¹ there. The solves' Hessian takes the tangent: the energy is convex, so
//! it is positive, and a Newton step from below overshoots at most onto the stiffer side, which
//! the line search sees.

use crate::model::layout::SimParams;

/// An element's law: where it buckles in compression and what it keeps beyond, and how it
/// stiffens in tension.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StretchLaw {
    /// The compression (in the element's stretch units: m for a spring, strain for a membrane
    /// condition) at which it buckles.
    pub onset: f32,
    /// The share of its stiffness it keeps beyond; 0: linear in compression.
    pub fraction: f32,
    /// g: the tangent stiffness's relative growth per unit of stretch in tension; 0: linear
    /// in tension.
    pub growth: f32,
    /// e: the stretch beyond which the tangent stiffness stays k·(1 + g·e).
    pub end: f32,
}

impl StretchLaw {
    /// A spring of rest length `rest`.
    pub fn spring(p: &SimParams, rest: f32) -> StretchLaw {
        StretchLaw {
            onset: p.euler_onset / rest,
            fraction: p.buckled_fraction,
            growth: 0.0,
            end: 0.0,
        }
    }

    /// A membrane condition of stiffness `stiffness` (k·A, N·m): `condition` 0 the warp, 1 the
    /// weft (`SimParams::stiffening`).
    pub fn membrane(p: &SimParams, stiffness: f32, condition: usize) -> StretchLaw {
        StretchLaw {
            onset: p.membrane_onset / stiffness,
            fraction: p.buckled_fraction,
            growth: p.stiffening[condition],
            end: p.stiffening[2],
        }
    }

    fn buckled(self, s: f32) -> bool {
        self.fraction > 0.0 && s < -self.onset
    }

    fn stiffening(self, s: f32) -> bool {
        self.growth != 0.0 && s > 0.0
    }

    /// The element's tension at stretch `s` for stiffness `k` (positive pulls).
    pub fn tension(self, k: f32, s: f32) -> f32 {
        if self.buckled(s) {
            -k * self.onset + self.fraction * k * (s + self.onset)
        } else if self.stiffening(s) {
            let t = s.min(self.end);
            k * (s + self.growth * t * (s - 0.5 * t))
        } else {
            k * s
        }
    }

    /// The tension over its linear value k·s (1 when linear): what the transverse term of a
    /// stretched condition's Hessian, tension/|w|, is scaled by.
    pub fn secant_ratio(self, s: f32) -> f32 {
        if self.stiffening(s) {
            self.tension(1.0, s) / s
        } else {
            1.0
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
        } else if self.stiffening(s) {
            k * (1.0 + self.growth * s.min(self.end))
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
            (false, false) if self.growth != 0.0 => {
                0.5 * k * ds * sum + k * self.stiffening_change(s1, s2, sum, ds)
            }
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
            0.5 * k * s * s + k * self.stiffening_energy(s)
        }
    }

    /// The stiffening's share of the energy per unit stiffness at stretch `s` (0 in
    /// compression): g·t·(s²/2 − t·s/2 + t²/6), t = min(s, e).
    fn stiffening_energy(self, s: f32) -> f32 {
        if !self.stiffening(s) {
            return 0.0;
        }
        let t = s.min(self.end);
        self.growth * t * (0.5 * s * s - 0.5 * t * s + t * t / 6.0)
    }

    /// The change of `stiffening_energy` from `s1` to `s2` (= s1 + `ds`, `sum` = s1 + s2): a
    /// product with ds where both lie on one piece, g·ds·(s1² + s1·s2 + s2²)/6 below the end
    /// and g·e·ds·(sum − e)/2 beyond it.
    fn stiffening_change(self, s1: f32, s2: f32, sum: f32, ds: f32) -> f32 {
        let (g, e) = (self.growth, self.end);
        let within = |s: f32| s > 0.0 && s <= e;
        if within(s1) && within(s2) {
            g * ds * (s1 * s1 + s1 * s2 + s2 * s2) / 6.0
        } else if s1 > e && s2 > e {
            0.5 * g * e * ds * (sum - e)
        } else {
            self.stiffening_energy(s2) - self.stiffening_energy(s1)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn linear_when_off() {
        let law = StretchLaw::spring(&SimParams::default(), 0.01);
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
        let law = StretchLaw::spring(&p, rest);
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
        let law = StretchLaw::membrane(&p, k * area, 0);
        let expected = std::f32::consts::PI.powi(2) * b / (k * side * side);
        // Four f32 roundings apart: 1e-6 relative.
        assert!((law.onset / expected - 1.0).abs() < 1e-6, "{}", law.onset);
        assert!((expected - 1.36e-3).abs() < 1e-5, "{expected}");
    }

    /// The jersey's weft: k = 42.9 N/m, its tangent 1,717 N/m at e = 1/6 (g = 234).
    fn stiffening_weft() -> (StretchLaw, f32) {
        let e = 1.0 / 6.0;
        let law = StretchLaw {
            onset: 0.0,
            fraction: 0.0,
            growth: (1717.0 / 42.9 - 1.0) / e,
            end: e,
        };
        (law, 42.9)
    }

    #[test]
    fn stiffening_tension_is_the_energy_s_derivative_and_the_tangent_its_own() {
        let (law, k) = stiffening_weft();
        let e = law.end;
        // The tension at the end strain is the trapezoid of the tangent, e·(k + k_e)/2; f32
        // rounding of a few products: 1e-6 relative.
        let expected = e * (k + 1717.0) / 2.0;
        assert!((law.tension(k, e) / expected - 1.0).abs() < 1e-5);
        // Linear at no strain and in compression, to the bit.
        assert_eq!(law.tension(k, -0.01), k * -0.01);
        assert_eq!(law.axial(k, -0.01), k);
        for s in [1e-4, 0.02, 0.1, 0.16, 0.17, 0.3] {
            // Central differences at h = 1e-3·s: the rule's error is the third derivative's
            // h²/6 (g·k·h²/3 for the tension, g·k·h for the tangent's jump at e), far under
            // 1e-3 of the value; f32 rounding of the differences 1e-7·value/1e-3 = 1e-4 of it.
            let h = 1e-3 * s;
            let (s1, s2) = (s - h, s + h);
            let de = law.energy_change(k, s1, s2, s1 + s2, s2 - s1) / (s2 - s1);
            let t = law.tension(k, s);
            assert!((de / t - 1.0).abs() < 2e-3, "s {s}: dE/ds {de} vs T {t}");
            let dt = (law.tension(k, s2) - law.tension(k, s1)) / (s2 - s1);
            let axial = law.axial(k, s);
            // At 0.17 the difference straddles nothing (e = 0.1667 < s1); at 0.16 neither.
            assert!(
                (dt / axial - 1.0).abs() < 2e-3,
                "s {s}: dT/ds {dt} vs {axial}"
            );
            // The secant ratio is T/(k·s), at least 1 where it stiffens.
            let ratio = law.secant_ratio(s);
            assert!(
                (ratio * k * s / t - 1.0).abs() < 1e-5 && ratio >= 1.0,
                "{ratio}"
            );
        }
        // Beyond the end the tangent stays k·(1 + g·e), the 1,717 N/m it was given.
        assert!((law.axial(k, 0.5) / 1717.0 - 1.0).abs() < 1e-5);
    }

    #[test]
    fn stiffening_energy_changes_agree_across_its_pieces() {
        // A change that crosses a piece's edge (0 or e) is a difference of energies, one
        // within a piece a product: summing steps 0 → 0.1 → 0.3 in either form must give the
        // same energy, to f32 rounding of energies of k·0.05 J (1e-6 relative).
        let (law, k) = stiffening_weft();
        let steps = [(0.0f32, 0.1f32), (0.1, 0.15), (0.15, 0.2), (0.2, 0.3)];
        let by_steps: f32 = (steps.iter())
            .map(|&(a, b)| law.energy_change(k, a, b, a + b, b - a))
            .sum();
        let whole = law.energy_change(k, -0.05, 0.3, 0.25, 0.35) + 0.5 * k * 0.05 * 0.05;
        assert!(
            (by_steps / whole - 1.0).abs() < 1e-5,
            "{by_steps} vs {whole}"
        );
        assert!((law.energy(k, 0.3) / whole - 1.0).abs() < 1e-5);
    }
}
