//! Active-set projected limited-memory BFGS (projected L-BFGS) for min F(x) on a box.
//!
//! Iteration k:
//!
//! 1. ε-active set (Bertsekas): with ε = min(ε̄, ‖P(x − ∇F) − x‖∞), variable i is *active* if
//!    xᵢ ≤ lᵢ + ε and ∂ᵢF > 0, or xᵢ ≥ uᵢ − ε and ∂ᵢF < 0. The others are *free* (set F).
//! 2. Direction: d_F = −H_F ∇_F F, d_A = (nearest bound) − x_A, where H_F is the L-BFGS inverse-Hessian
//!    approximation built from the last m pairs (s, y) restricted to the free variables (the
//!    two-loop recursion with inner products over F, pairs with s_Fᵀy_F ≤ 0 skipped) and
//!    H⁰ = (s_Fᵀy_F / y_Fᵀy_F) I. Free variables sitting on a bound with dᵢ pointing outward get
//!    dᵢ = 0. If ∇Fᵀd ≥ 0 the memory is dropped and d = −γ∇_F F.
//! 3. Projected Armijo search on the path x(α) = P(x + α d), α = 1, ½-ish (safeguarded
//!    quadratic interpolation):  F(x(α)) ≤ F(x) + 10⁻⁴ ∇Fᵀ(x(α) − x),  with ∇Fᵀ(x(α) − x) < 0.
//!    If it fails with a quasi-Newton direction, the memory is dropped and the iteration retried
//!    as a scaled projected-gradient step.
//! 4. The pair (s, y) is stored in a ring of m n-vectors when sᵀy > ε_mach yᵀy.
//!
//! Keeping the bound-active variables fixed lets the quasi-Newton model act on the face where
//! the iterate lives, so the method converges superlinearly-ish once the active set settles,
//! while the projected search lets many bounds change in one step. Memory: (2m + 5) n-vectors;
//! no n×n matrix is formed.
//!
//! # References
//! - D. P. Bertsekas, "Projected Newton methods for optimization problems with simple
//!   constraints", SIAM J. Control Optim. 20(2), 221–246, 1982.
//! - D. Kim, S. Sra, I. S. Dhillon, "Tackling box-constrained optimization via a new projected
//!   quasi-Newton approach", SIAM J. Sci. Comput. 32(6), 3548–3563, 2010.
//! - J. Nocedal, "Updating quasi-Newton matrices with limited storage", Math. Comp. 35,
//!   773–782, 1980 (two-loop recursion); D. C. Liu, J. Nocedal, "On the limited memory BFGS
//!   method for large scale optimization", Math. Program. 45, 503–528, 1989.
//! - R. H. Byrd, P. Lu, J. Nocedal, C. Zhu, "A limited memory algorithm for bound constrained
//!   optimization", SIAM J. Sci. Comput. 16(5), 1190–1208, 1995 (L-BFGS-B, the method this one
//!   simplifies: no generalized Cauchy point, the active set comes from the ε-rule instead).

use crate::inner::{Acceptance, InnerStatus, Iterate, Method, Smooth, line_search};
use crate::projection::{axpy_dot, dot, for_each_entry, map_blocks, norm_inf};

/// Upper limit ε̄ of the ε-active-set rule.
const ACTIVE_EPSILON: f64 = 1e-3;

/// With at most one active variable in this many, the two-loop recursion runs unmasked over
/// all variables and corrects its inner products at the active ones; with more, it masks
/// every pass. A fixed container (compression's placements) keeps one or two variables active
/// at every iteration, which would otherwise cost a masked pass per pair.
const SPARSE_ACTIVE: usize = 16;

/// Buffers of the projected L-BFGS method, allocated once and reused by every inner solve.
#[derive(Debug, Clone)]
pub(crate) struct LbfgsWorkspace {
    n: usize,
    memory: usize,
    /// m pairs, pair j at `s[j*n..(j+1)*n]`; `newest` is the slot of the last stored pair.
    s: Vec<f64>,
    y: Vec<f64>,
    stored: usize,
    newest: usize,
    /// Per-pair scratch for the two-loop recursion: 1/(s_Fᵀy_F) (the masked loops write 0 for
    /// a skipped pair) and αⱼ.
    rho: Vec<f64>,
    alpha: Vec<f64>,
    /// Full-space sᵀy and yᵀy of each stored pair, reused whenever no variable is active.
    pair_sy: Vec<f64>,
    pair_yy: Vec<f64>,
    /// 1.0 on free variables, 0.0 on active ones.
    free: Vec<f64>,
    all_free: bool,
    /// The active variables' indices, when there are few (see [`SPARSE_ACTIVE`]).
    active: Vec<usize>,
    /// The slots of the pairs with positive curvature on the free variables, newest first.
    usable: Vec<usize>,
    direction: Vec<f64>,
    x_trial: Vec<f64>,
    g_trial: Vec<f64>,
}

impl LbfgsWorkspace {
    /// `memory` = m, the number of stored pairs (≥ 1).
    pub(crate) fn new(n: usize, memory: usize) -> Self {
        let memory = memory.max(1);
        Self {
            n,
            memory,
            s: vec![0.0; memory * n],
            y: vec![0.0; memory * n],
            stored: 0,
            newest: 0,
            rho: vec![0.0; memory],
            alpha: vec![0.0; memory],
            pair_sy: vec![0.0; memory],
            pair_yy: vec![0.0; memory],
            free: vec![1.0; n],
            all_free: true,
            active: Vec::new(),
            usable: Vec::with_capacity(memory),
            direction: vec![0.0; n],
            x_trial: vec![0.0; n],
            g_trial: vec![0.0; n],
        }
    }

    /// Forgets every pair.
    pub(crate) fn reset(&mut self) {
        self.stored = 0;
    }

    /// Slot of the j-th newest pair (j = 0 newest).
    fn slot(&self, j: usize) -> usize {
        (self.newest + self.memory - j) % self.memory
    }

    /// The slot the next pair is written to.
    fn next_slot(&self) -> usize {
        if self.stored == 0 {
            0
        } else {
            (self.newest + 1) % self.memory
        }
    }

    /// Stores s = x_trial − x, y = g_trial − g if the curvature condition holds.
    fn push_pair(&mut self, x: &[f64], g: &[f64]) {
        let n = self.n;
        let slot = self.next_slot();
        let difference = |to: &mut [f64], a: &[f64], b: &[f64]| {
            map_blocks(to, |start, to| {
                for (k, t) in to.iter_mut().enumerate() {
                    *t = a[start + k] - b[start + k];
                }
            });
        };
        difference(&mut self.s[slot * n..(slot + 1) * n], &self.x_trial, x);
        difference(&mut self.y[slot * n..(slot + 1) * n], &self.g_trial, g);
        self.keep_if_curved(slot);
    }

    /// Stores the pair (s, y) if the curvature condition holds.
    pub(crate) fn store(&mut self, s: &[f64], y: &[f64]) {
        let n = self.n;
        let slot = self.next_slot();
        self.s[slot * n..(slot + 1) * n].copy_from_slice(s);
        self.y[slot * n..(slot + 1) * n].copy_from_slice(y);
        self.keep_if_curved(slot);
    }

    /// Number of pairs stored.
    pub(crate) fn stored(&self) -> usize {
        self.stored
    }

    /// Sets the free variables of the next [`apply`](Self::apply)s (1.0 free, 0.0 active).
    pub(crate) fn set_free(&mut self, free: &[f64], all_free: bool) {
        self.free.copy_from_slice(free);
        self.all_free = all_free;
        self.list_active();
    }

    /// Lists the active variables when there are few of them (none when all are free, or
    /// when too many are active for the unmasked recursion).
    fn list_active(&mut self) {
        self.active.clear();
        if self.all_free {
            return;
        }
        let limit = self.n / SPARSE_ACTIVE;
        for (i, &f) in self.free.iter().enumerate() {
            if f == 0.0 {
                if self.active.len() == limit {
                    self.active.clear();
                    return;
                }
                self.active.push(i);
            }
        }
    }

    /// `z = H_F r`, the inverse-Hessian approximation over the free variables applied to `r`
    /// (zero off F): the two-loop recursion. Returns false, with `z = r`, when no stored pair
    /// is usable.
    pub(crate) fn apply(&mut self, r: &[f64], z: &mut [f64]) -> bool {
        if self.stored == 0 || !self.two_loop(r) {
            z.copy_from_slice(r);
            return false;
        }
        for (zi, &d) in z.iter_mut().zip(&self.direction) {
            *zi = -d;
        }
        true
    }

    /// Makes the pair just written to `slot` the newest if it has positive curvature,
    /// `sᵀy > ε_mach yᵀy`.
    fn keep_if_curved(&mut self, slot: usize) {
        let n = self.n;
        let (s, y) = (
            &self.s[slot * n..(slot + 1) * n],
            &self.y[slot * n..(slot + 1) * n],
        );
        let (sy, yy) = (dot(s, y), dot(y, y));
        // A pair without positive curvature would make H indefinite; it is dropped.
        if sy > f64::EPSILON * yy && sy > 0.0 {
            self.pair_sy[slot] = sy;
            self.pair_yy[slot] = yy;
            self.newest = slot;
            self.stored = (self.stored + 1).min(self.memory);
        } else if self.stored == self.memory {
            // The rejected pair overwrote the oldest one, which is therefore gone.
            self.stored -= 1;
        }
    }

    /// Marks the ε-active variables (see the module docs).
    fn mark_free(&mut self, x: &[f64], g: &[f64], lower: &[f64], upper: &[f64], pg: f64) {
        self.all_free = mark_free(&mut self.free, (x, g), (lower, upper), pg);
        self.list_active();
    }

    /// d = −H_F g_F by the two-loop recursion over the free variables. Returns false when no
    /// stored pair was usable (then d = −γ g_F with the fallback scaling).
    fn two_loop(&mut self, g: &[f64]) -> bool {
        if self.all_free || !self.active.is_empty() {
            self.two_loop_unmasked(g)
        } else {
            self.two_loop_masked(g)
        }
    }

    /// [`two_loop`](Self::two_loop) with every variable free, or few active: the passes run
    /// over all variables, fused in pairs ([`simd::axpy_dot`]: each update of q with the next
    /// pair's inner product), and q and the inner products are corrected at the active
    /// variables only.
    fn two_loop_unmasked(&mut self, g: &[f64]) -> bool {
        let n = self.n;
        self.usable.clear();
        let mut gamma = None;
        for j in 0..self.stored {
            let slot = self.slot(j);
            let Some((sy, yy)) = self.curvature_on_free(slot) else {
                continue;
            };
            gamma.get_or_insert(sy / yy);
            self.rho[slot] = 1.0 / sy;
            self.usable.push(slot);
        }
        let Self {
            s,
            y,
            direction: q,
            active,
            usable,
            rho,
            alpha,
            ..
        } = self;
        let s_of = |slot: usize| &s[slot * n..(slot + 1) * n];
        let y_of = |slot: usize| &y[slot * n..(slot + 1) * n];
        q.copy_from_slice(g);
        zero_at(q, active);
        // First loop, newest to oldest: αⱼ = ρⱼ sⱼᵀq, q ← q − αⱼ yⱼ.
        // The last update's fused product is y_oldestᵀq, which the second loop starts from.
        let mut y_oldest_q = 0.0;
        if let Some(&first) = usable.first() {
            let mut sq = dot(s_of(first), q);
            for k in 0..usable.len() {
                let slot = usable[k];
                let a = rho[slot] * sq;
                alpha[slot] = a;
                let next = usable.get(k + 1).map_or(y_of(slot), |&next| s_of(next));
                sq = axpy_dot(q, -a, y_of(slot), next);
                sq -= correct_at(q, next, active);
            }
            y_oldest_q = sq;
        }
        let gamma = gamma.unwrap_or_else(|| {
            // Without curvature information, a first step of length at most 1 in sup-norm.
            let gn = norm_inf(q);
            if gn > 1.0 { 1.0 / gn } else { 1.0 }
        });
        for_each_entry(q, |qi| *qi *= gamma);
        // Second loop, oldest to newest: βⱼ = ρⱼ yⱼᵀq, q ← q + (αⱼ − βⱼ) sⱼ.
        if !usable.is_empty() {
            let mut yq = gamma * y_oldest_q;
            for k in (0..usable.len()).rev() {
                let slot = usable[k];
                let c = alpha[slot] - rho[slot] * yq;
                let next = k.checked_sub(1).map_or(s_of(slot), |k| y_of(usable[k]));
                yq = axpy_dot(q, c, s_of(slot), next);
                yq -= correct_at(q, next, active);
            }
        }
        for_each_entry(q, |v| *v = -*v);
        !usable.is_empty()
    }

    /// s_Fᵀy_F and y_Fᵀy_F of the pair in `slot` when it has positive curvature on the free
    /// variables: the full-space products less the terms of the few active variables, or,
    /// when those terms carry half of sᵀy or yᵀy or more (where the difference would lose
    /// digits), summed over the free variables.
    fn curvature_on_free(&self, slot: usize) -> Option<(f64, f64)> {
        let n = self.n;
        let (s, y) = (
            &self.s[slot * n..(slot + 1) * n],
            &self.y[slot * n..(slot + 1) * n],
        );
        let (mut sy, mut yy) = (self.pair_sy[slot], self.pair_yy[slot]);
        let (active_sy, active_yy) = self
            .active
            .iter()
            .fold((0.0, 0.0), |(a, b), &i| (a + s[i] * y[i], b + y[i] * y[i]));
        if active_yy <= 0.5 * yy && active_sy.abs() <= 0.5 * sy.abs() {
            (sy, yy) = (sy - active_sy, yy - active_yy);
        } else {
            (sy, yy) = (0.0, 0.0);
            for ((&si, &yi), &fi) in s.iter().zip(y).zip(&self.free) {
                sy += si * yi * fi;
                yy += yi * yi * fi;
            }
        }
        (sy > f64::EPSILON * yy && sy > 0.0 && yy > 0.0).then_some((sy, yy))
    }

    /// [`two_loop`](Self::two_loop) with many active variables: every pass masked.
    fn two_loop_masked(&mut self, g: &[f64]) -> bool {
        let n = self.n;
        let q = &mut self.direction;
        for ((qi, &gi), &fi) in q.iter_mut().zip(g).zip(&self.free) {
            *qi = gi * fi;
        }
        let mut gamma = None;
        for j in 0..self.stored {
            let slot = (self.newest + self.memory - j) % self.memory;
            let s = &self.s[slot * n..(slot + 1) * n];
            let y = &self.y[slot * n..(slot + 1) * n];
            let (mut sy, mut yy) = (self.pair_sy[slot], self.pair_yy[slot]);
            if !self.all_free {
                (sy, yy) = (0.0, 0.0);
                for ((&si, &yi), &fi) in s.iter().zip(y).zip(&self.free) {
                    sy += si * yi * fi;
                    yy += yi * yi * fi;
                }
            }
            if sy <= f64::EPSILON * yy || sy <= 0.0 {
                self.rho[slot] = 0.0;
                continue;
            }
            gamma.get_or_insert(sy / yy);
            self.rho[slot] = 1.0 / sy;
            // q is zero off F, so sᵀq needs no mask.
            let a = self.rho[slot] * dot(s, q);
            self.alpha[slot] = a;
            for ((qi, &yi), &fi) in q.iter_mut().zip(y).zip(&self.free) {
                *qi -= a * yi * fi;
            }
        }
        let used = gamma.is_some();
        let gamma = gamma.unwrap_or_else(|| {
            // Without curvature information, a first step of length at most 1 in sup-norm.
            let gn = norm_inf(q);
            if gn > 1.0 { 1.0 / gn } else { 1.0 }
        });
        for_each_entry(q, |qi| *qi *= gamma);
        for j in (0..self.stored).rev() {
            let slot = self.slot(j);
            if self.rho[slot] == 0.0 {
                continue;
            }
            let s = &self.s[slot * n..(slot + 1) * n];
            let y = &self.y[slot * n..(slot + 1) * n];
            let q = &mut self.direction;
            let b = self.rho[slot] * dot(y, q);
            let c = self.alpha[slot] - b;
            for ((qi, &si), &fi) in q.iter_mut().zip(s).zip(&self.free) {
                *qi += c * si * fi;
            }
        }
        for_each_entry(&mut self.direction, |v| *v = -*v);
        used
    }
}

/// Sets `q` to 0 at the `active` indices.
fn zero_at(q: &mut [f64], active: &[usize]) {
    for &i in active {
        q[i] = 0.0;
    }
}

/// Sets `q` to 0 at the `active` indices and returns Σ vᵢ qᵢ over them (before zeroing): what
/// an inner product vᵀq taken before the zeroing must lose.
fn correct_at(q: &mut [f64], v: &[f64], active: &[usize]) -> f64 {
    let mut sum = 0.0;
    for &i in active {
        sum += v[i] * q[i];
        q[i] = 0.0;
    }
    sum
}

/// Marks the ε-active variables of step 1 (module docs) in `free` (1.0 free, 0.0 active);
/// returns whether every variable is free.
pub(crate) fn mark_free(
    free: &mut [f64],
    (x, g): (&[f64], &[f64]),
    (lower, upper): (&[f64], &[f64]),
    pg: f64,
) -> bool {
    let eps = ACTIVE_EPSILON.min(pg);
    let blocks = map_blocks(free, |start, free| {
        let mut all_free = true;
        for (k, fr) in free.iter_mut().enumerate() {
            let (xi, gi, l, u) = (
                x[start + k],
                g[start + k],
                lower[start + k],
                upper[start + k],
            );
            let active = (xi - l <= eps && gi > 0.0) || (u - xi <= eps && gi < 0.0);
            *fr = if active { 0.0 } else { 1.0 };
            all_free &= !active;
        }
        all_free
    });
    blocks.into_iter().all(|b| b)
}

/// Completes a direction on the free variables: each ε-active variable is sent to its bound
/// (dᵢ = lᵢ − xᵢ or uᵢ − xᵢ; Bertsekas moves them by a gradient step instead, but leaving them
/// in place would strand a variable at distance ≤ ε from its bound forever, with
/// ‖P(x − ∇F) − x‖∞ stuck at that distance; each such component has gᵢdᵢ ≤ 0, so descent is
/// kept), and components pointing out of the box from a bound are zeroed (the projection would
/// discard them anyway, and keeping them would spoil the descent test).
pub(crate) fn complete_direction(
    direction: &mut [f64],
    free: &[f64],
    (x, g): (&[f64], &[f64]),
    (lower, upper): (&[f64], &[f64]),
) {
    map_blocks(direction, |start, direction| {
        for (k, d) in direction.iter_mut().enumerate() {
            let i = start + k;
            if free[i] == 0.0 {
                *d = if g[i] > 0.0 {
                    lower[i] - x[i]
                } else {
                    upper[i] - x[i]
                };
            }
            if (x[i] <= lower[i] && *d < 0.0) || (x[i] >= upper[i] && *d > 0.0) {
                *d = 0.0;
            }
        }
    });
}

impl Method for LbfgsWorkspace {
    fn begin(&mut self, _value: f64, _pg: f64) {
        self.reset();
    }

    fn step(&mut self, f: &mut dyn Smooth, at: Iterate<'_>) -> Result<f64, InnerStatus> {
        self.mark_free(at.x, at.grad, at.lower, at.upper, at.projected_gradient);
        step(f, at, self)
    }

    fn accept(&mut self, _k: usize, x: &[f64], grad: &[f64], _value: f64) {
        self.push_pair(x, grad);
    }

    fn trial(&self) -> (&[f64], &[f64]) {
        (&self.x_trial, &self.g_trial)
    }
}

/// One iteration's direction and search; falls back once to a projected-gradient direction.
fn step<S: Smooth + ?Sized>(
    f: &mut S,
    at: Iterate<'_>,
    ws: &mut LbfgsWorkspace,
) -> Result<f64, InnerStatus> {
    let (x, grad, lower, upper) = (at.x, at.grad, at.lower, at.upper);
    let mut quasi_newton = direction(x, grad, lower, upper, ws);
    if dot(grad, &ws.direction) >= 0.0 {
        ws.reset();
        quasi_newton = false;
        direction(x, grad, lower, upper, ws);
    }
    match projected_search(f, at, ws) {
        Err(InnerStatus::Stalled | InnerStatus::NonFinite) if quasi_newton => {
            // A poor quasi-Newton model, not a stationary point: retry along the gradient.
            ws.reset();
            direction(x, grad, lower, upper, ws);
            projected_search(f, at, ws)
        }
        other => other,
    }
}

/// Fills `ws.direction` (step 2 of the module docs); returns whether stored pairs were used.
fn direction(
    x: &[f64],
    grad: &[f64],
    lower: &[f64],
    upper: &[f64],
    ws: &mut LbfgsWorkspace,
) -> bool {
    let quasi_newton = ws.two_loop(grad);
    complete_direction(&mut ws.direction, &ws.free, (x, grad), (lower, upper));
    quasi_newton
}

/// Armijo backtracking on the projected path x(α) = P(x + α d).
fn projected_search<S: Smooth + ?Sized>(
    f: &mut S,
    at: Iterate<'_>,
    ws: &mut LbfgsWorkspace,
) -> Result<f64, InnerStatus> {
    let slope = dot(at.grad, &ws.direction);
    if slope >= 0.0 {
        return Err(InnerStatus::Stalled);
    }
    let trial = (&mut ws.x_trial[..], &mut ws.g_trial[..]);
    line_search(
        f,
        at,
        (&ws.direction, slope),
        Acceptance::ProjectedPath,
        trial,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Stores the pair (s, y) through the public path: x_trial − x and g_trial − g.
    fn push(ws: &mut LbfgsWorkspace, s: &[f64], y: &[f64]) {
        let zeros = vec![0.0; s.len()];
        ws.x_trial.copy_from_slice(s);
        ws.g_trial.copy_from_slice(y);
        ws.push_pair(&zeros, &zeros);
    }

    /// For H = diag(h) and the coordinate pairs (eᵢ, h eᵢ), the two-loop recursion reproduces
    /// H⁻¹ exactly, so d = −H⁻¹g; with variable 1 masked out, d restricted to the others.
    #[test]
    fn two_loop_inverts_a_diagonal_hessian_from_coordinate_pairs() {
        let h = [1.0, 4.0, 9.0];
        let mut ws = LbfgsWorkspace::new(3, 3);
        for i in 0..3 {
            let mut s = [0.0; 3];
            let mut y = [0.0; 3];
            s[i] = 1.0;
            y[i] = h[i];
            push(&mut ws, &s, &y);
        }
        assert_eq!(ws.stored, 3);
        let g = [2.0, -8.0, 27.0];
        assert!(ws.two_loop(&g));
        for i in 0..3 {
            assert!(
                (ws.direction[i] + g[i] / h[i]).abs() < 1e-14,
                "{:?}",
                ws.direction
            );
        }
        ws.set_free(&[1.0, 0.0, 1.0], false);
        ws.two_loop(&g);
        assert!((ws.direction[0] + 2.0).abs() < 1e-14);
        assert_eq!(ws.direction[1], 0.0);
        assert!((ws.direction[2] + 3.0).abs() < 1e-14);
    }

    /// With a few active variables, the unmasked recursion (corrected at the active ones)
    /// gives the masked one's direction up to rounding, also when a pair's y lies mostly on
    /// an active variable.
    #[test]
    fn few_active_variables_give_the_masked_direction() {
        let n = 200;
        let mut ws = LbfgsWorkspace::new(n, 5);
        let wave = |k: usize, i: usize| ((k * 31 + i * 7) as f64 * 0.173).sin();
        for k in 0..6 {
            let s: Vec<f64> = (0..n).map(|i| wave(k, i)).collect();
            // y = D s + a little coupling: positive curvature.
            let mut y: Vec<f64> = (0..n)
                .map(|i| (1.0 + (i % 9) as f64) * s[i] + 0.1 * s[(i + 1) % n])
                .collect();
            if k == 4 {
                // This pair's yᵀy lies mostly on active variable 17.
                y[17] = 400.0;
                let mut s = s.clone();
                s[17] = 1.0;
                push(&mut ws, &s, &y);
            } else {
                push(&mut ws, &s, &y);
            }
        }
        let g: Vec<f64> = (0..n).map(|i| wave(9, i) * 3.0).collect();
        let mut free = vec![1.0; n];
        for i in [0, 17, 103] {
            free[i] = 0.0;
        }
        ws.set_free(&free, false);
        assert_eq!(ws.active, [0, 17, 103]);
        let mut masked = ws.clone();
        assert!(ws.two_loop(&g));
        assert!(masked.two_loop_masked(&g));
        let scale = norm_inf(&masked.direction);
        for i in 0..n {
            assert!(
                (ws.direction[i] - masked.direction[i]).abs() <= 1e-12 * scale,
                "{i}: {} against {}",
                ws.direction[i],
                masked.direction[i]
            );
        }
        for i in [0, 17, 103] {
            assert_eq!(ws.direction[i], 0.0);
        }

        // Too many active variables for the correction: the masked loops run.
        let mut free = vec![1.0; n];
        free[..n / SPARSE_ACTIVE + 1].fill(0.0);
        ws.set_free(&free, false);
        assert!(ws.active.is_empty() && !ws.all_free);
    }

    #[test]
    fn ring_keeps_the_newest_pairs_and_drops_a_rejected_one() {
        let mut ws = LbfgsWorkspace::new(2, 2);
        push(&mut ws, &[1.0, 0.0], &[1.0, 0.0]);
        push(&mut ws, &[0.0, 1.0], &[0.0, 2.0]);
        push(&mut ws, &[1.0, 1.0], &[3.0, 3.0]);
        assert_eq!(ws.stored, 2);
        let newest = ws.slot(0);
        assert_eq!(&ws.s[newest * 2..newest * 2 + 2], &[1.0, 1.0]);
        let older = ws.slot(1);
        assert_eq!(&ws.s[older * 2..older * 2 + 2], &[0.0, 1.0]);
        // Negative curvature: rejected, and it overwrote the oldest slot, which is gone.
        push(&mut ws, &[1.0, 0.0], &[-1.0, 0.0]);
        assert_eq!(ws.stored, 1);
        let newest = ws.slot(0);
        assert_eq!(&ws.s[newest * 2..newest * 2 + 2], &[1.0, 1.0]);
    }
}
