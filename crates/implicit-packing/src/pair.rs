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
//! (module `linalg`: one-sided Jacobi after a pivoted QR), and the module `projection` solves the secular equation in that basis.
//!
//! # References
//! Birgin, Lobato, Martínez (2016), Sections 3–5.

use crate::lanes::Real;
use crate::linalg::{GradedSvd, dot, graded_svd, mat_t_vec};
use crate::projection::{self, DirectProjection, Projection};
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
pub(crate) fn epsilon_from_extremes<T: Real>(imin: T, imax: T, jmin: T, jmax: T) -> T {
    imin * (jmin * jmin) / ((imax * imax) * jmax)
}

/// True when the enclosing balls of radius `max(l_i)`, `max(l_j)` do not overlap: then `f = 0`
/// (Section 5.2, `|c_i − c_j| ≥ r_i + r_j`).
#[inline(always)]
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

/// An exact separation certificate: true when the plane orthogonal to the centre line
/// separates the ellipsoids with a margin, and then the pair term is exactly `0`, value and
/// gradient, so it need not be solved.
///
/// With `n = c_j − c_i` and the support function `h_E(n) = sqrt(nᵀ M n) = |P^½ Qᵀ n|` of
/// `E = {x : (x − c)ᵀ M⁻¹ (x − c) ≤ 1}`, `M = Q P Qᵀ`, the test is (both sides scaled by `|n|`)
///
/// ```text
/// (h_i(n) + h_j(n)) (1 + κ) < |n|²,     κ = 1e-12 · max(l_i) / min(l_i).
/// ```
///
/// Why `f = 0` then, and not merely "no overlap": the gap between the ellipsoids along `n̂` is
/// at least `κ |n| / (1 + κ)`, and `|n| ≥ h_i(n̂) ≥ min(l_i)`; mapped to the frame where `E_i`
/// is the unit ball (lengths shrink by at most `max(l_i)`) the gap gives
/// `d − 1 ≥ κ min(l_i) / ((1 + κ) max(l_i)) ≈ 1e-12`, so `max{0, 1 − d²} = 0` with a margin a
/// hundred times the solver's error on `d²` (≤ 3e-14 against the references). The second term
/// vanishes too: from `c − X = U S X` and `XᵀSX = 1`, `d = U |S X| ≤ U sqrt(λ_max(S))` and
/// `λ_max(S) ≤ max(l_i)² / min(l_j)²`, so `U ≥ d min(l_j) / max(l_i) ≥ d ε_ij ≥ ε_ij (1 + 1e-12)`
/// (Prop. 3.3's bound, `ε_ij ≤ min(l_j)/max(l_i)`, holds for every pair with `d ≥ 1`; equality
/// `U = ε_ij d` for two spheres, whence the relative margin). `κ` scales with the axis ratio of
/// `i` so that the margin on `d` does not shrink for needles; it rejects nothing that matters
/// (only pairs within a relative `1e-12 · ratio` of the certificate's boundary).
///
/// Cheap (two 3×3 products, two square roots), and at packing density it rejects most of the
/// candidate pairs whose enclosing balls meet (the `model` bench prints the share).
#[inline(always)]
pub fn separated_along_centre_line<const N: usize>(i: &Body<N>, j: &Body<N>) -> bool {
    certified_separated(i, j, &centre_line(i, j))
}

/// `Δ = c_i − c_j` in the frames of both bodies, `Q_iᵀ Δ` and `Q_jᵀ Δ`, and `|Δ|²`: the
/// certificate needs them (`n = −Δ`) and so does the pair term (`c = P_i^−½ Q_iᵀ Δ`,
/// `b = P_j^−½ Q_jᵀ Δ`), so the model's fast paths compute them once for both.
#[derive(Debug, Clone, Copy)]
pub(crate) struct CentreLine<const N: usize> {
    pub in_i: [f64; N],
    pub in_j: [f64; N],
    pub norm2: f64,
}

#[inline(always)]
pub(crate) fn centre_line<const N: usize>(i: &Body<N>, j: &Body<N>) -> CentreLine<N> {
    let ci = i.centre();
    let cj = j.centre();
    let mut delta = [0.0; N];
    for k in 0..N {
        delta[k] = ci[k] - cj[k];
    }
    CentreLine {
        in_i: mat_t_vec(&i.rotation(), &delta),
        in_j: mat_t_vec(&j.rotation(), &delta),
        norm2: dot(&delta, &delta),
    }
}

/// [`separated_along_centre_line`] from the centre line: `h(n) = |P^½ Qᵀ n|` with `n = −Δ`
/// (the sign does not change the norm).
#[inline(always)]
pub(crate) fn certified_separated<const N: usize>(
    i: &Body<N>,
    j: &Body<N>,
    line: &CentreLine<N>,
) -> bool {
    let support = |l: [f64; N], p: &[f64; N]| {
        let mut v = [0.0; N];
        for k in 0..N {
            v[k] = l[k] * p[k];
        }
        dot(&v, &v).sqrt()
    };
    let h = support(i.semi_axes(), &line.in_i) + support(j.semi_axes(), &line.in_j);
    // (h_i + h_j)(1 + κ) < |n|², multiplied by min(l_i) to avoid a division.
    let lo = i.min_semi_axis();
    h * (lo + SEPARATION_MARGIN * i.bounding_radius()) < line.norm2 * lo
}

/// The relative margin `κ / (max(l_i)/min(l_i))` of [`separated_along_centre_line`].
pub const SEPARATION_MARGIN: f64 = 1e-12;

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
    let st = setup(i, j);
    if allow_direct && let Some(d) = solve_direct(&st) {
        return direct_solution(&st, &d);
    }
    solve_svd(&st)
}

/// A direct-route solution in the form of [`PairSolution`] (the "eigenbasis" is the i-frame).
pub(crate) fn direct_solution<const N: usize>(
    st: &Setup<N>,
    d: &DirectProjection<N>,
) -> PairSolution<N> {
    let mut v = [[0.0; N]; N];
    for k in 0..N {
        v[k][k] = 1.0;
    }
    let svd = GradedSvd {
        sigma: [0.0; N],
        v,
        chat: st.c,
        g: st.b,
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
    PairSolution {
        svd,
        proj,
        c: st.c,
        x: d.x,
        eps: st.eps,
        direct: true,
    }
}

/// The SVD route of [`solve_pair_with`] from its setup.
pub(crate) fn solve_svd<const N: usize>(st: &Setup<N>) -> PairSolution<N> {
    let Setup { c, b, f, eps, .. } = *st;
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

/// What both routes start from: `c = P_i^−½ Q_iᵀ (c_i − c_j)` (eq. 3), `b = F c`, the factor
/// `F` and `ε_ij` (Prop. 3.3).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Setup<const N: usize> {
    pub c: [f64; N],
    /// `b = P_j^−½ Q_jᵀ (c_i − c_j) = F c`, computed from the centres (not as `F c`).
    pub b: [f64; N],
    pub f: [[f64; N]; N],
    /// The diagonal of `P_i^−½`.
    pub inv_li: [f64; N],
    pub eps: f64,
    /// `(max l_i / min l_i)(max l_j / min l_j) ≤ DIRECT_CONDITION_LIMIT`.
    pub well_conditioned: bool,
}

/// The common first stage of [`solve_pair_with`] and of the model's fast path.
#[inline(always)]
pub(crate) fn setup<const N: usize>(i: &Body<N>, j: &Body<N>) -> Setup<N> {
    setup_from(i, j, &centre_line(i, j))
}

/// [`setup`] from the centre line already computed for the certificate.
#[inline(always)]
pub(crate) fn setup_from<const N: usize>(
    i: &Body<N>,
    j: &Body<N>,
    line: &CentreLine<N>,
) -> Setup<N> {
    let inv_li = i.inv_semi_axes();
    let (c, b, f) = frame_factor(
        &line.in_i,
        &line.in_j,
        BodyOf {
            q: &i.rotation(),
            l: &i.semi_axes(),
            inv_l: &inv_li,
        },
        BodyOf {
            q: &j.rotation(),
            l: &j.semi_axes(),
            inv_l: &j.inv_semi_axes(),
        },
    );
    let (imin, imax, jmin, jmax) = (
        i.min_semi_axis(),
        i.bounding_radius(),
        j.min_semi_axis(),
        j.bounding_radius(),
    );
    Setup {
        c,
        b,
        f,
        inv_li,
        eps: epsilon_from_extremes(imin, imax, jmin, jmax),
        // (l_max,i / l_min,i)(l_max,j / l_min,j) ≤ limit, without divisions.
        well_conditioned: imax * jmax <= DIRECT_CONDITION_LIMIT * (imin * jmin),
    }
}

/// A body's rotation, semi-axes and their reciprocals, in any [`Real`] arithmetic (one body,
/// or four side by side): what the pair kernel's generic formulas read.
#[derive(Clone, Copy)]
pub(crate) struct BodyOf<'a, T, const N: usize> {
    pub q: &'a [[T; N]; N],
    pub l: &'a [T; N],
    pub inv_l: &'a [T; N],
}

/// `c = P_i^−½ Q_iᵀ Δ`, `b = P_j^−½ Q_jᵀ Δ` (eq. 3) from the centre line in both frames, and
/// `F = P_j^−½ (Q_jᵀ Q_i) P_i^½`, in any [`Real`] arithmetic (one pair or four).
#[inline(always)]
pub(crate) fn frame_factor<T: Real, const N: usize>(
    in_i: &[T; N],
    in_j: &[T; N],
    i: BodyOf<'_, T, N>,
    j: BodyOf<'_, T, N>,
) -> ([T; N], [T; N], [[T; N]; N]) {
    // `c` and `b` keep their divisions: one rounding less in the quantities everything else is
    // measured from. (Multiplying by the bodies' cached reciprocals is a little faster, but
    // it doubles the worst errors of the `random_moderate` cases of the test `reference`.)
    // The reciprocals serve F below and the gradient's force, P_i^−½ (c − X).
    let mut c = *in_i;
    let mut b = *in_j;
    for k in 0..N {
        c[k] = c[k] / i.l[k];
        b[k] = b[k] / j.l[k];
    }
    // F = P_j^−½ (Q_jᵀ Q_i) P_i^½, entry by entry: a graded matrix with an orthogonal core.
    // Each entry carries a relative error of a few ulps, which moves the singular values by as
    // little (the graded structure); N reciprocals replace N² divisions.
    let mut f = *i.q;
    for a in 0..N {
        for bcol in 0..N {
            let mut r = j.q[0][a] * i.q[0][bcol];
            for m in 1..N {
                r = r + j.q[m][a] * i.q[m][bcol];
            }
            f[a][bcol] = r * i.l[bcol] * j.inv_l[a];
        }
    }
    (c, b, f)
}

/// The direct route of [`solve_pair_with`], or `None` where it does not apply (centre inside,
/// `cond(F) > 8`, a distant pair) or does not settle.
#[inline(always)]
pub(crate) fn solve_direct<const N: usize>(st: &Setup<N>) -> Option<DirectProjection<N>> {
    if !st.well_conditioned {
        return None;
    }
    let b2: f64 = st.b.iter().map(|v| v * v).sum();
    if b2 > 1.0 {
        projection::solve_outside_direct(&st.f, &st.c, b2)
    } else {
        None
    }
}

/// Above this bound on `cond(F)` the direct solve is not used (see [`solve_pair_with`]).
pub(crate) const DIRECT_CONDITION_LIMIT: f64 = 8.0;

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
#[inline]
pub fn overlap_measure<const N: usize>(i: &Body<N>, j: &Body<N>) -> f64 {
    // The bounding-sphere exit stays inline, ahead of the dispatch: most calls in a loop over
    // all pairs end here, and a call through the dispatch would cost more than the test.
    if bounding_spheres_apart(i, j) {
        return 0.0;
    }
    if i.is_round() && j.is_round() {
        return crate::round::round_overlap_measure(i, j);
    }
    simd::multiversion!(call overlap_measure_impl::<N>(i: &Body<N>, j: &Body<N>) -> f64)
}

/// [`overlap_measure`], compiled twice (see `simd::multiversion`).
#[inline(always)]
fn overlap_measure_impl<const N: usize>(i: &Body<N>, j: &Body<N>) -> f64 {
    let line = centre_line(i, j);
    if certified_separated(i, j, &line) {
        return 0.0;
    }
    let st = setup_from(i, j, &line);
    if let Some(d) = solve_direct(&st) {
        let a = (1.0 - d.d2).max(0.0);
        let b = (st.eps - d.u).max(0.0);
        return a * a + b * b;
    }
    solve_svd(&st).f()
}
