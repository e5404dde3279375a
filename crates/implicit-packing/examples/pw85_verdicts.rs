//! The verdict of the implicit-variable pair term against PW85 on many random pairs (default
//! 1e6; pass another count as the first argument), and the contact-scale agreement on every
//! tenth pair of moderate shapes (for stiff shapes PW85's input, the rounded matrix Q P Qᵀ, is
//! itself perturbed beyond 1e-12).
//!
//! `cargo run --release -p implicit-packing --example pw85_verdicts [pairs]`
//!
//! Pairs: semi-axes uniform in [0.2, 2] (three in four pairs) or log-uniform in [1e-2, 1e2],
//! uniformly random orientations, centre distance uniform in [0, r_i + r_j]. Pairs with
//! |μ² − 1| < 1e-12 are not counted (there the verdict is decided by the last bits of either
//! function).

use implicit_packing::derivatives::pair_derivatives;
use implicit_packing::{Body, Ellipsoid, overlap_measure};
use testkit::{Rng, shape::upper};

fn body(rng: &mut Rng, centre: [f64; 3], stiff: bool) -> Ellipsoid {
    let mut l = [0.0; 3];
    for v in l.iter_mut() {
        *v = if stiff {
            10f64.powf(4.0 * rng.uniform() - 2.0)
        } else {
            0.2 + 1.8 * rng.uniform()
        };
    }
    let q = rng.unit_quaternion();
    Body::from_quaternion(centre, l, q).expect("valid shape")
}

fn main() {
    let n: usize = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(1_000_000);
    let mut rng = Rng::new(0x00C0_FFEE);
    let (mut agree, mut disagree, mut skipped, mut overlapping) = (0usize, 0usize, 0usize, 0usize);
    let (mut scale_checked, mut scale_worst, mut scale_over) = (0usize, 0.0f64, 0usize);
    for k in 0..n {
        let stiff = k % 4 == 3;
        let i = body(&mut rng, [0.0; 3], stiff);
        let dir = rng.direction();
        let dist = rng.uniform() * (i.bounding_radius() + 2.0);
        let j0 = body(&mut rng, [0.0; 3], stiff);
        let dist = dist.min(i.bounding_radius() + j0.bounding_radius());
        let r12 = [dist * dir[0], dist * dir[1], dist * dir[2]];
        let j = j0.with_centre(r12).expect("valid centre");
        let mu2 = match pw85::contact_function(
            &r12,
            &upper(&i.shape_matrix()),
            &upper(&j.shape_matrix()),
        ) {
            Ok(c) => c.mu2,
            Err(e) => {
                eprintln!("pair {k}: pw85 error {e}");
                continue;
            }
        };
        if (mu2 - 1.0).abs() < 1e-12 {
            skipped += 1;
            continue;
        }
        let f = overlap_measure(&i, &j);
        if (f > 0.0) == (mu2 < 1.0) {
            agree += 1;
        } else {
            disagree += 1;
            eprintln!("pair {k}: f = {f:e}, mu2 = {mu2:e}\n  {i:?}\n  {j:?}");
        }
        overlapping += usize::from(mu2 < 1.0);
        // Contact scale on every 10th moderate pair: move c_j along r12 until d² = 1.
        if !stiff && k % 10 == 0 && dist > 1e-3 {
            let expect = 1.0 / mu2.sqrt();
            let at = |kappa: f64| {
                let c = [kappa * r12[0], kappa * r12[1], kappa * r12[2]];
                let d = pair_derivatives(&i, &j.with_centre(c).expect("valid centre"));
                let slope: f64 = (0..3).map(|a| d.grad_d2.centre_j[a] * r12[a]).sum();
                (d.d2, slope)
            };
            let mut kappa = expect * 1.01;
            for _ in 0..60 {
                let (d2, slope) = at(kappa);
                let step = (d2 - 1.0) / slope;
                kappa -= step;
                if step.abs() <= 1e-16 * kappa {
                    break;
                }
            }
            let e = (kappa - expect).abs() / expect;
            scale_worst = scale_worst.max(e);
            scale_over += usize::from(e > 1e-12);
            scale_checked += 1;
        }
    }
    println!(
        "{n} pairs: {agree} verdicts agree, {disagree} disagree, {skipped} within 1e-12 of tangency; {overlapping} overlapping"
    );
    println!(
        "contact scale on {scale_checked} moderate pairs: worst relative difference from 1/μ {scale_worst:.2e}, {scale_over} above 1e-12"
    );
    if disagree > 0 || scale_over > 0 {
        std::process::exit(1);
    }
}
