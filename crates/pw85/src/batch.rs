//! Many pairs at once: slices in, slices out, four pairs at a time, and on all cores with the
//! `rayon` feature.
//!
//! The λ iteration of one pair is a chain of dependent operations (two divisions per step), so
//! a single call spends most of its time waiting on latency. [`contact_functions_into`]
//! advances the iterations of four independent pairs in lock-step, which lets the processor
//! overlap their chains; the results are identical to the scalar [`crate::contact_function`]
//! (same arithmetic, same stopping rule), only computed side by side.

use crate::arith::Dd;
use crate::contact::{Prepared, Solution, check_inputs_finite, check_positive_definite, start};
use crate::dispatch::multiversion;
use crate::error::Argument;
use crate::lanes::{Forms4, LANES, V4, maximise4};
use crate::poly::{RationalForm, Search, pencil3_lifted};
use crate::sym::Sym3;
use crate::{Contact, Error};

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

/// [`crate::contact_function`] for every pair, into `out[i]` for `pairs[i]`.
///
/// # Panics
/// If `out` is shorter than `pairs` (a programming error, not a data error).
pub fn contact_functions_into(pairs: &[Pair], out: &mut [Result<Contact, Error>]) {
    assert!(
        out.len() >= pairs.len(),
        "output slice shorter than the input"
    );
    let mut chunks = pairs.chunks_exact(LANES);
    let mut outs = out.chunks_exact_mut(LANES);
    for (chunk, o) in (&mut chunks).zip(&mut outs) {
        contact_x4(chunk, o);
    }
    let rest = chunks.remainder();
    let start = pairs.len() - rest.len();
    for (p, o) in rest.iter().zip(&mut out[start..]) {
        *o = crate::contact_function(&p.r12, &p.q1, &p.q2);
    }
}

/// [`crate::contact_function`] for every pair.
pub fn contact_functions(pairs: &[Pair]) -> Vec<Result<Contact, Error>> {
    let mut out = vec![Ok(EMPTY_CONTACT); pairs.len()];
    contact_functions_into(pairs, &mut out);
    out
}

/// [`crate::overlap`] for every pair, into `out[i]` for `pairs[i]`. The verdict usually stops
/// after one or two evaluations, so there is little latency to hide and this is a plain loop.
///
/// # Panics
/// If `out` is shorter than `pairs`.
pub fn overlaps_into(pairs: &[Pair], out: &mut [Result<bool, Error>]) {
    assert!(
        out.len() >= pairs.len(),
        "output slice shorter than the input"
    );
    for (p, o) in pairs.iter().zip(out.iter_mut()) {
        *o = crate::overlap(&p.r12, &p.q1, &p.q2);
    }
}

/// [`crate::overlap`] for every pair.
pub fn overlaps(pairs: &[Pair]) -> Vec<Result<bool, Error>> {
    pairs
        .iter()
        .map(|p| crate::overlap(&p.r12, &p.q1, &p.q2))
        .collect()
}

/// [`contact_functions_into`] on all cores (rayon), in chunks of 1024 pairs.
#[cfg(feature = "rayon")]
pub fn par_contact_functions_into(pairs: &[Pair], out: &mut [Result<Contact, Error>]) {
    use rayon::prelude::*;
    assert!(
        out.len() >= pairs.len(),
        "output slice shorter than the input"
    );
    pairs
        .par_chunks(1024)
        .zip(out.par_chunks_mut(1024))
        .for_each(|(p, o)| contact_functions_into(p, o));
}

/// [`overlaps_into`] on all cores (rayon), in chunks of 1024 pairs.
#[cfg(feature = "rayon")]
pub fn par_overlaps_into(pairs: &[Pair], out: &mut [Result<bool, Error>]) {
    use rayon::prelude::*;
    assert!(
        out.len() >= pairs.len(),
        "output slice shorter than the input"
    );
    pairs
        .par_chunks(1024)
        .zip(out.par_chunks_mut(1024))
        .for_each(|(p, o)| overlaps_into(p, o));
}

multiversion! {
    /// Four pairs in lock-step (see [`crate::lanes`]). Lanes with invalid input, coincident
    /// centres or a degenerate pencil are answered by the scalar code and carry a stand-in
    /// pair through the lane arithmetic.
    fn contact_x4(pairs: &[Pair], out: &mut [Result<Contact, Error>]) -> () => contact_x4_portable;
}

/// A pair that is valid and well scaled, to fill the lanes of pairs answered separately.
const STAND_IN: Pair = Pair {
    r12: [2.0, 0.0, 0.0],
    q1: [1.0, 0.0, 0.0, 1.0, 0.0, 1.0],
    q2: [1.0, 0.0, 0.0, 1.0, 0.0, 1.0],
};

#[inline(always)]
fn contact_x4_portable(pairs: &[Pair], out: &mut [Result<Contact, Error>]) {
    let finite: [bool; LANES] = core::array::from_fn(|k| {
        check_inputs_finite(&pairs[k].r12, &pairs[k].q1, &pairs[k].q2).is_ok()
    });
    let lane: [&Pair; LANES] =
        core::array::from_fn(|k| if finite[k] { &pairs[k] } else { &STAND_IN });
    let r: [V4; 3] = core::array::from_fn(|i| V4::from_fn(|k| lane[k].r12[i]));
    let a: [V4; 6] = core::array::from_fn(|i| V4::from_fn(|k| lane[k].q1[i]));
    let b: [V4; 6] = core::array::from_fn(|i| V4::from_fn(|k| lane[k].q2[i]));
    let rm = r.map(V4::magnitude);
    let am = a.map(V4::magnitude);
    let bm = b.map(V4::magnitude);
    let c = pencil3_lifted(r, a, b).coefficients;
    let m = pencil3_lifted(rm, am, bm).coefficients;

    // Per lane: validation, normalisation and orientation, exactly as the scalar path.
    let mut active = [None; LANES];
    for k in 0..LANES {
        let p = &pairs[k];
        if !finite[k] {
            out[k] = crate::contact_function(&p.r12, &p.q1, &p.q2);
            continue;
        }
        let prepared = Prepared {
            rational: RationalForm {
                alpha: c.alpha.map(|x| x.0[k]),
                beta: c.beta.map(|x| x.0[k]),
            },
            bound: RationalForm {
                alpha: m.alpha.map(|x| x.0[k]),
                beta: m.beta.map(|x| x.0[k]),
            },
        };
        let (beta, bound) = (prepared.rational.beta, prepared.bound.beta);
        let checked = check_positive_definite(Argument::Q1, &p.q1, beta[0], bound[0])
            .and_then(|()| check_positive_definite(Argument::Q2, &p.q2, beta[3], bound[3]));
        if let Err(e) = checked {
            out[k] = Err(e);
            continue;
        }
        match prepared.normalised() {
            Some((scale, form)) => active[k] = Some((prepared, scale, start(&form))),
            None => out[k] = Ok(Contact::COINCIDENT),
        }
    }
    if active.iter().all(Option::is_none) {
        return;
    }
    let stand_in = active.iter().flatten().map(|x| x.2).next();
    let forms: [RationalForm; LANES] = core::array::from_fn(|k| {
        active[k].map_or_else(|| stand_in.map_or(RationalForm::UNIT, |s| s.0), |x| x.2.0)
    });
    let t0: [f64; LANES] = core::array::from_fn(|k| {
        active[k].map_or_else(|| stand_in.map_or(0.5, |s| s.1.t), |x| x.2.1.t)
    });
    let results = maximise4(&Forms4::new(&forms), t0);
    for k in 0..LANES {
        let Some((prepared, scale, (form, _, reversed))) = active[k] else {
            continue;
        };
        let p = &pairs[k];
        out[k] = if results[k].fallback {
            crate::contact_function(&p.r12, &p.q1, &p.q2)
        } else {
            let mut search = Search::new(results[k].t);
            search.f = results[k].f;
            search.done = true;
            Ok(
                prepared.finish(scale, Solution::of(&form, &search, reversed), || {
                    crate::poly::coefficients::<Dd>(&p.r12, &p.q1, &p.q2)
                }),
            )
        };
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
        let batch = contact_functions(&pairs);
        for (p, b) in pairs.iter().zip(&batch) {
            let s = crate::contact_function(&p.r12, &p.q1, &p.q2);
            // Debug text, not ==: the NaN carried by a NonFinite error is not equal to itself.
            assert_eq!(format!("{s:?}"), format!("{b:?}"));
        }
        let verdicts = overlaps(&pairs);
        for (p, v) in pairs.iter().zip(&verdicts) {
            assert_eq!(
                format!("{:?}", crate::overlap(&p.r12, &p.q1, &p.q2)),
                format!("{v:?}")
            );
        }
    }
}

#[cfg(all(test, feature = "rayon"))]
mod parallel_tests {
    use super::*;

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
        let mut seq = vec![Ok(EMPTY_CONTACT); pairs.len()];
        let mut par = vec![Ok(EMPTY_CONTACT); pairs.len()];
        contact_functions_into(&pairs, &mut seq);
        par_contact_functions_into(&pairs, &mut par);
        assert_eq!(seq, par);
        let mut vs = vec![Ok(false); pairs.len()];
        let mut vp = vec![Ok(false); pairs.len()];
        overlaps_into(&pairs, &mut vs);
        par_overlaps_into(&pairs, &mut vp);
        assert_eq!(vs, vp);
        assert!(vs.contains(&Ok(true)) && vs.contains(&Ok(false)));
    }
}
