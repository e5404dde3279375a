//! Exact containment of an ellipsoid in a ball, an ellipsoid or a box centred at the origin,
//! with derivatives (no sampling of the boundary).
//!
//! The packing paper takes its containment models from its reference \[8\]; ours are derived here.
//!
//! **Ball of radius `r` and axis-aligned ellipsoid with semi-axes `A = (A_1, …, A_n)`.** With
//! `C = diag(A)` (`C = r I` for the ball), `E = {c + Q P^½ u : |u| ≤ 1}` lies in the container iff
//!
//! ```text
//! h = max_{|u| = 1} |C⁻¹ (c + G' u)|² ≤ 1,   G' = Q P^½,
//! ```
//!
//! i.e. the ellipsoidal container reduces to a ball by its own transformation `C⁻¹`. With the SVD
//! `G = C⁻¹ Q P^½ = W Σ Vᵀ` and `ĉ = Wᵀ C⁻¹ c`, the stationarity condition
//! `Gᵀ (C⁻¹c + G u) = μ u` gives `û_k = σ_k ĉ_k / (μ − σ_k²)`, and the maximum is the root
//! `μ ≥ σ_max²` of the secular equation
//!
//! ```text
//! Σ_k σ_k² ĉ_k² / (μ − σ_k²)² = 1,     h = Σ_k (ĉ_k μ / (μ − σ_k²))²,
//! ```
//!
//! solved for `τ = μ − σ_max² ∈ [σ_max |ĉ_top|, |Σ ĉ|]` by the same safeguarded Newton as the pair
//! term (hard case `ĉ_top = 0`: `τ = 0`). By the envelope theorem, with `p*` the farthest point and
//! `q = C⁻¹ p*`:
//!
//! ```text
//! ∂h/∂c = 2 C⁻¹ q,   ∂h/∂α = ω_α · (2 (p* − c) × C⁻¹ q),   ∂h/∂A_k = −2 q_k² / A_k.
//! ```
//!
//! **Box with half-sides `L_k`.** By the support function of `E` in direction `e_k`,
//! `max_{p∈E} ±p_k = ±c_k + sqrt(M_kk)`, `M = Q P Qᵀ`; so `E ⊆ box` iff
//! `g_k± = (±c_k + sqrt(M_kk)) / L_k − 1 ≤ 0` for every k. Derivatives:
//! `∂ sqrt(M_kk)/∂α = ω_α · (M e_k × e_k) / sqrt(M_kk)`.
//!
//! The residual of one ellipsoid is `Σ max{0, g}²` over its constraints (`g = h − 1` for the
//! ball and the ellipsoid, `g_k±` for the box): zero iff the ellipsoid is inside, once
//! continuously differentiable, dimensionless like the pair term.
//!
//! # References
//! Birgin, Lobato, Martínez (2016), Section 6 and its reference \[8\] (E. G. Birgin, R. D. Lobato,
//! J. M. Martínez, *Packing ellipsoids by nonlinear optimization*, J. Global Optim. 65 (2016)).

use crate::derivatives::spin;
use crate::error::Error;
use crate::linalg::{graded_svd, mat_t_vec, torque};
use crate::projection::newton;
use crate::shape::Body;

/// A container centred at the origin, axis-aligned.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Container<const N: usize> {
    /// A ball (disc in 2D) of radius `radius`.
    Ball {
        /// The radius `r`.
        radius: f64,
    },
    /// An axis-aligned ellipsoid (ellipse in 2D) with the given semi-axes.
    Ellipsoid {
        /// The semi-axes `A_k` along the coordinate axes.
        semi_axes: [f64; N],
    },
    /// An axis-aligned box (rectangle in 2D) `[−L_1, L_1] × …`.
    Box {
        /// The half-sides `L_k`.
        half_sides: [f64; N],
    },
    /// A periodic cell: space tiled by the lattice `{H n : n ∈ Zᴺ}`, nothing to contain.
    Periodic {
        /// The cell matrix `H`, upper triangular with a positive diagonal; its columns are the
        /// lattice vectors (see [`crate::periodic`]).
        cell: [[f64; N]; N],
    },
}

/// The shape of a container (ball, ellipsoid, box), without its dimensions: [`Container`] is a
/// shape with its dimensions.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ContainerShape {
    /// A ball: one dimension, the radius.
    Ball,
    /// An axis-aligned ellipsoid: `N` dimensions, the semi-axes.
    Ellipsoid,
    /// An axis-aligned box: `N` dimensions, the half-sides.
    Box,
    /// A periodic cell: `N (N + 1) / 2` dimensions, the entries of the upper-triangular cell
    /// matrix in the order `[l_x, l_y, (l_z,) xy, (xz, yz)]` ([`crate::periodic`]).
    Periodic,
}

impl ContainerShape {
    /// The number of container variables in dimension `n`.
    pub fn dimension_count(self, n: usize) -> usize {
        match self {
            ContainerShape::Ball => 1,
            ContainerShape::Periodic => n * (n + 1) / 2,
            _ => n,
        }
    }
}

impl<const N: usize> Container<N> {
    /// A container of the given kind from its variables (`[r]` or `N` semi-axes / half-sides).
    pub fn from_dimensions(kind: ContainerShape, dims: &[f64]) -> Result<Self, Error> {
        let expected = kind.dimension_count(N);
        Error::check_length("container dimensions", expected, dims.len())?;
        if kind == ContainerShape::Periodic {
            return Ok(Container::Periodic {
                cell: crate::periodic::cell_from_dimensions(dims)?,
            });
        }
        for (dimension, &value) in dims.iter().enumerate() {
            if !(value.is_finite() && value > 0.0) {
                return Err(Error::InvalidContainer { dimension, value });
            }
        }
        let mut a = [0.0; N];
        if kind != ContainerShape::Ball {
            a.copy_from_slice(dims);
        }
        Ok(match kind {
            ContainerShape::Ball => Container::Ball { radius: dims[0] },
            ContainerShape::Ellipsoid => Container::Ellipsoid { semi_axes: a },
            ContainerShape::Box | ContainerShape::Periodic => Container::Box { half_sides: a },
        })
    }

    /// The kind of this container.
    pub fn kind(&self) -> ContainerShape {
        match self {
            Container::Ball { .. } => ContainerShape::Ball,
            Container::Ellipsoid { .. } => ContainerShape::Ellipsoid,
            Container::Box { .. } => ContainerShape::Box,
            Container::Periodic { .. } => ContainerShape::Periodic,
        }
    }

    /// The container's variables, the inverse of [`Container::from_dimensions`] (`N (N + 1) / 2`
    /// entries are written for a periodic cell, `N` for the others, of which a ball uses one).
    pub fn dimensions(&self) -> Vec<f64> {
        match *self {
            Container::Ball { radius } => vec![radius],
            Container::Ellipsoid { semi_axes: a } | Container::Box { half_sides: a } => a.to_vec(),
            Container::Periodic { cell } => crate::periodic::cell_dimensions(&cell),
        }
    }

    /// Area (2D) or volume (3D) of the container, and its derivative with respect to each
    /// container variable (only the first is used for a ball).
    ///
    /// Ball: `π r²`, `4π r³/3`; ellipsoid: `π A₁A₂`, `4π A₁A₂A₃/3`; box: `Π 2 L_k`; periodic
    /// cell: `det H = Π H_kk`, whose derivatives with respect to the tilts (the variables after
    /// the first `N`) are zero.
    pub fn measure(&self) -> (f64, [f64; N]) {
        let mut grad = [0.0; N];
        let unit = unit_ball_measure::<N>();
        match *self {
            Container::Periodic { cell } => {
                let d: [f64; N] = std::array::from_fn(|k| cell[k][k]);
                product_and_partials(1.0, &d)
            }
            Container::Ball { radius } => {
                let v = unit * radius.powi(N as i32);
                grad[0] = N as f64 * v / radius;
                (v, grad)
            }
            Container::Ellipsoid { semi_axes: a } | Container::Box { half_sides: a } => {
                let factor = if matches!(self, Container::Box { .. }) {
                    2f64.powi(N as i32)
                } else {
                    unit
                };
                product_and_partials(factor, &a)
            }
        }
    }
}

/// `factor · Π a_k` and its partial derivatives.
fn product_and_partials<const N: usize>(factor: f64, a: &[f64; N]) -> (f64, [f64; N]) {
    let grad =
        std::array::from_fn(|k| factor * (0..N).filter(|&m| m != k).map(|m| a[m]).product::<f64>());
    (factor * a.iter().product::<f64>(), grad)
}

/// Area of the unit disc (2D) or volume of the unit ball (3D).
fn unit_ball_measure<const N: usize>() -> f64 {
    if N == 2 {
        std::f64::consts::PI
    } else {
        4.0 * std::f64::consts::PI / 3.0
    }
}

impl<const N: usize> Container<N> {
    /// Hessian of [`Container::measure`] with respect to the container variables (only the
    /// `[0][0]` entry for a ball: `N (N − 1) · unit · r^(N−2)`; for a periodic cell the block of
    /// the diagonal entries, the tilts having none).
    pub fn measure_hessian(&self) -> [[f64; N]; N] {
        let mut h = [[0.0; N]; N];
        let unit = unit_ball_measure::<N>();
        let (factor, a) = match *self {
            Container::Ball { radius } => {
                h[0][0] = (N * (N - 1)) as f64 * unit * radius.powi(N as i32 - 2);
                return h;
            }
            Container::Ellipsoid { semi_axes } => (unit, semi_axes),
            Container::Box { half_sides } => (2f64.powi(N as i32), half_sides),
            Container::Periodic { cell } => (1.0, std::array::from_fn(|k| cell[k][k])),
        };
        for r in 0..N {
            for c in 0..N {
                if r != c {
                    h[r][c] = factor
                        * (0..N)
                            .filter(|&m| m != r && m != c)
                            .map(|m| a[m])
                            .product::<f64>();
                }
            }
        }
        h
    }
}

/// Derivative of a containment residual with respect to one ellipsoid and the container.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContainmentGradient<const N: usize> {
    /// With respect to the centre.
    pub centre: [f64; N],
    /// Torque: the derivative with respect to an angle `α` is `ω_α · torque`.
    pub torque: [f64; 3],
    /// With respect to the container variables (only `[0]` for a ball).
    pub container: [f64; N],
}

/// The farthest point of `E` in the metric of an ellipsoidal container `C = diag(a)`:
/// `h = max_{p ∈ E} |C⁻¹ p|²` and the maximiser `p*` (world frame).
pub fn farthest_point<const N: usize>(body: &Body<N>, a: &[f64; N]) -> (f64, [f64; N]) {
    let q = body.rotation();
    let l = body.semi_axes();
    let c = body.centre();
    // G = C⁻¹ Q P^½ is graded like the pair factor: the same accurate SVD applies.
    let mut g = [[0.0; N]; N];
    let mut c_scaled = [0.0; N];
    for r in 0..N {
        c_scaled[r] = c[r] / a[r];
        for k in 0..N {
            g[r][k] = q[r][k] * l[k] / a[r];
        }
    }
    let mut c_body = mat_t_vec(&q, &c);
    for k in 0..N {
        c_body[k] /= l[k];
    }
    // With (c, b) = (G⁻¹ C⁻¹ c, C⁻¹ c), the SVD's `g` are the left-basis coordinates ĉ.
    let svd = graded_svd(&g, &c_body, &c_scaled);
    let chat = svd.g;
    let sigma = svd.sigma;
    let mut top = 0;
    for k in 1..N {
        if sigma[k] > sigma[top] {
            top = k;
        }
    }
    let s_top = sigma[top] * sigma[top];
    let mut a2 = [0.0; N];
    let mut delta = [0.0; N];
    let mut is_top = [false; N];
    let mut a2_top = 0.0;
    let mut a2_all = 0.0;
    for k in 0..N {
        a2[k] = sigma[k] * sigma[k] * chat[k] * chat[k];
        a2_all += a2[k];
        let d = s_top - sigma[k] * sigma[k];
        if d <= 8.0 * f64::EPSILON * s_top {
            is_top[k] = true;
            a2_top += a2[k];
        } else {
            delta[k] = d;
        }
    }
    let phi = |tau: f64| {
        let mut p = 0.0;
        let mut dp = 0.0;
        // A term with no weight is absent from the secular equation: skipped, it cannot
        // give 0/0 when τ reaches 0 (the centre orthogonal to the top axis, off the hard case).
        for k in (0..N).filter(|&k| a2[k] != 0.0) {
            let t = tau + delta[k];
            let v = a2[k] / (t * t);
            p += v;
            dp -= 2.0 * v / t;
        }
        (p, dp)
    };
    let mut hard = false;
    let tau = if a2_top == 0.0 && {
        let rest: f64 = (0..N)
            .filter(|&k| !is_top[k])
            .map(|k| a2[k] / (delta[k] * delta[k]))
            .sum();
        rest <= 1.0
    } {
        hard = true;
        0.0
    } else {
        let lo = a2_top.sqrt();
        let hi = a2_all.sqrt();
        if lo >= hi {
            lo
        } else {
            newton(phi, lo, hi, if lo > 0.0 { lo } else { 0.5 * hi })
        }
    };
    let mu = tau + s_top;
    let mut uhat = [0.0; N];
    let mut phat = [0.0; N];
    let mut used = 0.0;
    for k in 0..N {
        if hard && is_top[k] {
            continue;
        }
        let t = tau + delta[k];
        uhat[k] = sigma[k] * chat[k] / t;
        phat[k] = chat[k] * mu / t;
        used += uhat[k] * uhat[k];
    }
    if hard {
        let u = (1.0 - used).max(0.0).sqrt();
        uhat[top] = u;
        phat[top] = sigma[top] * u;
    }
    let h: f64 = phat.iter().map(|p| p * p).sum();
    // p* = c + Q P^½ V û.
    let mut u_body = [0.0; N];
    for k in 0..N {
        for m in 0..N {
            u_body[m] += svd.v[k][m] * uhat[k];
        }
    }
    let mut p = c;
    for r in 0..N {
        for m in 0..N {
            p[r] += q[r][m] * l[m] * u_body[m];
        }
    }
    (h, p)
}

fn container_axes<const N: usize>(container: &Container<N>) -> [f64; N] {
    match *container {
        Container::Ball { radius } => [radius; N],
        Container::Ellipsoid { semi_axes } => semi_axes,
        Container::Box { half_sides } => half_sides,
        // Never asked: a periodic cell contains everything.
        Container::Periodic { .. } => [f64::INFINITY; N],
    }
}

/// The containment residual `Σ max{0, g}²` of one ellipsoid (zero iff it is inside).
pub fn containment_residual<const N: usize>(body: &Body<N>, container: &Container<N>) -> f64 {
    containment_impl(body, container, false).0
}

/// The containment residual and its gradient.
pub fn containment_gradient<const N: usize>(
    body: &Body<N>,
    container: &Container<N>,
) -> (f64, ContainmentGradient<N>) {
    containment_impl(body, container, true)
}

fn containment_impl<const N: usize>(
    body: &Body<N>,
    container: &Container<N>,
    want_grad: bool,
) -> (f64, ContainmentGradient<N>) {
    let mut grad = ContainmentGradient {
        centre: [0.0; N],
        torque: [0.0; 3],
        container: [0.0; N],
    };
    let c = body.centre();
    match *container {
        Container::Periodic { .. } => (0.0, grad),
        Container::Box { half_sides } => {
            // Cheap exact exclusion: the enclosing ball is inside the box. The computed
            // support `s_k` exceeds the largest semi-axis by a few ulps at most (the rows of Q
            // are unit to rounding), far below the margin, so every `g` below would be ≤ 0:
            // the result is the same, bit for bit. Most ellipsoids of a packing are here.
            let r = body.bounding_radius() * (1.0 + 1e-12);
            if (0..N).all(|k| c[k].abs() + r <= half_sides[k] * (1.0 - 1e-12)) {
                return (0.0, grad);
            }
            let q = body.rotation();
            let l = body.semi_axes();
            let mut value = 0.0;
            for k in 0..N {
                // M e_k and M_kk = Σ_m Q_km² l_m².
                let mut m = [0.0; N];
                for r in 0..N {
                    for s in 0..N {
                        m[r] += q[r][s] * l[s] * l[s] * q[k][s];
                    }
                }
                let support = m[k].sqrt();
                for sign in [1.0, -1.0] {
                    let g = (sign * c[k] + support) / half_sides[k] - 1.0;
                    if g <= 0.0 {
                        continue;
                    }
                    value += g * g;
                    if want_grad {
                        let w = 2.0 * g / half_sides[k];
                        grad.centre[k] += w * sign;
                        let mut e = [0.0; N];
                        e[k] = 1.0;
                        let t = torque(&m, &e);
                        for a in 0..3 {
                            grad.torque[a] += w * t[a] / support;
                        }
                        grad.container[k] -= w * (g + 1.0);
                    }
                }
            }
            (value, grad)
        }
        Container::Ball { .. } | Container::Ellipsoid { .. } => {
            let a = container_axes(container);
            if let Container::Ball { radius } = *container {
                // Cheap exact exclusion: the enclosing ball of the body is inside.
                let cn = c.iter().map(|x| x * x).sum::<f64>().sqrt();
                if cn + body.bounding_radius() <= radius {
                    return (0.0, grad);
                }
            }
            let (h, p) = farthest_point(body, &a);
            let g = h - 1.0;
            if g <= 0.0 {
                return (0.0, grad);
            }
            if want_grad {
                let w = 2.0 * g;
                let mut cq = [0.0; N];
                let mut lever = [0.0; N];
                for k in 0..N {
                    cq[k] = p[k] / (a[k] * a[k]);
                    lever[k] = p[k] - c[k];
                    grad.centre[k] = w * 2.0 * cq[k];
                }
                let t = torque(&lever, &cq);
                for k in 0..3 {
                    grad.torque[k] = w * 2.0 * t[k];
                }
                for k in 0..N {
                    let qk = p[k] / a[k];
                    let d = -2.0 * qk * qk / a[k];
                    if matches!(container, Container::Ball { .. }) {
                        grad.container[0] += w * d;
                    } else {
                        grad.container[k] = w * d;
                    }
                }
            }
            (g * g, grad)
        }
    }
}

/// A direction for the second derivatives of containment: centre velocity, world angular
/// velocity (`dQ = [w]× Q`; 2D: only `w[2]`), container variables (only `[0]` for a ball).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContainmentDirection<const N: usize> {
    /// `δc`.
    pub centre: [f64; N],
    /// Angular velocity.
    pub spin: [f64; 3],
    /// `δ` of the container variables.
    pub container: [f64; N],
}

/// The containment residual, its gradient, and the derivative of the gradient along `dir`
/// (a Hessian–vector product in force/torque form). `None` in the hard case of the farthest
/// point (the ellipsoid centred on the container's centre with a degenerate top direction),
/// where the Hessian does not exist.
///
/// * Box: `g = (±c_k + s_k)/L_k − 1`, `s_k = sqrt(M_kk)`: `δs_k = w·(M e_k × e_k)/s_k`,
///   `δ(M e_k) = w × M e_k − M (w × e_k)`, and the product rule on `∇g`.
/// * Ball and ellipsoid: the farthest point moves with the maximiser `u*` of
///   `|C⁻¹(c + Q P^½ u)|²` on the unit sphere; with `B = P^½ Qᵀ C⁻² Q P^½` and its multiplier
///   `μ` (`(B − μ I) u* = −P^½ Qᵀ C⁻² c`), `δu*` solves
///   `[B − μI, −u*; u*ᵀ, 0] [δu; δμ] = [−r; 0]`,
///   `r = P^½ Qᵀ [−w × C⁻² p* + δ(C⁻²) p* + C⁻² (w × (p* − c) + δc)]`, and
///   `δp* = δc + w × (p* − c) + Q P^½ δu*`.
///
/// For a residual `ρ = max{0, g}²`: `δ∇ρ = 2 δg ∇g + 2 g δ∇g`.
pub fn containment_gradient_derivative<const N: usize>(
    body: &Body<N>,
    container: &Container<N>,
    dir: &ContainmentDirection<N>,
) -> Option<(f64, ContainmentGradient<N>, ContainmentGradient<N>)> {
    let zero = ContainmentGradient {
        centre: [0.0; N],
        torque: [0.0; 3],
        container: [0.0; N],
    };
    let (value, grad) = containment_gradient(body, container);
    let mut hv = zero;
    if value == 0.0 {
        return Some((0.0, grad, hv));
    }
    let c = body.centre();
    let q = body.rotation();
    let l = body.semi_axes();
    let w = &dir.spin;
    match *container {
        Container::Box { half_sides } => {
            let mm = body.shape_matrix();
            for k in 0..N {
                let mut m = [0.0; N];
                for r in 0..N {
                    m[r] = mm[r][k];
                }
                let s = m[k].sqrt();
                let lk = half_sides[k];
                let dl = dir.container[k];
                let mut e = [0.0; N];
                e[k] = 1.0;
                let mxe = torque(&m, &e);
                let ds = (0..3).map(|a| w[a] * mxe[a]).sum::<f64>() / s;
                // δ(M e_k) = w × m − M (w × e_k).
                let we = spin(w, &e);
                let mut dm = spin(w, &m);
                for r in 0..N {
                    for cc in 0..N {
                        dm[r] -= mm[r][cc] * we[cc];
                    }
                }
                let dmxe = torque(&dm, &e);
                for sign in [1.0, -1.0] {
                    let g = (sign * c[k] + s) / lk - 1.0;
                    if g <= 0.0 {
                        continue;
                    }
                    // ∇g and its derivative.
                    let t: [f64; 3] = std::array::from_fn(|a| mxe[a] / (s * lk));
                    let dg = sign * dir.centre[k] / lk + (0..3).map(|a| t[a] * w[a]).sum::<f64>()
                        - (g + 1.0) * dl / lk;
                    let dt: [f64; 3] =
                        std::array::from_fn(|a| dmxe[a] / (s * lk) - t[a] * (ds / s + dl / lk));
                    let gc = sign / lk;
                    let dgc = -sign * dl / (lk * lk);
                    let gl = -(g + 1.0) / lk;
                    let dgl = -dg / lk + (g + 1.0) * dl / (lk * lk);
                    hv.centre[k] += 2.0 * (dg * gc + g * dgc);
                    for a in 0..3 {
                        hv.torque[a] += 2.0 * (dg * t[a] + g * dt[a]);
                    }
                    hv.container[k] += 2.0 * (dg * gl + g * dgl);
                }
            }
            Some((value, grad, hv))
        }
        // The residual is zero in a periodic cell, returned above.
        Container::Periodic { .. } => Some((value, grad, hv)),
        Container::Ball { .. } | Container::Ellipsoid { .. } => {
            let is_ball = matches!(container, Container::Ball { .. });
            let a = container_axes(container);
            let mut da = [0.0; N];
            for k in 0..N {
                da[k] = if is_ball {
                    dir.container[0]
                } else {
                    dir.container[k]
                };
            }
            let (h, p) = farthest_point(body, &a);
            let g = h - 1.0;
            let mut e = [0.0; N];
            let mut aa = [0.0; N];
            let mut cinv2 = [0.0; N];
            let mut dcinv2 = [0.0; N];
            for k in 0..N {
                e[k] = p[k] - c[k];
                cinv2[k] = 1.0 / (a[k] * a[k]);
                aa[k] = p[k] * cinv2[k];
                dcinv2[k] = -2.0 * da[k] / (a[k] * a[k] * a[k]);
            }
            // u* (body frame), B, k and μ.
            let mut u = [0.0; N];
            let mut kv = [0.0; N];
            let mut b = [[0.0; N]; N];
            for s in 0..N {
                u[s] = (0..N).map(|r| q[r][s] * e[r]).sum::<f64>() / l[s];
                kv[s] = l[s] * (0..N).map(|r| q[r][s] * cinv2[r] * c[r]).sum::<f64>();
                for t in 0..N {
                    b[s][t] =
                        l[s] * l[t] * (0..N).map(|r| q[r][s] * cinv2[r] * q[r][t]).sum::<f64>();
                }
            }
            let mu: f64 = (0..N)
                .map(|s| u[s] * ((0..N).map(|t| b[s][t] * u[t]).sum::<f64>() + kv[s]))
                .sum();
            // r = P^½ Qᵀ [−w × aa + δ(C⁻²) p + C⁻² (w × e + δc)].
            let wa = spin(w, &aa);
            let we = spin(w, &e);
            let mut world = [0.0; N];
            for k in 0..N {
                world[k] = -wa[k] + dcinv2[k] * p[k] + cinv2[k] * (we[k] + dir.centre[k]);
            }
            let mut rhs = [0.0; 4];
            let mut mat = [[0.0; 4]; 4];
            for s in 0..N {
                rhs[s] = -l[s] * (0..N).map(|r| q[r][s] * world[r]).sum::<f64>();
                for t in 0..N {
                    mat[s][t] = b[s][t] - if s == t { mu } else { 0.0 };
                }
                mat[s][N] = -u[s];
                mat[N][s] = u[s];
            }
            let sol = crate::linalg::solve_small(&mut mat, &mut rhs, N + 1)?;
            let mut du = [0.0; N];
            du.copy_from_slice(&sol[..N]);
            let mut dp = [0.0; N];
            for r in 0..N {
                dp[r] = dir.centre[r] + we[r] + (0..N).map(|s| q[r][s] * l[s] * du[s]).sum::<f64>();
            }
            let mut daa = [0.0; N];
            for k in 0..N {
                daa[k] = dcinv2[k] * p[k] + cinv2[k] * dp[k];
            }
            // ∇h and δ∇h.
            let gh_t = torque(&e, &aa);
            let mut gh_a = [0.0; N];
            let mut dgh_a = [0.0; N];
            for k in 0..N {
                let a3 = a[k] * a[k] * a[k];
                gh_a[k] = -2.0 * p[k] * p[k] / a3;
                dgh_a[k] =
                    -2.0 * (2.0 * p[k] * dp[k] / a3 - 3.0 * p[k] * p[k] * da[k] / (a3 * a[k]));
            }
            let dh = (0..N)
                .map(|k| 2.0 * aa[k] * dir.centre[k] + gh_a[k] * da[k])
                .sum::<f64>()
                + (0..3).map(|s| 2.0 * gh_t[s] * w[s]).sum::<f64>();
            let dlever = sub_n(&dp, &dir.centre);
            let dt = add3(&torque(&dlever, &aa), &torque(&e, &daa));
            for k in 0..N {
                hv.centre[k] = 2.0 * (dh * 2.0 * aa[k] + g * 2.0 * daa[k]);
            }
            for s in 0..3 {
                hv.torque[s] = 2.0 * (dh * 2.0 * gh_t[s] + g * 2.0 * dt[s]);
            }
            for k in 0..N {
                let v = 2.0 * (dh * gh_a[k] + g * dgh_a[k]);
                if is_ball {
                    hv.container[0] += v;
                } else {
                    hv.container[k] = v;
                }
            }
            Some((value, grad, hv))
        }
    }
}

fn sub_n<const N: usize>(a: &[f64; N], b: &[f64; N]) -> [f64; N] {
    std::array::from_fn(|k| a[k] - b[k])
}

fn add3(a: &[f64; 3], b: &[f64; 3]) -> [f64; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}
