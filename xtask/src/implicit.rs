//! The implicit-variable criterion as the harness sees it: the one module that calls the
//! crate `implicit-packing`. Everything the studies need from the model (U, d², ε, f, X, the
//! verdict and the gradients) goes through here, so that a change of that crate's API is a
//! change of this file only. Nothing of the model is re-implemented here.

use crate::error::Error;
use crate::sample::{Pair2, Pair3};
use implicit_packing::derivatives::{PairDerivatives, pair_derivatives};
use implicit_packing::{Body, Ellipse, Ellipsoid, PairTerm, overlap_measure, pair_term};

fn refused(context: &str) -> impl FnOnce(implicit_packing::Error) -> Error + '_ {
    move |e| Error::Implicit {
        context: context.to_string(),
        message: e.to_string(),
    }
}

/// The two bodies of a pair (i is mapped to the unit ball).
pub fn bodies(p: &Pair3) -> Result<(Ellipsoid, Ellipsoid), Error> {
    Ok((
        Body::from_quaternion(p.ci, p.li, p.oi).map_err(refused("ellipsoid i"))?,
        Body::from_quaternion(p.cj, p.lj, p.oj).map_err(refused("ellipsoid j"))?,
    ))
}

/// The two ellipses of a 2D pair.
pub fn ellipses(p: &Pair2) -> Result<(Ellipse, Ellipse), Error> {
    Ok((
        Body::ellipse(p.ci, p.li, p.oi).map_err(refused("ellipse i"))?,
        Body::ellipse(p.cj, p.lj, p.oj).map_err(refused("ellipse j"))?,
    ))
}

/// The full pair term (eq. 34 with X, U, d², ε).
pub fn term(p: &Pair3) -> Result<PairTerm<3>, Error> {
    let (i, j) = bodies(p)?;
    Ok(pair_term(&i, &j))
}

/// The pair term of given bodies.
pub fn term_of<const N: usize>(i: &Body<N>, j: &Body<N>) -> PairTerm<N> {
    pair_term(i, j)
}

/// f alone, with the model's early exits (what a packing loop calls).
pub fn measure<const N: usize>(i: &Body<N>, j: &Body<N>) -> f64 {
    overlap_measure(i, j)
}

/// f, d², U and their gradients (Appendix A.1).
pub fn derivatives(i: &Ellipsoid, j: &Ellipsoid) -> PairDerivatives<3> {
    pair_derivatives(i, j)
}

/// The bodies scaled by ν about the origin (Lemma 4.4).
pub fn scaled(i: &Ellipsoid, j: &Ellipsoid, nu: f64) -> Result<(Ellipsoid, Ellipsoid), Error> {
    Ok((
        i.scaled(nu).map_err(refused("a scaled ellipsoid"))?,
        j.scaled(nu).map_err(refused("a scaled ellipsoid"))?,
    ))
}

/// The body with another centre.
pub fn moved(b: &Ellipsoid, centre: [f64; 3]) -> Result<Ellipsoid, Error> {
    b.with_centre(centre).map_err(refused("a moved ellipsoid"))
}

/// The body turned by the small rotation `exp([w]×)` (world frame) about its centre: used to
/// differentiate with respect to the angular velocity `w` (dQ = \[w\]× Q).
pub fn turned(b: &Ellipsoid, w: [f64; 3]) -> Result<Ellipsoid, Error> {
    let angle = (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]).sqrt();
    let dq = if angle == 0.0 {
        [1.0, 0.0, 0.0, 0.0]
    } else {
        let (s, c) = (0.5 * angle).sin_cos();
        [c, s * w[0] / angle, s * w[1] / angle, s * w[2] / angle]
    };
    let q = b.quaternion();
    // Hamilton product dq ⊗ q: first q, then the world rotation dq.
    let prod = [
        dq[0] * q[0] - dq[1] * q[1] - dq[2] * q[2] - dq[3] * q[3],
        dq[0] * q[1] + dq[1] * q[0] + dq[2] * q[3] - dq[3] * q[2],
        dq[0] * q[2] - dq[1] * q[3] + dq[2] * q[0] + dq[3] * q[1],
        dq[0] * q[3] + dq[1] * q[2] - dq[2] * q[1] + dq[3] * q[0],
    ];
    Body::from_quaternion(b.centre(), b.semi_axes(), prod).map_err(refused("a turned ellipsoid"))
}

/// `S = FᵀF`, `F = P_j^−½ Q_jᵀ Q_i P_i^½` (the matrix of E_j in the frame where E_i is the unit
/// ball), formed explicitly. Only the KKT and Prop. 4.2 checks use it, on moderate shapes
/// where forming S is accurate; the model itself never forms S.
pub fn s_matrix(i: &Ellipsoid, j: &Ellipsoid) -> [[f64; 3]; 3] {
    let (qi, qj, li, lj) = (i.rotation(), j.rotation(), i.semi_axes(), j.semi_axes());
    let mut f = [[0.0; 3]; 3];
    for r in 0..3 {
        for c in 0..3 {
            // (Q_jᵀ Q_i)_{rc} = Σ_k Q_j[k][r] Q_i[k][c]
            let m: f64 = (0..3).map(|k| qj[k][r] * qi[k][c]).sum();
            f[r][c] = m * li[c] / lj[r];
        }
    }
    let mut s = [[0.0; 3]; 3];
    for r in 0..3 {
        for c in 0..3 {
            s[r][c] = (0..3).map(|k| f[k][r] * f[k][c]).sum();
        }
    }
    s
}
