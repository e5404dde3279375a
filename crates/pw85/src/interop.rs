//! Conversions between nalgebra matrices and the PW85 storage (feature `nalgebra`).

use crate::contact::check_finite;
use crate::error::{Argument, Error};
use crate::sym::{Sym2, Sym3};
use nalgebra::{Matrix2, Matrix3};

/// Relative asymmetry tolerated in a matrix converted to symmetric storage.
pub const SYMMETRY_TOLERANCE: f64 = 1e-12;

/// The upper triangle of a symmetric 3×3 matrix, after checking that it is finite and
/// symmetric to [`SYMMETRY_TOLERANCE`] (relative to its largest entry). `argument` names the
/// matrix in the error.
///
/// # Errors
/// [`Error::NonFinite`] for a NaN or infinite entry; [`Error::NotSymmetric`] otherwise when
/// Mᵢⱼ and Mⱼᵢ differ by more than the tolerance.
pub fn sym3_from_matrix(m: &Matrix3<f64>, argument: Argument) -> Result<Sym3, Error> {
    check_finite(argument, m.as_slice())?;
    let scale = m.amax();
    for (i, j) in [(0, 1), (0, 2), (1, 2)] {
        if (m[(i, j)] - m[(j, i)]).abs() > SYMMETRY_TOLERANCE * scale {
            return Err(Error::NotSymmetric {
                argument,
                row: i,
                column: j,
            });
        }
    }
    Ok([
        m[(0, 0)],
        m[(0, 1)],
        m[(0, 2)],
        m[(1, 1)],
        m[(1, 2)],
        m[(2, 2)],
    ])
}

/// The full symmetric matrix of a PW85-stored one.
pub fn matrix_from_sym3(q: &Sym3) -> Matrix3<f64> {
    Matrix3::new(q[0], q[1], q[2], q[1], q[3], q[4], q[2], q[4], q[5])
}

/// The 2D counterpart of [`sym3_from_matrix`]: [Q11, Q12, Q22].
///
/// # Errors
/// As [`sym3_from_matrix`].
pub fn sym2_from_matrix(m: &Matrix2<f64>, argument: Argument) -> Result<Sym2, Error> {
    check_finite(argument, m.as_slice())?;
    if (m[(0, 1)] - m[(1, 0)]).abs() > SYMMETRY_TOLERANCE * m.amax() {
        return Err(Error::NotSymmetric {
            argument,
            row: 0,
            column: 1,
        });
    }
    Ok([m[(0, 0)], m[(0, 1)], m[(1, 1)]])
}

/// The full symmetric matrix of a PW85-stored 2×2 one.
pub fn matrix_from_sym2(q: &Sym2) -> Matrix2<f64> {
    Matrix2::new(q[0], q[1], q[1], q[2])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_and_contact() {
        let m = Matrix3::new(4.0, 1.0, -0.5, 1.0, 3.0, 0.25, -0.5, 0.25, 2.0);
        let q = sym3_from_matrix(&m, Argument::Q1).unwrap();
        assert_eq!(matrix_from_sym3(&q), m);
        let c = crate::contact_function(&[3.0, 0.0, 0.0], &q, &q).unwrap();
        assert!(c.mu2 > 0.0);
        let m2 = Matrix2::new(2.0, 0.5, 0.5, 1.0);
        assert_eq!(
            matrix_from_sym2(&sym2_from_matrix(&m2, Argument::Q2).unwrap()),
            m2
        );
    }

    #[test]
    fn asymmetric_and_non_finite_matrices_are_errors() {
        let m = Matrix3::new(4.0, 1.0, 0.0, 1.5, 3.0, 0.0, 0.0, 0.0, 2.0);
        assert!(matches!(
            sym3_from_matrix(&m, Argument::Q2),
            Err(Error::NotSymmetric {
                argument: Argument::Q2,
                row: 0,
                column: 1
            })
        ));
        let m = Matrix2::new(f64::NAN, 0.0, 0.0, 1.0);
        assert!(matches!(
            sym2_from_matrix(&m, Argument::Q1),
            Err(Error::NonFinite { .. })
        ));
    }
}
