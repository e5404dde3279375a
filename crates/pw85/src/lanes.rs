//! Four pairs side by side, lane by lane, for the batched path (and, in [`Ends4`], the two ends
//! of one pair's pencil with their magnitudes, for the scalar path).
//!
//! [`V4`] holds one `f64` per pair and does every operation lane-wise: written this way, the
//! compiler keeps the four lanes in one 256-bit register where AVX is available (two 128-bit
//! ones otherwise). Each lane performs exactly the operations of the scalar code in the same
//! order, so the batched results equal the scalar ones bit for bit; the lanes only differ in
//! when they stop, and a lane that has stopped keeps its state (selects, not branches).

use crate::arith::Arith;
use crate::poly::{OddsForm, OddsSearch};
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

impl crate::arith::Fused for V4 {
    #[inline(always)]
    fn fused_mul_add(self, b: V4, c: V4) -> V4 {
        V4::from_fn(|k| self.0[k].mul_add(b.0[k], c.0[k]))
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

/// One pair's two ellipsoids side by side, with their magnitudes: lanes
/// [x(Q1), x(Q2), Σ|terms| of x(Q1), Σ|terms| of x(Q2)] for a formula x written once (the
/// [`crate::arith::Mag`] arithmetic in the last two lanes). The coefficient formulas of the
/// two ends of the pencil (adj Qᵢ, det Qᵢ, rᵀ adj Qᵢ r, tr(adj Qᵢ Qⱼ)) are the same formula
/// on Q1 and on Q2, so one evaluation gives four results in one 256-bit register; every lane
/// performs exactly the operations of the scalar `f64` (or `Mag`) evaluation, so the results
/// are the same bits.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Ends4(pub V4);

/// a − b is a + (−1) b in the value lanes and a + b in the magnitude lanes: multiplying by
/// ±1 is exact, so each lane rounds exactly as its own subtraction or addition would.
const SUB_SIGNS: V4 = V4([-1.0, -1.0, 1.0, 1.0]);

impl Add for Ends4 {
    type Output = Ends4;
    #[inline(always)]
    fn add(self, o: Ends4) -> Ends4 {
        Ends4(self.0 + o.0)
    }
}
impl Sub for Ends4 {
    type Output = Ends4;
    #[allow(clippy::suspicious_arithmetic_impl)] // see SUB_SIGNS
    #[inline(always)]
    fn sub(self, o: Ends4) -> Ends4 {
        Ends4(self.0 + o.0 * SUB_SIGNS)
    }
}
impl Mul for Ends4 {
    type Output = Ends4;
    #[inline(always)]
    fn mul(self, o: Ends4) -> Ends4 {
        Ends4(self.0 * o.0)
    }
}
impl Arith for Ends4 {
    #[inline(always)]
    fn lift(x: f64) -> Self {
        Ends4(V4([x, x, x.abs(), x.abs()]))
    }
    #[inline(always)]
    fn to_f64(self) -> f64 {
        self.0.0[0]
    }
}

impl Ends4 {
    /// [a, b, |a|, |b|].
    #[inline(always)]
    pub(crate) fn of(a: f64, b: f64) -> Self {
        Ends4(V4([a, b, a.abs(), b.abs()]))
    }
}

impl V4 {
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

/// The odds iteration of [`crate::contact_function`] ([`OddsSearch`]) on four pairs at once,
/// from the starting points `u0`.
///
/// The Halley terms are computed for all lanes together (the same generic formulas as the
/// scalar code, so the same bits), then each lane applies the scalar bracket and stopping rule
/// to its own state. A stopped lane's state is frozen.
#[inline(always)]
pub(crate) fn maximise4<const FMA: bool>(
    odds: &OddsForm<V4>,
    u0: [f64; LANES],
) -> [OddsSearch; LANES] {
    let mut search = u0.map(OddsSearch::new);
    while search.iter().any(|s| !s.done) {
        let (p, n, v, step) = odds.halley_terms::<FMA>(V4::from_fn(|k| search[k].u));
        // Left to itself the optimiser sinks these lane-wise computations into the per-lane
        // loop below (a stopped lane does not use its values) and computes them one lane at a
        // time, undoing the vectorisation; materialising them keeps the four lanes together.
        let (p, n, v, step) = core::hint::black_box((p, n, v, step));
        for (k, s) in search.iter_mut().enumerate() {
            if !s.done {
                s.advance((p.0[k], n.0[k], v.0[k], step.0[k]));
            }
        }
    }
    search
}
