//! Derivatives of the pair term (Appendix A): first derivatives in the envelope-theorem form,
//! and exact directional derivatives of the gradient (Hessian–vector products).
//!
//! Write `Δ = c_i − c_j`, `M = Q_j P_j⁻¹ Q_jᵀ` (so `E_j = {p : (p − c_j)ᵀ M (p − c_j) ≤ 1}`),
//! and map the projection back to the world frame: the contact point is `p* = c_j + y` with
//! `y = Q_i P_i^½ X`, and `n = M y` is half the gradient of `E_j`'s quadratic form there. A
//! rotation angle `α` moves `Q` by `∂Q/∂α = [ω_α]× Q` ([`crate::shape`]).
//!
//! **`d²`.** `d²(p) = min {|x − c|² : xᵀ S x = 1}`, so by the envelope theorem its derivative is
//! that of the Lagrangian `|x − c|² + U (xᵀ S x − 1)` at fixed `(X, U)`; no implicit solve is
//! needed. Written out, a force and two torques:
//!
//! ```text
//! ∂d²/∂c_i = 2U n = 2 Q_i P_i^−½ (c − X) =: F,      ∂d²/∂c_j = −F,
//! ∂d²/∂α_i = ω_α · ((p* − c_i) × F),               ∂d²/∂α_j = −ω_α · ((p* − c_j) × F).
//! ```
//!
//! **`U`.** Differentiating `G(U, p) = xᵀ S x − 1` with `x = (I + U S)⁻¹ c` (the implicit-function
//! step of A.1, reduced to one scalar equation):
//!
//! ```text
//! dU/dp = (2 zᵀ ∂c + xᵀ ∂S x − 2U zᵀ ∂S x) / (2 Σ_k s_k² x̂_k² / t_k),   z = (I + U S)⁻¹ S X.
//! ```
//!
//! In the hard case `U = −1/λ_max(S)` and `dU = v_topᵀ ∂S v_top / λ_max²`.
//!
//! **`f`** (eq. 34): `∇f = −2 max{0, 1 − d²} ∇d² − 2 max{0, ε − U} ∇U`.
//!
//! `a1_reference` (feature `internals`) solves the `(n+1) × (n+1)` linear system of Appendix A.1 for `dX/dp`, `dU/dp`
//! parameter by parameter, with `S` formed explicitly: slow and less accurate on stiff pairs, it
//! is kept as the scalar reference the fast path is tested against.
//!
//! **Second derivatives.** [`pair_gradient_derivative`] differentiates the force/torque form of
//! `∇f` once more along a direction, with `δX`, `δU` from the A.1 system solved in the
//! eigenbasis: exact Hessian–vector products without forming the 12×12 Hessian of A.2.
//!
//! # References
//! Birgin, Lobato, Martínez (2016), Appendix A.1–A.2, eqs. (38)–(41).

use crate::lanes::{Real, each};
use crate::linalg::torque;
use crate::pair::{
    BodyOf, PairSolution, bounding_spheres_apart, centre_line, certified_separated,
    direct_solution, setup_from, solve_direct, solve_pair_with, solve_svd,
};
use crate::projection::DirectProjection;
use crate::round::RoundPair;
use crate::shape::{Body, angular_velocities_3d};

/// A vector of a pair's placement space, or of its dual: centre parts and world-frame angular
/// parts of `i` and `j`.
///
/// As a gradient ([`PairGradient`]) the angular parts are torques: for any angle `α` of body
/// `i` with world-frame angular velocity `ω_α` (`∂Q_i/∂α = [ω_α]× Q_i`), the derivative is
/// `ω_α · angular_i`. As a direction ([`PairDirection`]) they are angular velocities
/// (`dQ = [w]× Q`). In 2D only the third component is used: the derivative with respect to
/// `θ`, or the rate of `θ`. `T` is `f64`, or one of the model's SIMD lanes types inside the
/// crate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PairVector<T, const N: usize> {
    /// The part of the centre `c_i`.
    pub centre_i: [T; N],
    /// The part of the centre `c_j`.
    pub centre_j: [T; N],
    /// The angular part of `i`: a torque in a gradient, an angular velocity in a direction.
    pub angular_i: [T; 3],
    /// The angular part of `j`.
    pub angular_j: [T; 3],
}

/// Gradient of a scalar pair quantity with respect to the placements of `i` and `j`, the
/// rotational part as torques.
pub type PairGradient<const N: usize> = PairVector<f64, N>;

/// A direction in the placement space of a pair: centre velocities and world angular
/// velocities.
pub type PairDirection<const N: usize> = PairVector<f64, N>;

impl<const N: usize> PairGradient<N> {
    /// The zero gradient.
    pub const ZERO: Self = PairGradient {
        centre_i: [0.0; N],
        centre_j: [0.0; N],
        angular_i: [0.0; 3],
        angular_j: [0.0; 3],
    };

    #[inline(always)]
    fn axpy(&mut self, a: f64, other: &Self) {
        for k in 0..N {
            self.centre_i[k] += a * other.centre_i[k];
            self.centre_j[k] += a * other.centre_j[k];
        }
        for k in 0..3 {
            self.angular_i[k] += a * other.angular_i[k];
            self.angular_j[k] += a * other.angular_j[k];
        }
    }
}

/// Derivatives with respect to the angles `[φ, θ, ψ]` of eq. 2 from a torque.
pub fn angle_gradient_3d(angles: [f64; 3], torque: &[f64; 3]) -> [f64; 3] {
    let w = angular_velocities_3d(angles);
    [
        w[0][0] * torque[0] + w[0][1] * torque[1] + w[0][2] * torque[2],
        w[1][0] * torque[0] + w[1][1] * torque[1] + w[1][2] * torque[2],
        w[2][0] * torque[0] + w[2][1] * torque[1] + w[2][2] * torque[2],
    ]
}

/// The pair term `f` with its gradient, and `d²`, `U` with theirs.
#[derive(Debug, Clone, Copy)]
pub struct PairDerivatives<const N: usize> {
    /// `f` of eq. 34.
    pub f: f64,
    /// `∇f`.
    pub grad_f: PairGradient<N>,
    /// `d²`.
    pub d2: f64,
    /// `∇d²` (envelope theorem).
    pub grad_d2: PairGradient<N>,
    /// `U`.
    pub u: f64,
    /// `∇U` (implicit function).
    pub grad_u: PairGradient<N>,
}

/// World-frame vectors of a solved pair: `Δ`, `y`, the force `F = ∂d²/∂c_i`.
struct Frames<T, const N: usize> {
    delta: [T; N],
    y: [T; N],
    force: [T; N],
}

/// `Q_i P_i^{±½} V w` for a vector `w` in the eigenbasis.
#[inline(always)]
fn to_world<const N: usize>(
    i: &Body<N>,
    sol: &PairSolution<N>,
    w: &[f64; N],
    power: f64,
) -> [f64; N] {
    let q = i.rotation();
    let l = i.semi_axes();
    // On the direct route the basis is the i-frame itself (V = I).
    let mut frame = [0.0; N];
    if sol.direct {
        frame = *w;
    } else {
        for k in 0..N {
            for m in 0..N {
                frame[m] += sol.svd.v[k][m] * w[k];
            }
        }
    }
    for m in 0..N {
        frame[m] = if power > 0.0 {
            frame[m] * l[m]
        } else {
            frame[m] / l[m]
        };
    }
    let mut out = [0.0; N];
    for r in 0..N {
        for m in 0..N {
            out[r] += q[r][m] * frame[m];
        }
    }
    out
}

fn frames<const N: usize>(i: &Body<N>, j: &Body<N>, sol: &PairSolution<N>) -> Frames<f64, N> {
    let ci = i.centre();
    let cj = j.centre();
    let mut delta = [0.0; N];
    for k in 0..N {
        delta[k] = ci[k] - cj[k];
    }
    let y = to_world(i, sol, &sol.proj.xhat, 1.0);
    // c − X from the projection, where it was computed without cancellation.
    let mut dhat = [0.0; N];
    for k in 0..N {
        dhat[k] = 2.0 * sol.proj.dhat[k];
    }
    let force = to_world(i, sol, &dhat, -1.0);
    Frames { delta, y, force }
}

/// `∇d²` from the world-frame vectors: the force `F` on `c_i`, `−F` on `c_j`, and the torques
/// `(y − Δ) × F` on `i` and `−y × F` on `j`.
#[inline(always)]
fn grad_d2<T: Real, const N: usize>(fr: &Frames<T, N>) -> PairVector<T, N> {
    let mut lever_i = fr.y;
    for k in 0..N {
        lever_i[k] = fr.y[k] - fr.delta[k];
    }
    let ti = torque(&lever_i, &fr.force);
    let tj = torque(&fr.y, &fr.force);
    PairVector {
        centre_i: fr.force,
        centre_j: each(fr.force, |v| -v),
        angular_i: ti,
        angular_j: each(tj, |v| -v),
    }
}

/// `∇f = −2 (1 − d²) ∇d²` on the direct route with `U ≥ ε` (only the first term of `f` is
/// active), from the direct solution `X`, `c − X` in the i-frame (where the direct route
/// works, `V = I`): `y = Q_i P_i^½ X`, `F = Q_i P_i^−½ 2 (c − X)`. In any [`Real`] arithmetic;
/// `a = 1 − d² > 0`. The sum starts from `+0`, as [`PairGradient::axpy`] onto zero does, so
/// that one pair and four give the same bits.
#[inline(always)]
pub(crate) fn direct_gradient<T: Real, const N: usize>(
    a: T,
    settled: &DirectProjection<N, T>,
    body_i: BodyOf<'_, T, N>,
    delta: &[T; N],
) -> PairVector<T, N> {
    let zero = T::splat(0.0);
    let mut fr = Frames {
        delta: *delta,
        y: [zero; N],
        force: [zero; N],
    };
    let mut ys = fr.y;
    let mut fs = fr.y;
    for m in 0..N {
        ys[m] = settled.x[m] * body_i.l[m];
        fs[m] = T::splat(2.0) * settled.c_minus_x[m] * body_i.inv_l[m];
    }
    for r in 0..N {
        for m in 0..N {
            fr.y[r] = fr.y[r] + body_i.q[r][m] * ys[m];
            fr.force[r] = fr.force[r] + body_i.q[r][m] * fs[m];
        }
    }
    let g = grad_d2(&fr);
    let k = T::splat(-2.0) * a;
    let axpy = |v: T| zero + k * v;
    PairVector {
        centre_i: each(g.centre_i, axpy),
        centre_j: each(g.centre_j, axpy),
        angular_i: each(g.angular_i, axpy),
        angular_j: each(g.angular_j, axpy),
    }
}

fn grad_u<const N: usize>(
    i: &Body<N>,
    sol: &PairSolution<N>,
    fr: &Frames<f64, N>,
) -> PairGradient<N> {
    let mut g = PairGradient::ZERO;
    let mut s = [0.0; N];
    for k in 0..N {
        s[k] = sol.svd.sigma[k] * sol.svd.sigma[k];
    }
    if sol.proj.hard {
        let mut top = 0;
        for k in 1..N {
            if s[k] > s[top] {
                top = k;
            }
        }
        let mut e = [0.0; N];
        e[top] = 1.0;
        let yv = to_world(i, sol, &e, 1.0);
        e[top] = s[top];
        let nv = to_world(i, sol, &e, -1.0);
        let t = torque(&yv, &nv);
        let scale = 2.0 / (s[top] * s[top]);
        for k in 0..3 {
            g.angular_i[k] = scale * t[k];
            g.angular_j[k] = -scale * t[k];
        }
        return g;
    }
    let u = sol.proj.u;
    let mut sx = [0.0; N];
    let mut zhat = [0.0; N];
    let mut sz = [0.0; N];
    let mut den = 0.0;
    for k in 0..N {
        let xk = sol.proj.xhat[k];
        sx[k] = s[k] * xk;
        zhat[k] = sx[k] / sol.proj.t[k];
        sz[k] = s[k] * zhat[k];
        den += sx[k] * zhat[k];
    }
    let den = 2.0 * den;
    let n = to_world(i, sol, &sx, -1.0);
    let uw = to_world(i, sol, &zhat, -1.0);
    let yz = to_world(i, sol, &zhat, 1.0);
    let nz = to_world(i, sol, &sz, -1.0);
    let y = &fr.y;
    let y_n = torque(y, &n);
    let uw_delta = torque(&uw, &fr.delta);
    let yz_n = torque(&yz, &n);
    let y_nz = torque(y, &nz);
    for k in 0..N {
        g.centre_i[k] = 2.0 * uw[k] / den;
        g.centre_j[k] = -g.centre_i[k];
    }
    for k in 0..3 {
        g.angular_i[k] = (2.0 * uw_delta[k] + 2.0 * y_n[k] - 2.0 * u * (yz_n[k] + y_nz[k])) / den;
        // n × y_z = −(y_z × n).
        g.angular_j[k] = (-2.0 * y_n[k] - 2.0 * u * (-yz_n[k] - y_nz[k])) / den;
    }
    g
}

/// `f`, `d²`, `U` of eq. 34 with their gradients with respect to both placements.
pub fn pair_derivatives<const N: usize>(i: &Body<N>, j: &Body<N>) -> PairDerivatives<N> {
    let sol = solve_pair_with(i, j, false);
    let fr = frames(i, j, &sol);
    let gd = grad_d2(&fr);
    let gu = grad_u(i, &sol, &fr);
    let a = (1.0 - sol.proj.d2).max(0.0);
    let b = (sol.eps - sol.proj.u).max(0.0);
    let mut gf = PairGradient::ZERO;
    gf.axpy(-2.0 * a, &gd);
    gf.axpy(-2.0 * b, &gu);
    PairDerivatives {
        f: a * a + b * b,
        grad_f: gf,
        d2: sol.proj.d2,
        grad_d2: gd,
        u: sol.proj.u,
        grad_u: gu,
    }
}

/// The pair term `f` and its gradient, doing only the work that is needed: nothing when the
/// bounding spheres are apart or the centre-line plane separates the pair, no `∇U` unless
/// `U < ε`, no gradient at all when `f = 0`.
#[inline]
pub fn pair_gradient<const N: usize>(i: &Body<N>, j: &Body<N>) -> (f64, PairGradient<N>) {
    // The bounding-sphere exit ahead of the dispatch, as in `overlap_measure`.
    if bounding_spheres_apart(i, j) {
        return (0.0, PairGradient::ZERO);
    }
    if i.is_round() && j.is_round() {
        return round_pair_gradient(i, j);
    }
    simd::multiversion!(call pair_gradient_impl::<N>(i: &Body<N>, j: &Body<N>) -> (f64, PairGradient<N>)
    )
}

/// [`pair_gradient`], compiled twice (see `simd::multiversion`): everything on its fast path
/// is `#[inline(always)]` so that it is compiled with the caller's instruction set.
#[inline(always)]
fn pair_gradient_impl<const N: usize>(i: &Body<N>, j: &Body<N>) -> (f64, PairGradient<N>) {
    let line = centre_line(i, j);
    if certified_separated(i, j, &line) {
        return (0.0, PairGradient::ZERO);
    }
    let st = setup_from(i, j, &line);
    // The common case in a packing, on the direct route with U ≥ ε: only ∇d² is needed, and
    // it is assembled straight from the direct solution (the eigenbasis is the i-frame) as
    // `frames` and `grad_d2` below do, without building a `PairSolution`.
    let direct = solve_direct(&st);
    if let Some(d) = &direct
        && d.u >= st.eps
    {
        let a = (1.0 - d.d2).max(0.0);
        if a == 0.0 {
            return (0.0, PairGradient::ZERO);
        }
        let ci = i.centre();
        let cj = j.centre();
        let mut delta = [0.0; N];
        for m in 0..N {
            delta[m] = ci[m] - cj[m];
        }
        let body_i = BodyOf {
            q: &i.rotation(),
            l: &i.semi_axes(),
            inv_l: &st.inv_li,
        };
        return (a * a, direct_gradient(a, d, body_i, &delta));
    }
    let sol = match direct {
        Some(d) => direct_solution(&st, &d),
        None => solve_svd(&st),
    };
    let a = (1.0 - sol.proj.d2).max(0.0);
    let b = (sol.eps - sol.proj.u).max(0.0);
    if a == 0.0 && b == 0.0 {
        return (0.0, PairGradient::ZERO);
    }
    let fr = frames(i, j, &sol);
    let mut gf = PairGradient::ZERO;
    if a > 0.0 {
        gf.axpy(-2.0 * a, &grad_d2(&fr));
    }
    if b > 0.0 {
        // ∇U works in the eigenbasis, which the direct route does not compute.
        if sol.direct {
            let full = solve_pair_with(i, j, false);
            let fr_full = frames(i, j, &full);
            gf.axpy(-2.0 * b, &grad_u(i, &full, &fr_full));
        } else {
            gf.axpy(-2.0 * b, &grad_u(i, &sol, &fr));
        }
    }
    (a * a + b * b, gf)
}

/// Scalar reference: `d d²/dp` and `dU/dp` through the linear system of Appendix A.1, for one
/// parameter `p` given by the derivatives of the placements it moves: `dc_i`, `dc_j` (centre
/// velocities) and `w_i`, `w_j` (world angular velocities, `dQ = [w]× Q`; in 2D only `w[2]`).
///
/// Solves, with `S` formed explicitly,
///
/// ```text
/// [ I + U S   S X ] [dX]     [ U ∂S X − ∂c ]
/// [ (S X)ᵀ     0  ] [dU] = − [ ½ Xᵀ ∂S X  ]
/// ```
///
/// and returns `(d d²/dp, dU/dp)` with `d d²/dp = 2 (X − c)ᵀ (dX − ∂c)`.
#[cfg(any(test, feature = "internals"))]
pub fn a1_reference<const N: usize>(
    i: &Body<N>,
    j: &Body<N>,
    dc_i: &[f64; N],
    dc_j: &[f64; N],
    w_i: &[f64; 3],
    w_j: &[f64; 3],
) -> (f64, f64) {
    let sol = solve_pair_with(i, j, false);
    let (qi, qj, li, lj) = (i.rotation(), j.rotation(), i.semi_axes(), j.semi_axes());
    let (ci, cj) = (i.centre(), j.centre());
    // [w]× as an N×N matrix (2D: the rotation generator about e_z).
    let skew = |w: &[f64; 3]| -> [[f64; N]; N] {
        let mut k = [[0.0; N]; N];
        if N == 3 {
            let full = [[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]];
            for r in 0..N {
                for s in 0..N {
                    k[r][s] = full[r][s];
                }
            }
        } else {
            k[0][1] = -w[2];
            k[1][0] = w[2];
        }
        k
    };
    let mul = |a: &[[f64; N]; N], b: &[[f64; N]; N]| -> [[f64; N]; N] {
        let mut c = [[0.0; N]; N];
        for r in 0..N {
            for s in 0..N {
                for m in 0..N {
                    c[r][s] += a[r][m] * b[m][s];
                }
            }
        }
        c
    };
    let tr = |a: &[[f64; N]; N]| -> [[f64; N]; N] {
        let mut c = [[0.0; N]; N];
        for r in 0..N {
            for s in 0..N {
                c[r][s] = a[s][r];
            }
        }
        c
    };
    let dqi = mul(&skew(w_i), &qi);
    let dqj = mul(&skew(w_j), &qj);
    // S = A B Aᵀ with A = P_i^½ Q_iᵀ, B = Q_j P_j⁻¹ Q_jᵀ.
    let mut pi_half = [[0.0; N]; N];
    let mut pj_inv = [[0.0; N]; N];
    let mut pi_mhalf = [[0.0; N]; N];
    for k in 0..N {
        pi_half[k][k] = li[k];
        pi_mhalf[k][k] = 1.0 / li[k];
        pj_inv[k][k] = 1.0 / (lj[k] * lj[k]);
    }
    let a = mul(&pi_half, &tr(&qi));
    let da = mul(&pi_half, &tr(&dqi));
    let bm = mul(&mul(&qj, &pj_inv), &tr(&qj));
    let db = {
        let x = mul(&mul(&dqj, &pj_inv), &tr(&qj));
        let mut s = x;
        let xt = tr(&x);
        for r in 0..N {
            for c in 0..N {
                s[r][c] += xt[r][c];
            }
        }
        s
    };
    let s_mat = mul(&mul(&a, &bm), &tr(&a));
    let mut ds = mul(&mul(&da, &bm), &tr(&a));
    let ds2 = mul(&mul(&a, &db), &tr(&a));
    let ds3 = mul(&mul(&a, &bm), &tr(&da));
    for r in 0..N {
        for c in 0..N {
            ds[r][c] += ds2[r][c] + ds3[r][c];
        }
    }
    // c = P_i^−½ Q_iᵀ Δ; ∂c = P_i^−½ (∂Q_iᵀ Δ + Q_iᵀ ∂Δ).
    let mut delta = [0.0; N];
    let mut ddelta = [0.0; N];
    for k in 0..N {
        delta[k] = ci[k] - cj[k];
        ddelta[k] = dc_i[k] - dc_j[k];
    }
    let mut dc = [0.0; N];
    for k in 0..N {
        let mut v = 0.0;
        for m in 0..N {
            v += dqi[m][k] * delta[m] + qi[m][k] * ddelta[m];
        }
        dc[k] = pi_mhalf[k][k] * v;
    }
    let x = sol.x;
    let u = sol.proj.u;
    let c = sol.c;
    let mut sx = [0.0; N];
    let mut dsx = [0.0; N];
    for r in 0..N {
        for m in 0..N {
            sx[r] += s_mat[r][m] * x[m];
            dsx[r] += ds[r][m] * x[m];
        }
    }
    // The (N+1)×(N+1) system, solved by Gaussian elimination with partial pivoting.
    let mut m = [[0.0; 4]; 4];
    let mut rhs = [0.0; 4];
    for r in 0..N {
        for s in 0..N {
            m[r][s] = u * s_mat[r][s] + if r == s { 1.0 } else { 0.0 };
        }
        m[r][N] = sx[r];
        m[N][r] = sx[r];
        rhs[r] = -(u * dsx[r] - dc[r]);
    }
    rhs[N] = -0.5 * (0..N).map(|k| x[k] * dsx[k]).sum::<f64>();
    // A singular system (a degenerate pair) gives NaN, which the callers' checks catch.
    let sol_vec = crate::linalg::solve_small(&mut m, &mut rhs, N + 1).unwrap_or([f64::NAN; 4]);
    let mut dd2 = 0.0;
    for k in 0..N {
        dd2 += 2.0 * (x[k] - c[k]) * (sol_vec[k] - dc[k]);
    }
    (dd2, sol_vec[N])
}

// ---------------------------------------------------------------------------------------------
// Second derivatives: directional derivatives of the gradient (Hessian–vector products).
// ---------------------------------------------------------------------------------------------

/// `w × v` for a world angular velocity `w` and an `N`-vector `v` (2D: rotation about e_z).
#[inline(always)]
pub(crate) fn spin<const N: usize>(w: &[f64; 3], v: &[f64; N]) -> [f64; N] {
    let mut out = [0.0; N];
    if N == 3 {
        out[0] = w[1] * v[2] - w[2] * v[1];
        out[1] = w[2] * v[0] - w[0] * v[2];
        out[2] = w[0] * v[1] - w[1] * v[0];
    } else {
        out[0] = -w[2] * v[1];
        out[1] = w[2] * v[0];
    }
    out
}

#[inline(always)]
fn add<const K: usize>(a: &[f64; K], b: &[f64; K]) -> [f64; K] {
    let mut o = *a;
    for k in 0..K {
        o[k] += b[k];
    }
    o
}

#[inline(always)]
fn sub<const K: usize>(a: &[f64; K], b: &[f64; K]) -> [f64; K] {
    let mut o = *a;
    for k in 0..K {
        o[k] -= b[k];
    }
    o
}

#[inline(always)]
fn scale<const K: usize>(a: f64, b: &[f64; K]) -> [f64; K] {
    let mut o = *b;
    for v in o.iter_mut() {
        *v *= a;
    }
    o
}

#[inline(always)]
fn dotk<const K: usize>(a: &[f64; K], b: &[f64; K]) -> f64 {
    (0..K).map(|k| a[k] * b[k]).sum()
}

/// World ↔ frame maps of a solved pair, for the second derivatives.
struct Maps<'a, const N: usize> {
    i: &'a Body<N>,
    sol: &'a PairSolution<N>,
    /// `M = Q_j P_j⁻¹ Q_jᵀ` (world frame).
    m: [[f64; N]; N],
}

impl<const N: usize> Maps<'_, N> {
    fn m_times(&self, v: &[f64; N]) -> [f64; N] {
        let mut o = [0.0; N];
        for r in 0..N {
            for c in 0..N {
                o[r] += self.m[r][c] * v[c];
            }
        }
        o
    }
    /// Eigen coordinates `Vᵀ P_i^{±½} Q_iᵀ v` of a world vector `v`: the power +½ (`scaled`)
    /// is the transpose of `to_world` with power +1.
    fn eig_of_world(&self, v: &[f64; N], scaled: bool) -> [f64; N] {
        let q = self.i.rotation();
        let l = self.i.semi_axes();
        let mut frame = [0.0; N];
        for k in 0..N {
            for r in 0..N {
                frame[k] += q[r][k] * v[r];
            }
            if scaled {
                frame[k] *= l[k];
            } else {
                frame[k] /= l[k];
            }
        }
        let mut out = [0.0; N];
        for k in 0..N {
            for m in 0..N {
                out[k] += self.sol.svd.v[k][m] * frame[m];
            }
        }
        out
    }
    /// `Vᵀ δS v` in eigen coordinates for the i-frame vector `v` with world images
    /// `y_v = Q_i P_i^½ v`, `n_v = M y_v`: `δS v = P_i^½ Q_iᵀ [M (w × y_v) − w × n_v]`,
    /// `w = w_i − w_j` (only the relative rotation moves `S`).
    fn ds_times(&self, w: &[f64; 3], yv: &[f64; N], nv: &[f64; N]) -> [f64; N] {
        let world = sub(&self.m_times(&spin(w, yv)), &spin(w, nv));
        self.eig_of_world(&world, true)
    }
}

/// Gradient of `f` and its derivative along a direction: `∇f` and `(∇²f) · dir`, both in the
/// force/torque form of [`PairGradient`]. Returns `None` in the hard case, where `U` and `X`
/// are not differentiable.
///
/// The derivative of `∇d² = (F, (p* − c_i) × F, −F, −(p* − c_j) × F)`, `F = 2 Q_i P_i^−½ (c − X)`,
/// and of `∇U` (see [`pair_derivatives`]) needs `δX`, `δU`: the implicit-function system of
/// Appendix A.1 solved in the eigenbasis, where `I + U S = V diag(t) Vᵀ`:
///
/// ```text
/// δX̂ = (r̂ − â δU) / t,  δU = (Σ â r̂ / t + ½ Xᵀ δS X) / (Σ â² / t),
/// r̂ = Vᵀ (δc − U δS X),  â = s ⊙ X̂,  Xᵀ δS X = 2 (w_i − w_j) · (y × n),
/// ```
///
/// then the product rule through every term (`δ(w × v) = w × δv` for the rotating frames).
/// With `A = max{0, 1 − d²}`, `B = max{0, ε − U}`:
/// `δ∇f = 2 [A > 0] δd² ∇d² − 2A δ∇d² + 2 [B > 0] δU ∇U − 2B δ∇U`.
pub fn pair_gradient_derivative<const N: usize>(
    i: &Body<N>,
    j: &Body<N>,
    dir: &PairDirection<N>,
) -> Option<(f64, PairGradient<N>, PairGradient<N>)> {
    if i.is_round() && j.is_round() {
        return Some(round_pair_gradient_derivative(i, j, dir));
    }
    let sol = solve_pair_with(i, j, false);
    if sol.proj.hard {
        return None;
    }
    let fr = frames(i, j, &sol);
    let gd = grad_d2(&fr);
    let a = (1.0 - sol.proj.d2).max(0.0);
    let bterm = (sol.eps - sol.proj.u).max(0.0);
    let f = a * a + bterm * bterm;
    let mut grad = PairGradient::ZERO;
    let mut hv = PairGradient::ZERO;
    if f == 0.0 {
        return Some((0.0, grad, hv));
    }
    let gu = grad_u(i, &sol, &fr);
    grad.axpy(-2.0 * a, &gd);
    grad.axpy(-2.0 * bterm, &gu);

    let (qj, lj) = (j.rotation(), j.semi_axes());
    let mut m = [[0.0; N]; N];
    for r in 0..N {
        for c in 0..N {
            m[r][c] = (0..N).map(|k| qj[r][k] * qj[c][k] / (lj[k] * lj[k])).sum();
        }
    }
    let maps = Maps { i, sol: &sol, m };
    let u = sol.proj.u;
    let mut s = [0.0; N];
    let mut ahat = [0.0; N];
    let mut zhat = [0.0; N];
    let mut szhat = [0.0; N];
    let t = sol.proj.t;
    for k in 0..N {
        s[k] = sol.svd.sigma[k] * sol.svd.sigma[k];
        ahat[k] = s[k] * sol.proj.xhat[k];
        zhat[k] = ahat[k] / t[k];
        szhat[k] = s[k] * zhat[k];
    }
    let y = fr.y;
    let delta = fr.delta;
    let force = fr.force;
    let n = to_world(i, &sol, &ahat, -1.0);
    let w = sub(&dir.angular_i, &dir.angular_j);
    let ddelta = sub(&dir.centre_i, &dir.centre_j);

    // δc (eigen coordinates) = Vᵀ P_i^−½ Q_iᵀ (δΔ − w_i × Δ).
    let dc_world = sub(&ddelta, &spin(&dir.angular_i, &delta));
    let dchat = maps.eig_of_world(&dc_world, false);
    let dsx = maps.ds_times(&w, &y, &n);
    let xdsx = 2.0 * dotk(&w, &torque(&y, &n));
    let mut num = 0.5 * xdsx;
    let mut den_u = 0.0;
    let mut rhat = [0.0; N];
    for k in 0..N {
        rhat[k] = dchat[k] - u * dsx[k];
        num += ahat[k] * rhat[k] / t[k];
        den_u += ahat[k] * ahat[k] / t[k];
    }
    let du = num / den_u;
    let mut dxhat = [0.0; N];
    for k in 0..N {
        dxhat[k] = (rhat[k] - ahat[k] * du) / t[k];
    }

    // d² part.
    let dy = add(&spin(&dir.angular_i, &y), &to_world(i, &sol, &dxhat, 1.0));
    let mut dcmx = [0.0; N];
    for k in 0..N {
        dcmx[k] = 2.0 * (dchat[k] - dxhat[k]);
    }
    let dforce = add(
        &spin(&dir.angular_i, &force),
        &to_world(i, &sol, &dcmx, -1.0),
    );
    let lever = sub(&y, &delta);
    let dlever = sub(&dy, &ddelta);
    let dti = add(&torque(&dlever, &force), &torque(&lever, &dforce));
    let dtj = scale(-1.0, &add(&torque(&dy, &force), &torque(&y, &dforce)));
    let dd2 = dotk(&force, &ddelta)
        + dotk(&gd.angular_i, &dir.angular_i)
        + dotk(&gd.angular_j, &dir.angular_j);
    let dgd = PairGradient {
        centre_i: dforce,
        centre_j: scale(-1.0, &dforce),
        angular_i: dti,
        angular_j: dtj,
    };
    if a > 0.0 {
        hv.axpy(2.0 * dd2, &gd);
        hv.axpy(-2.0 * a, &dgd);
    }

    // U part.
    if bterm > 0.0 {
        let uw = to_world(i, &sol, &zhat, -1.0);
        let yz = to_world(i, &sol, &zhat, 1.0);
        let nz = to_world(i, &sol, &szhat, -1.0);
        let den = 2.0 * dotk(&ahat, &zhat);
        // δ(S X) = δS X + S δX and δz = [δ(SX) − δU S z − U δS z] / t in eigen coordinates.
        let dszhat = maps.ds_times(&w, &yz, &nz);
        let mut dsxhat = [0.0; N];
        let mut dzhat = [0.0; N];
        for k in 0..N {
            dsxhat[k] = dsx[k] + s[k] * dxhat[k];
            dzhat[k] = (dsxhat[k] - du * szhat[k] - u * dszhat[k]) / t[k];
        }
        let duw = add(&spin(&dir.angular_i, &uw), &to_world(i, &sol, &dzhat, -1.0));
        let dyz = add(&spin(&dir.angular_i, &yz), &to_world(i, &sol, &dzhat, 1.0));
        let dn = add(
            &sub(
                &spin(&dir.angular_j, &n),
                &maps.m_times(&spin(&dir.angular_j, &y)),
            ),
            &maps.m_times(&dy),
        );
        let dnz = add(
            &sub(
                &spin(&dir.angular_j, &nz),
                &maps.m_times(&spin(&dir.angular_j, &yz)),
            ),
            &maps.m_times(&dyz),
        );
        let dden = 2.0 * (dotk(&dsxhat, &zhat) + dotk(&ahat, &dzhat));
        let kk = add(&torque(&yz, &n), &torque(&y, &nz));
        let dkk = add(
            &add(&torque(&dyz, &n), &torque(&yz, &dn)),
            &add(&torque(&dy, &nz), &torque(&y, &dnz)),
        );
        let y_n = torque(&y, &n);
        let dy_n = add(&torque(&dy, &n), &torque(&y, &dn));
        let ni = add(
            &scale(2.0, &torque(&uw, &delta)),
            &sub(&scale(2.0, &y_n), &scale(2.0 * u, &kk)),
        );
        let nj = add(&scale(-2.0, &y_n), &scale(2.0 * u, &kk));
        let dni = add(
            &scale(2.0, &add(&torque(&duw, &delta), &torque(&uw, &ddelta))),
            &sub(
                &scale(2.0, &dy_n),
                &add(&scale(2.0 * du, &kk), &scale(2.0 * u, &dkk)),
            ),
        );
        let dnj = add(
            &scale(-2.0, &dy_n),
            &add(&scale(2.0 * du, &kk), &scale(2.0 * u, &dkk)),
        );
        let q = dden / (den * den);
        let dgu = PairGradient {
            centre_i: sub(&scale(2.0 / den, &duw), &scale(2.0 * q, &uw)),
            centre_j: sub(&scale(2.0 * q, &uw), &scale(2.0 / den, &duw)),
            angular_i: sub(&scale(1.0 / den, &dni), &scale(q, &ni)),
            angular_j: sub(&scale(1.0 / den, &dnj), &scale(q, &nj)),
        };
        hv.axpy(2.0 * du, &gu);
        hv.axpy(-2.0 * bterm, &dgu);
    }
    Some((f, grad, hv))
}

/// `∂ω_α/∂β` for the angles `[φ, θ, ψ]` of eq. 2: `out[α][β]` is a world vector.
pub fn angular_velocity_derivatives_3d(angles: [f64; 3]) -> [[[f64; 3]; 3]; 3] {
    let [_, theta, psi] = angles;
    let (st, ct) = theta.sin_cos();
    let (sp, cp) = psi.sin_cos();
    let z = [0.0; 3];
    // ω_φ = (cθ cψ, cθ sψ, −sθ), ω_θ = (−sψ, cψ, 0), ω_ψ = e_z.
    [
        [z, [-st * cp, -st * sp, -ct], [-ct * sp, ct * cp, 0.0]],
        [z, z, [-cp, -sp, 0.0]],
        [z, z, z],
    ]
}

/// The gradient of the closed form for the slope `f'(t)`: `±f'(t) n / r_i` on the centres, no
/// torque (module `round`).
fn round_gradient<const N: usize>(pair: &RoundPair<N>, slope: f64) -> PairGradient<N> {
    let mut g = PairGradient::ZERO;
    for k in 0..N {
        g.centre_i[k] = slope * pair.normal[k] / pair.r_i;
        g.centre_j[k] = -g.centre_i[k];
    }
    g
}

/// `f` and its gradient for two round items: no torques.
pub fn round_pair_gradient<const N: usize>(i: &Body<N>, j: &Body<N>) -> (f64, PairGradient<N>) {
    let pair = RoundPair::of(i, j);
    let f = pair.value();
    if f == 0.0 {
        return (0.0, PairGradient::ZERO);
    }
    (f, round_gradient(&pair, pair.slope()))
}

/// `f`, its gradient and the Hessian of `f` times the direction `dir` for two round items (the
/// angular parts of `dir` play no part).
pub fn round_pair_gradient_derivative<const N: usize>(
    i: &Body<N>,
    j: &Body<N>,
    dir: &PairDirection<N>,
) -> (f64, PairGradient<N>, PairGradient<N>) {
    let pair = RoundPair::of(i, j);
    let f = pair.value();
    if f == 0.0 {
        return (0.0, PairGradient::ZERO, PairGradient::ZERO);
    }
    let slope = pair.slope();
    let mut du = [0.0; N];
    for k in 0..N {
        du[k] = dir.centre_i[k] - dir.centre_j[k];
    }
    let n = &pair.normal;
    let along = (0..N).map(|k| n[k] * du[k]).sum::<f64>();
    let radial = pair.curvature() / (pair.r_i * pair.r_i);
    let tangential = if pair.distance > 0.0 {
        slope / (pair.r_i * pair.distance)
    } else {
        0.0
    };
    let mut hv = PairGradient::ZERO;
    for k in 0..N {
        hv.centre_i[k] = radial * along * n[k] + tangential * (du[k] - along * n[k]);
        hv.centre_j[k] = -hv.centre_i[k];
    }
    (f, round_gradient(&pair, slope), hv)
}
