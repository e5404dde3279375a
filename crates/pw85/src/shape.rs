//! Quadratic forms Q = Σₖ lₖ² vₖ vₖᵀ (theory eq. 2) from semi-axis lengths lₖ and their
//! directions vₖ, the columns of a rotation.
//!
//! Conventions (shared with `validation/reference/README.md` and the packing paper): semi-axis k
//! lies along column k of the rotation matrix R, so Q = R diag(l²) Rᵀ; a quaternion
//! (w, x, y, z) is the Hamilton active rotation v ↦ q v q*, normalised by w² + x² + y² + z²;
//! in 2D, R = [[cos θ, −sin θ], [sin θ, cos θ]] (packing paper eq. 1).

use crate::error::Error;
use crate::sym::{Sym2, Sym3};

/// A rotation matrix, row-major: `r[i][j]` is row i, column j.
pub type Rotation = [[f64; 3]; 3];

/// Deviation from orthonormality tolerated in a user-supplied rotation matrix, per entry of
/// RᵀR − I. Loose enough for matrices that went through single precision or a text file with
/// 8 digits, tight enough to catch a matrix that is not a rotation at all.
pub const ROTATION_TOLERANCE: f64 = 1e-6;

/// The spheroid with equatorial semi-axis `a`, polar semi-axis `c` and axis of revolution
/// `n`: Q = a² I + (c² − a²) n̂ n̂ᵀ (n is normalised here).
///
/// # Errors
/// [`Error::InvalidSemiAxis`] unless a and c are positive and finite (index 0 for a, 1 for c);
/// [`Error::InvalidRotation`] when n is zero or not finite.
pub fn spheroid(a: f64, c: f64, n: &[f64; 3]) -> Result<Sym3, Error> {
    check_axes(&[a, c])?;
    let norm2 = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
    if !(norm2.is_finite() && norm2 > 0.0) {
        return Err(Error::InvalidRotation {
            reason: "the axis of revolution must be a non-zero finite vector",
        });
    }
    let k = (c * c - a * a) / norm2;
    let a2 = a * a;
    Ok([
        a2 + k * n[0] * n[0],
        k * n[0] * n[1],
        k * n[0] * n[2],
        a2 + k * n[1] * n[1],
        k * n[1] * n[2],
        a2 + k * n[2] * n[2],
    ])
}

/// Q = R diag(l²) Rᵀ from semi-axes `axes` and a rotation matrix whose column k is the
/// direction of semi-axis k.
///
/// # Errors
/// [`Error::InvalidSemiAxis`], or [`Error::InvalidRotation`] when R is not finite, not
/// orthogonal within [`ROTATION_TOLERANCE`], or has determinant −1.
pub fn from_axes_rotation(axes: &[f64; 3], rotation: &Rotation) -> Result<Sym3, Error> {
    check_axes(axes)?;
    check_rotation(rotation)?;
    Ok(from_axes_rotation_unchecked(axes, rotation))
}

/// Q from semi-axes and a quaternion (w, x, y, z), normalised here.
///
/// # Errors
/// [`Error::InvalidSemiAxis`], or [`Error::InvalidRotation`] for a zero or non-finite
/// quaternion.
pub fn from_axes_quaternion(axes: &[f64; 3], quaternion: &[f64; 4]) -> Result<Sym3, Error> {
    check_axes(axes)?;
    Ok(from_axes_rotation_unchecked(
        axes,
        &rotation_from_quaternion(quaternion)?,
    ))
}

/// Q from semi-axes and the rotation angles `[φ, θ, ψ]` of the packing paper's eq. 2,
/// R = R_z(ψ) R_y(θ) R_x(φ) (see [`rotation_from_angles`]).
///
/// # Errors
/// [`Error::InvalidSemiAxis`], or [`Error::InvalidRotation`] for a non-finite angle.
pub fn from_axes_angles(axes: &[f64; 3], angles: &[f64; 3]) -> Result<Sym3, Error> {
    check_axes(axes)?;
    if angles.iter().any(|a| !a.is_finite()) {
        return Err(Error::InvalidRotation {
            reason: "the rotation angles must be finite",
        });
    }
    Ok(from_axes_rotation_unchecked(
        axes,
        &rotation_from_angles(angles),
    ))
}

/// The 2D quadratic form [Q11, Q12, Q22] of an ellipse with semi-axes `axes` whose first
/// semi-axis makes the angle θ with the x axis (packing paper eq. 1).
///
/// # Errors
/// [`Error::InvalidSemiAxis`], or [`Error::InvalidRotation`] for a non-finite angle.
pub fn from_axes_angle_2d(axes: &[f64; 2], theta: f64) -> Result<Sym2, Error> {
    check_axes(axes)?;
    if !theta.is_finite() {
        return Err(Error::InvalidRotation {
            reason: "the rotation angle must be finite",
        });
    }
    let (s, c) = theta.sin_cos();
    let (a2, b2) = (axes[0] * axes[0], axes[1] * axes[1]);
    Ok([
        a2 * c * c + b2 * s * s,
        (a2 - b2) * c * s,
        a2 * s * s + b2 * c * c,
    ])
}

/// The rotation matrix of a quaternion (w, x, y, z), normalised by w² + x² + y² + z² (the
/// Hamilton convention, active rotation v ↦ q v q*).
///
/// # Errors
/// [`Error::InvalidRotation`] for a zero or non-finite quaternion.
pub fn rotation_from_quaternion(q: &[f64; 4]) -> Result<Rotation, Error> {
    let [w, x, y, z] = *q;
    let n = w * w + x * x + y * y + z * z;
    if !(n.is_finite() && n > 0.0) {
        return Err(Error::InvalidRotation {
            reason: "the quaternion must be non-zero and finite",
        });
    }
    let s = 2.0 / n;
    Ok([
        [
            1.0 - s * (y * y + z * z),
            s * (x * y - w * z),
            s * (x * z + w * y),
        ],
        [
            s * (x * y + w * z),
            1.0 - s * (x * x + z * z),
            s * (y * z - w * x),
        ],
        [
            s * (x * z - w * y),
            s * (y * z + w * x),
            1.0 - s * (x * x + y * y),
        ],
    ])
}

/// The rotation of the packing paper's eq. 2 for the angles `[φ, θ, ψ]` (in the order they
/// are applied: about x, then y, then z; the same order as the `implicit-packing` crate):
///
/// ```text
///     ⎡ cθ cψ   sφ sθ cψ − cφ sψ   sφ sψ + cφ sθ cψ ⎤
/// R = ⎢ cθ sψ   cφ cψ + sφ sθ sψ   cφ sθ sψ − sφ cψ ⎥  = R_z(ψ) R_y(θ) R_x(φ).
///     ⎣ −sθ     sφ cθ              cφ cθ            ⎦
/// ```
pub fn rotation_from_angles(angles: &[f64; 3]) -> Rotation {
    let (sf, cf) = angles[0].sin_cos();
    let (st, ct) = angles[1].sin_cos();
    let (sp, cp) = angles[2].sin_cos();
    [
        [ct * cp, sf * st * cp - cf * sp, sf * sp + cf * st * cp],
        [ct * sp, cf * cp + sf * st * sp, cf * st * sp - sf * cp],
        [-st, sf * ct, cf * ct],
    ]
}

fn from_axes_rotation_unchecked(axes: &[f64; 3], r: &Rotation) -> Sym3 {
    let l2 = axes.map(|l| l * l);
    let q = |i: usize, j: usize| (0..3).map(|k| l2[k] * r[i][k] * r[j][k]).sum::<f64>();
    [q(0, 0), q(0, 1), q(0, 2), q(1, 1), q(1, 2), q(2, 2)]
}

fn check_axes(axes: &[f64]) -> Result<(), Error> {
    match axes.iter().position(|&l| !(l.is_finite() && l > 0.0)) {
        Some(index) => Err(Error::InvalidSemiAxis {
            index,
            value: axes[index],
        }),
        None => Ok(()),
    }
}

fn check_rotation(r: &Rotation) -> Result<(), Error> {
    if r.iter().flatten().any(|x| !x.is_finite()) {
        return Err(Error::InvalidRotation {
            reason: "the rotation matrix has a non-finite entry",
        });
    }
    for i in 0..3 {
        for j in 0..3 {
            let dot: f64 = (0..3).map(|k| r[k][i] * r[k][j]).sum();
            let expected = if i == j { 1.0 } else { 0.0 };
            if (dot - expected).abs() > ROTATION_TOLERANCE {
                return Err(Error::InvalidRotation {
                    reason: "the matrix is not orthogonal (its columns must be orthonormal)",
                });
            }
        }
    }
    let det = r[0][0] * (r[1][1] * r[2][2] - r[1][2] * r[2][1])
        - r[0][1] * (r[1][0] * r[2][2] - r[1][2] * r[2][0])
        + r[0][2] * (r[1][0] * r[2][1] - r[1][1] * r[2][0]);
    if det < 0.0 {
        return Err(Error::InvalidRotation {
            reason: "the matrix is a reflection (determinant −1), not a rotation",
        });
    }
    Ok(())
}

#[cfg(test)]
// Index loops read like the matrix algebra they check.
#[allow(clippy::needless_range_loop)]
mod tests {
    use super::*;
    use crate::sym::{det_sym, mat_vec};

    #[test]
    fn quaternion_and_angles_agree_on_a_rotation_about_z() {
        let psi = 0.7_f64;
        let q = [(psi / 2.0).cos(), 0.0, 0.0, (psi / 2.0).sin()];
        let a = rotation_from_quaternion(&q).unwrap();
        let b = rotation_from_angles(&[0.0, 0.0, psi]);
        for i in 0..3 {
            for j in 0..3 {
                assert!((a[i][j] - b[i][j]).abs() < 1e-15);
            }
        }
    }

    #[test]
    fn semi_axis_k_lies_along_column_k() {
        let axes = [3.0, 2.0, 0.5];
        let r = rotation_from_angles(&[0.3, -1.1, 2.0]);
        let q = from_axes_rotation(&axes, &r).unwrap();
        for k in 0..3 {
            let v = [r[0][k], r[1][k], r[2][k]];
            let qv = mat_vec(&q, &v);
            for i in 0..3 {
                assert!((qv[i] - axes[k] * axes[k] * v[i]).abs() < 1e-13);
            }
        }
        assert!((det_sym(&q) - (3.0f64 * 2.0 * 0.5).powi(2)).abs() < 1e-12);
    }

    #[test]
    fn spheroid_has_its_axes() {
        let q = spheroid(0.5, 2.0, &[0.0, 3.0, 4.0]).unwrap();
        let n = [0.0, 0.6, 0.8];
        let qn = mat_vec(&q, &n);
        for i in 0..3 {
            assert!((qn[i] - 4.0 * n[i]).abs() < 1e-14);
        }
        assert!((det_sym(&q) - 0.25 * 0.25 * 4.0).abs() < 1e-14);
    }

    #[test]
    fn bad_shapes_are_typed_errors() {
        assert_eq!(
            spheroid(0.0, 1.0, &[1.0, 0.0, 0.0]),
            Err(Error::InvalidSemiAxis {
                index: 0,
                value: 0.0
            })
        );
        assert!(matches!(
            spheroid(1.0, 1.0, &[0.0, 0.0, 0.0]),
            Err(Error::InvalidRotation { .. })
        ));
        assert!(matches!(
            from_axes_quaternion(&[1.0, -2.0, 1.0], &[1.0, 0.0, 0.0, 0.0]),
            Err(Error::InvalidSemiAxis { index: 1, .. })
        ));
        assert!(matches!(
            from_axes_quaternion(&[1.0, 2.0, f64::NAN], &[1.0, 0.0, 0.0, 0.0]),
            Err(Error::InvalidSemiAxis { index: 2, .. })
        ));
        assert!(matches!(
            from_axes_quaternion(&[1.0; 3], &[0.0; 4]),
            Err(Error::InvalidRotation { .. })
        ));
        let mut r = rotation_from_angles(&[0.1, 0.2, 0.3]);
        r[0][0] *= 1.1;
        assert!(matches!(
            from_axes_rotation(&[1.0; 3], &r),
            Err(Error::InvalidRotation { .. })
        ));
        let reflection = [[-1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        assert!(matches!(
            from_axes_rotation(&[1.0; 3], &reflection),
            Err(Error::InvalidRotation { .. })
        ));
        assert!(matches!(
            from_axes_angle_2d(&[1.0, 1.0], f64::INFINITY),
            Err(Error::InvalidRotation { .. })
        ));
    }

    #[test]
    fn ellipse_form() {
        let q = from_axes_angle_2d(&[2.0, 1.0], std::f64::consts::FRAC_PI_2).unwrap();
        assert!((q[0] - 1.0).abs() < 1e-15 && q[1].abs() < 1e-15 && (q[2] - 4.0).abs() < 1e-15);
    }
}
