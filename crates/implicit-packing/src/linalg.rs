//! Small fixed-size linear algebra, hand-written for speed (N = 2 or 3: every loop unrolls).
//!
//! The one non-trivial routine is [`graded_svd`], the singular value decomposition of the factor
//! `F = P_j^−½ Q_jᵀ Q_i P_i^½` of `S_ij = FᵀF`. `F` is *graded*: a row scaling times an
//! orthogonal matrix times a column scaling, `F = D₁ R D₂`. Its singular values are determined to
//! high relative accuracy by its entries (a relative perturbation of `R` moves them by a relative
//! amount of the same size), although `cond(S)` may reach 1e16; forming `S` would square the
//! condition number and destroy the small eigenvalues. We therefore
//!
//! 1. sort the rows of `F` by decreasing norm and take a Householder QR factorisation with column
//!    pivoting, `Π F P = Q_h T` (accurate for row-graded matrices when rows are pre-sorted), and
//! 2. run one-sided (Hestenes) Jacobi on `Tᵀ`, whose columns are the rows of `T`: column scaling
//!    does not affect one-sided Jacobi, so the singular values come out to a few ulps (this is the
//!    preconditioned Jacobi method of Demmel–Veselić and Drmač).
//!
//! # References
//! J. Demmel, K. Veselić, *Jacobi's method is more accurate than QR*, SIAM J. Matrix Anal. Appl.
//! 13 (1992). J. Demmel et al., *Computing the singular value decomposition with high relative
//! accuracy*, Linear Algebra Appl. 299 (1999). Z. Drmač, *A QR-preconditioned QR SVD method*, 1997.

use crate::lanes::Real;

/// Dot product.
#[inline(always)]
pub(crate) fn dot<T: Real, const N: usize>(a: &[T; N], b: &[T; N]) -> T {
    // Started from the first product, not from 0.0: `0.0 + x` cannot be folded (it turns
    // −0 into +0), and that one extra addition lengthened every dependent 3×3 product of the
    // pair kernel by a third.
    let mut s = a[0] * b[0];
    for k in 1..N {
        s = s + a[k] * b[k];
    }
    s
}

/// `Qᵀ v` for a row-major `Q`.
#[inline(always)]
pub(crate) fn mat_t_vec<T: Real, const N: usize>(q: &[[T; N]; N], v: &[T; N]) -> [T; N] {
    let mut out = *v;
    for k in 0..N {
        let mut s = q[0][k] * v[0];
        for m in 1..N {
            s = s + q[m][k] * v[m];
        }
        out[k] = s;
    }
    out
}

/// `Q v` for a row-major `Q`.
#[cfg(test)]
#[inline(always)]
pub(crate) fn mat_vec<const N: usize>(q: &[[f64; N]; N], v: &[f64; N]) -> [f64; N] {
    let mut out = [0.0; N];
    for m in 0..N {
        out[m] = dot(&q[m], v);
    }
    out
}

/// The "torque" `r × n`, as a 3-vector; in 2D only its third component is non-zero.
#[inline(always)]
pub(crate) fn torque<T: Real, const N: usize>(r: &[T; N], n: &[T; N]) -> [T; 3] {
    if N == 3 {
        [
            r[1] * n[2] - r[2] * n[1],
            r[2] * n[0] - r[0] * n[2],
            r[0] * n[1] - r[1] * n[0],
        ]
    } else {
        [T::splat(0.0), T::splat(0.0), r[0] * n[1] - r[1] * n[0]]
    }
}

/// One Hestenes rotation of columns `p`, `q` (kept as rows of `a`), applied to `bb` as well.
///
/// Rotates while `|γ| > 4ε sqrt(αβ)` (tested squared: the magnitudes the shapes allow keep
/// `αβ` and `γ²` normal). With `d = β − α`, `e = 2γ`, `w = |d| + sqrt(d² + e²)`, the rotation
/// `t = tan θ = sign(d) e / w` has `cos θ = w / sqrt(w² + e²)`, `sin θ = sign(d) e / sqrt(w² + e²)`:
/// two square roots and one division on the critical path instead of the textbook three
/// divisions (this routine dominates the cost of a pair term).
#[inline(always)]
fn jacobi_rotation<const N: usize>(
    a: &mut [[f64; N]; N],
    bb: &mut [f64; N],
    norms2: &mut [f64; N],
    p: usize,
    q: usize,
    largest: &mut f64,
) -> bool {
    const TOL2: f64 = 16.0 * f64::EPSILON * f64::EPSILON;
    let alpha = norms2[p];
    let beta = norms2[q];
    let gamma = dot(&a[p], &a[q]);
    let g2 = gamma * gamma;
    let ab = alpha * beta;
    if g2 <= TOL2 * ab {
        return false;
    }
    *largest = largest.max(g2 / ab);
    let d = beta - alpha;
    let e = 2.0 * gamma;
    let w = d.abs() + (d * d + e * e).sqrt();
    let inv = 1.0 / (w * w + e * e).sqrt();
    let cs = w * inv;
    let sn = if d >= 0.0 { e * inv } else { -e * inv };
    for m in 0..N {
        let ap = a[p][m];
        let aq = a[q][m];
        a[p][m] = cs * ap - sn * aq;
        a[q][m] = sn * ap + cs * aq;
    }
    let bp = bb[p];
    let bq = bb[q];
    bb[p] = cs * bp - sn * bq;
    bb[q] = sn * bp + cs * bq;
    // Recomputed rather than updated by ±tγ: the update loses the small norms.
    norms2[p] = dot(&a[p], &a[p]);
    norms2[q] = dot(&a[q], &a[q]);
    true
}

/// SVD of a graded `F` (rows: right singular vectors `v_k`), together with the coordinates of a
/// vector `c` in the right basis and of `b = F c` in the left basis.
#[derive(Debug, Clone, Copy)]
pub(crate) struct GradedSvd<const N: usize> {
    /// Singular values `σ_k` (unsorted).
    pub sigma: [f64; N],
    /// `v[k]` is the k-th right singular vector.
    pub v: [[f64; N]; N],
    /// `ĉ_k = v_kᵀ c`.
    pub chat: [f64; N],
    /// `g_k = w_kᵀ b = σ_k ĉ_k`.
    pub g: [f64; N],
}

/// Singular value decomposition of a graded `N × N` matrix `F`, see the module documentation.
///
/// `c` and `b` must satisfy `b = F c` mathematically; each of `ĉ_k = v_kᵀ c` and
/// `g_k = σ_k ĉ_k` is computed by the route with the smaller error bound: through `v_k` (error
/// `≈ ε σ_k |c|` on `g_k`) or through the left vector `w_k` (error `≈ ε |b|`).
pub(crate) fn graded_svd<const N: usize>(
    f: &[[f64; N]; N],
    c: &[f64; N],
    b: &[f64; N],
) -> GradedSvd<N> {
    // Row order by decreasing norm (the permutation only relabels the left basis).
    let mut row_norm2 = [0.0; N];
    for r in 0..N {
        row_norm2[r] = dot(&f[r], &f[r]);
    }
    let mut order = [0usize; N];
    for (k, o) in order.iter_mut().enumerate() {
        *o = k;
    }
    for k in 1..N {
        let mut m = k;
        while m > 0 && row_norm2[order[m]] > row_norm2[order[m - 1]] {
            order.swap(m, m - 1);
            m -= 1;
        }
    }
    let mut a = [[0.0; N]; N];
    let mut bb = [0.0; N];
    for r in 0..N {
        a[r] = f[order[r]];
        bb[r] = b[order[r]];
    }

    // Householder QR with column pivoting.
    let mut cols = [0usize; N];
    for (k, o) in cols.iter_mut().enumerate() {
        *o = k;
    }
    for k in 0..N {
        let mut best = k;
        let mut best_norm = -1.0;
        for j in k..N {
            let mut s = 0.0;
            for r in k..N {
                s += a[r][j] * a[r][j];
            }
            if s > best_norm {
                best_norm = s;
                best = j;
            }
        }
        if best != k {
            for row in a.iter_mut() {
                row.swap(k, best);
            }
            cols.swap(k, best);
        }
        if k + 1 == N || best_norm == 0.0 {
            continue;
        }
        let norm = best_norm.sqrt();
        let x0 = a[k][k];
        let alpha = if x0 >= 0.0 { -norm } else { norm };
        // v = x − α e₁, H = I − 2 v vᵀ / vᵀv; vᵀv = 2 (|x|² − α x₀) without cancellation.
        let mut v = [0.0; N];
        v[k] = x0 - alpha;
        for r in k + 1..N {
            v[r] = a[r][k];
        }
        let vtv = 2.0 * (best_norm - alpha * x0);
        let beta = 2.0 / vtv;
        a[k][k] = alpha;
        for r in k + 1..N {
            a[r][k] = 0.0;
        }
        for j in k + 1..N {
            let mut s = 0.0;
            for r in k..N {
                s += v[r] * a[r][j];
            }
            let s = s * beta;
            for r in k..N {
                a[r][j] -= s * v[r];
            }
        }
        let mut s = 0.0;
        for r in k..N {
            s += v[r] * bb[r];
        }
        let s = s * beta;
        for r in k..N {
            bb[r] -= s * v[r];
        }
    }

    // One-sided Jacobi on Tᵀ: its columns are the rows of T, kept in `a`.
    let mut norms2 = [0.0; N];
    for k in 0..N {
        norms2[k] = dot(&a[k], &a[k]);
    }
    // Pairs visited with constant indices, so that the columns stay in registers.
    for _sweep in 0..30 {
        let mut largest = 0.0f64;
        let mut rotated = jacobi_rotation(&mut a, &mut bb, &mut norms2, 0, 1, &mut largest);
        if N == 3 {
            rotated |= jacobi_rotation(&mut a, &mut bb, &mut norms2, 0, 2, &mut largest);
            rotated |= jacobi_rotation(&mut a, &mut bb, &mut norms2, 1, 2, &mut largest);
        }
        // Convergence is quadratic: once every rotation of a sweep was below 1e-16 in γ²/αβ
        // (|γ| < 1e-8 sqrt(αβ)), the next sweep would find nothing to rotate.
        if !rotated || largest < 1e-16 {
            break;
        }
    }

    let c_norm = dot(c, c).sqrt();
    let b_norm = dot(&bb, &bb).sqrt();
    let mut out = GradedSvd {
        sigma: [0.0; N],
        v: [[0.0; N]; N],
        chat: [0.0; N],
        g: [0.0; N],
    };
    for k in 0..N {
        let sigma = norms2[k].sqrt();
        out.sigma[k] = sigma;
        let inv = 1.0 / sigma;
        for m in 0..N {
            out.v[k][cols[m]] = a[k][m] * inv;
        }
        if sigma * c_norm <= b_norm {
            let ch = dot(&out.v[k], c);
            out.chat[k] = ch;
            out.g[k] = sigma * ch;
        } else {
            out.g[k] = bb[k];
            out.chat[k] = bb[k] * inv;
        }
    }
    out
}

/// Gaussian elimination with partial pivoting on the leading `dim × dim` block; `None` if the
/// matrix is singular to working precision.
pub(crate) fn solve_small(
    m: &mut [[f64; 4]; 4],
    rhs: &mut [f64; 4],
    dim: usize,
) -> Option<[f64; 4]> {
    let scale = m.iter().flatten().fold(0.0f64, |s, v| s.max(v.abs()));
    for col in 0..dim {
        let mut p = col;
        for r in col + 1..dim {
            if m[r][col].abs() > m[p][col].abs() {
                p = r;
            }
        }
        if m[p][col].abs() <= 1e-13 * scale {
            return None;
        }
        m.swap(col, p);
        rhs.swap(col, p);
        for r in col + 1..dim {
            let factor = m[r][col] / m[col][col];
            for s in col..dim {
                m[r][s] -= factor * m[col][s];
            }
            rhs[r] -= factor * rhs[col];
        }
    }
    let mut x = [0.0; 4];
    for r in (0..dim).rev() {
        let mut v = rhs[r];
        for s in r + 1..dim {
            v -= m[r][s] * x[s];
        }
        x[r] = v / m[r][r];
    }
    Some(x)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn svd_reconstructs_a_graded_matrix() {
        let q = crate::shape::rotation_3d([0.3, 1.0, -0.7]);
        let d1 = [1e4, 1.0, 1e-3];
        let d2 = [1e-2, 3.0, 1e5];
        let mut f = [[0.0; 3]; 3];
        for r in 0..3 {
            for k in 0..3 {
                f[r][k] = d1[r] * q[r][k] * d2[k];
            }
        }
        let c = [0.3, -2.0, 1e-3];
        let b = mat_vec(&f, &c);
        let svd = graded_svd(&f, &c, &b);
        // Orthonormal right vectors, and |F v_k| = σ_k.
        for k in 0..3 {
            for l in 0..3 {
                let d = dot(&svd.v[k], &svd.v[l]);
                let expect = if k == l { 1.0 } else { 0.0 };
                assert!((d - expect).abs() < 1e-14, "{k} {l} {d}");
            }
            let fv = mat_vec(&f, &svd.v[k]);
            let n = dot(&fv, &fv).sqrt();
            assert!(
                (n / svd.sigma[k] - 1.0).abs() < 1e-12,
                "{n} {}",
                svd.sigma[k]
            );
        }
        // Product of singular values equals |det F| = Π d1 Π d2 to full relative accuracy.
        let det: f64 = d1.iter().product::<f64>() * d2.iter().product::<f64>();
        let prod: f64 = svd.sigma.iter().product();
        assert!((prod / det - 1.0).abs() < 1e-14, "{prod} {det}");
        for k in 0..3 {
            assert!((svd.g[k] - svd.sigma[k] * svd.chat[k]).abs() <= 1e-12 * dot(&b, &b).sqrt());
        }
    }
}
