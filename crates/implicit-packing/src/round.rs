//! The pair term of two round items (circles or balls) in closed form: the distance of the
//! centres decides it, and no projection is solved.
//!
//! For radii `r_i`, `r_j` and centres `D = |c_i − c_j|` apart, the frame of eq. 21 maps `E_i` to
//! the unit ball and `E_j` to the ball of radius `ρ = r_j / r_i` about the origin (`S = I/ρ²`),
//! with `i`'s centre at `c = (c_i − c_j)/r_i`. The projection of `c` onto the sphere is
//! `X = ρ c/|c|`, so `|c − X| = |t|` with
//!
//! ```text
//! t = (D − r_j) / r_i,
//! ```
//!
//! and eq. 22, `c = (1 + U/ρ²) X`, gives `U = ρ t`; `ε_ij = ρ` (the `ε` of Section 3 for two
//! balls). Eq. 34 is then
//!
//! ```text
//! f(D) = max{0, 1 − t²}² + ρ² max{0, 1 − t}²,
//! f'(t) = −4 t max{0, 1 − t²} − 2 ρ² max{0, 1 − t},
//! f''(t) = −4 max{0, 1 − t²} + 8 t² [t² < 1] + 2 ρ² [t < 1],
//! ```
//!
//! with `∂f/∂c_i = −∂f/∂c_j = f'(t) n / r_i`, `n = (c_i − c_j)/D`, no torque, and the Hessian
//! in `u = c_i − c_j`: `f''(t)/r_i² n nᵀ + f'(t)/(r_i D) (I − n nᵀ)`
//! ([`crate::derivatives::round_pair_gradient`] and
//! [`crate::derivatives::round_pair_gradient_derivative`]).
//!
//! # References
//! E. G. Birgin, R. D. Lobato, J. M. Martínez, *A nonlinear programming model with implicit
//! variables for packing ellipsoids*, J. Global Optim. 68 (2017), eqs. 21, 22, 34.

use crate::shape::Body;

/// The pair of round items `i`, `j` reduced to what `f` depends on.
pub(crate) struct RoundPair<const N: usize> {
    /// `t = (D − r_j)/r_i`.
    pub(crate) t: f64,
    /// `ρ = r_j / r_i`.
    pub(crate) rho: f64,
    /// `r_i`.
    pub(crate) r_i: f64,
    /// `D`.
    pub(crate) distance: f64,
    /// `n = (c_i − c_j)/D` (`e_1` when the centres coincide).
    pub(crate) normal: [f64; N],
}

impl<const N: usize> RoundPair<N> {
    pub(crate) fn of(i: &Body<N>, j: &Body<N>) -> Self {
        let (ci, cj) = (i.centre(), j.centre());
        let mut u = [0.0; N];
        for k in 0..N {
            u[k] = ci[k] - cj[k];
        }
        let distance = u.iter().map(|v| v * v).sum::<f64>().sqrt();
        let mut normal = [0.0; N];
        if distance > 0.0 {
            for k in 0..N {
                normal[k] = u[k] / distance;
            }
        } else {
            normal[0] = 1.0;
        }
        let (r_i, r_j) = (i.bounding_radius(), j.bounding_radius());
        RoundPair {
            t: (distance - r_j) / r_i,
            rho: r_j / r_i,
            r_i,
            distance,
            normal,
        }
    }

    /// `A = max{0, 1 − t²}` and `B = ρ max{0, 1 − t}`.
    fn parts(&self) -> (f64, f64) {
        let t = self.t;
        ((1.0 - t * t).max(0.0), self.rho * (1.0 - t).max(0.0))
    }

    /// `f = A² + B²` (eq. 34).
    pub(crate) fn value(&self) -> f64 {
        let (a, b) = self.parts();
        a * a + b * b
    }

    /// `f'(t) = −4 t A − 2 ρ B`.
    pub(crate) fn slope(&self) -> f64 {
        let (a, b) = self.parts();
        -4.0 * self.t * a - 2.0 * self.rho * b
    }

    /// `f''(t)`.
    pub(crate) fn curvature(&self) -> f64 {
        let t = self.t;
        let (a, _) = self.parts();
        let inside = if t * t < 1.0 { 8.0 * t * t } else { 0.0 };
        let behind = if t < 1.0 {
            2.0 * self.rho * self.rho
        } else {
            0.0
        };
        -4.0 * a + inside + behind
    }
}

/// `f` of eq. 34 for two round items (see the module documentation).
pub fn round_overlap_measure<const N: usize>(i: &Body<N>, j: &Body<N>) -> f64 {
    RoundPair::of(i, j).value()
}
