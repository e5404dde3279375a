//! Pseudo-random pairs of ellipsoids and ellipses, the same for every run and machine.
//!
//! The generator is SplitMix64, and the pairs are built with +, −, ×, / and √ only (all
//! correctly rounded in IEEE arithmetic): `exp`, `ln` and `sin` differ by an ulp between libm
//! implementations, which would make the snapshots machine-dependent. Values spread over
//! decades come from [`Spread::spread`] (a reciprocal-uniform law) rather than a log-uniform one
//! for that reason; only the 2D sampler uses `sin` and `cos`.

use crate::error::{self, Error};
use pw85::Sym2;

pub use testkit::Rng;

/// The one law the harness needs beyond the test kit's.
pub trait Spread {
    /// In [lo, hi] with 1/x uniform: spread over decades like a log-uniform law (denser near
    /// `lo`), from rational operations only.
    fn spread(&mut self, lo: f64, hi: f64) -> f64;
}

impl Spread for Rng {
    fn spread(&mut self, lo: f64, hi: f64) -> f64 {
        1.0 / self.range(1.0 / hi, 1.0 / lo)
    }
}

/// One pair of ellipsoids in the packing paper's parametrisation (centre, semi-axes,
/// quaternion), convertible to the PW85 one (r12, Q1, Q2) by [`Pw85Form`] (the test kit's).
pub use testkit::reference::EllipsoidPair as Pair3;

/// One pair of ellipses (centre, semi-axes, angle of the first semi-axis; the test kit's).
pub use testkit::reference::EllipsePair as Pair2;

/// The PW85 form of a pair (the test kit's).
pub use testkit::shape::Pair3 as Pw85Pair;

/// The PW85 form of a pair: r12 and the two quadratic forms.
pub trait Pw85Form {
    /// r12, Q1, Q2.
    type Form;
    /// The form, or the error of a body PW85 refuses.
    fn pw85(&self) -> Result<Self::Form, Error>;
}

impl Pw85Form for Pair3 {
    type Form = Pw85Pair;

    fn pw85(&self) -> Result<Pw85Pair, Error> {
        Ok(Pw85Pair {
            r12: [0, 1, 2].map(|k| self.cj[k] - self.ci[k]),
            q1: pw85::shape::from_axes_quaternion(&self.li, &self.oi)
                .map_err(error::pw85("the first ellipsoid of a pair"))?,
            q2: pw85::shape::from_axes_quaternion(&self.lj, &self.oj)
                .map_err(error::pw85("the second ellipsoid of a pair"))?,
        })
    }
}

impl Pw85Form for Pair2 {
    type Form = ([f64; 2], Sym2, Sym2);

    fn pw85(&self) -> Result<Self::Form, Error> {
        Ok((
            [self.cj[0] - self.ci[0], self.cj[1] - self.ci[1]],
            pw85::shape::from_axes_angle_2d(&self.li, self.oi)
                .map_err(error::pw85("the first ellipse of a pair"))?,
            pw85::shape::from_axes_angle_2d(&self.lj, self.oj)
                .map_err(error::pw85("the second ellipse of a pair"))?,
        ))
    }
}

/// The same pair with j moved to `ci + t (cj − ci)`.
pub fn at_distance_factor(pair: &Pair3, t: f64) -> Pair3 {
    let mut p = *pair;
    p.cj = [0, 1, 2].map(|k| pair.ci[k] + t * (pair.cj[k] - pair.ci[k]));
    p
}

/// Random triaxial semi-axes: the largest 1, the others in [1/aspect, 1], log-uniform.
pub fn axes(rng: &mut Rng, aspect: f64) -> [f64; 3] {
    let mut l = [1.0, rng.spread(1.0 / aspect, 1.0), 1.0 / aspect];
    // Shuffle so that the long axis is not always the first column of the rotation.
    let k = (rng.uniform() * 3.0) as usize % 3;
    l.swap(0, k);
    l
}

/// A pair with uniform axes in [0.3, 2], uniform rotations and j's centre uniform in the
/// cube [−3, 3]³ about i's (about half overlap): built from rational operations and √ only.
pub fn stable_pair(rng: &mut Rng) -> Pair3 {
    let li = [0; 3].map(|_| rng.range(0.3, 2.0));
    let qi = rng.unit_quaternion();
    let lj = [0; 3].map(|_| rng.range(0.3, 2.0));
    let qj = rng.unit_quaternion();
    let cj = [0; 3].map(|_| rng.range(-3.0, 3.0));
    Pair3 {
        ci: [0.0; 3],
        li,
        oi: qi,
        cj,
        lj,
        oj: qj,
    }
}

/// A random pair whose axes have ratios up to `aspect` and whose centre distance is `s` times
/// the contact distance along a random direction, `s` uniform in [`s_lo`, `s_hi`]: μ² = s²
/// up to rounding, so about as many overlapping as separated pairs for [0.5, 1.5].
pub fn pair_near_contact(rng: &mut Rng, aspect: f64, s_lo: f64, s_hi: f64) -> Result<Pair3, Error> {
    let li = axes(rng, aspect);
    let lj = axes(rng, aspect);
    let qi = rng.unit_quaternion();
    let qj = rng.unit_quaternion();
    let d = rng.direction();
    let ci = [0; 3].map(|_| rng.range(-2.0, 2.0));
    let unit = Pair3 {
        ci,
        li,
        oi: qi,
        cj: [0, 1, 2].map(|k| ci[k] + d[k]),
        lj,
        oj: qj,
    };
    // μ is proportional to the centre distance along a fixed direction (eq. 11 is quadratic in
    // r12), so one contact function at distance 1 places the pair at any μ.
    let p = unit.pw85()?;
    let mu = pw85::contact_function(&p.r12, &p.q1, &p.q2)
        .map_err(error::pw85("a random pair"))?
        .mu2
        .sqrt();
    let s = rng.range(s_lo, s_hi);
    Ok(at_distance_factor(&unit, s / mu))
}

/// A random pair of ellipses near contact, as [`pair_near_contact`].
pub fn pair_near_contact_2d(
    rng: &mut Rng,
    aspect: f64,
    s_lo: f64,
    s_hi: f64,
) -> Result<Pair2, Error> {
    let li = [1.0, rng.spread(1.0 / aspect, 1.0)];
    let lj = [rng.spread(1.0 / aspect, 1.0), 1.0];
    let ti = rng.range(0.0, std::f64::consts::PI);
    let tj = rng.range(0.0, std::f64::consts::PI);
    let a = rng.range(0.0, 2.0 * std::f64::consts::PI);
    let d = [a.cos(), a.sin()];
    let unit = Pair2 {
        ci: [0.0; 2],
        li,
        oi: ti,
        cj: d,
        lj,
        oj: tj,
    };
    let (r, q1, q2) = unit.pw85()?;
    let mu = pw85::contact_function(&r, &q1, &q2)
        .map_err(error::pw85("a random pair of ellipses"))?
        .mu2
        .sqrt();
    let s = rng.range(s_lo, s_hi) / mu;
    Ok(Pair2 {
        cj: [s * d[0], s * d[1]],
        ..unit
    })
}
