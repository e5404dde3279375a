//! Symmetric matrices in the storage of the PW85 library, and the small kernels on them.
//!
//! A symmetric 3×3 matrix is `[f64; 6]`, its upper triangle in row-major order (theory eq. 3):
//!
//! ```text
//!     ⎡ q[0] q[1] q[2] ⎤
//! Q = ⎢      q[3] q[4] ⎥
//!     ⎣ sym.      q[5] ⎦
//! ```
//!
//! A symmetric 2×2 matrix is `[f64; 3]` = Q11, Q12, Q22.
//!
//! These kernels are hand-written rather than taken from nalgebra: at this size the generic
//! dense code spends more time on dimension bookkeeping than on arithmetic, and the contact
//! function calls them tens of millions of times.

use crate::arith::Arith;

/// A symmetric 3×3 matrix: Q11, Q12, Q13, Q22, Q23, Q33.
pub type Sym3 = [f64; 6];
/// A symmetric 2×2 matrix: Q11, Q12, Q22.
pub type Sym2 = [f64; 3];

/// Determinant of a symmetric 3×3 matrix, by cofactor expansion along the first row.
pub fn det_sym(a: &Sym3) -> f64 {
    det_generic(a, &adjugate_generic(a))
}

/// The adjugate adj(A) (transpose of the cofactor matrix; symmetric when A is), in the same
/// storage. For invertible A, adj(A) = det(A) A⁻¹.
pub fn adjugate(a: &Sym3) -> Sym3 {
    adjugate_generic(a)
}

/// xᵀ adj(A) x, the numerator of xᵀ A⁻¹ x = xᵀ adj(A) x / det(A) (theory eq. 16a).
pub fn xt_adj_x(x: &[f64; 3], a: &Sym3) -> f64 {
    quadratic_form_generic(&outer_generic(x), &adjugate_generic(a))
}

/// The quadratic form xᵀ A x.
pub fn quadratic_form(x: &[f64; 3], a: &Sym3) -> f64 {
    quadratic_form_generic(&outer_generic(x), a)
}

/// The product A x.
pub fn mat_vec(a: &Sym3, x: &[f64; 3]) -> [f64; 3] {
    [
        a[0] * x[0] + a[1] * x[1] + a[2] * x[2],
        a[1] * x[0] + a[3] * x[1] + a[4] * x[2],
        a[2] * x[0] + a[4] * x[1] + a[5] * x[2],
    ]
}

/// The mixed adjugate M(A, B) = adj(A + B) − adj(A) − adj(B), so that
/// adj(sA + tB) = s² adj(A) + st M(A, B) + t² adj(B). It is positive semi-definite when A and
/// B are (it is the polarisation of the second compound matrix).
pub fn mixed_adjugate(a: &Sym3, b: &Sym3) -> Sym3 {
    mixed_adjugate_generic(a, b)
}

/// tr(adj(A) B), the derivative of det(A + εB) at ε = 0. Positive when A and B are positive
/// definite.
pub fn trace_adj_product(a: &Sym3, b: &Sym3) -> f64 {
    frobenius_generic(&adjugate_generic(a), b)
}

/// Determinant of a symmetric 2×2 matrix.
pub fn det_sym_2d(a: &Sym2) -> f64 {
    a[0] * a[2] - a[1] * a[1]
}

/// xᵀ adj(A) x for a symmetric 2×2 matrix, where adj(A) = [[A22, −A12], [−A12, A11]].
pub fn xt_adj_x_2d(x: &[f64; 2], a: &Sym2) -> f64 {
    a[2] * x[0] * x[0] - 2.0 * a[1] * x[0] * x[1] + a[0] * x[1] * x[1]
}

/// Solves A y = x for a symmetric positive definite A by an LDLᵀ factorisation (no square
/// roots). Returns `None` when a pivot is not positive (A not positive definite, as computed).
pub fn solve_ldlt(a: &Sym3, x: &[f64; 3]) -> Option<[f64; 3]> {
    let d1 = a[0];
    if d1.partial_cmp(&0.0) != Some(core::cmp::Ordering::Greater) {
        return None;
    }
    let l21 = a[1] / d1;
    let l31 = a[2] / d1;
    let d2 = a[3] - l21 * a[1];
    if d2.partial_cmp(&0.0) != Some(core::cmp::Ordering::Greater) {
        return None;
    }
    let l32 = (a[4] - l31 * a[1]) / d2;
    let d3 = a[5] - l31 * a[2] - l32 * l32 * d2;
    if d3.partial_cmp(&0.0) != Some(core::cmp::Ordering::Greater) {
        return None;
    }
    let z1 = x[0];
    let z2 = x[1] - l21 * z1;
    let z3 = x[2] - l31 * z1 - l32 * z2;
    let y3 = z3 / d3;
    let y2 = z2 / d2 - l32 * y3;
    let y1 = z1 / d1 - l21 * y2 - l31 * y3;
    Some([y1, y2, y3])
}

// ---- generic forms, shared by the f64, magnitude and double-double evaluations ----

#[inline(always)]
pub(crate) fn lift6<T: Arith>(a: &Sym3) -> [T; 6] {
    a.map(T::lift)
}

/// The entries of x xᵀ in symmetric storage.
#[inline(always)]
pub(crate) fn outer_generic<T: Arith>(x: &[f64; 3]) -> [T; 6] {
    let [x0, x1, x2] = x.map(T::lift);
    [x0 * x0, x0 * x1, x0 * x2, x1 * x1, x1 * x2, x2 * x2]
}

#[inline(always)]
pub(crate) fn adjugate_generic<T: Arith>(a: &[T; 6]) -> [T; 6] {
    let [a0, a1, a2, a3, a4, a5] = *a;
    [
        a3 * a5 - a4 * a4,
        a2 * a4 - a1 * a5,
        a1 * a4 - a2 * a3,
        a0 * a5 - a2 * a2,
        a1 * a2 - a0 * a4,
        a0 * a3 - a1 * a1,
    ]
}

#[inline(always)]
pub(crate) fn det_generic<T: Arith>(a: &[T; 6], adj: &[T; 6]) -> T {
    a[0] * adj[0] + a[1] * adj[1] + a[2] * adj[2]
}

#[inline(always)]
pub(crate) fn mixed_adjugate_generic<T: Arith>(a: &[T; 6], b: &[T; 6]) -> [T; 6] {
    [
        a[3] * b[5] + b[3] * a[5] - (a[4] * b[4]).twice(),
        a[2] * b[4] + b[2] * a[4] - (a[1] * b[5] + b[1] * a[5]),
        a[1] * b[4] + b[1] * a[4] - (a[2] * b[3] + b[2] * a[3]),
        a[0] * b[5] + b[0] * a[5] - (a[2] * b[2]).twice(),
        a[1] * b[2] + b[1] * a[2] - (a[0] * b[4] + b[0] * a[4]),
        a[0] * b[3] + b[0] * a[3] - (a[1] * b[1]).twice(),
    ]
}

/// Σᵢⱼ Aᵢⱼ Bᵢⱼ = tr(A B) for symmetric A, B.
#[inline(always)]
pub(crate) fn frobenius_generic<T: Arith>(a: &[T; 6], b: &[T; 6]) -> T {
    a[0] * b[0] + a[3] * b[3] + a[5] * b[5] + (a[1] * b[1] + a[2] * b[2] + a[4] * b[4]).twice()
}

/// xᵀ A x given the entries of x xᵀ.
#[inline(always)]
pub(crate) fn quadratic_form_generic<T: Arith>(xx: &[T; 6], a: &[T; 6]) -> T {
    frobenius_generic(xx, a)
}

#[cfg(test)]
// Index loops read like the matrix algebra they check.
#[allow(clippy::needless_range_loop)]
mod tests {
    use super::*;

    const A: Sym3 = [4.0, 1.0, -0.5, 3.0, 0.25, 2.0];
    const B: Sym3 = [1.5, -0.3, 0.2, 2.5, 0.7, 3.5];

    fn full(a: &Sym3) -> [[f64; 3]; 3] {
        [[a[0], a[1], a[2]], [a[1], a[3], a[4]], [a[2], a[4], a[5]]]
    }

    fn det_full(m: &[[f64; 3]; 3]) -> f64 {
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    }

    #[test]
    fn det_matches_the_full_expansion() {
        assert!((det_sym(&A) - det_full(&full(&A))).abs() < 1e-13);
    }

    #[test]
    fn adjugate_times_matrix_is_det_identity() {
        let adj = full(&adjugate(&A));
        let a = full(&A);
        let d = det_sym(&A);
        for i in 0..3 {
            for j in 0..3 {
                let p: f64 = (0..3).map(|k| adj[i][k] * a[k][j]).sum();
                let expected = if i == j { d } else { 0.0 };
                assert!((p - expected).abs() < 1e-12, "({i},{j}): {p} vs {expected}");
            }
        }
    }

    #[test]
    fn mixed_adjugate_expands_the_pencil() {
        let (s, t) = (0.3, 0.7);
        let pencil: Sym3 = core::array::from_fn(|k| s * A[k] + t * B[k]);
        let lhs = adjugate(&pencil);
        let (aa, ab, bb) = (adjugate(&A), mixed_adjugate(&A, &B), adjugate(&B));
        for k in 0..6 {
            let rhs = s * s * aa[k] + s * t * ab[k] + t * t * bb[k];
            assert!((lhs[k] - rhs).abs() < 1e-13, "entry {k}");
        }
    }

    #[test]
    fn trace_adj_product_is_the_derivative_of_det() {
        let h = 1e-6;
        let plus: Sym3 = core::array::from_fn(|k| A[k] + h * B[k]);
        let minus: Sym3 = core::array::from_fn(|k| A[k] - h * B[k]);
        let fd = (det_sym(&plus) - det_sym(&minus)) / (2.0 * h);
        assert!((fd - trace_adj_product(&A, &B)).abs() < 1e-7);
    }

    #[test]
    fn xt_adj_x_is_det_times_inverse_form() {
        let x = [0.3, -1.2, 2.0];
        let y = solve_ldlt(&A, &x).unwrap();
        let direct = x[0] * y[0] + x[1] * y[1] + x[2] * y[2];
        assert!((xt_adj_x(&x, &A) - det_sym(&A) * direct).abs() < 1e-12);
    }

    #[test]
    fn ldlt_rejects_indefinite_matrices() {
        assert!(solve_ldlt(&[1.0, 2.0, 0.0, 1.0, 0.0, 1.0], &[1.0, 0.0, 0.0]).is_none());
        assert!(solve_ldlt(&[f64::NAN, 0.0, 0.0, 1.0, 0.0, 1.0], &[1.0, 0.0, 0.0]).is_none());
    }

    #[test]
    fn two_d_kernels() {
        let a: Sym2 = [2.0, 0.5, 1.0];
        assert_eq!(det_sym_2d(&a), 1.75);
        // xᵀ adj(A) x = det(A) xᵀ A⁻¹ x; A⁻¹ = [[1, -0.5], [-0.5, 2]] / 1.75.
        let x = [1.0, 2.0];
        assert!((xt_adj_x_2d(&x, &a) - (1.0 - 2.0 + 8.0)).abs() < 1e-15);
    }
}
