//! Projection onto the box Ω = {x : l ≤ x ≤ u} and the projected-gradient stationarity measure.
//!
//! The measure used everywhere (inner stopping test, reported optimality) is the sup-norm of the
//! projected gradient step,
//!
//! ```text
//! ‖P_Ω(x − ∇F(x)) − x‖∞,
//! ```
//!
//! which vanishes exactly at the first-order stationary points of F on Ω (Birgin & Martínez 2014,
//! §3.1 and chapter 9). Infinite bounds are handled by the IEEE comparisons in `clamp`.
//!
//! # References
//! - E. G. Birgin, J. M. Martínez, *Practical Augmented Lagrangian Methods for Constrained
//!   Optimization*, SIAM, 2014.

/// Projects one coordinate onto [lower, upper]; `max` then `min` keeps ±∞ bounds harmless.
#[inline]
pub(crate) fn clamp(v: f64, lower: f64, upper: f64) -> f64 {
    v.max(lower).min(upper)
}

/// Projects `x` onto the box in place.
pub(crate) fn project(x: &mut [f64], lower: &[f64], upper: &[f64]) {
    for ((xi, &l), &u) in x.iter_mut().zip(lower).zip(upper) {
        *xi = clamp(*xi, l, u);
    }
}

/// ‖P(x − g) − x‖∞.
pub(crate) fn projected_gradient_norm(x: &[f64], g: &[f64], lower: &[f64], upper: &[f64]) -> f64 {
    x.iter()
        .zip(g)
        .zip(lower.iter().zip(upper))
        .map(|((&xi, &gi), (&l, &u))| (clamp(xi - gi, l, u) - xi).abs())
        .fold(0.0, f64::max)
}

/// Euclidean inner product: eight partial sums in a fixed order ([`simd::dot`]), so that
/// results are reproducible bit for bit on every processor and long sums do not wait on one
/// running total.
#[inline]
pub(crate) fn dot(a: &[f64], b: &[f64]) -> f64 {
    simd::dot(a, b)
}

/// Sup-norm ([`simd::norm_inf`]: NaN entries are skipped, as by `f64::max`).
#[inline]
pub(crate) fn norm_inf(a: &[f64]) -> f64 {
    simd::norm_inf(a)
}

/// gᵀ(t − x), the directional change of a step from x to t ([`simd::step_dot`]).
#[inline]
pub(crate) fn step_dot(g: &[f64], t: &[f64], x: &[f64]) -> f64 {
    simd::step_dot(g, t, x)
}

/// True if every entry is finite.
#[inline]
pub(crate) fn all_finite(a: &[f64]) -> bool {
    a.iter().all(|v| v.is_finite())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn projected_gradient_vanishes_only_where_the_gradient_points_out_of_the_box() {
        let l = [0.0, f64::NEG_INFINITY, -1.0];
        let u = [1.0, 2.0, f64::INFINITY];
        // At the lower bound with a positive gradient the step is blocked.
        assert_eq!(
            projected_gradient_norm(&[0.0, 0.0, 0.0], &[3.0, 0.0, 0.0], &l, &u),
            0.0
        );
        // With a negative gradient it is not, and the step is cut by the upper bound.
        assert_eq!(
            projected_gradient_norm(&[0.0, 0.0, 0.0], &[-3.0, 0.0, 0.0], &l, &u),
            1.0
        );
        // Infinite bounds never cut.
        assert_eq!(
            projected_gradient_norm(&[0.0, 0.0, 5.0], &[0.0, 7.0, -4.0], &l, &u),
            7.0
        );
        let mut x = [-2.0, -1e300, 1e300];
        project(&mut x, &l, &u);
        assert_eq!(x, [0.0, -1e300, 1e300]);
    }
}
