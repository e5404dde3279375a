//! The rational form of f(λ): the polynomials a(λ), b(λ), c(λ) of the theory (eqs. 15–20), and
//! the Bernstein form in which ellipack actually evaluates them.
//!
//! With Q(λ) = (1 − λ) Q1 + λ Q2 (eq. 10), eq. 11 reads
//!
//! ```text
//! f(λ) = λ (1 − λ) r12ᵀ Q(λ)⁻¹ r12 = λ (1 − λ) a(λ) / b(λ),          (15)
//! a(λ) = r12ᵀ adj Q(λ) r12,   b(λ) = det Q(λ).                         (16a, 16b)
//! ```
//!
//! The PW85 library recovers the monomial coefficients of a and b by sampling them at
//! λ ∈ {−1, 0, ½, 1} (eq. 17) and finds λ₀ as the root of c(λ) = f′(λ) b(λ)² (eqs. 18–20). Both
//! are provided here as building blocks (and the `baseline` module uses them), but the solver
//! works with the same polynomials in the Bernstein basis of s = 1 − λ and t = λ:
//!
//! ```text
//! a(λ) = s² α₀ + s t α₁ + t² α₂,             α₀ = rᵀ adj(Q1) r, α₁ = rᵀ M(Q1, Q2) r, α₂ = rᵀ adj(Q2) r
//! b(λ) = s³ β₀ + s² t β₁ + s t² β₂ + t³ β₃,   β₀ = det Q1, β₁ = tr(adj(Q1) Q2), β₂ = tr(adj(Q2) Q1), β₃ = det Q2
//! ```
//!
//! where M is the mixed adjugate ([`crate::sym::mixed_adjugate`]). For positive definite Q1, Q2
//! every α and β is non-negative, so on 0 ≤ λ ≤ 1 each of a, b and f is a sum of non-negative
//! terms: evaluating them loses no digits, whatever the conditioning of Q(λ). All the
//! cancellation sits in the coefficients themselves, where it can be measured and, when needed,
//! removed with extra precision (see [`crate::contact_function`]).

use crate::arith::{Arith, Fused, mul_add};
use crate::arith::{is_positive, select_gt};
use crate::sym::{
    Sym3, adjugate_generic, det_generic, det_sym, frobenius_generic, lift6, mixed_adjugate_generic,
    quadratic_form_generic, solve_ldlt, xt_adj_x,
};

/// Q(λ) = (1 − λ) Q1 + λ Q2 (eq. 10).
pub fn pencil(lambda: f64, q1: &Sym3, q2: &Sym3) -> Sym3 {
    core::array::from_fn(|k| (1.0 - lambda) * q1[k] + lambda * q2[k])
}

/// Monomial coefficients [a₀, a₁, a₂] of a(λ) = r12ᵀ adj Q(λ) r12, by sampling a at −1, 0 and 1
/// (eqs. 17a–17c, as the PW85 library does).
pub fn a_coefficients(r12: &[f64; 3], q1: &Sym3, q2: &Sym3) -> [f64; 3] {
    let a = |lambda: f64| xt_adj_x(r12, &pencil(lambda, q1, q2));
    let (am1, a0, a1) = (a(-1.0), a(0.0), a(1.0));
    [a0, 0.5 * (a1 - am1), 0.5 * (a1 + am1) - a0]
}

/// Monomial coefficients [b₀, b₁, b₂, b₃] of b(λ) = det Q(λ), by sampling b at −1, 0, ½ and 1
/// (eqs. 17d–17g, as the PW85 library does).
pub fn b_coefficients(q1: &Sym3, q2: &Sym3) -> [f64; 4] {
    let b = |lambda: f64| det_sym(&pencil(lambda, q1, q2));
    let (bm1, b0, bh, b1) = (b(-1.0), b(0.0), b(0.5), b(1.0));
    [
        b0,
        8.0 * bh / 3.0 - 2.0 * b0 - 0.5 * b1 - bm1 / 6.0,
        0.5 * (b1 + bm1) - b0,
        -8.0 * bh / 3.0 + 2.0 * b0 + b1 - bm1 / 3.0,
    ]
}

/// Coefficients [c₀, …, c₆] of c(λ) = f′(λ) b(λ)² (eqs. 19, 20a–20g).
pub fn c_coefficients(a: &[f64; 3], b: &[f64; 4]) -> [f64; 7] {
    let [a0, a1, a2] = *a;
    let [b0, b1, b2, b3] = *b;
    [
        a0 * b0,
        2.0 * (a1 - a0) * b0,
        -a0 * (b1 + b2) + 3.0 * b0 * (a2 - a1) + a1 * b1,
        2.0 * (b1 * (a2 - a1) - a0 * b3) - 4.0 * a2 * b0,
        (a0 - a1) * b3 + (a2 - a1) * b2 - 3.0 * a2 * b1,
        -2.0 * a2 * b2,
        -a2 * b3,
    ]
}

/// Evaluates a polynomial given by its monomial coefficients (Horner).
pub fn polyval(coefficients: &[f64], x: f64) -> f64 {
    coefficients.iter().rev().fold(0.0, |acc, &c| acc * x + c)
}

/// f(λ) = λ (1 − λ) r12ᵀ Q(λ)⁻¹ r12 (eq. 11), by an LDLᵀ solve: the straightforward evaluation.
/// Returns NaN when Q(λ) is not positive definite as computed.
pub fn f_direct(lambda: f64, r12: &[f64; 3], q1: &Sym3, q2: &Sym3) -> f64 {
    match solve_ldlt(&pencil(lambda, q1, q2), r12) {
        Some(s) => lambda * (1.0 - lambda) * (r12[0] * s[0] + r12[1] * s[1] + r12[2] * s[2]),
        None => f64::NAN,
    }
}

/// The residual of eq. 13 at λ: with x₀(λ) from eq. 9, the two quadratic forms
/// u₁ = (x₀ − c₁)ᵀ Q1⁻¹ (x₀ − c₁) = (1 − λ)² sᵀ Q1 s and u₂ = (x₀ − c₂)ᵀ Q2⁻¹ (x₀ − c₂) = λ² sᵀ Q2 s,
/// s = Q(λ)⁻¹ r12. Returns (u₁, u₂); at the maximiser λ₀ both equal μ².
pub fn eq13_forms(lambda: f64, r12: &[f64; 3], q1: &Sym3, q2: &Sym3) -> (f64, f64) {
    let Some(s) = solve_ldlt(&pencil(lambda, q1, q2), r12) else {
        return (f64::NAN, f64::NAN);
    };
    let t = lambda;
    let u = 1.0 - lambda;
    (
        u * u * crate::sym::quadratic_form(&s, q1),
        t * t * crate::sym::quadratic_form(&s, q2),
    )
}

/// f(λ) = λ (1 − λ) a(λ) / b(λ) written with its numerator and denominator in Bernstein form
/// (see the module documentation). `alpha` and `beta` are the Bernstein coefficients without
/// binomial weights: a = s²α₀ + stα₁ + t²α₂, b = s³β₀ + s²tβ₁ + st²β₂ + t³β₃, s = 1 − λ, t = λ.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RationalForm {
    /// α₀, α₁, α₂.
    pub alpha: [f64; 3],
    /// β₀, β₁, β₂, β₃.
    pub beta: [f64; 4],
}

/// The first two derivatives of ln f at one λ.
#[derive(Clone, Copy, Debug)]
pub(crate) struct LogDerivatives {
    /// d ln f / dλ.
    pub g1: f64,
    /// d² ln f / dλ².
    pub g2: f64,
}

impl RationalForm {
    /// The Bernstein coefficients of a pair of ellipsoids (computed in `f64`).
    pub fn new(r12: &[f64; 3], q1: &Sym3, q2: &Sym3) -> Self {
        coefficients::<f64>(r12, q1, q2).to_f64()
    }

    /// a(λ).
    pub fn a(&self, lambda: f64) -> f64 {
        pencil_values(&self.alpha, &self.beta, lambda)[0]
    }

    /// b(λ).
    pub fn b(&self, lambda: f64) -> f64 {
        pencil_values(&self.alpha, &self.beta, lambda)[3]
    }

    /// f(λ) = λ (1 − λ) a(λ) / b(λ) (eq. 15).
    pub fn f(&self, lambda: f64) -> f64 {
        f_value(&self.alpha, &self.beta, lambda)
    }

    /// The same function of μ = 1 − λ: the coefficient lists reversed (Q1 and Q2 swapped).
    pub fn reversed(&self) -> Self {
        let [a0, a1, a2] = self.alpha;
        let [b0, b1, b2, b3] = self.beta;
        Self {
            alpha: [a2, a1, a0],
            beta: [b3, b2, b1, b0],
        }
    }

    /// (ln f)′ and (ln f)″ at λ. ln f is concave on (0, 1) because f is (a minimum of
    /// functions affine in λ, eq. 5), so (ln f)′ decreases from +∞ to −∞.
    #[inline]
    pub(crate) fn log_derivatives(&self, lambda: f64) -> LogDerivatives {
        let (s, t) = (1.0 - lambda, lambda);
        let [a, da, dda, b, db, ddb] = pencil_values(&self.alpha, &self.beta, lambda);
        // One division instead of four: 1/(ts), 1/a and 1/b all follow from 1/(ts·a·b). The
        // coefficients are normalised (largest 1), so the product stays far from underflow
        // except for pencils spanning hundreds of decades, which take the slow path.
        let ts = t * s;
        let inv = 1.0 / (ts * a * b);
        let (its, ia, ib) = if inv.is_finite() {
            (a * b * inv, ts * b * inv, ts * a * inv)
        } else {
            (1.0 / ts, 1.0 / a, 1.0 / b)
        };
        let (la, lb) = (da * ia, db * ib);
        let poles = (s - t) * its;
        LogDerivatives {
            g1: poles + la - lb,
            g2: -(t * t + s * s) * its * its + dda * ia - la * la - ddb * ib + lb * lb,
        }
    }

    /// The numerator and denominator of a Newton step on ψ = λ(1 − λ)(ln f)′, without
    /// divisions: with P = λ(1 − λ), (ln f)′ = n₁ / (P a b) and (ln f)″ = n₂ / (P a b)², where
    ///
    /// ```text
    /// n₁ = (1 − 2λ) a b + P (a′ b − a b′)
    /// n₂ = −(λ² + (1 − λ)²) a² b² + P² [b² (a″ a − a′²) − a² (b″ b − b′²)]
    /// ```
    ///
    /// Returns (n₁, n₂, P a b). The iteration is bound by the latency of its dependency chain,
    /// so one division per step instead of five matters.
    #[inline(always)]
    pub(crate) fn newton_terms(&self, lambda: f64) -> (f64, f64, f64) {
        newton_terms(&self.alpha, &self.beta, lambda)
    }

    /// The maximiser of f on [0, 1], from the starting point `t0` ∈ (0, 1): returns (λ₀, f(λ₀),
    /// iterations).
    ///
    /// Newton's method on ψ(λ) = λ (1 − λ) (ln f)′(λ), which has the root of f′ but none of its
    /// poles at 0 and 1: where f ≈ K λ near λ = 0 (a tiny first ellipsoid), ψ is nearly linear
    /// and one step lands on λ₀ ≈ 1/K, whereas Newton on f′ itself would overshoot out of
    /// [0, 1]. The root stays bracketed ((ln f)′ is decreasing), steps leaving the bracket are
    /// replaced by bisection (geometric when the bracket spans decades).
    ///
    /// Stopping: the relative gain of a Newton step in f is about G = (ln f)′² / (2 |(ln f)″|).
    /// Once G < 1e-12 the iteration is in its quadratic regime and the step's own remaining
    /// gain is of order G² — far below the resolution of a double — so that step is taken and
    /// only f (not its derivatives) is evaluated at the new point.
    pub fn maximise(&self, t0: f64) -> (f64, f64, u32) {
        let mut search = Search::new(t0);
        while !search.done {
            self.search_step(&mut search);
        }
        (search.t, search.f, search.iterations)
    }

    /// One iteration of [`RationalForm::maximise`] on `search`; when it sets `search.done`,
    /// `search.t` is λ₀ and `search.f` is f(λ₀). Separate so that the batched path can advance
    /// several independent searches side by side (their dependency chains then overlap).
    #[inline(always)]
    pub(crate) fn search_step(&self, search: &mut Search) {
        let t = search.t;
        search.iterations += 1;
        let (mut n1, mut n2, mut pab) = self.newton_terms(t);
        if !is_positive(pab - 1e-60) {
            // a and b so small that n₂ ~ (ab)² would underflow: use the divided form, which
            // is the same formula with P a b = 1.
            let d = self.log_derivatives(t);
            (n1, n2, pab) = (d.g1, d.g2, 1.0);
        }
        if n1 > 0.0 {
            search.lo = t;
        } else {
            search.hi = t;
        }
        let (lo, hi) = (search.lo, search.hi);
        let p = t * (1.0 - t);
        let next = t - p * n1 * pab / ((1.0 - 2.0 * t) * n1 * pab + p * n2);
        let inside = next > lo && next < hi;
        // G < 1e-12 ⇔ n₁² < −2e-12 n₂; NaN (a degenerate pencil) stops too.
        let converged = n1 * n1 < -2e-12 * n2;
        if converged || !is_positive(-n2) || search.iterations >= 200 {
            search.done = true;
            search.f = self.f(t);
            if inside && converged {
                // f(next) ≥ f(t) unless rounding says otherwise: keep the larger lower bound.
                search.f = self.f(next).max(search.f);
                search.t = next;
            }
            return;
        }
        let next = if inside {
            next
        } else if lo > 0.0 && hi > 16.0 * lo {
            (lo * hi).sqrt()
        } else {
            0.5 * (lo + hi)
        };
        if next == t || hi - lo <= 4.0 * f64::EPSILON * t {
            search.done = true;
            search.f = self.f(t);
            return;
        }
        search.t = next;
    }

    /// A starting point for [`RationalForm::maximise`]: the exact maximiser for two spheres
    /// whose radii are the radial extents ρᵢ = (r̂ᵀ Qᵢ⁻¹ r̂)^(−1/2) of the ellipsoids along r12,
    /// λ = ρ₁ / (ρ₁ + ρ₂), with ρ₂/ρ₁ = sqrt((α₀/β₀)/(α₂/β₃)).
    pub fn initial_guess(&self) -> f64 {
        let t = 1.0 / (1.0 + self.sphere_ratio());
        if t > 0.0 && t < 1.0 { t } else { 0.5 }
    }

    /// ρ₂/ρ₁ = sqrt((α₀/β₀)/(α₂/β₃)) of [`RationalForm::initial_guess`] (NaN or ±∞ for a
    /// degenerate form).
    pub(crate) fn sphere_ratio(&self) -> f64 {
        (self.alpha[0] * self.beta[3] / (self.alpha[2] * self.beta[0])).sqrt()
    }
}

/// a, a′, a″, b, b′, b″ at λ from the Bernstein coefficients, in any arithmetic (the scalar
/// solver and the four-lane batch share these formulas, so their results agree bit for bit).
#[inline(always)]
pub(crate) fn pencil_values<T: Arith>(alpha: &[T; 3], beta: &[T; 4], lambda: T) -> [T; 6] {
    let c = T::lift;
    let (s, t) = (c(1.0) - lambda, lambda);
    let [a0, a1, a2] = *alpha;
    let [b0, b1, b2, b3] = *beta;
    [
        s * (s * a0 + t * a1) + t * t * a2,
        c(2.0) * (t * a2 - s * a0) + (s - t) * a1,
        c(2.0) * (a0 + a2 - a1),
        s * s * (s * b0 + t * b1) + t * t * (s * b2 + t * b3),
        c(3.0) * (t * t * b3 - s * s * b0) + s * (s - c(2.0) * t) * b1 + t * (c(2.0) * s - t) * b2,
        c(6.0) * (s * b0 + t * b3)
            + (c(2.0) * t - c(4.0) * s) * b1
            + (c(2.0) * s - c(4.0) * t) * b2,
    ]
}

/// [`RationalForm::newton_terms`] in any arithmetic.
#[inline(always)]
pub(crate) fn newton_terms<T: Arith + core::ops::Neg<Output = T>>(
    alpha: &[T; 3],
    beta: &[T; 4],
    lambda: T,
) -> (T, T, T) {
    let [a, da, dda, b, db, ddb] = pencil_values(alpha, beta, lambda);
    let (s, t) = (T::lift(1.0) - lambda, lambda);
    let p = t * s;
    let ab = a * b;
    let n1 = (s - t) * ab + p * (da * b - a * db);
    let n2 = -(t * t + s * s) * ab * ab
        + p * p * (b * b * (dda * a - da * da) - a * a * (ddb * b - db * db));
    (n1, n2, p * ab)
}

/// f(λ) = λ (1 − λ) a(λ) / b(λ) in any arithmetic.
#[inline(always)]
pub(crate) fn f_value<T: Arith + core::ops::Div<Output = T>>(
    alpha: &[T; 3],
    beta: &[T; 4],
    lambda: T,
) -> T {
    let [a, _, _, b, _, _] = pencil_values(alpha, beta, lambda);
    lambda * (T::lift(1.0) - lambda) * a / b
}

/// The polynomials of the maximisation in the odds u = λ / (1 − λ), in any arithmetic.
///
/// Dividing a(λ) by (1 − λ)² and b(λ) by (1 − λ)³ (eq. 16) gives the ordinary polynomials
/// A(u) = α₀ + α₁u + α₂u² and B(u) = β₀ + β₁u + β₂u² + β₃u³, and eq. 15 becomes
///
/// ```text
/// f = u A(u) / ((1 + u) B(u)),
/// u (1 + u) A B · d ln f / du = p(u) = A B + u (1 + u) (A′B − A B′).
/// ```
///
/// p is the numerator c(λ) of f′ (eqs. 18–20) in the variable u: a polynomial of degree 6 with
/// p(0) = α₀β₀ > 0 and leading coefficient −α₂β₃ < 0, whose one positive root is the maximiser
/// u₀ = λ₀ / (1 − λ₀). Its coefficients are formed once per pair; afterwards every iterate
/// costs only the evaluation of p, A, B and their first two derivatives (Estrin's scheme:
/// few dependent operations), which is what the latency-bound iteration needs. The root of p
/// is well conditioned: iterated to convergence in `f64` it came out within 5e-16 relative of
/// 60-digit roots of the same coefficients on the worst bench pairs, where the λ form of the
/// Newton terms left up to 8e-12.
#[derive(Clone, Copy, Debug)]
pub(crate) struct OddsForm<T> {
    /// p and its derivatives, monomial coefficients.
    p: [T; 7],
    dp: [T; 6],
    ddp: [T; 5],
    /// A, B and the coefficients of A′, A″ = 2α₂, B′ and B″.
    alpha: [T; 3],
    beta: [T; 4],
    da: [T; 2],
    dda: T,
    db: [T; 3],
    ddb: [T; 2],
}

/// What one Halley evaluation ([`OddsForm::halley_terms`]) yields at u: the terms of the step
/// rule, and A(u), B(u), from which the error estimate is formed at the last iterate.
#[derive(Clone, Copy, Debug)]
pub(crate) struct HalleyTerms<T> {
    /// p(u).
    pub p: T,
    /// N = p′V − pV′.
    pub n: T,
    /// V = A B.
    pub v: T,
    /// The next iterate is u − step.
    pub step: T,
    /// A(u) and B(u).
    pub a: T,
    pub b: T,
}

impl<T: Copy> HalleyTerms<T> {
    /// (p, N, V, step): what the step rule reads.
    #[inline(always)]
    pub(crate) fn step_terms(&self) -> (T, T, T, T) {
        (self.p, self.n, self.v, self.step)
    }
}

/// Σ cₖ uᵏ by Estrin's scheme, given u, u² and u⁴ (N ≤ 8): pairs cₖ + cₖ₊₁u first, then
/// combined with u² and u⁴, so that a degree-6 polynomial costs six dependent operations
/// instead of Horner's twelve (no fused multiply–add on the portable build).
#[inline(always)]
fn estrin<const FMA: bool, T: Fused, const N: usize>(c: &[T; N], u: T, u2: T, u4: T) -> T {
    let pair = |j: usize| {
        if 2 * j + 1 < N {
            mul_add::<FMA, T>(c[2 * j + 1], u, c[2 * j])
        } else {
            c[2 * j]
        }
    };
    let low = if N > 2 {
        mul_add::<FMA, T>(pair(1), u2, pair(0))
    } else {
        pair(0)
    };
    if N > 4 {
        let high = if N > 6 {
            mul_add::<FMA, T>(pair(3), u2, pair(2))
        } else {
            pair(2)
        };
        mul_add::<FMA, T>(high, u4, low)
    } else {
        low
    }
}

impl<T: Arith + core::ops::Neg<Output = T>> OddsForm<T> {
    /// The coefficients of p, A, B and their derivatives from the Bernstein coefficients α,
    /// β (which are the monomial coefficients of A and B).
    #[inline(always)]
    pub(crate) fn new(alpha: &[T; 3], beta: &[T; 4]) -> Self {
        let c = T::lift;
        let [_, a1, a2] = *alpha;
        let [_, b1, b2, b3] = *beta;
        let p = odds_numerator(alpha, beta);
        let k = |k: usize| c(k as f64);
        Self {
            p,
            dp: core::array::from_fn(|i| k(i + 1) * p[i + 1]),
            ddp: core::array::from_fn(|i| k((i + 1) * (i + 2)) * p[i + 2]),
            alpha: *alpha,
            beta: *beta,
            da: [a1, a2.twice()],
            dda: a2.twice(),
            db: [b1, b2.twice(), c(3.0) * b3],
            ddb: [b2.twice(), c(6.0) * b3],
        }
    }

    /// Halley's step on h = p / V (= (1 + u) d ln f / d ln u: dividing by V = A B removes the
    /// clusters of roots of A and B near u = 0 that make p itself steep when one ellipsoid is
    /// much smaller than the other), at u: returns p, N, V, the step and A, B ([`HalleyTerms`]), with
    /// N = p′V − pV′ and the next iterate u − step, where
    ///
    /// ```text
    /// step = 2 h h′ / (2 h′² − h h″) = 2 p N V / (2 N² − p V (p″V − p V″) + 2 p V′ N)
    ///      = 2 p N / (2 N p′ − p (p″V − p V″))          (using N + p V′ = p′ V).
    /// ```
    ///
    /// One division; Halley's cubic convergence takes 2.5 evaluations on average from the
    /// sphere estimate, where Newton's took 3.15 (bench distribution). V and its derivatives
    /// come from those of A and B (V′ = A′B + AB′, V″ = A″B + 2A′B′ + AB″), which gives A(u)
    /// and B(u) for the error estimate at no extra cost.
    #[inline(always)]
    pub(crate) fn halley_terms<const FMA: bool>(&self, u: T) -> HalleyTerms<T>
    where
        T: Fused + core::ops::Div<Output = T>,
    {
        let u2 = u * u;
        let u4 = u2 * u2;
        let p = estrin::<FMA, T, 7>(&self.p, u, u2, u4);
        let dp = estrin::<FMA, T, 6>(&self.dp, u, u2, u4);
        let ddp = estrin::<FMA, T, 5>(&self.ddp, u, u2, u4);
        let a = estrin::<FMA, T, 3>(&self.alpha, u, u2, u4);
        let da = estrin::<FMA, T, 2>(&self.da, u, u2, u4);
        let b = estrin::<FMA, T, 4>(&self.beta, u, u2, u4);
        let db = estrin::<FMA, T, 3>(&self.db, u, u2, u4);
        let ddb = estrin::<FMA, T, 2>(&self.ddb, u, u2, u4);
        let v = a * b;
        let dv = mul_add::<FMA, T>(da, b, a * db);
        let ddv = mul_add::<FMA, T>(a, ddb, self.dda * b) + da.twice() * db;
        let n = mul_add::<FMA, T>(dp, v, -(p * dv));
        let num = (p + p) * n;
        // 2 N p′ − p (p″V − p V″), grouped so that the products of p start before N and V″
        // are known: a shorter chain to the division than multiplying the bracket by p.
        let den = mul_add::<FMA, T>(
            n,
            dp.twice(),
            mul_add::<FMA, T>(p * p, ddv, -((p * ddp) * v)),
        );
        HalleyTerms {
            p,
            n,
            v,
            step: num / den,
            a,
            b,
        }
    }
}

/// The monomial coefficients of p(u) = A B + u (1 + u) (A′B − A B′) ([`OddsForm`]): with
/// W = A′B − A B′ (degree 4), W_k = (1 − k) α₁β_k + (3 − k) α₂β_{k−1} − (k + 1) α₀β_{k+1}, and
/// p_k = (A B)_k + W_{k−1} + W_{k−2}.
#[inline(always)]
pub(crate) fn odds_numerator<T: Arith + core::ops::Neg<Output = T>>(
    alpha: &[T; 3],
    beta: &[T; 4],
) -> [T; 7] {
    let c = T::lift;
    let [a0, a1, a2] = *alpha;
    let [b0, b1, b2, b3] = *beta;
    [
        a0 * b0,
        c(2.0) * (a1 * b0),
        (c(3.0) * (a2 * b0) + a1 * b1 + a1 * b0) - (a0 * b2 + a0 * b1),
        c(2.0) * ((a2 * b1 + a2 * b0) - (a0 * b3 + a0 * b2)),
        (a2 * b2 + a2 * b1) - (a1 * b3 + a1 * b2 + c(3.0) * (a0 * b3)),
        -(c(2.0) * (a1 * b3)),
        -(a2 * b3),
    ]
}

/// p(u) from [`odds_numerator`]'s coefficients, evaluated exactly as in
/// [`OddsForm::halley_terms`].
#[inline(always)]
pub(crate) fn odds_numerator_at<const FMA: bool>(p: &[f64; 7], u: f64) -> f64 {
    let u2 = u * u;
    estrin::<FMA, f64, 7>(p, u, u2, u2 * u2)
}

/// The iteration on u = λ / (1 − λ) ([`OddsForm::halley_terms`]), one pair's state; the
/// batched path keeps one per lane and applies the same rule.
#[derive(Clone, Copy, Debug)]
pub(crate) struct OddsSearch {
    /// The current iterate; u₀ once `done` (and not `fallback`).
    pub u: f64,
    lo: f64,
    hi: f64,
    iterations: u32,
    /// The search has finished.
    pub done: bool,
    /// Below these V and |N| the step's products could underflow ([`Tiny`]).
    tiny: Tiny,
    /// The values left the range where the step is trustworthy (coefficients spanning
    /// hundreds of decades, NaN): the caller must use the λ iteration instead.
    pub fallback: bool,
}

/// A Halley step shorter than this (relative to u) is the last one: the error after it is
/// about C · TOL³ with C ≤ 0.3 on the bench distribution. Measured against fully converged
/// roots: 8e-15 relative in u at most (1e-5 would leave 5e-16 for 0.09 more evaluations per
/// pair, 1e-4 would leave 2e-13); the λ iteration it replaces left up to 8e-12.
pub(crate) const HALLEY_LAST_STEP: f64 = 3e-5;

/// The values of V = A B and |N| below which [`OddsSearch::advance`] gives up (the λ
/// iteration takes over): 1e-60 for a normalised form (largest α and largest β in [1, 2)),
/// where the products of the step (N², p N V) would otherwise come near underflow and lose
/// their digits silently. For a form whose α and β were not divided by their powers of two
/// sα and sβ, V is sα sβ times and N (sα sβ)² times its normalised value, exactly, and so
/// are these thresholds: the decisions are the same.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Tiny {
    v: f64,
    n: f64,
}

impl Tiny {
    /// The thresholds of a normalised form.
    pub(crate) const NORMALISED: Tiny = Tiny { v: 1e-60, n: 1e-60 };

    /// The thresholds of a form sα sβ = `product` times its normalised one (a power of two
    /// in [2⁻¹²⁸, 2¹²⁸], so that these are exact).
    #[inline(always)]
    pub(crate) fn scaled(product: f64) -> Tiny {
        Tiny {
            v: 1e-60 * product,
            n: 1e-60 * product * product,
        }
    }
}

impl OddsSearch {
    /// A search from `u0`; one that cannot start (u0 not a positive number) is a fallback.
    #[inline(always)]
    pub(crate) fn new(u0: f64, tiny: Tiny) -> Self {
        let ok = u0 > 0.0 && u0 < f64::INFINITY;
        Self {
            u: u0,
            lo: 0.0,
            hi: f64::INFINITY,
            iterations: 0,
            done: !ok,
            fallback: !ok,
            tiny,
        }
    }

    /// One step from the terms of [`OddsForm::halley_terms`] at `self.u`. The root stays
    /// bracketed (p > 0 below it); a step that leaves the bracket is replaced by bisection,
    /// geometric since u spans decades. (`crate::lanes::OddsSearch4::advance` applies the same
    /// rule to four searches with selects; a change here must be made there too, and the
    /// batch test compares the two bit for bit.)
    #[inline(always)]
    pub(crate) fn advance<const FMA: bool>(&mut self, (p, n, v, step): (f64, f64, f64, f64)) {
        let u = self.u;
        self.iterations += 1;
        // Below `tiny` the products of the step (N², p N V) could underflow and the step lose
        // its digits silently; NaN fails the test too.
        if !(v > self.tiny.v && n.abs() > self.tiny.n) || self.iterations > 100 {
            self.done = true;
            self.fallback = true;
            return;
        }
        // Blends, not a branch: which side of the root the iterate fell is a coin toss.
        self.lo = select_gt::<FMA>(p, 0.0, u, self.lo);
        self.hi = select_gt::<FMA>(p, 0.0, self.hi, u);
        let (lo, hi) = (self.lo, self.hi);
        let next = u - step;
        let small = step.abs() <= HALLEY_LAST_STEP * u;
        // Near a simple root Halley's step and Newton's (p V / N) agree; where h′ ≈ 0 far
        // from the root Halley's step is tiny too (≈ −2h′/h″) while Newton's is huge, and
        // stopping there would return a λ far from the maximiser (found on 1 pair in 1e6 by
        // `cargo xtask validate`: λ = 0.559 instead of 0.256). Such a step is replaced by the
        // bracket's expansion or bisection. The test needs no division: |p V| ≤ 2 tol u |N|.
        let trusted = (p * v).abs() <= 2.0 * HALLEY_LAST_STEP * u * n.abs();
        if small && trusted && next >= lo && next <= hi {
            self.u = next;
            self.done = true;
            return;
        }
        let next = if next > lo && next < hi && (trusted || !small) {
            next
        } else if hi == f64::INFINITY {
            4.0 * u
        } else if lo == 0.0 {
            0.25 * u
        } else {
            (lo * hi).sqrt()
        };
        if next == u {
            // The bracket is down to adjacent doubles.
            self.done = true;
            return;
        }
        self.u = next;
    }
}

/// The state of one λ iteration ([`RationalForm::search_step`]).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Search {
    /// The current iterate; λ₀ once `done`.
    pub t: f64,
    /// The bracket of λ₀.
    pub lo: f64,
    pub hi: f64,
    /// f(t) once `done`.
    pub f: f64,
    pub iterations: u32,
    pub done: bool,
}

impl Search {
    pub(crate) fn new(t0: f64) -> Self {
        Self {
            t: t0,
            lo: 0.0,
            hi: 1.0,
            f: f64::NAN,
            iterations: 0,
            done: false,
        }
    }
}

/// The Bernstein coefficients in a generic arithmetic.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Coefficients<T> {
    pub alpha: [T; 3],
    pub beta: [T; 4],
}

impl<T: Arith> Coefficients<T> {
    pub fn to_f64(self) -> RationalForm {
        RationalForm {
            alpha: self.alpha.map(T::to_f64),
            beta: self.beta.map(T::to_f64),
        }
    }
}

/// The Bernstein coefficients of a pair of ellipsoids, in arithmetic `T`, formed from
/// adj(Q1), adj(Q2) and the mixed adjugate M(Q1, Q2) (eq. 16).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Pencil3<T> {
    pub coefficients: Coefficients<T>,
}

#[inline(always)]
pub(crate) fn pencil3<T: Arith>(r12: &[f64; 3], q1: &Sym3, q2: &Sym3) -> Pencil3<T> {
    pencil3_lifted(r12.map(T::lift), lift6(q1), lift6(q2))
}

/// [`pencil3`] on inputs already in arithmetic `T` (the batched path fills each `T` with the
/// entries of several pairs).
#[inline(always)]
pub(crate) fn pencil3_lifted<T: Arith>(r12: [T; 3], a: [T; 6], b: [T; 6]) -> Pencil3<T> {
    let [x0, x1, x2] = r12;
    let rr = [x0 * x0, x0 * x1, x0 * x2, x1 * x1, x1 * x2, x2 * x2];
    let adj1 = adjugate_generic(&a);
    let adj2 = adjugate_generic(&b);
    let mixed = mixed_adjugate_generic(&a, &b);
    let coefficients = Coefficients {
        alpha: [
            quadratic_form_generic(&rr, &adj1),
            quadratic_form_generic(&rr, &mixed),
            quadratic_form_generic(&rr, &adj2),
        ],
        beta: [
            det_generic(&a, &adj1),
            frobenius_generic(&adj1, &b),
            frobenius_generic(&adj2, &a),
            det_generic(&b, &adj2),
        ],
    };
    Pencil3 { coefficients }
}

#[inline(always)]
pub(crate) fn coefficients<T: Arith>(r12: &[f64; 3], q1: &Sym3, q2: &Sym3) -> Coefficients<T> {
    pencil3::<T>(r12, q1, q2).coefficients
}

/// The 2D coefficients, degree-elevated to the 3D Bernstein form so that one solver serves
/// both: for ellipses a(λ) = s α₀ + t α₂ is linear and b(λ) = s² β₀ + st β₁ + t² β₂ quadratic;
/// multiplying both by (s + t) = 1 gives a quadratic and a cubic with non-negative
/// coefficients again.
#[inline(always)]
pub(crate) fn coefficients_2d<T: Arith>(
    r12: &[f64; 2],
    q1: &[f64; 3],
    q2: &[f64; 3],
) -> Coefficients<T> {
    let [a0, a1, a2] = q1.map(T::lift);
    let [b0, b1, b2] = q2.map(T::lift);
    let [x, y] = r12.map(T::lift);
    let (xx, xy, yy) = (x * x, x * y, y * y);
    // adj of [[q0, q1], [q1, q2]] is [[q2, −q1], [−q1, q0]].
    let alpha0 = a2 * xx + a0 * yy - (a1 * xy).twice();
    let alpha2 = b2 * xx + b0 * yy - (b1 * xy).twice();
    let beta0 = a0 * a2 - a1 * a1;
    let beta1 = a2 * b0 + a0 * b2 - (a1 * b1).twice();
    let beta2 = b0 * b2 - b1 * b1;
    Coefficients {
        alpha: [alpha0, alpha0 + alpha2, alpha2],
        beta: [beta0, beta0 + beta1, beta1 + beta2, beta2],
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const R: [f64; 3] = [1.1, -0.4, 2.3];
    const Q1: Sym3 = [4.0, 1.0, -0.5, 3.0, 0.25, 2.0];
    const Q2: Sym3 = [1.5, -0.3, 0.2, 2.5, 0.7, 3.5];

    #[test]
    fn sampled_coefficients_reproduce_a_and_b() {
        let a = a_coefficients(&R, &Q1, &Q2);
        let b = b_coefficients(&Q1, &Q2);
        for lambda in [-0.7, 0.0, 0.3, 0.5, 0.9, 1.4] {
            let q = pencil(lambda, &Q1, &Q2);
            let (ea, eb) = (xt_adj_x(&R, &q), det_sym(&q));
            assert!((polyval(&a, lambda) - ea).abs() <= 1e-13 * ea.abs().max(1.0));
            assert!((polyval(&b, lambda) - eb).abs() <= 1e-13 * eb.abs().max(1.0));
        }
    }

    #[test]
    fn bernstein_form_equals_monomial_form() {
        let rf = RationalForm::new(&R, &Q1, &Q2);
        let a = a_coefficients(&R, &Q1, &Q2);
        let b = b_coefficients(&Q1, &Q2);
        for lambda in [0.0, 0.2, 0.5, 0.8, 1.0] {
            assert!((rf.a(lambda) - polyval(&a, lambda)).abs() <= 1e-12 * rf.a(lambda));
            assert!((rf.b(lambda) - polyval(&b, lambda)).abs() <= 1e-12 * rf.b(lambda));
        }
        assert!(rf.alpha.iter().chain(&rf.beta).all(|&c| c > 0.0));
    }

    #[test]
    fn c_is_f_prime_times_b_squared() {
        let a = a_coefficients(&R, &Q1, &Q2);
        let b = b_coefficients(&Q1, &Q2);
        let c = c_coefficients(&a, &b);
        let f = |l: f64| l * (1.0 - l) * polyval(&a, l) / polyval(&b, l);
        for lambda in [0.1, 0.35, 0.6, 0.85] {
            let h = 1e-5;
            let fd = (f(lambda + h) - f(lambda - h)) / (2.0 * h);
            let bb = polyval(&b, lambda);
            let rel = (polyval(&c, lambda) - fd * bb * bb).abs() / (fd * bb * bb).abs().max(1e-3);
            assert!(rel < 1e-7, "λ = {lambda}: relative mismatch {rel}");
        }
    }

    #[test]
    fn rational_form_matches_direct_evaluation() {
        let rf = RationalForm::new(&R, &Q1, &Q2);
        for lambda in [0.05, 0.5, 0.95] {
            let direct = f_direct(lambda, &R, &Q1, &Q2);
            assert!((rf.f(lambda) - direct).abs() <= 1e-14 * direct);
        }
    }

    #[test]
    fn log_derivatives_match_finite_differences() {
        let rf = RationalForm::new(&R, &Q1, &Q2);
        let g = |l: f64| rf.f(l).ln();
        for lambda in [0.1, 0.4, 0.7] {
            let h = 1e-5;
            let d = rf.log_derivatives(lambda);
            let g1 = (g(lambda + h) - g(lambda - h)) / (2.0 * h);
            let g2 = (g(lambda + h) - 2.0 * g(lambda) + g(lambda - h)) / (h * h);
            assert!((d.g1 - g1).abs() < 1e-7 * g1.abs().max(1.0));
            assert!((d.g2 - g2).abs() < 1e-4 * g2.abs().max(1.0));
            assert!(d.g2 < 0.0, "ln f is concave");
        }
    }

    #[test]
    fn maximiser_satisfies_eq13() {
        let rf = RationalForm::new(&R, &Q1, &Q2);
        let (lambda, mu2, _) = rf.maximise(rf.initial_guess());
        let (u1, u2) = eq13_forms(lambda, &R, &Q1, &Q2);
        assert!((u1 - mu2).abs() < 1e-12 * mu2, "{u1} vs {mu2}");
        assert!((u2 - mu2).abs() < 1e-12 * mu2, "{u2} vs {mu2}");
    }

    #[test]
    fn two_d_coefficients_are_the_elevated_planar_pencil() {
        let (r, q1, q2) = ([0.7, -1.3], [2.0, 0.3, 1.0], [0.5, -0.1, 3.0]);
        let c = coefficients_2d::<f64>(&r, &q1, &q2).to_f64();
        for lambda in [0.1, 0.5, 0.9] {
            let q: [f64; 3] = core::array::from_fn(|k| (1.0 - lambda) * q1[k] + lambda * q2[k]);
            let det = q[0] * q[2] - q[1] * q[1];
            let a = q[2] * r[0] * r[0] - 2.0 * q[1] * r[0] * r[1] + q[0] * r[1] * r[1];
            assert!((c.a(lambda) - a).abs() < 1e-14 * a);
            assert!((c.b(lambda) - det).abs() < 1e-14 * det);
        }
    }
}
