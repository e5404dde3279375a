//! Many pairs at once: slices in, slices out, four pairs at a time, and on all cores with the
//! `rayon` feature.
//!
//! The λ iteration of one pair is a chain of dependent operations (two divisions per step), so
//! a single call spends most of its time waiting on latency. [`contact_functions_into`]
//! advances the iterations of four independent pairs in lock-step, which lets the processor
//! overlap their chains; the results are identical to the scalar [`crate::contact_function`]
//! (same arithmetic, same stopping rule), only computed side by side.

use crate::contact::{Prepared, Solution, start};
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

/// How many pairs advance side by side.
const LANES: usize = 4;

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

/// Four pairs in lock-step. Lanes with invalid input or coincident centres are answered
/// directly and sit out the iteration.
#[inline]
fn contact_x4(pairs: &[Pair], out: &mut [Result<Contact, Error>]) {
    let prepared: [Result<Prepared, Error>; LANES] =
        core::array::from_fn(|k| Prepared::new(&pairs[k].r12, &pairs[k].q1, &pairs[k].q2));
    let normalised = core::array::from_fn::<_, LANES, _>(|k| {
        prepared[k].as_ref().ok().and_then(Prepared::normalised)
    });
    let mut lanes = core::array::from_fn::<_, LANES, _>(|k| normalised[k].map(|(_, f)| start(&f)));
    loop {
        let mut busy = false;
        for lane in lanes.iter_mut().flatten() {
            let (form, search, _) = lane;
            if !search.done {
                form.search_step(search);
                busy = true;
            }
        }
        if !busy {
            break;
        }
    }
    for k in 0..LANES {
        out[k] = match (&prepared[k], normalised[k], lanes[k]) {
            (Err(e), _, _) => Err(*e),
            (Ok(p), Some((scale, _)), Some((form, search, reversed))) => {
                let pair = &pairs[k];
                Ok(p.finish(scale, Solution::of(&form, &search, reversed), || {
                    crate::poly::coefficients::<crate::arith::Dd>(&pair.r12, &pair.q1, &pair.q2)
                }))
            }
            _ => Ok(Contact::COINCIDENT),
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
