//! Nematic order of each body axis: the order tensor
//! `Q = (N ⟨u uᵀ⟩ − I) / (N − 1)` over the items' unit axes u (3D: `Q = (3⟨u uᵀ⟩ − I) / 2`;
//! 2D: `Q = 2⟨u uᵀ⟩ − I`), whose largest eigenvalue is the order parameter S (1 when every
//! axis is parallel; 0 for isotropic axes, up to O(1/√m) for m random ones; in 3D as low as
//! −1/2 for axes all perpendicular to one direction) and whose eigenvector is the director.
//! In 2D S equals `|⟨e^{2iθ}⟩|`, the order parameter S₂ of two-dimensional nematics.
//!
//! An axis counts only for the items that define it, those whose semi-axis along it differs
//! from their others: a circle or a ball defines none (its rotation is arbitrary, the identity
//! in a packing), a spheroid only its distinct axis. An axis no item defines has no order.
//!
//! # References
//! - P. G. de Gennes, J. Prost, *The Physics of Liquid Crystals*, 2nd ed., Oxford (1993), §2.1.

use implicit_packing::Body;
use nalgebra::{Matrix2, Matrix3};

/// The nematic order of one body axis.
#[derive(Clone, Debug, PartialEq)]
pub struct Nematic {
    /// The body axis: column k of the rotation, along semi-axis k.
    pub axis: usize,
    /// The order parameter S, the largest eigenvalue of Q.
    pub order: f64,
    /// The director, its eigenvector (unit; 2D: z = 0), sign chosen with its largest
    /// component positive.
    pub director: [f64; 3],
}

/// [`Nematic`] of every body axis that some item defines (see the module documentation),
/// averaged over those items.
pub fn nematic_order<const N: usize>(bodies: &[Body<N>]) -> Vec<Nematic> {
    (0..N).filter_map(|axis| of_axis(bodies, axis)).collect()
}

/// Whether `axis` is defined for `body`: its semi-axis along it differs from the others.
fn defines<const N: usize>(body: &Body<N>, axis: usize) -> bool {
    let l = body.semi_axes();
    (0..N).all(|k| k == axis || l[k] != l[axis])
}

fn of_axis<const N: usize>(bodies: &[Body<N>], axis: usize) -> Option<Nematic> {
    let mut t = [[0.0; 3]; 3];
    let mut count = 0usize;
    for b in bodies.iter().filter(|b| defines(b, axis)) {
        count += 1;
        let r = b.rotation();
        let u: [f64; 3] = std::array::from_fn(|k| if k < N { r[k][axis] } else { 0.0 });
        for p in 0..3 {
            for q in 0..3 {
                t[p][q] += u[p] * u[q];
            }
        }
    }
    if count == 0 {
        return None;
    }
    let m = count as f64;
    let n = N as f64;
    let q = |p: usize, r: usize| (n * t[p][r] / m - if p == r { 1.0 } else { 0.0 }) / (n - 1.0);
    let (order, director) = if N == 2 {
        let e = Matrix2::new(q(0, 0), q(0, 1), q(1, 0), q(1, 1)).symmetric_eigen();
        let k = e.eigenvalues.imax();
        let v = e.eigenvectors.column(k);
        (e.eigenvalues[k], [v[0], v[1], 0.0])
    } else {
        let e = Matrix3::from_fn(q).symmetric_eigen();
        let k = e.eigenvalues.imax();
        let v = e.eigenvectors.column(k);
        (e.eigenvalues[k], [v[0], v[1], v[2]])
    };
    let largest = director
        .iter()
        .copied()
        .fold(0.0_f64, |a, b| if b.abs() > a.abs() { b } else { a });
    let sign = if largest < 0.0 { -1.0 } else { 1.0 };
    Some(Nematic {
        axis,
        order,
        director: director.map(|v| v * sign),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn aligned_axes_have_order_one_along_their_director() {
        let bodies: Vec<Body<3>> = (0..10)
            .map(|i| {
                // Turned about the first axis only: it stays along x.
                let a = 0.3 * i as f64;
                let q = [(a / 2.0).cos(), (a / 2.0).sin(), 0.0, 0.0];
                Body::from_quaternion([i as f64, 0.0, 0.0], [2.0, 1.0, 0.5], q).unwrap()
            })
            .collect();
        let s = nematic_order(&bodies);
        assert!((s[0].order - 1.0).abs() < 1e-12);
        assert!((s[0].director[0] - 1.0).abs() < 1e-12);
        assert!(s[1].order < 1.0);
    }

    /// Balls define no axis; spheroids only their distinct one, whose order counts them alone.
    #[test]
    fn round_items_have_no_axes_and_spheroids_one() {
        let ball = Body::from_angles([0.0; 3], [1.0; 3], [0.0; 3]).unwrap();
        assert!(nematic_order(&[ball, ball]).is_empty());
        let along_z = Body::from_angles([0.0; 3], [1.0, 1.0, 2.0], [0.0; 3]).unwrap();
        let s = nematic_order(&[along_z, ball, along_z]);
        assert_eq!(s.len(), 1);
        assert_eq!(s[0].axis, 2);
        assert!((s[0].order - 1.0).abs() < 1e-12);
        assert!((s[0].director[2] - 1.0).abs() < 1e-12);
        let circle = Body::ellipse([0.0, 0.0], [1.0, 1.0], 0.0).unwrap();
        let ellipse = Body::ellipse([0.0, 0.0], [2.0, 1.0], 0.4).unwrap();
        assert_eq!(nematic_order(&[circle, ellipse]).len(), 2);
    }

    #[test]
    fn in_2d_s_is_the_modulus_of_the_mean_of_exp_2i_theta() {
        let angles = [0.1, 0.5, 1.3, 2.0, 2.9, 0.7];
        let bodies: Vec<Body<2>> = angles
            .iter()
            .map(|&t| Body::ellipse([0.0, 0.0], [2.0, 1.0], t).unwrap())
            .collect();
        let (c, s) = angles.iter().fold((0.0, 0.0), |(c, s), t: &f64| {
            (c + (2.0 * t).cos(), s + (2.0 * t).sin())
        });
        let expected = (c * c + s * s).sqrt() / angles.len() as f64;
        assert!((nematic_order(&bodies)[0].order - expected).abs() < 1e-12);
    }
}
