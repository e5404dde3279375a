//! Four pairs side by side, lane by lane, for the batched path.
//!
//! [`V4`] holds one `f64` per pair and does every operation lane-wise: written this way, the
//! compiler keeps the four lanes in one 256-bit register where AVX is available (two 128-bit
//! ones otherwise). Each lane performs exactly the operations of the scalar code in the same
//! order, so the batched results equal the scalar ones bit for bit; the lanes only differ in
//! when they stop, and a lane that has stopped keeps its state (selects, not branches).

use crate::arith::Arith;
use crate::poly::RationalForm;
use core::ops::{Add, Div, Mul, Neg, Sub};

/// Number of lanes.
pub(crate) const LANES: usize = 4;

/// One value per lane.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct V4(pub [f64; LANES]);

macro_rules! lanewise {
    ($trait:ident, $method:ident, $op:tt) => {
        impl $trait for V4 {
            type Output = V4;
            #[inline(always)]
            fn $method(self, o: V4) -> V4 {
                V4([
                    self.0[0] $op o.0[0],
                    self.0[1] $op o.0[1],
                    self.0[2] $op o.0[2],
                    self.0[3] $op o.0[3],
                ])
            }
        }
    };
}
lanewise!(Add, add, +);
lanewise!(Sub, sub, -);
lanewise!(Mul, mul, *);
lanewise!(Div, div, /);

impl Neg for V4 {
    type Output = V4;
    #[inline(always)]
    fn neg(self) -> V4 {
        V4(self.0.map(|x| -x))
    }
}

impl Arith for V4 {
    #[inline(always)]
    fn lift(x: f64) -> Self {
        V4([x; LANES])
    }
    #[inline(always)]
    fn to_f64(self) -> f64 {
        self.0[0]
    }
}

/// Magnitudes, one per lane: the `Mag` arithmetic (differences add) on four pairs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct M4(pub [f64; LANES]);

impl Add for M4 {
    type Output = M4;
    #[inline(always)]
    fn add(self, o: M4) -> M4 {
        M4((V4(self.0) + V4(o.0)).0)
    }
}
impl Sub for M4 {
    type Output = M4;
    // Deliberate: the magnitude of a − b is |a| + |b|.
    #[allow(clippy::suspicious_arithmetic_impl)]
    #[inline(always)]
    fn sub(self, o: M4) -> M4 {
        M4((V4(self.0) + V4(o.0)).0)
    }
}
impl Mul for M4 {
    type Output = M4;
    #[inline(always)]
    fn mul(self, o: M4) -> M4 {
        M4((V4(self.0) * V4(o.0)).0)
    }
}
impl Arith for M4 {
    #[inline(always)]
    fn lift(x: f64) -> Self {
        M4([x.abs(); LANES])
    }
    #[inline(always)]
    fn to_f64(self) -> f64 {
        self.0[0]
    }
}

impl V4 {
    #[inline(always)]
    pub(crate) fn splat(x: f64) -> Self {
        V4([x; LANES])
    }
    /// |x| lane-wise, as the magnitude arithmetic's input.
    #[inline(always)]
    pub(crate) fn magnitude(self) -> M4 {
        M4(self.0.map(f64::abs))
    }
    #[inline(always)]
    pub(crate) fn from_fn(f: impl FnMut(usize) -> f64) -> Self {
        V4(core::array::from_fn(f))
    }
}

/// The rational forms of four pairs, coefficient by coefficient.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Forms4 {
    alpha: [V4; 3],
    beta: [V4; 4],
}

impl Forms4 {
    #[inline(always)]
    pub(crate) fn new(forms: &[RationalForm; LANES]) -> Self {
        Self {
            alpha: core::array::from_fn(|i| V4::from_fn(|k| forms[k].alpha[i])),
            beta: core::array::from_fn(|i| V4::from_fn(|k| forms[k].beta[i])),
        }
    }

    /// [`RationalForm::newton_terms`], lane-wise (the same generic formulas).
    #[inline(always)]
    fn newton_terms(&self, lambda: V4) -> (V4, V4, V4) {
        crate::poly::newton_terms(&self.alpha, &self.beta, lambda)
    }

    /// [`RationalForm::f`], lane-wise.
    #[inline(always)]
    fn f(&self, lambda: V4) -> V4 {
        crate::poly::f_value(&self.alpha, &self.beta, lambda)
    }
}

/// The outcome of one lane of [`maximise4`].
#[derive(Clone, Copy, Debug)]
pub(crate) struct LaneResult {
    /// λ₀ in the lane's own orientation.
    pub t: f64,
    /// f(λ₀).
    pub f: f64,
    /// The lane met a pencil so small that the scalar iteration switches to its divided form:
    /// the caller must solve this lane with the scalar code.
    pub fallback: bool,
}

/// [`RationalForm::maximise`] on four forms at once, from the starting points `t0`.
///
/// Each lane follows the scalar iteration step for step: the Newton terms and the step are
/// computed for all lanes together, then each lane applies the scalar bracket, stopping and
/// safeguard rules to its own state. A stopped lane's state is frozen.
#[inline(always)]
pub(crate) fn maximise4(forms: &Forms4, t0: [f64; LANES]) -> [LaneResult; LANES] {
    let mut t = V4(t0);
    let mut lo = [0.0_f64; LANES];
    let mut hi = [1.0_f64; LANES];
    let mut iterations = [0u32; LANES];
    let mut done = [false; LANES];
    let mut fallback = [false; LANES];
    // Where each lane stopped, and whether it took the last Newton step.
    let mut stop = [0.0_f64; LANES];
    let mut next_at_stop = [0.0_f64; LANES];
    let mut take_next = [false; LANES];
    while done.iter().any(|d| !d) {
        let (n1, n2, pab) = forms.newton_terms(t);
        let p = t * (V4::splat(1.0) - t);
        let next = t - p * n1 * pab / ((V4::splat(1.0) - V4::splat(2.0) * t) * n1 * pab + p * n2);
        // Left to itself the optimiser sinks these lane-wise computations into the per-lane
        // loop below (a stopped lane does not use its values) and computes them one lane at a
        // time, undoing the vectorisation; materialising them keeps the four lanes together.
        let (n1, n2, pab, next) = core::hint::black_box((n1, n2, pab, next));
        for k in 0..LANES {
            if done[k] {
                continue;
            }
            let tk = t.0[k];
            iterations[k] += 1;
            if !crate::arith::is_positive(pab.0[k] - 1e-60) {
                done[k] = true;
                fallback[k] = true;
                continue;
            }
            let (n1, n2) = (n1.0[k], n2.0[k]);
            if n1 > 0.0 {
                lo[k] = tk;
            } else {
                hi[k] = tk;
            }
            let nx = next.0[k];
            let inside = nx > lo[k] && nx < hi[k];
            let converged = n1 * n1 < -2e-12 * n2;
            if converged || !crate::arith::is_positive(-n2) || iterations[k] >= 200 {
                done[k] = true;
                stop[k] = tk;
                next_at_stop[k] = nx;
                take_next[k] = inside && converged;
                continue;
            }
            let nx = if inside {
                nx
            } else if lo[k] > 0.0 && hi[k] > 16.0 * lo[k] {
                (lo[k] * hi[k]).sqrt()
            } else {
                0.5 * (lo[k] + hi[k])
            };
            if nx == tk || hi[k] - lo[k] <= 4.0 * f64::EPSILON * tk {
                done[k] = true;
                stop[k] = tk;
                next_at_stop[k] = tk;
                continue;
            }
            t.0[k] = nx;
        }
    }
    let f_stop = forms.f(V4(stop));
    let f_next = forms.f(V4(next_at_stop));
    core::array::from_fn(|k| {
        if take_next[k] {
            LaneResult {
                t: next_at_stop[k],
                f: f_next.0[k].max(f_stop.0[k]),
                fallback: fallback[k],
            }
        } else {
            LaneResult {
                t: stop[k],
                f: f_stop.0[k],
                fallback: fallback[k],
            }
        }
    })
}
