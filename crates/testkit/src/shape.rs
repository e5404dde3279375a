//! Quadratic forms of ellipsoids and ellipses, and random pairs of them.
//!
//! Conventions (those of `validation/reference/README.md`): semi-axis k lies along column k of
//! the rotation; the 3D rotation of a quaternion (w, x, y, z) is the active Hamilton rotation
//! `v ↦ q v q*`, normalised by `w² + x² + y² + z²`; the 2D rotation by θ is
//! `[[cos θ, −sin θ], [sin θ, cos θ]]`. A form is `Q = R diag(a²) Rᵀ`, stored as its upper
//! triangle row by row: `[Q11, Q12, Q13, Q22, Q23, Q33]` in 3D, `[Q11, Q12, Q22]` in 2D.

use crate::Rng;

/// The rotation matrix of a quaternion (w, x, y, z), which need not be exactly unit: column k
/// is the image of axis k under v ↦ q v q*, computed as v + 2w (u × v) + 2 u × (u × v) for the
/// normalised q = (w, u) — another route than the matrix formula the crates use, so that a
/// test comparing the two can fail.
pub fn rotation(q: [f64; 4]) -> [[f64; 3]; 3] {
    let norm = q.iter().map(|v| v * v).sum::<f64>().sqrt();
    let [w, x, y, z] = q.map(|v| v / norm);
    let u = [x, y, z];
    let cross = |a: [f64; 3], b: [f64; 3]| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    let image = |k: usize| {
        let v: [f64; 3] = std::array::from_fn(|i| if i == k { 1.0 } else { 0.0 });
        let t = cross(u, v);
        let tt = cross(u, t);
        std::array::from_fn(|i| v[i] + 2.0 * w * t[i] + 2.0 * tt[i])
    };
    let columns: [[f64; 3]; 3] = std::array::from_fn(image);
    std::array::from_fn(|row| std::array::from_fn(|col| columns[col][row]))
}

/// `R diag(a²) Rᵀ` for the semi-axes `axes` and the rotation of the quaternion `q`.
pub fn ellipsoid_form(axes: [f64; 3], q: [f64; 4]) -> [f64; 6] {
    let r = rotation(q);
    let entry = |i: usize, j: usize| (0..3).map(|k| r[i][k] * axes[k] * axes[k] * r[j][k]).sum();
    [
        entry(0, 0),
        entry(0, 1),
        entry(0, 2),
        entry(1, 1),
        entry(1, 2),
        entry(2, 2),
    ]
}

/// `R diag(a²) Rᵀ` for the semi-axes `axes` and the rotation by `theta`.
pub fn ellipse_form(axes: [f64; 2], theta: f64) -> [f64; 3] {
    let (s, c) = theta.sin_cos();
    let (a2, b2) = (axes[0] * axes[0], axes[1] * axes[1]);
    [
        c * c * a2 + s * s * b2,
        c * s * (a2 - b2),
        s * s * a2 + c * c * b2,
    ]
}

/// The upper triangle of a symmetric 3 × 3 matrix, row by row (the storage of the forms).
pub fn upper(m: &[[f64; 3]; 3]) -> [f64; 6] {
    [m[0][0], m[0][1], m[0][2], m[1][1], m[1][2], m[2][2]]
}

/// A pair of ellipsoids in the PW85 parametrisation: `r12 = c2 − c1` and the two forms.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pair3 {
    /// Centre of the second minus centre of the first.
    pub r12: [f64; 3],
    /// Form of the first.
    pub q1: [f64; 6],
    /// Form of the second.
    pub q2: [f64; 6],
}

/// A pair of ellipses in the PW85 parametrisation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pair2 {
    /// Centre of the second minus centre of the first.
    pub r12: [f64; 2],
    /// Form of the first.
    pub q1: [f64; 3],
    /// Form of the second.
    pub q2: [f64; 3],
}

impl Rng {
    /// The form of an ellipsoid with the given semi-axes, uniformly randomly oriented.
    pub fn ellipsoid(&mut self, axes: [f64; 3]) -> [f64; 6] {
        ellipsoid_form(axes, self.unit_quaternion())
    }

    /// The form of an ellipse with the given semi-axes, at an angle uniform in [0, 2π).
    pub fn ellipse(&mut self, axes: [f64; 2]) -> [f64; 3] {
        ellipse_form(axes, std::f64::consts::TAU * self.uniform())
    }

    /// Semi-axes `10^u` with `u` uniform in [−decades, 0] each: aspect ratios up to
    /// `10^decades`.
    pub fn axes<const D: usize>(&mut self, decades: f64) -> [f64; D] {
        std::array::from_fn(|_| 10f64.powf(self.range(-decades, 0.0)))
    }

    /// Two randomly oriented ellipsoids with the given semi-axes, centres `distance` apart in a
    /// uniformly random direction.
    pub fn ellipsoid_pair(&mut self, axes1: [f64; 3], axes2: [f64; 3], distance: f64) -> Pair3 {
        let q1 = self.ellipsoid(axes1);
        let q2 = self.ellipsoid(axes2);
        let r12 = self.direction().map(|x| x * distance);
        Pair3 { r12, q1, q2 }
    }

    /// Two randomly oriented ellipses with the given semi-axes, centres `distance` apart in a
    /// uniformly random direction.
    pub fn ellipse_pair(&mut self, axes1: [f64; 2], axes2: [f64; 2], distance: f64) -> Pair2 {
        let q1 = self.ellipse(axes1);
        let q2 = self.ellipse(axes2);
        let (s, c) = (std::f64::consts::TAU * self.uniform()).sin_cos();
        Pair2 {
            r12: [distance * c, distance * s],
            q1,
            q2,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() <= 1e-14 * (1.0 + b.abs())
    }

    #[test]
    fn rotation_is_orthogonal_and_matches_half_turns() {
        let mut rng = Rng::new(3);
        for _ in 0..1000 {
            let r = rotation(rng.unit_quaternion());
            for i in 0..3 {
                for j in 0..3 {
                    let dot: f64 = (0..3).map(|k| r[k][i] * r[k][j]).sum();
                    assert!(close(dot, f64::from(u8::from(i == j))), "{r:?}");
                }
            }
        }
        // A quarter turn about z (q = (cos π/4, 0, 0, sin π/4)) takes x to y.
        let h = std::f64::consts::FRAC_1_SQRT_2;
        let r = rotation([h, 0.0, 0.0, h]);
        assert!(close(r[1][0], 1.0) && close(r[0][1], -1.0) && close(r[2][2], 1.0));
    }

    #[test]
    fn forms_have_the_semi_axes_as_principal_lengths() {
        let mut rng = Rng::new(4);
        for _ in 0..1000 {
            let axes = rng.axes::<3>(2.0);
            let q = rng.unit_quaternion();
            let f = ellipsoid_form(axes, q);
            let r = rotation(q);
            // Column k of R is the direction of semi-axis k: Q r_k = a_k² r_k.
            let m = [[f[0], f[1], f[2]], [f[1], f[3], f[4]], [f[2], f[4], f[5]]];
            for k in 0..3 {
                for i in 0..3 {
                    let qr: f64 = (0..3).map(|j| m[i][j] * r[j][k]).sum();
                    assert!((qr - axes[k] * axes[k] * r[i][k]).abs() <= 1e-14, "{qr}");
                }
            }
            let (a, theta) = ([axes[0], axes[1]], rng.range(-3.0, 3.0));
            let e = ellipse_form(a, theta);
            let (s, c) = theta.sin_cos();
            assert!(close(e[0] * c + e[1] * s, a[0] * a[0] * c));
            assert!(close(e[1] * c + e[2] * s, a[0] * a[0] * s));
        }
    }

    #[test]
    fn pairs_are_at_the_requested_distance() {
        let mut rng = Rng::new(5);
        let p = rng.ellipsoid_pair([1.0, 0.5, 0.25], [2.0, 1.0, 1.0], 3.0);
        let d: f64 = p.r12.iter().map(|x| x * x).sum::<f64>().sqrt();
        assert!(close(d, 3.0));
        let p = rng.ellipse_pair([1.0, 0.5], [2.0, 1.0], 3.0);
        assert!(close(p.r12[0].hypot(p.r12[1]), 3.0));
    }
}
