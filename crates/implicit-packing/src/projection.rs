//! Projection of `c` onto the surface `{x : xᵀ S x = 1}`: the secular equation (eqs. 21–22, 35).
//!
//! In the eigenbasis of `S = V diag(s) Vᵀ` (`s_k = σ_k²` from the SVD of the factor `F`), with
//! `ĉ = Vᵀ c` and `g_k = σ_k ĉ_k`, the KKT condition `X + U S X − c = 0` (eq. 22) gives
//!
//! ```text
//! x̂_k = ĉ_k / t_k,   t_k = 1 + U s_k,   φ(U) = Σ_k g_k² / t_k² = 1   (X on the surface)
//! d² = |c − X|² = Σ_k (ĉ_k U s_k / t_k)²
//! ```
//!
//! * `φ(0) = |b|² > 1` (centre of the unit ball outside `E_j^ij`): `U > 0`, unique (Prop. 3.1);
//!   `U ∈ [(|b|−1)/s_max, (|b|−1)/s_min]`.
//! * `φ(0) < 1` (centre inside): `U ∈ [−1/s_max, 0)` is unique (Prop. 4.2). We solve for
//!   `t = 1 + U s_max ∈ [|g_top|, |b|]` instead of `U`, writing `t_k = δ_k + t r_k` with
//!   `r_k = s_k/s_max`, `δ_k = 1 − r_k`: near the pole `t → 0` (the near-hard case) `t` keeps
//!   its relative accuracy, which `1 + U s_max` would lose. When the root has `t > ½` the last
//!   steps are taken in `U` again, so that a small `|U|` keeps its relative accuracy too.
//! * Hard case (`g_top = 0` and `Σ_{k≠top} g_k²/δ_k² ≤ 1`): `U = −1/s_max`, `t = 0`, and `X`
//!   is not unique; we return the branch with a non-negative first top component.
//!
//! The root is found by safeguarded Newton on `h = 1 − φ^−½`, which is nearly linear in `U`
//! (exactly linear when one term dominates), inside a bracket that every step shrinks.
//!
//! # References
//! Birgin, Lobato, Martínez (2016), eqs. (21)–(22), (35)–(36), Prop. 3.1, Prop. 4.2, Lemma 4.2.

use crate::lanes::{Real, splat_n};
use crate::linalg::dot;

/// Solution of the secular equation in the eigenbasis of `S`.
#[derive(Debug, Clone, Copy)]
pub struct Projection<const N: usize> {
    /// The multiplier `U` of eq. 22.
    pub u: f64,
    /// Components of `X` in the eigenbasis, `x̂_k`.
    pub xhat: [f64; N],
    /// `t_k = 1 + U s_k` (computed without cancellation).
    pub t: [f64; N],
    /// `c − X` in the eigenbasis, `ĉ_k − x̂_k = ĉ_k U s_k / t_k` (computed without cancellation).
    pub dhat: [f64; N],
    /// `d² = |c − X|²`.
    pub d2: f64,
    /// `c` lies inside `E_j^ij` (`cᵀ S c < 1`).
    pub inside: bool,
    /// Hard case: `U = −1/s_max` and `X` is not unique.
    pub hard: bool,
}

impl<const N: usize> Projection<N> {
    /// The solution at `U = u` with its vectors zero and `d² = 0`, for the caller to fill in.
    fn zeroed(u: f64, inside: bool, hard: bool) -> Self {
        Projection {
            u,
            xhat: [0.0; N],
            t: [0.0; N],
            dhat: [0.0; N],
            d2: 0.0,
            inside,
            hard,
        }
    }
}

/// Data that locates the eigen-structure for the inside parametrisation.
struct Inside<const N: usize> {
    r: [f64; N],
    delta: [f64; N],
    top: [bool; N],
    s_top: f64,
}

#[inline(always)]
fn phi_u<const N: usize>(s: &[f64; N], g2: &[f64; N], u: f64) -> (f64, f64) {
    let mut phi = 0.0;
    let mut dphi = 0.0;
    for k in 0..N {
        let inv = 1.0 / (1.0 + u * s[k]);
        // A term without weight is absent: 0, not 0·∞ = NaN at a pole (see `phi_t`).
        let q = if g2[k] == 0.0 { 0.0 } else { g2[k] * inv * inv };
        phi += q;
        dphi -= 2.0 * s[k] * q * inv;
    }
    (phi, dphi)
}

#[inline(always)]
fn phi_t<const N: usize>(ins: &Inside<N>, g2: &[f64; N], t: f64) -> (f64, f64) {
    let mut phi = 0.0;
    let mut dphi = 0.0;
    for k in 0..N {
        let inv = 1.0 / (ins.delta[k] + t * ins.r[k]);
        // A term without weight is absent from the secular equation. At t = 0, where the
        // bracket starts when the centre is orthogonal to the top direction, its pole would
        // give 0·∞ = NaN; elsewhere 0 is what the product gives anyway, bit for bit.
        let q = if g2[k] == 0.0 { 0.0 } else { g2[k] * inv * inv };
        phi += q;
        dphi -= 2.0 * ins.r[k] * q * inv;
    }
    (phi, dphi)
}

/// A Newton step below this fraction of the iterate is the last one: convergence is quadratic,
/// so the step after it would be below an ulp. (Waiting for a step below an ulp instead costs
/// one or two more iterations spent chasing rounding noise in `φ − 1`.)
pub(crate) const NEWTON_FINAL: f64 = 1e-9;

/// A Halley step below this fraction of the iterate is the last one in
/// [`solve_outside_direct`]: convergence is cubic, so the error after it is about (2e-6)³.
const HALLEY_FINAL: f64 = 2e-6;

/// Safeguarded Newton on `h(z) = 1 − φ(z)^−½` for a decreasing `φ`, root in `[lo, hi]`.
#[inline(always)]
pub(crate) fn newton<F: Fn(f64) -> (f64, f64)>(
    eval: F,
    mut lo: f64,
    mut hi: f64,
    mut z: f64,
) -> f64 {
    let mut tried_end = false;
    for _ in 0..100 {
        let (phi, dphi) = eval(z);
        if phi == 1.0 {
            return z;
        }
        if phi > 1.0 {
            lo = lo.max(z);
        } else {
            hi = hi.min(z);
        }
        // Newton on h = 1 − φ^−½: h/h' = (1 − φ^−½) / (½ φ^−3/2 φ') = 2φ (√φ − 1) / φ'.
        let step = -2.0 * phi * (phi.sqrt() - 1.0) / dphi;
        // Converged: the step is small enough that the next one would be below an ulp. A step
        // just past an end of the bracket means the root is at that end (to rounding): the end
        // is then the better estimate. (Returning `z` instead lost up to the 1e-9 of this
        // convergence test when the root sits at an end of the bracket, see below.)
        if step.abs() <= NEWTON_FINAL * z.abs() {
            return (z + step).clamp(lo, hi);
        }
        let mut next = z + step;
        // h = 1 − φ^−½ is increasing and nearly linear (φ^−½ is exactly linear for one term),
        // so from the lower end of the bracket Newton converges monotonically in practice.
        // A step out of the bracket is tried once at the end it points to: the root lies at an
        // end of the initial bracket when one term dominates (c along an eigenvector, as for
        // aligned ellipsoids, where U = (|b| − 1)/s_k exactly), and the step overshoots it by
        // rounding; bisecting there took ~30 halvings to reach the convergence test above.
        // Otherwise it falls back to bisection.
        if !(next > lo && next < hi && step.is_finite()) {
            next = if step.is_finite() && !tried_end {
                tried_end = true;
                if next >= hi { hi } else { lo }
            } else {
                0.5 * (lo + hi)
            };
        }
        if hi - lo <= 2.0 * f64::EPSILON * lo.abs().max(hi.abs()) {
            return next;
        }
        z = next;
    }
    z
}

/// Result of [`solve_outside_direct`]: `U`, `X`, `c − X` and `d²` after the last step (`T`
/// is `f64`; the crate's four-pair kernel uses the same struct with four lanes per value).
#[derive(Debug, Clone, Copy)]
pub struct DirectProjection<const N: usize, T = f64> {
    /// The multiplier `U > 0`.
    pub u: T,
    /// `X`.
    pub x: [T; N],
    /// `c − X = U S X`.
    pub c_minus_x: [T; N],
    /// `d² = |c − X|²`.
    pub d2: T,
}

/// Adjugate and determinant of a symmetric positive definite 2×2 or 3×3 matrix (hand-written:
/// the loops of a generic routine do not unroll into the cofactor formulas). Used only on
/// `I + U S` with `U > 0` and `cond(S) ≤ 64`, whose eigenvalues are ≥ 1 and condition number is
/// below 64, so the cofactors lose little. The caller never divides by the determinant inside
/// the Newton loop (see [`solve_outside_direct`]): the division left the critical path.
#[inline(always)]
fn spd_adjugate<T: Real, const N: usize>(m: &[[T; N]; N]) -> ([[T; N]; N], T) {
    let mut adj = [splat_n::<T, N>(0.0); N];
    if N == 2 {
        adj[0][0] = m[1][1];
        adj[1][1] = m[0][0];
        adj[0][1] = -m[0][1];
        adj[1][0] = adj[0][1];
        (adj, m[0][0] * m[1][1] - m[0][1] * m[0][1])
    } else {
        let c00 = m[1][1] * m[2][2] - m[1][2] * m[1][2];
        let c01 = m[0][2] * m[1][2] - m[0][1] * m[2][2];
        let c02 = m[0][1] * m[1][2] - m[0][2] * m[1][1];
        adj[0][0] = c00;
        adj[0][1] = c01;
        adj[0][2] = c02;
        adj[1][1] = m[0][0] * m[2][2] - m[0][2] * m[0][2];
        adj[1][2] = m[0][1] * m[0][2] - m[0][0] * m[1][2];
        adj[2][2] = m[0][0] * m[1][1] - m[0][1] * m[0][1];
        adj[1][0] = c01;
        adj[2][0] = c02;
        adj[2][1] = adj[1][2];
        (adj, m[0][0] * c00 + m[0][1] * c01 + m[0][2] * c02)
    }
}

#[inline(always)]
fn sym_mat_vec<T: Real, const N: usize>(m: &[[T; N]; N], v: &[T; N]) -> [T; N] {
    let mut o = *v;
    for a in 0..N {
        o[a] = dot(&m[a], v);
    }
    o
}

/// `|v|²`, summed in index order.
#[inline(always)]
pub(crate) fn norm2<T: Real, const N: usize>(v: &[T; N]) -> T {
    dot(v, v)
}

/// Above this `|b|² = cᵀSc` the direct solve is not attempted: its unnormalised quantities
/// (`p ≈ φ det²`, `q ≈ det³ |φ'|`, see [`solve_outside_direct`]) grow like powers of `|b|`,
/// and with `|b|² ≤ 1e16` and `cond(S) ≤ 64` they stay far inside the range of `f64`. Such
/// distant pairs never reach the solver in a packing (their enclosing balls are apart).
pub const DIRECT_B2_LIMIT: f64 = 1e16;

/// The outside case (`|b|² = cᵀSc > 1`, `U > 0`) without an eigen-decomposition, for a
/// well-conditioned factor `F` (`S = FᵀF` is formed).
///
/// Halley's method on `h(U) = 1 − φ(U)^−½`, `φ(U) = xᵀ S x`, `x(U) = (I + U S)⁻¹ c`,
/// `φ' = −2 sᵀ M s` and `φ'' = 6 zᵀ S z` (`M = (I + U S)⁻¹`, `s = S x`, `z = M s = −dx/dU`),
/// kept above `U_lo = (|b| − 1)/‖F‖²_F ≤ U` (a lower bound since `λ_max(S) ≤ ‖F‖²_F`). `h`
/// is increasing and concave; where Halley's factor `1 + δ_N h''/(2h')` falls below ½ the
/// Newton step `δ_N` is taken instead, which from the left of the root increases monotonically
/// to it. Returns `None` if the iteration does not settle or `|b|² > DIRECT_B2_LIMIT` (the
/// caller then takes the SVD route).
///
/// Cost (this loop is most of the cost of a pair term in a packing): with `M = adj/det`, the
/// unnormalised `a = adj c`, `p = aᵀ S a = φ det²`, `q = (S a)ᵀ adj (S a) = −½ φ' det³` and
/// `r = (adj S a)ᵀ S (adj S a) = zᵀ S z det⁴` give `δ_N = 2φ(√φ − 1)/(−φ') = (p/q) e`,
/// `e = √p − det`, `h''/h' = (3/det)(q/p − r/q)`, and Halley's step over one denominator,
/// `2 det p q e / (2 det q² + 3 e (q² − r p))`: one square root and one division, which run
/// side by side, and no division by `det`. Against Newton's method from the same start: one
/// solve more per iteration and about one iteration fewer per pair, so about the same
/// instructions in a shorter dependency chain (compare with the `pair` and `model` benches).
///
/// The last step is not followed by another solve: `x(U + δ) = x − δ z + δ² M S z + O(δ³)`
/// (`x'' = 2 M S z`), and `|δ| ≤ 2e-6 U` (after a Halley step, whose error is then of order
/// `(δ/U)³ ≈ 1e-17`) makes the `O(δ³)` term (relative `≲ (δ/U)³`, as `U^k |x^(k)| ≤ k! |x|`
/// componentwise in the eigenbasis for `U > 0`) far below an ulp. `c − X = U S X` follows
/// the same expansion.
#[inline(always)]
pub fn solve_outside_direct<const N: usize>(
    f: &[[f64; N]; N],
    c: &[f64; N],
    b2: f64,
) -> Option<DirectProjection<N>> {
    if b2 > DIRECT_B2_LIMIT {
        return None;
    }
    let DirectStart { s, lo, u0 } = DirectStart::new(f, c, b2);
    let mut u = u0;
    for _ in 0..DIRECT_MAX_ITERATIONS {
        let h = HalleyAt::at(&s, c, u);
        if !h.step.is_finite() {
            return None;
        }
        if h.settled(u) {
            return Some(h.finish(&s, u));
        }
        u = h.next(u, lo);
    }
    None
}

/// The direct solve gives up after this many iterations (the caller then takes the SVD
/// route); Halley's method from the start below takes two or three.
pub(crate) const DIRECT_MAX_ITERATIONS: usize = 60;

/// `S = FᵀF`, the lower bound `U_lo` and the start `U₀` of [`solve_outside_direct`].
#[derive(Debug, Clone, Copy)]
pub(crate) struct DirectStart<T, const N: usize> {
    pub s: [[T; N]; N],
    pub lo: T,
    pub u0: T,
}

impl<T: Real, const N: usize> DirectStart<T, N> {
    /// The start of [`solve_outside_direct`], in any [`Real`] arithmetic (one pair or four).
    #[inline(always)]
    pub(crate) fn new(f: &[[T; N]; N], c: &[T; N], b2: T) -> Self {
        let mut s = *f;
        for a in 0..N {
            for b in a..N {
                let mut v = f[0][a] * f[0][b];
                for k in 1..N {
                    v = v + f[k][a] * f[k][b];
                }
                s[a][b] = v;
                s[b][a] = v;
            }
        }
        // Lower bound from λ_max(S) ≤ ‖F‖²_F. The start replaces S by a multiple s̄ I of the
        // identity, U₀ = (|b| − 1)/s̄, exact when c is an eigenvector. Two means of the eigenvalues
        // offer themselves: weighted by ĉ_k², s̄ = cᵀSc/|c|² = |b|²/|c|², which tends to put U₀
        // below the root, and weighted by g_k² (the weights of φ), s̄ = |Sc|²/|b|², which tends to
        // put it above; their average is the start. On the `pair` bench's pairs the median
        // relative error of U₀ falls from 8.7e-2 (first mean alone) to 3.5e-2, and the number of
        // solves per pair from 3.6 to 3.4.
        // ‖F‖²_F = tr S: two additions after S instead of a chain of nine.
        let mut fro2 = s[0][0];
        for a in 1..N {
            fro2 = fro2 + s[a][a];
        }
        let one = T::splat(1.0);
        let bn = b2.sqrt();
        let lo = (bn - one) / fro2;
        let c2 = norm2(c);
        let sc = sym_mat_vec(&s, c);
        let sc2 = norm2(&sc);
        let u0 = (T::splat(0.5) * (bn - one) * (c2 / b2 + b2 / sc2)).max(lo);
        DirectStart { s, lo, u0 }
    }
}

/// What one Halley iteration of [`solve_outside_direct`] computes at `U`: with
/// `M = (I + U S)⁻¹ = adj / det`, the unnormalised `a = adj c` (`ax`), `S a`, `adj S a`
/// (`az`), `S adj S a`, and the step.
#[derive(Debug, Clone, Copy)]
pub(crate) struct HalleyAt<T: Real, const N: usize> {
    adj: [[T; N]; N],
    det: T,
    ax: [T; N],
    sax: [T; N],
    az: [T; N],
    saz: [T; N],
    /// The step `δ` to add to `U`.
    pub step: T,
    /// Whether `δ` is Halley's step (else Newton's).
    halley: T::Mask,
}

impl<T: Real, const N: usize> HalleyAt<T, N> {
    /// One iteration of [`solve_outside_direct`] at `u`, in any [`Real`] arithmetic.
    #[inline(always)]
    pub(crate) fn at(s: &[[T; N]; N], c: &[T; N], u: T) -> Self {
        let one = T::splat(1.0);
        let two = T::splat(2.0);
        let mut m = *s;
        for a in 0..N {
            for b in 0..N {
                m[a][b] = m[a][b] * u;
            }
            m[a][a] = m[a][a] + one;
        }
        let (adj, det) = spd_adjugate(&m);
        let ax = sym_mat_vec(&adj, c);
        let sax = sym_mat_vec(s, &ax);
        // p = φ det²: with cond(S) ≤ 64 the formed S loses little that |F x|² would keep.
        let p = dot(&ax, &sax);
        let az = sym_mat_vec(&adj, &sax);
        let q = dot(&sax, &az);
        // r = (az)ᵀ S (az) = zᵀ S z det⁴, with φ'' = 6 zᵀ S z: Halley's correction.
        let saz = sym_mat_vec(s, &az);
        let r = dot(&az, &saz);
        // Halley on h: δ = δ_N / (1 + δ_N h''/(2h')), δ_N = (p/q)(√p − det),
        // h''/h' = (3/det)(q/p − r/q); over one denominator:
        // δ = 2 det p q e / (2 det q² + 3 e (q² − r p)), e = √p − det.
        let e = p.sqrt() - det;
        let qq = q * q;
        let newton_den = two * det * qq;
        let halley_den = newton_den + T::splat(3.0) * e * (qq - r * p);
        // Halley's factor 1 + δ_N h''/(2h') below ½ (a long step where h bends a lot): take
        // Newton's step, (p/q) e over the same numerator, which keeps the monotone approach.
        let halley = halley_den.ge(T::splat(0.5) * newton_den);
        let step = (two * det * p * q * e) / T::select(halley, halley_den, newton_den);
        HalleyAt {
            adj,
            det,
            ax,
            sax,
            az,
            saz,
            step,
            halley,
        }
    }
}

impl<T: Real, const N: usize> HalleyAt<T, N> {
    /// The iteration has settled: a Halley step shorter than `HALLEY_FINAL · U`.
    #[inline(always)]
    pub(crate) fn settled(&self, u: T) -> T::Mask {
        self.halley & self.step.abs().le(T::splat(HALLEY_FINAL) * u)
    }

    /// The next iterate. From the right of the root a step of the concave h lands left of it,
    /// possibly below the lower bound: then restart from the bound, whence the iterates
    /// increase.
    #[inline(always)]
    pub(crate) fn next(&self, u: T, lo: T) -> T {
        (u + self.step).max(lo)
    }

    /// The solution after the last step. Cubic convergence: after this step the error is
    /// ~(2e-6)³, below an ulp. X and S X follow to second order in δ:
    /// x(U + δ) = x − δ z + δ² M S z + O(δ³), z = M S x = −dx/dU, M = (I + U S)⁻¹ = adj / det;
    /// c − X = U S X.
    #[inline(always)]
    pub(crate) fn finish(&self, s: &[[T; N]; N], u: T) -> DirectProjection<N, T> {
        let u = u + self.step;
        let rd = T::splat(1.0) / self.det;
        let dr = self.step * rd;
        let w = sym_mat_vec(&self.adj, &self.saz);
        let sw = sym_mat_vec(s, &w);
        let mut x = w;
        let mut cmx = w;
        for a in 0..N {
            x[a] = (self.ax[a] - dr * (self.az[a] - dr * w[a])) * rd;
            cmx[a] = u * ((self.sax[a] - dr * (self.saz[a] - dr * sw[a])) * rd);
        }
        DirectProjection {
            u,
            x,
            c_minus_x: cmx,
            d2: norm2(&cmx),
        }
    }
}

/// Solves the secular equation for eigenvalues `s`, `ĉ = Vᵀc` and `g_k = σ_k ĉ_k`.
pub fn solve<const N: usize>(s: &[f64; N], chat: &[f64; N], g: &[f64; N]) -> Projection<N> {
    let mut g2 = [0.0; N];
    for k in 0..N {
        g2[k] = g[k] * g[k];
    }
    let b2: f64 = g2.iter().sum();
    let mut s_max = 0.0f64;
    let mut s_min = f64::INFINITY;
    for &sk in s.iter() {
        s_max = s_max.max(sk);
        s_min = s_min.min(sk);
    }
    if b2 == 1.0 {
        return Projection {
            u: 0.0,
            xhat: *chat,
            t: [1.0; N],
            dhat: [0.0; N],
            d2: 0.0,
            inside: false,
            hard: false,
        };
    }
    if b2 > 1.0 {
        let bn = b2.sqrt();
        let lo = (bn - 1.0) / s_max;
        let hi = (bn - 1.0) / s_min;
        let u = if lo == hi {
            lo
        } else {
            newton(|u| phi_u(s, &g2, u), lo, hi, lo)
        };
        return finish_u(s, chat, u, false);
    }

    // Inside: parametrise by t = 1 + U s_max.
    let mut ins = Inside {
        r: [0.0; N],
        delta: [0.0; N],
        top: [false; N],
        s_top: s_max,
    };
    let mut g2_top = 0.0;
    for k in 0..N {
        let gap = (s_max - s[k]) / s_max;
        if gap <= 8.0 * f64::EPSILON {
            ins.top[k] = true;
            ins.r[k] = 1.0;
            ins.delta[k] = 0.0;
            g2_top += g2[k];
        } else {
            ins.r[k] = s[k] / s_max;
            ins.delta[k] = gap;
        }
    }
    if g2_top == 0.0 {
        let mut rest = 0.0;
        for k in 0..N {
            if !ins.top[k] {
                rest += g2[k] / (ins.delta[k] * ins.delta[k]);
            }
        }
        if rest <= 1.0 {
            return finish_hard(s, chat, &ins);
        }
    }
    let lo = g2_top.sqrt();
    let hi = b2.sqrt().min(1.0);
    let start = if lo > 0.0 { lo } else { 0.5 * hi };
    let t = if lo >= hi {
        lo
    } else {
        newton(|t| phi_t(&ins, &g2, t), lo, hi, start)
    };
    if t > 0.5 {
        let ulo = -(1.0 - lo) / s_max;
        let uhi = -(1.0 - hi) / s_max;
        let u0 = -(1.0 - t) / s_max;
        let u = newton(|u| phi_u(s, &g2, u), ulo, uhi.min(0.0), u0);
        return finish_u(s, chat, u, true);
    }
    let mut p = Projection::zeroed(-(1.0 - t) / s_max, true, false);
    let one_minus_t = 1.0 - t;
    for k in 0..N {
        let tk = ins.delta[k] + t * ins.r[k];
        p.t[k] = tk;
        p.xhat[k] = chat[k] / tk;
        let dk = -chat[k] * one_minus_t * ins.r[k] / tk;
        p.dhat[k] = dk;
        p.d2 += dk * dk;
    }
    p
}

fn finish_u<const N: usize>(s: &[f64; N], chat: &[f64; N], u: f64, inside: bool) -> Projection<N> {
    let mut p = Projection::zeroed(u, inside, false);
    for k in 0..N {
        let us = u * s[k];
        let tk = 1.0 + us;
        p.t[k] = tk;
        p.xhat[k] = chat[k] / tk;
        let dk = chat[k] * us / tk;
        p.dhat[k] = dk;
        p.d2 += dk * dk;
    }
    p
}

fn finish_hard<const N: usize>(s: &[f64; N], chat: &[f64; N], ins: &Inside<N>) -> Projection<N> {
    let mut p = Projection::zeroed(-1.0 / ins.s_top, true, true);
    let mut used = 0.0;
    let mut first_top = None;
    for k in 0..N {
        if ins.top[k] {
            if first_top.is_none() {
                first_top = Some(k);
            }
            continue;
        }
        let tk = ins.delta[k];
        p.t[k] = tk;
        p.xhat[k] = chat[k] / tk;
        used += s[k] * p.xhat[k] * p.xhat[k];
        let dk = -chat[k] * ins.r[k] / tk;
        p.dhat[k] = dk;
        p.d2 += dk * dk;
    }
    if let Some(k) = first_top {
        let x = ((1.0 - used).max(0.0) / ins.s_top).sqrt();
        p.xhat[k] = x;
        p.dhat[k] = -x;
        p.d2 += x * x;
    }
    p
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check_kkt<const N: usize>(s: &[f64; N], chat: &[f64; N], p: &Projection<N>) {
        let mut cons = 0.0;
        for k in 0..N {
            cons += s[k] * p.xhat[k] * p.xhat[k];
            let res = p.xhat[k] + p.u * s[k] * p.xhat[k] - chat[k];
            assert!(
                res.abs() <= 1e-13 * (1.0 + chat[k].abs() + p.xhat[k].abs()),
                "k={k} res={res}"
            );
        }
        assert!((cons - 1.0).abs() < 1e-13, "constraint {cons}");
    }

    #[test]
    fn outside_inside_and_hard_cases_satisfy_kkt() {
        let s: [f64; 3] = [4.0, 1.0, 0.25];
        for chat in [
            [1.0, 2.0, 3.0],
            [0.1, 0.2, 0.1],
            [1e-9, 0.1, 0.3],
            [0.0, 0.1, 0.3],
            [0.0, 0.0, 0.0],
        ] {
            let g: Vec<f64> = (0..3).map(|k| s[k].sqrt() * chat[k]).collect();
            let p = solve(&s, &chat, &[g[0], g[1], g[2]]);
            check_kkt(&s, &chat, &p);
            assert!(p.u >= -1.0 / 4.0);
        }
    }
}
