//! The pair term: overlap measure of two ellipsoids (eqs. 3, 21–22, 34–36, Prop. 3.3).
//!
//! The transformation `T_ij(x) = P_i^−½ Q_iᵀ (x − c_j)` (eq. 3) maps `E_i` to the unit ball
//! centred at
//!
//! ```text
//! c = c_i^ij = P_i^−½ Q_iᵀ (c_i − c_j)
//! ```
//!
//! and `E_j` to `{x : xᵀ S x ≤ 1}`, `S = S_ij = FᵀF`, `F = P_j^−½ Q_jᵀ Q_i P_i^½`. With `X` a
//! global minimiser of `|x − c|²` subject to `xᵀ S x = 1` (eq. 35) and `U` its multiplier
//! (`X + U S X − c = 0`, eq. 22), the pair term is (eq. 34)
//!
//! ```text
//! f = max{0, 1 − d²}² + max{0, ε_ij − U}²,    d² = |c − X|²,
//! ε_ij = λ_min(P_i⁻¹) λ_min(P_i^½) λ_min(P_j) λ_min(P_j^−½)     (Prop. 3.3)
//! ```
//!
//! `f = 0` if and only if the ellipsoids do not overlap (Lemma 4.3); `f` is invariant under a
//! common scaling of both ellipsoids (Lemma 4.4). `f`, `U`, `X` and `d²` are not symmetric in
//! `(i, j)`: `i` is the ellipsoid mapped to the unit ball. Only the verdict is symmetric.
//!
//! `S` is never formed: its condition number reaches 1e16 for axis ratios of 1e4 because it is a
//! square. The SVD of the graded factor `F` gives its eigenvalues to a few ulps
//! (module `linalg`: one-sided Jacobi after a pivoted QR), and [`crate::projection`] solves the secular equation in that basis.
//!
//! # References
//! Birgin, Lobato, Martínez (2016), Sections 3–5.

use crate::linalg::{GradedSvd, graded_svd, mat_t_vec};
use crate::projection::{self, Projection};
use crate::shape::Body;

/// Everything the pair term computes, for reporting and for the derivatives.
#[derive(Debug, Clone, Copy)]
pub struct PairTerm<const N: usize> {
    /// The overlap measure `f` of eq. 34 (`0` iff no overlap).
    pub f: f64,
    /// `d² = |c − X|²`: squared distance in the frame where `E_i` is the unit ball.
    pub d2: f64,
    /// The multiplier `U` of eq. 22.
    pub u: f64,
    /// `ε_ij` of Prop. 3.3.
    pub eps: f64,
    /// `c = c_i^ij = P_i^−½ Q_iᵀ (c_i − c_j)`.
    pub c: [f64; N],
    /// `X`, a global minimiser of eq. 35, in the same frame as `c`.
    pub x: [f64; N],
    /// `X` is the unique minimiser (false in the hard case, where `U = −1/λ_max(S)`).
    pub x_unique: bool,
    /// `c` lies strictly inside `E_j^ij` (then `U ≤ 0` and the ellipsoids overlap).
    pub centre_inside: bool,
}

/// `ε_ij = λ_min(P_i⁻¹) λ_min(P_i^½) λ_min(P_j) λ_min(P_j^−½)
///       = min(l_i) min(l_j)² / (max(l_i)² max(l_j))` (Prop. 3.3): a positive lower bound of `U`
/// at any non-overlapping configuration.
pub fn epsilon<const N: usize>(li: &[f64; N], lj: &[f64; N]) -> f64 {
    let (mut imin, mut imax, mut jmin, mut jmax) = (f64::INFINITY, 0.0f64, f64::INFINITY, 0.0f64);
    for k in 0..N {
        imin = imin.min(li[k]);
        imax = imax.max(li[k]);
        jmin = jmin.min(lj[k]);
        jmax = jmax.max(lj[k]);
    }
    epsilon_from_extremes(imin, imax, jmin, jmax)
}

/// `ε_ij` from the extreme semi-axes: five roundings, ≤ 2.5 ulps.
#[inline(always)]
fn epsilon_from_extremes(imin: f64, imax: f64, jmin: f64, jmax: f64) -> f64 {
    imin * (jmin * jmin) / ((imax * imax) * jmax)
}

/// True when the enclosing balls of radius `max(l_i)`, `max(l_j)` do not overlap: then `f = 0`
/// (Section 5.2, `|c_i − c_j| ≥ r_i + r_j`).
pub fn bounding_spheres_apart<const N: usize>(i: &Body<N>, j: &Body<N>) -> bool {
    let ci = i.centre();
    let cj = j.centre();
    let mut dist2 = 0.0;
    for k in 0..N {
        let d = ci[k] - cj[k];
        dist2 += d * d;
    }
    let r = i.bounding_radius() + j.bounding_radius();
    dist2 >= r * r
}

/// True when the plane orthogonal to the centre line separates the ellipsoids: with
/// `n = c_j − c_i` and the support function `h(n) = |P^½ Qᵀ n|`, `h_i(n) + h_j(n) < |n|²`
/// (both sides scaled by `|n|`). Then they do not overlap and `f = 0`. A margin of 8 ulps keeps
/// rounding from declaring a barely overlapping pair separated.
///
/// Cheap (two 3×3 products and two square roots) and exact as an exclusion: the pair term need
/// not be solved for most non-overlapping neighbours in a packing.
pub fn separated_along_centre_line<const N: usize>(i: &Body<N>, j: &Body<N>) -> bool {
    let ci = i.centre();
    let cj = j.centre();
    let mut n = [0.0; N];
    let mut n2 = 0.0;
    for k in 0..N {
        n[k] = cj[k] - ci[k];
        n2 += n[k] * n[k];
    }
    let support = |b: &Body<N>| {
        let q = b.rotation();
        let l = b.semi_axes();
        let mut s = 0.0;
        for k in 0..N {
            let mut p = 0.0;
            for m in 0..N {
                p += q[m][k] * n[m];
            }
            let v = l[k] * p;
            s += v * v;
        }
        s.sqrt()
    };
    support(i) + support(j) < n2 * (1.0 - 8.0 * f64::EPSILON)
}

/// The SVD route with the direct route allowed where it applies.
pub(crate) fn solve_pair<const N: usize>(i: &Body<N>, j: &Body<N>) -> PairSolution<N> {
    solve_pair_with(i, j, true)
}

/// The full solution of one pair: the SVD of `F`, the secular-equation solution and the frames.
/// On the direct route (`direct = true`) the "eigenbasis" is the identity: `svd.v = I`,
/// `proj.xhat = X`, `proj.dhat = c − X`, and `svd.sigma`, `proj.t` are not set.
#[derive(Debug, Clone, Copy)]
pub(crate) struct PairSolution<const N: usize> {
    pub svd: GradedSvd<N>,
    pub proj: Projection<N>,
    pub c: [f64; N],
    pub x: [f64; N],
    pub eps: f64,
    pub direct: bool,
}

impl<const N: usize> PairSolution<N> {
    pub(crate) fn f(&self) -> f64 {
        let a = (1.0 - self.proj.d2).max(0.0);
        let b = (self.eps - self.proj.u).max(0.0);
        a * a + b * b
    }
}

/// Solves eq. 35 for one pair.
///
/// Two routes. When `c` lies outside `E_j^ij` (`|b|² > 1`, so `U > 0` and `I + U S` is
/// positive definite with eigenvalues ≥ 1) and
/// `cond(F) ≤ (max l_i/min l_i)(max l_j/min l_j) ≤ 8` (so `cond(S) ≤ 64`: forming `S` costs
/// at most ~64 ulps in the worst direction, ~1.4e-14, the size of the SVD route's own error;
/// with a bound of 16 the two routes were measured to differ by up to 9e-14), the *direct*
/// route solves the secular equation by Newton with the inverse of `I + U S`, with no
/// eigen-decomposition; it is two to three times faster and covers the paper's shapes (axis
/// ratios up to 2.8 for identical ellipsoids) at packing density. Every other pair
/// (centre inside, hard case, stiff shapes) takes the SVD route. `allow_direct = false` forces
/// the SVD route, which `∇U` needs (it works in the eigenbasis).
pub(crate) fn solve_pair_with<const N: usize>(
    i: &Body<N>,
    j: &Body<N>,
    allow_direct: bool,
) -> PairSolution<N> {
    let qi = i.rotation();
    let qj = j.rotation();
    let li = i.semi_axes();
    let lj = j.semi_axes();
    let ci = i.centre();
    let cj = j.centre();
    let mut delta = [0.0; N];
    for k in 0..N {
        delta[k] = ci[k] - cj[k];
    }
    let mut c = mat_t_vec(&qi, &delta);
    let mut b = mat_t_vec(&qj, &delta);
    for k in 0..N {
        c[k] /= li[k];
        b[k] /= lj[k];
    }
    // F = P_j^−½ (Q_jᵀ Q_i) P_i^½, entry by entry: a graded matrix with an orthogonal core.
    // Each entry carries a relative error of a few ulps, which moves the singular values by as
    // little (the graded structure); N reciprocals replace N² divisions.
    let mut inv_lj = [0.0; N];
    for a in 0..N {
        inv_lj[a] = 1.0 / lj[a];
    }
    let mut f = [[0.0; N]; N];
    for a in 0..N {
        for bcol in 0..N {
            let mut r = 0.0;
            for m in 0..N {
                r += qj[m][a] * qi[m][bcol];
            }
            f[a][bcol] = r * li[bcol] * inv_lj[a];
        }
    }
    let (imin, imax, jmin, jmax) = (
        i.min_semi_axis(),
        i.bounding_radius(),
        j.min_semi_axis(),
        j.bounding_radius(),
    );
    let eps = epsilon_from_extremes(imin, imax, jmin, jmax);
    if allow_direct {
        let b2: f64 = b.iter().map(|v| v * v).sum();
        // (l_max,i / l_min,i)(l_max,j / l_min,j) ≤ limit, without divisions.
        if b2 > 1.0
            && imax * jmax <= DIRECT_CONDITION_LIMIT * (imin * jmin)
            && let Some(d) = projection::solve_outside_direct(&f, &c, b2)
        {
            {
                let mut v = [[0.0; N]; N];
                for k in 0..N {
                    v[k][k] = 1.0;
                }
                let svd = GradedSvd {
                    sigma: [0.0; N],
                    v,
                    chat: c,
                    g: b,
                };
                let proj = Projection {
                    u: d.u,
                    xhat: d.x,
                    t: [0.0; N],
                    dhat: d.c_minus_x,
                    d2: d.d2,
                    inside: false,
                    hard: false,
                };
                return PairSolution {
                    svd,
                    proj,
                    c,
                    x: d.x,
                    eps,
                    direct: true,
                };
            }
        }
    }
    let svd = graded_svd(&f, &c, &b);
    let mut s = [0.0; N];
    for k in 0..N {
        s[k] = svd.sigma[k] * svd.sigma[k];
    }
    let proj = projection::solve(&s, &svd.chat, &svd.g);
    let mut x = [0.0; N];
    for k in 0..N {
        for m in 0..N {
            x[m] += svd.v[k][m] * proj.xhat[k];
        }
    }
    PairSolution {
        svd,
        proj,
        c,
        x,
        eps,
        direct: false,
    }
}

/// Above this bound on `cond(F)` the direct solve is not used (see [`solve_pair`]).
const DIRECT_CONDITION_LIMIT: f64 = 8.0;

/// How [`pair_term_by`] solves eq. 35.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Route {
    /// The fastest accurate route: a direct Newton solve with `LDLᵀ` when the centre is outside
    /// and `cond(F) ≤ 8`, the SVD route otherwise.
    Auto,
    /// Always the SVD of the factor `F` and the secular equation in its basis.
    Svd,
}

/// [`pair_term`] by a chosen route (both must agree to a few ulps; the tests compare them).
pub fn pair_term_by<const N: usize>(i: &Body<N>, j: &Body<N>, route: Route) -> PairTerm<N> {
    let sol = solve_pair_with(i, j, route == Route::Auto);
    PairTerm {
        f: sol.f(),
        d2: sol.proj.d2,
        u: sol.proj.u,
        eps: sol.eps,
        c: sol.c,
        x: sol.x,
        x_unique: !sol.proj.hard,
        centre_inside: sol.proj.inside,
    }
}

/// The pair term of eq. 34 with everything it computes (`X`, `U`, `d²`, `ε`, `c`).
///
/// Always solves eq. 35, even when the bounding spheres are apart; use [`overlap_measure`] in
/// loops.
pub fn pair_term<const N: usize>(i: &Body<N>, j: &Body<N>) -> PairTerm<N> {
    pair_term_by(i, j, Route::Auto)
}

/// The overlap measure `f` of eq. 34, `0` at once when the bounding spheres are apart or the
/// plane orthogonal to the centre line separates the ellipsoids.
pub fn overlap_measure<const N: usize>(i: &Body<N>, j: &Body<N>) -> f64 {
    if bounding_spheres_apart(i, j) || separated_along_centre_line(i, j) {
        return 0.0;
    }
    solve_pair(i, j).f()
}
