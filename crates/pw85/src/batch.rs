//! Many pairs at once: slices in, slices out, four pairs at a time, and on all cores with the
//! `rayon` feature.
//!
//! The λ iteration of one pair is a chain of dependent operations (one division per step), so
//! a single call spends much of its time waiting on latency. [`contact_functions`]
//! advances the iterations of four independent pairs in lock-step, and computes the
//! coefficients, the normalisation, the orientation, μ² and its error estimate for the four
//! pairs at once (one 256-bit register per quantity); only validation, the rare refinement
//! and the fallbacks run lane by lane. The results are identical to the scalar
//! [`crate::contact_function`] (same arithmetic in each lane, same stopping rule), only
//! computed side by side.

use crate::arith::Arith;
use crate::contact::{
    Prepared, Scale4, check_positive_definite, depth_weighted, odds_amplification, odds_solution,
    oriented, positive_definite4, refine,
};
use crate::error::Argument;
use crate::lanes::{LANES, V4, coefficients4, maximise4};
use crate::poly::RationalForm;
use crate::sym::{Sym2, Sym3};
use crate::{Contact, Error};
use simd::multiversion;

/// One pair of ellipsoids: r12 = c2 − c1 and the two quadratic forms.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pair {
    /// c2 − c1.
    pub r12: [f64; 3],
    /// Quadratic form of the first ellipsoid.
    pub q1: Sym3,
    /// Quadratic form of the second ellipsoid.
    pub q2: Sym3,
}

/// A placeholder value to pre-fill output buffers with (μ² and λ are NaN).
pub const EMPTY_CONTACT: Contact = Contact {
    mu2: f64::NAN,
    lambda: f64::NAN,
    error_estimate: f64::NAN,
    refined: false,
};

/// `out[i] = one(&pairs[i])`, by `four` on each whole chunk of four pairs.
#[inline(always)]
fn by_fours<P, R>(
    pairs: &[P],
    out: &mut [R],
    four: impl Fn(&[P], &mut [R]),
    one: impl Fn(&P) -> R,
) {
    assert!(
        out.len() >= pairs.len(),
        "output slice shorter than the input"
    );
    let mut chunks = pairs.chunks_exact(LANES);
    let mut outs = out.chunks_exact_mut(LANES);
    for (chunk, o) in (&mut chunks).zip(&mut outs) {
        four(chunk, o);
    }
    let rest = chunks.remainder();
    let start = pairs.len() - rest.len();
    for (p, o) in rest.iter().zip(&mut out[start..]) {
        *o = one(p);
    }
}

/// `out[i] = one(&pairs[i])`.
#[inline(always)]
fn each<P, R>(pairs: &[P], out: &mut [R], one: impl Fn(&P) -> R) {
    assert!(
        out.len() >= pairs.len(),
        "output slice shorter than the input"
    );
    for (p, o) in pairs.iter().zip(out.iter_mut()) {
        *o = one(p);
    }
}

/// One pair of ellipses: r12 = c2 − c1 and the two quadratic forms (Q11, Q12, Q22).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pair2d {
    /// c2 − c1.
    pub r12: [f64; 2],
    /// Quadratic form of the first ellipse.
    pub q1: Sym2,
    /// Quadratic form of the second ellipse.
    pub q2: Sym2,
}

/// Where a batch runs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Parallelism {
    /// On the calling thread.
    #[default]
    Serial,
    /// On all cores, in chunks of 1024 pairs (with the `rayon` feature; without it, on the
    /// calling thread).
    Threads,
}

mod sealed {
    pub trait Sealed {}
    impl Sealed for super::Pair {}
    impl Sealed for super::Pair2d {}
}

/// A pair the batch functions take: [`Pair`] (two ellipsoids) or [`Pair2d`] (two ellipses).
/// The dimension is the pair's type: one set of functions serves both.
pub trait BatchPair: sealed::Sealed + Sync + Sized {
    /// The contact functions of `pairs` into `out`, on the calling thread.
    #[doc(hidden)]
    fn contacts(pairs: &[Self], out: &mut [Result<Contact, Error>]);
    /// The verdicts of `pairs` into `out`, on the calling thread.
    #[doc(hidden)]
    fn verdicts(pairs: &[Self], out: &mut [Result<bool, Error>]);
}

impl BatchPair for Pair {
    fn contacts(pairs: &[Self], out: &mut [Result<Contact, Error>]) {
        by_fours(pairs, out, contact_x4, |p| {
            crate::contact_function(&p.r12, &p.q1, &p.q2)
        });
    }
    fn verdicts(pairs: &[Self], out: &mut [Result<bool, Error>]) {
        each(pairs, out, |p| crate::overlap(&p.r12, &p.q1, &p.q2));
    }
}

impl BatchPair for Pair2d {
    fn contacts(pairs: &[Self], out: &mut [Result<Contact, Error>]) {
        by_fours(pairs, out, contact_x4_2d, |p| {
            crate::contact::contact_function_2d(&p.r12, &p.q1, &p.q2)
        });
    }
    fn verdicts(pairs: &[Self], out: &mut [Result<bool, Error>]) {
        each(pairs, out, |p| {
            crate::overlap::overlap_2d(&p.r12, &p.q1, &p.q2)
        });
    }
}

/// `run` on the calling thread, or on all cores in chunks of 1024 pairs.
fn split<P: Sync, R: Send>(
    pairs: &[P],
    out: &mut [R],
    parallelism: Parallelism,
    run: impl Fn(&[P], &mut [R]) + Sync + Send,
) {
    assert!(
        out.len() >= pairs.len(),
        "output slice shorter than the input"
    );
    match parallelism {
        #[cfg(feature = "rayon")]
        Parallelism::Threads => {
            use rayon::prelude::*;
            pairs
                .par_chunks(1024)
                .zip(out.par_chunks_mut(1024))
                .for_each(|(p, o)| run(p, o));
        }
        _ => run(pairs, out),
    }
}

/// The contact function ([`crate::contact_function`], 2D forms) of every
/// pair, into `out[i]` for `pairs[i]`: four pairs at a time, in lock-step (the results are the
/// scalar function's, to the bit), on the calling thread or on all cores. The ellipses'
/// coefficients are degree-elevated to the same Bernstein form, so both dimensions share the
/// four-lane solve.
///
/// # Panics
/// If `out` is shorter than `pairs` (a programming error, not a data error).
pub fn contact_functions<P: BatchPair>(
    pairs: &[P],
    out: &mut [Result<Contact, Error>],
    parallelism: Parallelism,
) {
    split(pairs, out, parallelism, P::contacts);
}

/// The verdict ([`crate::overlap`], 2D forms) of every pair, into `out[i]` for
/// `pairs[i]`. The verdict usually stops after one or two evaluations, so there is little
/// latency to hide: each chunk is a plain loop.
///
/// # Panics
/// If `out` is shorter than `pairs`.
pub fn overlaps<P: BatchPair>(
    pairs: &[P],
    out: &mut [Result<bool, Error>],
    parallelism: Parallelism,
) {
    split(pairs, out, parallelism, P::verdicts);
}

multiversion! {
    /// Four pairs in lock-step (see [`crate::lanes`]). Lanes with invalid input, coincident
    /// centres or a degenerate pencil are answered by the scalar code and carry another
    /// lane's pair (or a stand-in) through the lane arithmetic.
    fn contact_x4(pairs: &[Pair], out: &mut [Result<Contact, Error>]) -> () => fused contact_x4_portable;
}

multiversion! {
    /// Four pairs of ellipses in lock-step: validation and coefficients lane by lane (the
    /// scalar [`Prepared::new_2d`], cheap in 2D), the solve four lanes at a time.
    fn contact_x4_2d(pairs: &[Pair2d], out: &mut [Result<Contact, Error>]) -> () => fused contact_x4_2d_portable;
}

#[inline(always)]
fn contact_x4_2d_portable<const FMA: bool>(pairs: &[Pair2d], out: &mut [Result<Contact, Error>]) {
    let mut lanes = Lanes {
        alpha: [V4::lift(0.0); 3],
        beta: [V4::lift(0.0); 4],
        bound_alpha: [V4::lift(0.0); 3],
        bound_beta: [V4::lift(0.0); 4],
        valid: [false; LANES],
    };
    for (k, p) in pairs.iter().enumerate().take(LANES) {
        // Lanes outside the fast path's window, with NaN or ±∞, or refused as not positive
        // definite get the scalar function (its rescue, its typed error).
        let prepared = match crate::contact::inputs_finite_2d(&p.r12, &p.q1, &p.q2) {
            Ok(true) => Prepared::new_2d(&p.r12, &p.q1, &p.q2).ok(),
            _ => None,
        };
        let Some(prepared) = prepared else {
            out[k] = crate::contact::contact_function_2d(&p.r12, &p.q1, &p.q2);
            continue;
        };
        let (r, b) = (prepared.rational, prepared.bound);
        for i in 0..3 {
            lanes.alpha[i].0[k] = r.alpha[i];
            lanes.bound_alpha[i].0[k] = b.alpha[i];
        }
        for i in 0..4 {
            lanes.beta[i].0[k] = r.beta[i];
            lanes.bound_beta[i].0[k] = b.beta[i];
        }
        lanes.valid[k] = true;
    }
    solve_x4::<FMA>(
        &lanes,
        out,
        |k| crate::contact::contact_function_2d(&pairs[k].r12, &pairs[k].q1, &pairs[k].q2),
        |k| crate::contact::exact_coefficients_2d(&pairs[k].r12, &pairs[k].q1, &pairs[k].q2),
    );
}

/// A pair that is valid and well scaled, to fill the lanes of pairs answered separately.
const STAND_IN: Pair = Pair {
    r12: [2.0, 0.0, 0.0],
    q1: [1.0, 0.0, 0.0, 1.0, 0.0, 1.0],
    q2: [1.0, 0.0, 0.0, 1.0, 0.0, 1.0],
};

#[inline(always)]
fn contact_x4_portable<const FMA: bool>(pairs: &[Pair], out: &mut [Result<Contact, Error>]) {
    // The probe of `check_inputs_finite` (Σ (x·P − x·P), NaN for NaN, ±∞ and entries beyond
    // the fast path's window), four lanes at a time; a lane that fails it gets the scalar
    // function: its typed error, or its rescue of a pair at extreme scales.
    let inputs = |p: &Pair| -> [f64; 15] {
        core::array::from_fn(|i| match i {
            0..3 => p.r12[i],
            3..9 => p.q1[i - 3],
            _ => p.q2[i - 9],
        })
    };
    let all: [[f64; 15]; LANES] = core::array::from_fn(|k| inputs(&pairs[k]));
    #[allow(clippy::eq_op)] // x − x is the point: NaN for NaN and ±∞, 0 otherwise.
    let probe = (0..15).fold(V4::from_fn(|_| 0.0), |acc, i| {
        let x = V4::from_fn(|k| all[k][i] * crate::extreme::PROBE);
        acc + (x - x)
    });
    let finite: [bool; LANES] = core::array::from_fn(|k| probe.0[k] == 0.0);
    let lane: [&Pair; LANES] =
        core::array::from_fn(|k| if finite[k] { &pairs[k] } else { &STAND_IN });
    let r: [V4; 3] = core::array::from_fn(|i| V4::from_fn(|k| lane[k].r12[i]));
    let a: [V4; 6] = core::array::from_fn(|i| V4::from_fn(|k| lane[k].q1[i]));
    let b: [V4; 6] = core::array::from_fn(|i| V4::from_fn(|k| lane[k].q2[i]));
    let (c, m) = coefficients4::<FMA>(r, a, b);

    // Per lane, the validation of the scalar path; in the common case (every lane finite
    // and clearly positive definite, as the cheap tests decide) in one branch for all four.
    let mut valid = [true; LANES];
    let clear = finite.iter().all(|&f| f)
        & positive_definite4(&a, c.beta[0], m.1[0])
        & positive_definite4(&b, c.beta[3], m.1[3]);
    if !clear {
        for k in 0..LANES {
            let p = &pairs[k];
            if !finite[k] {
                out[k] = crate::contact_function(&p.r12, &p.q1, &p.q2);
                valid[k] = false;
                continue;
            }
            let checked = check_positive_definite(Argument::Q1, &p.q1, c.beta[0].0[k], m.1[0].0[k])
                .and_then(|()| {
                    check_positive_definite(Argument::Q2, &p.q2, c.beta[3].0[k], m.1[3].0[k])
                });
            if checked.is_err() {
                // The scalar function's error, or its answer where the refusal came from an
                // underflow or overflow of the determinants.
                out[k] = crate::contact_function(&p.r12, &p.q1, &p.q2);
                valid[k] = false;
            }
        }
    }
    let lanes = Lanes {
        alpha: c.alpha,
        beta: c.beta,
        bound_alpha: m.0,
        bound_beta: m.1,
        valid,
    };
    solve_x4::<FMA>(
        &lanes,
        out,
        |k| crate::contact_function(&pairs[k].r12, &pairs[k].q1, &pairs[k].q2),
        |k| crate::contact::exact_coefficients(&pairs[k].r12, &pairs[k].q1, &pairs[k].q2),
    );
}

/// Four pairs side by side: their `f64` Bernstein coefficients and Σ|terms|, one lane each,
/// and which lanes passed validation (the others are answered already).
struct Lanes {
    alpha: [V4; 3],
    beta: [V4; 4],
    bound_alpha: [V4; 3],
    bound_beta: [V4; 4],
    valid: [bool; LANES],
}

/// The rational form of lane `k`.
#[inline(always)]
fn lane_form(alpha: &[V4; 3], beta: &[V4; 4], k: usize) -> RationalForm {
    RationalForm {
        alpha: alpha.map(|x| x.0[k]),
        beta: beta.map(|x| x.0[k]),
    }
}

/// What [`crate::contact::Prepared::contact`] does after validation, for four lanes at once:
/// normalisation, orientation, the odds iteration ([`maximise4`]), μ² and its error estimate,
/// lane-wise; the refinement (`exact(k)`: lane `k`'s double-double coefficients) and the
/// fallback to the λ iteration (`scalar(k)`: the scalar function on lane `k`'s pair) lane by
/// lane. Shared by the 3D and 2D batches: both reduce to the same Bernstein form.
#[inline(always)]
fn solve_x4<const FMA: bool>(
    lanes: &Lanes,
    out: &mut [Result<Contact, Error>],
    scalar: impl Fn(usize) -> Result<Contact, Error>,
    exact: impl Fn(usize) -> RationalForm,
) {
    // A valid lane without a scale (r12 = 0, or coefficients that underflowed) or with one
    // near the subnormal range gets the scalar function, which tells the two apart.
    let (scales, positive) = Scale4::of(&lanes.alpha, &lanes.beta);
    let live: [bool; LANES] =
        core::array::from_fn(|k| lanes.valid[k] && positive[k] && scales.lane(k).is_normal());
    for k in 0..LANES {
        if lanes.valid[k] && !live[k] {
            out[k] = scalar(k);
        }
    }
    let Some(first) = live.iter().position(|&l| l) else {
        return;
    };
    // Lanes answered already carry a live lane's pair through the arithmetic.
    let source: [usize; LANES] = core::array::from_fn(|k| if live[k] { k } else { first });
    let scale = scales.picked(&source);
    let pick = |x: V4| V4::from_fn(|k| x.0[source[k]]);
    let (alpha, beta) = (lanes.alpha.map(pick), lanes.beta.map(pick));
    let (bound_alpha, bound_beta) = (lanes.bound_alpha.map(pick), lanes.bound_beta.map(pick));

    // Scale::apply and orient, lane-wise (the same operations).
    let (inv_a, inv_b) = scale.inverses();
    let alpha = alpha.map(|x| V4::from_fn(|k| (x.0[k] * inv_a.0[k]).max(0.0)));
    let beta = beta.map(|x| V4::from_fn(|k| (x.0[k] * inv_b.0[k]).max(0.0)));
    let x = alpha[2] * beta[0];
    let y = alpha[0] * beta[3];
    let reversed: [bool; LANES] = core::array::from_fn(|k| x.0[k] > y.0[k]);
    let swap =
        |keep: V4, other: V4| V4::from_fn(|k| if reversed[k] { other.0[k] } else { keep.0[k] });
    let alpha = [swap(alpha[0], alpha[2]), alpha[1], swap(alpha[2], alpha[0])];
    let beta = [
        swap(beta[0], beta[3]),
        swap(beta[1], beta[2]),
        swap(beta[2], beta[1]),
        swap(beta[3], beta[0]),
    ];
    let u0: [f64; LANES] =
        core::array::from_fn(|k| (x.0[k].min(y.0[k]) / x.0[k].max(y.0[k])).sqrt());

    let (u, [last_u, last_a, last_b], fallback) = maximise4::<FMA>(&alpha, &beta, u0);

    // Solution::at and the error estimate of Prepared::finish, lane-wise.
    let [t, s, f, _, _] = odds_solution(&alpha, &beta, u);
    let lambda = swap(t, s);
    let (bound_alpha, bound_beta) = oriented(depth_weighted(&bound_alpha, &bound_beta), swap);
    let (x, d) = odds_amplification(
        &bound_alpha,
        &bound_beta,
        [last_u, last_a, last_b, inv_a, inv_b],
    );
    // Scale::contact, lane-wise.
    let mu2 = f * scale.ratio();
    for k in 0..LANES {
        if !live[k] {
            continue;
        }
        if fallback[k] {
            out[k] = scalar(k);
            continue;
        }
        let fraction = (x.0[k], d.0[k]);
        if Prepared::needs_refinement(fraction) {
            let prepared = Prepared {
                rational: lane_form(&lanes.alpha, &lanes.beta, k),
                bound: lane_form(&lanes.bound_alpha, &lanes.bound_beta, k),
            };
            out[k] = Ok(refine::<FMA>(&prepared, || exact(k), scale.lane(k)));
            continue;
        }
        // Written where it is stored: a `Contact` merged from both paths was assembled on
        // the stack with 8-byte stores and copied with one 32-byte load, which store
        // forwarding cannot serve.
        out[k] = Ok(Contact {
            mu2: mu2.0[k],
            lambda: lambda.0[k],
            error_estimate: Prepared::estimate(fraction.0 / fraction.1),
            refined: false,
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn contacts<P: BatchPair>(pairs: &[P]) -> Vec<Result<Contact, Error>> {
        let mut out = vec![Ok(EMPTY_CONTACT); pairs.len()];
        contact_functions(pairs, &mut out, Parallelism::Serial);
        out
    }

    fn verdicts<P: BatchPair>(pairs: &[P]) -> Vec<Result<bool, Error>> {
        let mut out = vec![Ok(false); pairs.len()];
        overlaps(pairs, &mut out, Parallelism::Serial);
        out
    }

    /// Lanes at scales where the largest α or β is subnormal or beyond 2¹⁰²³ (their
    /// normalisation takes the other branch of the power of two, and they are refined),
    /// mixed with ordinary lanes in one chunk: still the scalar function's bits.
    #[test]
    fn batch_equals_scalar_at_extreme_scales() {
        let q1 = crate::shape::from_axes_angles(&[1.0, 0.3, 0.2], &[0.3, 1.1, 2.0]).unwrap();
        let q2 = crate::shape::from_axes_angles(&[0.5, 0.4, 0.1], &[2.3, 0.2, 0.7]).unwrap();
        let scaled = |k: f64, r12: [f64; 3]| Pair {
            r12: r12.map(|x| x * k),
            q1: q1.map(|x| x * k * k),
            q2: q2.map(|x| x * k * k),
        };
        let mut pairs = Vec::new();
        for (i, &k) in [1.0, 1e-52, 3e51, 1e-53, 2e-52, 1e-55, 1.0, 5e51]
            .iter()
            .enumerate()
        {
            let t = i as f64;
            pairs.push(scaled(k, [0.9 + 0.1 * t, -0.3, 0.2 * t]));
        }
        let batch = contacts(&pairs);
        let mut other_branch = 0;
        for (p, b) in pairs.iter().zip(&batch) {
            let s = crate::contact_function(&p.r12, &p.q1, &p.q2);
            assert_eq!(format!("{s:?}"), format!("{b:?}"));
            let form = crate::contact::exact_coefficients(&p.r12, &p.q1, &p.q2);
            let normal = |xs: &[f64]| {
                let largest = xs.iter().fold(0.0_f64, |m, &x| m.max(x));
                (f64::MIN_POSITIVE..2f64.powi(1023)).contains(&largest)
            };
            other_branch += usize::from(!normal(&form.alpha) || !normal(&form.beta));
        }
        assert!(other_branch >= 4, "{other_branch}");
    }

    #[test]
    fn batch_equals_scalar_bit_for_bit_including_errors() {
        let mut pairs = Vec::new();
        let mut x = 0.3_f64;
        let mut next = || {
            x = (x * 3.9 * (1.0 - x)).clamp(1e-6, 1.0 - 1e-6);
            x
        };
        for i in 0..103 {
            let q1 = crate::shape::from_axes_angles(
                &[0.2 + next(), 0.1 + next(), 0.05 + next()],
                &[next() * 6.0, next() * 6.0, next() * 6.0],
            )
            .unwrap();
            let mut q2 = crate::shape::from_axes_angles(
                &[0.2 + next(), 0.01 + 0.1 * next(), 0.05 + next()],
                &[next() * 6.0, next() * 6.0, next() * 6.0],
            )
            .unwrap();
            let mut r12 = [next() - 0.5, next() - 0.5, next() - 0.5].map(|v| 3.0 * v);
            match i % 17 {
                3 => q2[1] = 10.0,      // not positive definite
                5 => r12[1] = f64::NAN, // not finite
                7 => r12 = [0.0; 3],    // coincident
                _ => {}
            }
            pairs.push(Pair { r12, q1, q2 });
        }
        let batch = contacts(&pairs);
        for (p, b) in pairs.iter().zip(&batch) {
            let s = crate::contact_function(&p.r12, &p.q1, &p.q2);
            // Debug text, not ==: the NaN carried by a NonFinite error is not equal to itself.
            assert_eq!(format!("{s:?}"), format!("{b:?}"));
        }
        let verdicts = verdicts(&pairs);
        for (p, v) in pairs.iter().zip(&verdicts) {
            assert_eq!(
                format!("{:?}", crate::overlap(&p.r12, &p.q1, &p.q2)),
                format!("{v:?}")
            );
        }
    }
}

#[cfg(test)]
mod portable_tests {
    use super::*;

    /// The portable build of the four-lane path (what processors without AVX2 and FMA run;
    /// the public functions dispatch to the AVX2 build here) equals the portable scalar path
    /// bit for bit, in 3D and 2D.
    #[test]
    fn portable_lanes_equal_portable_scalar() {
        let mut x = 0.41_f64;
        let mut next = || {
            x = (x * 3.97 * (1.0 - x)).clamp(1e-9, 1.0 - 1e-9);
            x
        };
        for i in 0..4000 {
            let thin = 10f64.powf(-6.0 * next());
            let mut chunk = [STAND_IN; LANES];
            let mut chunk_2d = [Pair2d {
                r12: [0.0; 2],
                q1: [1.0, 0.0, 1.0],
                q2: [1.0, 0.0, 1.0],
            }; LANES];
            for k in 0..LANES {
                let q1 = crate::shape::from_axes_angles(
                    &[1.0, 0.1 + next(), thin],
                    &[next() * 6.0, next() * 6.0, next() * 6.0],
                )
                .unwrap();
                let q2 = crate::shape::from_axes_angles(
                    &[0.2 + next(), 1e-3 + next(), 0.05 + next()],
                    &[next() * 6.0, next() * 6.0, next() * 6.0],
                )
                .unwrap();
                let r12 = [next() - 0.5, next() - 0.5, next() - 0.5].map(|v| 3.0 * v);
                chunk[k] = Pair { r12, q1, q2 };
                let e1 = crate::shape::from_axes_angle_2d(&[1.0, thin], next() * 6.0).unwrap();
                let e2 =
                    crate::shape::from_axes_angle_2d(&[0.3, 0.1 + next()], next() * 6.0).unwrap();
                chunk_2d[k] = Pair2d {
                    r12: [r12[0], r12[1]],
                    q1: e1,
                    q2: e2,
                };
            }
            if i % 7 == 3 {
                chunk[i % LANES].q2[1] = 10.0;
                chunk_2d[i % LANES].r12 = [0.0; 2];
            }
            let mut out = [Ok(EMPTY_CONTACT); LANES];
            contact_x4_portable::<false>(&chunk, &mut out);
            let mut out_2d = [Ok(EMPTY_CONTACT); LANES];
            contact_x4_2d_portable::<false>(&chunk_2d, &mut out_2d);
            for k in 0..LANES {
                let p = &chunk[k];
                let s =
                    crate::contact::contact_function_portable::<false>(&p.r12, &p.q1, &p.q2, true);
                assert_eq!(format!("{s:?}"), format!("{:?}", out[k]));
                let p = &chunk_2d[k];
                let s = crate::contact::contact_function_2d_portable::<false>(&p.r12, &p.q1, &p.q2);
                assert_eq!(format!("{s:?}"), format!("{:?}", out_2d[k]));
            }
        }
    }
}

#[cfg(all(test, feature = "rayon"))]
mod parallel_tests {
    use super::*;

    /// Serial and threaded runs of `pairs` agree, and the verdicts are not all alike.
    fn assert_threads_match_serial<P: BatchPair>(pairs: &[P]) {
        let mut seq = vec![Ok(EMPTY_CONTACT); pairs.len()];
        let mut par = vec![Ok(EMPTY_CONTACT); pairs.len()];
        contact_functions(pairs, &mut seq, Parallelism::Serial);
        contact_functions(pairs, &mut par, Parallelism::Threads);
        assert_eq!(seq, par);
        let mut vs = vec![Ok(false); pairs.len()];
        let mut vp = vec![Ok(false); pairs.len()];
        overlaps(pairs, &mut vs, Parallelism::Serial);
        overlaps(pairs, &mut vp, Parallelism::Threads);
        assert_eq!(vs, vp);
        assert!(vs.contains(&Ok(true)) && vs.contains(&Ok(false)));
    }

    #[test]
    fn parallel_batches_equal_sequential_ones() {
        let q = crate::shape::from_axes_angles(&[1.0, 0.75, 0.5], &[0.3, 0.2, 0.1]).unwrap();
        let pairs: Vec<Pair> = (0..5000)
            .map(|i| {
                let x = 0.5 + (i as f64) * 7e-4;
                Pair {
                    r12: [x, 0.3 * x, -0.2],
                    q1: q,
                    q2: q,
                }
            })
            .collect();
        assert_threads_match_serial(&pairs);

        let e = crate::shape::from_axes_angle_2d(&[1.0, 0.5], 0.3).unwrap();
        let pairs_2d: Vec<Pair2d> = pairs
            .iter()
            .map(|p| Pair2d {
                r12: [p.r12[0], p.r12[1]],
                q1: e,
                q2: e,
            })
            .collect();
        assert_threads_match_serial(&pairs_2d);
    }
}
