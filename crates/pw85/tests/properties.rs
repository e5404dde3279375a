//! Invariances, closed forms, gradients, the verdict, and robustness on arbitrary input.
#![allow(clippy::needless_range_loop)] // index loops read like the matrix algebra

use proptest::prelude::*;
use pw85::shape::{from_axes_angle_2d, from_axes_quaternion, rotation_from_quaternion};
use pw85::{Argument, Error, Sym3, contact_details, contact_function, overlap};
use testkit::Rng;

/// An ellipsoid with semi-axes spread over `max_aspect_decades` decades, built by pw85 itself
/// (the code under test) from a random rotation.
fn ellipsoid(rng: &mut Rng, max_aspect_decades: f64) -> Sym3 {
    let axes = core::array::from_fn(|_| 10f64.powf(rng.range(-max_aspect_decades, 0.0)));
    from_axes_quaternion(&axes, &rng.unit_quaternion()).unwrap()
}

/// A random unit vector: the first column of a random rotation.
fn direction(rng: &mut Rng) -> [f64; 3] {
    let r = rotation_from_quaternion(&rng.unit_quaternion()).unwrap();
    [r[0][0], r[1][0], r[2][0]]
}

/// Two random ellipsoids and a centre offset along a random direction, each component scaled
/// by its own draw from `distance`.
fn random_pair(
    rng: &mut Rng,
    max_aspect_decades: f64,
    distance: (f64, f64),
) -> (Sym3, Sym3, [f64; 3]) {
    let (q1, q2) = (
        ellipsoid(rng, max_aspect_decades),
        ellipsoid(rng, max_aspect_decades),
    );
    let r = direction(rng).map(|x| x * rng.range(distance.0, distance.1));
    (q1, q2, r)
}

fn rotate(q: &Sym3, r: &[[f64; 3]; 3]) -> Sym3 {
    let m = [[q[0], q[1], q[2]], [q[1], q[3], q[4]], [q[2], q[4], q[5]]];
    let e = |i: usize, j: usize| {
        let mut s = 0.0;
        for k in 0..3 {
            for l in 0..3 {
                s += r[i][k] * m[k][l] * r[j][l];
            }
        }
        s
    };
    [e(0, 0), e(0, 1), e(0, 2), e(1, 1), e(1, 2), e(2, 2)]
}

fn rel(a: f64, b: f64) -> f64 {
    ((a - b) / b).abs()
}

/// Runs `check` on `count` pairs from [`random_pair`] with the given spread, drawn from a
/// generator seeded with `seed` that `check` may draw from too.
fn each_random_pair(
    seed: u64,
    count: usize,
    max_aspect_decades: f64,
    distance: (f64, f64),
    mut check: impl FnMut(&mut Rng, Sym3, Sym3, [f64; 3]),
) {
    let mut rng = Rng::new(seed);
    for _ in 0..count {
        let (q1, q2, r) = random_pair(&mut rng, max_aspect_decades, distance);
        check(&mut rng, q1, q2, r);
    }
}

/// Asserts that `c` has the μ² of `base` within the relative tolerance `tol`; `what` names
/// the change between them.
fn assert_same_mu2(what: &str, c: pw85::Contact, base: pw85::Contact, tol: f64) {
    assert!(
        rel(c.mu2, base.mu2) < tol,
        "{what}: {} vs {}",
        c.mu2,
        base.mu2
    );
}

#[test]
fn spheres_have_the_closed_form() {
    let mut rng = Rng::new(1);
    for _ in 0..1000 {
        let (a1, a2) = (rng.range(0.01, 10.0), rng.range(0.01, 10.0));
        let q1 = pw85::spheroid(a1, a1, &[0.0, 0.0, 1.0]).unwrap();
        let q2 = pw85::spheroid(a2, a2, &[0.0, 0.0, 1.0]).unwrap();
        let r = direction(&mut rng).map(|x| x * rng.range(0.01, 30.0));
        let c = contact_function(&r, &q1, &q2).unwrap();
        let d = (r[0] * r[0] + r[1] * r[1] + r[2] * r[2]).sqrt();
        let mu = d / (a1 + a2);
        assert!(rel(c.mu2, mu * mu) < 1e-14, "{} vs {}", c.mu2, mu * mu);
        assert!((c.lambda - a1 / (a1 + a2)).abs() < 1e-8);
    }
}

#[test]
fn invariant_under_rotation_scaling_swap_and_translation() {
    each_random_pair(2, 2000, 1.0, (0.1, 4.0), |rng, q1, q2, r| {
        let base = contact_function(&r, &q1, &q2).unwrap();

        let rot = rotation_from_quaternion(&rng.unit_quaternion()).unwrap();
        let rr: [f64; 3] = core::array::from_fn(|i| (0..3).map(|k| rot[i][k] * r[k]).sum());
        let c = contact_function(&rr, &rotate(&q1, &rot), &rotate(&q2, &rot)).unwrap();
        assert_same_mu2("rotation", c, base, 1e-13);

        let (r_nu, q1_nu, q2_nu) = scaled(rng.range(1e-3, 1e3), r, q1, q2);
        let c = contact_function(&r_nu, &q1_nu, &q2_nu).unwrap();
        assert_same_mu2("scaling", c, base, 1e-13);

        let c = contact_function(&r.map(|x| -x), &q2, &q1).unwrap();
        assert_same_mu2("swap", c, base, 1e-14);
        assert!((c.lambda - (1.0 - base.lambda)).abs() < 1e-7, "swap: λ");

        // Translating both centres: r12 = (c2 + t) − (c1 + t), rounded.
        let t = direction(rng).map(|x| 10.0 * x);
        let c1 = direction(rng);
        let c2: [f64; 3] = core::array::from_fn(|k| c1[k] + r[k]);
        let moved: [f64; 3] = core::array::from_fn(|k| (c2[k] + t[k]) - (c1[k] + t[k]));
        let direct: [f64; 3] = core::array::from_fn(|k| c2[k] - c1[k]);
        let a = contact_function(&moved, &q1, &q2).unwrap();
        let b = contact_function(&direct, &q1, &q2).unwrap();
        // Only the rounding of the translated centres (≈ 1e-15 · 10 / |r|) separates them.
        assert_same_mu2("translation", a, b, 1e-13);
    });
}

#[test]
fn coincident_centres_give_zero() {
    let q1 = from_axes_quaternion(&[1.0, 2.0, 3.0], &[1.0, 0.2, 0.0, 0.1]).unwrap();
    let q2 = from_axes_quaternion(&[0.5, 0.2, 3.0], &[0.3, 0.2, 0.9, 0.1]).unwrap();
    let c = contact_function(&[0.0; 3], &q1, &q2).unwrap();
    assert_eq!(c.mu2, 0.0);
    assert!((0.0..=1.0).contains(&c.lambda));
    assert!(overlap(&[0.0; 3], &q1, &q2).unwrap());
}

#[test]
fn overlap_agrees_with_mu2_including_near_tangency() {
    let mut rng = Rng::new(3);
    let mut decided = 0;
    for i in 0..20_000 {
        let (q1, q2) = (ellipsoid(&mut rng, 2.0), ellipsoid(&mut rng, 2.0));
        let dir = direction(&mut rng);
        let unit = contact_function(&dir, &q1, &q2).unwrap();
        // Place the pair at μ² = target: μ² scales with |r|².
        let target = match i % 4 {
            0 => rng.range(0.2, 5.0),
            1 => 1.0 + rng.range(-1e-6, 1e-6),
            2 => 1.0 + rng.range(-1e-10, 1e-10),
            _ => 1.0 + rng.range(-1e-3, 1e-3),
        };
        let r = dir.map(|x| x * (target / unit.mu2).sqrt());
        let c = contact_function(&r, &q1, &q2).unwrap();
        if (c.mu2 - 1.0).abs() <= 4.0 * c.error_estimate.max(1e-15) {
            continue;
        }
        decided += 1;
        assert_eq!(
            overlap(&r, &q1, &q2).unwrap(),
            c.mu2 < 1.0,
            "pair {i}: μ² = {}",
            c.mu2
        );
    }
    assert!(decided > 19_000);
}

/// The central difference of `f` at `x` along coordinate `k`, with step 1e-6.
fn central_difference<const K: usize>(x: [f64; K], k: usize, f: impl Fn(&[f64; K]) -> f64) -> f64 {
    let h = 1e-6;
    let (mut p, mut m) = (x, x);
    p[k] += h;
    m[k] -= h;
    (f(&p) - f(&m)) / (2.0 * h)
}

#[test]
fn gradients_match_central_differences() {
    each_random_pair(4, 300, 0.7, (0.3, 3.0), |_, q1, q2, r| {
        let d = contact_details(&r, &q1, &q2).unwrap();
        let mu2 = |r: &[f64; 3], q1: &Sym3, q2: &Sym3| contact_function(r, q1, q2).unwrap().mu2;
        for k in 0..3 {
            let fd = central_difference(r, k, |p| mu2(p, &q1, &q2));
            assert!(
                (fd - d.grad_r12[k]).abs() < 1e-6 * (1.0 + fd.abs()),
                "∂/∂r[{k}]"
            );
        }
        for k in 0..6 {
            let fd = central_difference(q1, k, |p| mu2(&r, p, &q2));
            assert!(
                (fd - d.grad_q1[k]).abs() < 1e-6 * (1.0 + fd.abs()),
                "∂/∂q1[{k}]"
            );
            let fd = central_difference(q2, k, |p| mu2(&r, &q1, p));
            assert!(
                (fd - d.grad_q2[k]).abs() < 1e-6 * (1.0 + fd.abs()),
                "∂/∂q2[{k}]"
            );
        }
        // The contact point lies on both ellipsoids scaled by μ (eq. 14), with a common normal.
        let x1 = d.point;
        let x2: [f64; 3] = core::array::from_fn(|k| x1[k] - r[k]);
        let inv_form = |q: &Sym3, x: &[f64; 3]| {
            let s = pw85::sym::solve_ldlt(q, x).unwrap();
            x[0] * s[0] + x[1] * s[1] + x[2] * s[2]
        };
        let mu2v = d.contact.mu2;
        assert!(rel(inv_form(&q1, &x1), mu2v) < 1e-12);
        assert!(rel(inv_form(&q2, &x2), mu2v) < 1e-12);
        let n1 = pw85::sym::solve_ldlt(&q1, &x1).unwrap();
        let norm = (n1[0] * n1[0] + n1[1] * n1[1] + n1[2] * n1[2]).sqrt();
        for k in 0..3 {
            assert!((n1[k] / norm - d.normal[k]).abs() < 1e-10);
        }
    });
}

#[test]
fn two_d_equals_the_3d_embedding() {
    let mut rng = Rng::new(5);
    for _ in 0..2000 {
        let a = [rng.range(0.01, 3.0), rng.range(0.01, 3.0)];
        let b = [rng.range(0.01, 3.0), rng.range(0.01, 3.0)];
        let (ta, tb) = (rng.range(-3.0, 3.0), rng.range(-3.0, 3.0));
        let (q1, q2) = (
            from_axes_angle_2d(&a, ta).unwrap(),
            from_axes_angle_2d(&b, tb).unwrap(),
        );
        let r = [rng.range(-5.0, 5.0), rng.range(-5.0, 5.0)];
        let c2 = contact_function(&r, &q1, &q2).unwrap();
        // Any common extent along z leaves μ² unchanged: Q(λ) is block diagonal.
        let z = rng.range(0.1, 2.0);
        let e = |q: &[f64; 3]| [q[0], q[1], 0.0, q[2], 0.0, z];
        let c3 = contact_function(&[r[0], r[1], 0.0], &e(&q1), &e(&q2)).unwrap();
        assert!(rel(c2.mu2, c3.mu2) < 1e-13, "{} vs {}", c2.mu2, c3.mu2);
        assert!((c2.lambda - c3.lambda).abs() < 1e-7);
        if (c2.mu2 - 1.0).abs() > 1e-12 {
            assert_eq!(overlap(&r, &q1, &q2).unwrap(), c2.mu2 < 1.0);
        }
    }
}

/// Every one of the fifteen inputs, made NaN, +∞ or −∞ in turn, is named by its argument and
/// index, by the contact function and by the overlap test (the fast probe reads the inputs as
/// overlapping vectors; none may be missed).
#[test]
fn every_non_finite_input_is_named() {
    let q1 = [2.0, 0.1, 0.2, 1.5, 0.3, 1.0];
    let q2 = [1.0, -0.1, 0.0, 2.0, 0.2, 3.0];
    let r = [1.0, 2.0, -0.5];
    for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        for position in 0..15 {
            let (mut r, mut q1, mut q2) = (r, q1, q2);
            let (argument, index) = match position {
                0..3 => (Argument::R12, position),
                3..9 => (Argument::Q1, position - 3),
                _ => (Argument::Q2, position - 9),
            };
            match position {
                0..3 => r[index] = bad,
                3..9 => q1[index] = bad,
                _ => q2[index] = bad,
            }
            for result in both_results(&r, &q1, &q2) {
                assert_eq!(
                    refusal(&result),
                    Some(Refusal::NonFinite(argument, index)),
                    "{bad} at {position}: {result:?}"
                );
            }
        }
    }
    assert!(contact_function(&r, &q1, &q2).is_ok());
}

/// The results of the contact function and of the overlap test on one pair, without their
/// values, so that a test can check that both refuse it alike.
fn both_results(r: &[f64; 3], q1: &Sym3, q2: &Sym3) -> [Result<(), Error>; 2] {
    [
        contact_function(r, q1, q2).map(|_| ()),
        overlap(r, q1, q2).map(|_| ()),
    ]
}

/// The refusals whose argument and position the tests check, without the offending value.
#[derive(Debug, PartialEq)]
enum Refusal {
    /// `Error::NonFinite`: the argument and the index of the entry.
    NonFinite(Argument, usize),
    /// `Error::NotPositiveDefinite`: the argument and the order of the failing minor.
    NotPositiveDefinite(Argument, usize),
}

/// The refusal of `result`; `None` for an answer or any other error.
fn refusal<T>(result: &Result<T, Error>) -> Option<Refusal> {
    match result {
        Err(Error::NonFinite {
            argument, index, ..
        }) => Some(Refusal::NonFinite(*argument, *index)),
        Err(Error::NotPositiveDefinite {
            argument, minor, ..
        }) => Some(Refusal::NotPositiveDefinite(*argument, *minor)),
        _ => None,
    }
}

#[test]
fn bad_input_gives_typed_errors() {
    let q = [1.0, 0.0, 0.0, 1.0, 0.0, 1.0];
    let r = [1.0, 0.0, 0.0];
    let mut bad = q;
    bad[4] = f64::NAN;
    assert_eq!(
        refusal(&contact_function(&r, &q, &bad)),
        Some(Refusal::NonFinite(Argument::Q2, 4))
    );
    assert_eq!(
        refusal(&overlap(&[0.0, f64::INFINITY, 0.0], &q, &q)),
        Some(Refusal::NonFinite(Argument::R12, 1))
    );
    // Each leading minor in turn.
    let cases: [(Sym3, usize); 4] = [
        ([-1.0, 0.0, 0.0, 1.0, 0.0, 1.0], 1),
        ([1.0, 2.0, 0.0, 1.0, 0.0, 1.0], 2),
        ([1.0, 0.0, 0.0, 1.0, 2.0, 1.0], 3),
        ([0.0; 6], 1),
    ];
    for (m, minor) in cases {
        for result in both_results(&r, &m, &q) {
            assert_eq!(
                refusal(&result),
                Some(Refusal::NotPositiveDefinite(Argument::Q1, minor)),
                "{m:?}: {result:?}"
            );
        }
    }
    // Singular by one ulp: rank-one needle plus a perturbation below f64 resolution of det.
    let singular = [1.0, 1.0, 1.0, 1.0, 1.0, 1.0];
    assert_eq!(
        refusal(&contact_function(&r, &q, &singular)),
        Some(Refusal::NotPositiveDefinite(Argument::Q2, 2))
    );
    assert_eq!(
        refusal(&contact_function(
            &[1.0, 0.0],
            &[1.0, 1.0, 1.0],
            &[1.0, 0.0, 1.0]
        )),
        Some(Refusal::NotPositiveDefinite(Argument::Q1, 2))
    );
    let message = contact_function(&r, &[1.0, 2.0, 0.0, 1.0, 0.0, 1.0], &q)
        .unwrap_err()
        .to_string();
    assert!(
        message.contains("Q1") && message.contains("order 2"),
        "{message}"
    );
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]

    #[test]
    fn no_finite_input_panics(
        r in prop::array::uniform3(-1e6f64..1e6),
        q1 in prop::array::uniform6(-1e3f64..1e3),
        q2 in prop::array::uniform6(-1e3f64..1e3),
    ) {
        let c = contact_function(&r, &q1, &q2);
        let v = overlap(&r, &q1, &q2);
        prop_assert_eq!(c.is_ok(), v.is_ok());
        if let (Ok(c), Ok(v)) = (c, v) {
            prop_assert!((0.0..=1.0).contains(&c.lambda));
            prop_assert!(c.mu2 >= 0.0);
            if (c.mu2 - 1.0).abs() > 1e-9 {
                prop_assert_eq!(v, c.mu2 < 1.0);
            }
        }
    }

    #[test]
    fn every_spd_input_gives_lambda_in_unit_interval(
        axes1 in prop::array::uniform3(1e-4f64..1e2),
        axes2 in prop::array::uniform3(1e-4f64..1e2),
        quat1 in prop::array::uniform4(-1f64..1.0),
        quat2 in prop::array::uniform4(-1f64..1.0),
        r in prop::array::uniform3(-1e3f64..1e3),
    ) {
        prop_assume!(quat1.iter().any(|x| x.abs() > 1e-3) && quat2.iter().any(|x| x.abs() > 1e-3));
        let q1 = from_axes_quaternion(&axes1, &quat1).unwrap();
        let q2 = from_axes_quaternion(&axes2, &quat2).unwrap();
        // The rounded Q of very flat shapes may not be positive definite; that is an error,
        // never a panic or a wrong number.
        if let Ok(c) = contact_function(&r, &q1, &q2) {
            prop_assert!((0.0..=1.0).contains(&c.lambda));
            prop_assert!(c.mu2 >= 0.0 && c.mu2.is_finite());
        }
    }
}

#[test]
fn refined_path_agrees_with_the_fast_path_within_its_bound() {
    each_random_pair(6, 2000, 1.5, (0.05, 5.0), |_, q1, q2, r| {
        let fast = contact_function(&r, &q1, &q2).unwrap();
        let exact = pw85::contact_function_refined(&r, &q1, &q2).unwrap();
        assert!(exact.refined);
        assert!(exact.error_estimate < 1e-15, "{}", exact.error_estimate);
        // The fast path's error is within its own estimate (the estimate is a bound).
        assert!(
            rel(fast.mu2, exact.mu2) <= fast.error_estimate + exact.error_estimate,
            "{} vs {} (estimate {:e})",
            fast.mu2,
            exact.mu2,
            fast.error_estimate
        );
    });
}

/// A pair on which the Halley iteration once stopped at its start: there h = p/V has h′ ≈ 0,
/// so Halley's step was tiny although p was far from 0, and λ = 0.559 came back instead of
/// 0.256 (found by `cargo xtask validate` among 1e6 pairs). Checked against the Brent baseline.
#[test]
fn halley_does_not_stop_where_the_derivative_vanishes() {
    let r = [
        0.36007638574278555,
        -0.27269395417913356,
        -0.18166772753057847,
    ];
    let q1 = [
        0.12134042233143592,
        0.03171636396136718,
        0.08771842837997272,
        0.9634352483507153,
        0.17423796180249643,
        0.10269523694701543,
    ];
    let q2 = [
        0.5991991576797356,
        0.29725195532654075,
        0.34627790835768774,
        0.1601445579602266,
        0.16876727761160956,
        0.4084151448558676,
    ];
    let c = pw85::contact_function(&r, &q1, &q2).unwrap();
    let b = pw85::baseline::brent(&r, &q1, &q2, 1e-14);
    assert!(
        (c.mu2 - b.mu2).abs() <= 1e-13 * b.mu2,
        "{c:?} against {b:?}"
    );
    assert!((c.lambda - b.lambda).abs() <= 1e-6, "{c:?} against {b:?}");
    // In every lane of a four-pair chunk (a single pair would take the scalar remainder path).
    let other = pw85::batch::Pair {
        r12: [1.0, 2.0, 0.5],
        q1,
        q2,
    };
    for lane in 0..4 {
        let mut chunk = [other; 4];
        chunk[lane] = pw85::batch::Pair { r12: r, q1, q2 };
        let batch = contacts(&chunk);
        assert_eq!(
            format!("{:?}", batch[lane]),
            format!("{:?}", Ok::<_, Error>(c))
        );
    }
}

/// Scaling r12 by a power of two ν and the matrices by ν² is exact, and μ² and λ do not
/// change. The solver works on the coefficients as they are where their scale is moderate and
/// normalises them where it is not; the two must give the same bits (the normalisation
/// is exact too). ν = 2^±11 and beyond take the normalised path, 2^±5 the other.
/// r scaled by ν and the two matrices by ν², in 3D or 2D.
fn scaled<const D: usize, const S: usize>(
    nu: f64,
    r: [f64; D],
    q1: [f64; S],
    q2: [f64; S],
) -> ([f64; D], [f64; S], [f64; S]) {
    let square = |q: [f64; S]| q.map(|x| nu * nu * x);
    (r.map(|x| nu * x), square(q1), square(q2))
}

#[test]
fn power_of_two_scalings_give_the_same_bits() {
    let mut rng = Rng::new(0x5CA1E);
    let bits = |c: pw85::Contact| (c.mu2.to_bits(), c.lambda.to_bits(), c.refined);
    for i in 0..1000 {
        let decades = [0.5, 2.0, 4.0][i % 3];
        let (q1, q2, r) = random_pair(&mut rng, decades, (0.05, 5.0));
        let base = bits(contact_function(&r, &q1, &q2).unwrap());
        let angle = rng.range(0.0, 6.3);
        let e1 = from_axes_angle_2d(&[1.0, 10f64.powf(-decades)], angle).unwrap();
        let e2 = from_axes_angle_2d(&[0.3, 0.2], -angle).unwrap();
        let r2 = [r[0], r[1]];
        let base_2d = bits(contact_function(&r2, &e1, &e2).unwrap());
        for k in [-60, -24, -11, -5, 5, 11, 24, 60] {
            let nu = 2f64.powi(k);
            let (r, q1, q2) = scaled(nu, r, q1, q2);
            assert_eq!(
                bits(contact_function(&r, &q1, &q2).unwrap()),
                base,
                "ν = 2^{k}"
            );
            let (r2, e1, e2) = scaled(nu, r2, e1, e2);
            assert_eq!(
                bits(contact_function(&r2, &e1, &e2).unwrap()),
                base_2d,
                "2D, ν = 2^{k}"
            );
        }
    }
}

/// The two shapes and the centre distance of extreme pair `i`: `shape` draws each shape with
/// its axes spread over 0.5, 2, 4 or 8 decades (by `i`), the first shape of every third pair is
/// scaled by 10^U (U uniform in [−6, 6]), and the distance is log-uniform in [1e-4, 1e2].
fn extreme_shapes<const S: usize>(
    rng: &mut Rng,
    i: usize,
    shape: impl Fn(&mut Rng, f64) -> [f64; S],
) -> ([f64; S], [f64; S], f64) {
    let decades = [0.5, 2.0, 4.0, 8.0][i % 4];
    let size = 10f64.powf(rng.range(-6.0, 6.0) * f64::from(i.is_multiple_of(3)));
    let q1 = shape(rng, decades).map(|x| x * size * size);
    let q2 = shape(rng, decades);
    (q1, q2, 10f64.powf(rng.range(-4.0, 2.0)))
}

/// The 2D batch (lane-wise solve shared with 3D) equals `contact_function` on ellipses bit for bit,
/// typed errors, coincident centres, refinements and extreme shapes included.
#[test]
fn batch_2d_equals_scalar_bit_for_bit() {
    let mut rng = Rng::new(0x2D_BA7C);
    let pairs: Vec<pw85::batch::Pair2d> = (0..20_003)
        .map(|i| {
            let (mut q1, q2, dist) = extreme_shapes(&mut rng, i, |rng, decades| {
                let axes = [0, 1].map(|_| 10f64.powf(rng.range(-decades, 0.0)));
                from_axes_angle_2d(&axes, rng.range(0.0, 6.3)).unwrap()
            });
            let angle = rng.range(0.0, 6.3);
            let mut r12 = [dist * angle.cos(), dist * angle.sin()];
            match i % 101 {
                3 => q1[1] = 10.0 * q1[0].max(q1[2]), // not positive definite
                5 => r12[1] = f64::INFINITY,          // not finite
                7 => r12 = [0.0; 2],                  // coincident
                _ => {}
            }
            pw85::batch::Pair2d { r12, q1, q2 }
        })
        .collect();
    let batch = contacts(&pairs);
    let verdicts = verdicts(&pairs);
    let (mut refined, mut errors) = (0, 0);
    for ((p, b), v) in pairs.iter().zip(&batch).zip(&verdicts) {
        let s = contact_function(&p.r12, &p.q1, &p.q2);
        refined += usize::from(s.is_ok_and(|c| c.refined));
        errors += usize::from(s.is_err());
        assert_eq!(format!("{s:?}"), format!("{b:?}"), "{p:?}");
        assert_eq!(
            format!("{:?}", overlap(&p.r12, &p.q1, &p.q2)),
            format!("{v:?}")
        );
    }
    assert!(refined > 100, "only {refined} refined pairs");
    assert!(errors >= 2 * 198, "only {errors} errors");
}

/// The four-lane path (branch-free step rule, `lanes::OddsSearch4`) equals the scalar one bit
/// for bit where the scalar rule takes its rare branches: aspect ratios up to 1e8 and size
/// ratios up to 1e12 (bracket expansion and contraction, geometric bisection, the λ fallback,
/// refinement), centre distances from deep overlap to far apart, lanes mixed at random.
#[test]
fn batch_equals_scalar_bit_for_bit_on_extreme_pairs() {
    let mut rng = Rng::new(0x0BA7_C4E5);
    let pairs: Vec<pw85::batch::Pair> = (0..20_000)
        .map(|i| {
            let (q1, q2, dist) = extreme_shapes(&mut rng, i, ellipsoid);
            pw85::batch::Pair {
                r12: direction(&mut rng).map(|x| x * dist),
                q1,
                q2,
            }
        })
        .collect();
    let batch = contacts(&pairs);
    let mut refined = 0;
    for (p, b) in pairs.iter().zip(&batch) {
        let s = contact_function(&p.r12, &p.q1, &p.q2);
        refined += usize::from(s.is_ok_and(|c| c.refined));
        assert_eq!(format!("{s:?}"), format!("{b:?}"), "{p:?}");
    }
    // The set exercises the rare paths, not only the ordinary one.
    assert!(refined > 100, "only {refined} refined pairs");
}

/// x · 2^e for any e (two steps where 2^e alone is not a double): exact unless the result
/// overflows or is subnormal.
fn times_power_of_two(x: f64, e: i32) -> f64 {
    let half = e / 2;
    x * 2f64.powi(half) * 2f64.powi(e - half)
}

/// The checks of one scaled pair against its unscaled contact `base`: μ² scaled by 2^`mu2_shift`
/// exactly (or +∞ with the verdict "apart" beyond the double range, or within the subnormal
/// range's absolute resolution with the verdict "overlap"), λ bit-identical, and `overlap`
/// agreeing.
/// Whether every entry survives x → x · 2^e → x (no rounding into the subnormal range): then
/// the scaled pair is exactly the scaled geometry.
fn exactly_scaled(xs: &[f64], e: i32) -> bool {
    xs.iter()
        .all(|&x| times_power_of_two(times_power_of_two(x, e), -e) == x)
}

fn assert_scaled(
    what: &str,
    base: pw85::Contact,
    mu2_shift: i32,
    contact: Result<pw85::Contact, Error>,
    verdict: Result<bool, Error>,
) {
    let c = contact.unwrap_or_else(|e| panic!("{what}: {e}"));
    let v = verdict.unwrap_or_else(|e| panic!("{what}: overlap: {e}"));
    let expected = times_power_of_two(base.mu2, mu2_shift);
    assert!(!c.mu2.is_nan(), "{what}: NaN");
    if expected >= f64::MIN_POSITIVE {
        assert_eq!(
            c.mu2.to_bits(),
            expected.to_bits(),
            "{what}: μ² {} vs {expected}",
            c.mu2
        );
        assert_eq!(c.lambda.to_bits(), base.lambda.to_bits(), "{what}: λ");
    } else {
        assert!(
            (c.mu2 - expected).abs() <= f64::MIN_POSITIVE,
            "{what}: μ² {} vs {expected}",
            c.mu2
        );
    }
    if expected == f64::INFINITY {
        assert!(!v, "{what}: an infinite μ² is apart");
    }
    if (expected - 1.0).abs() > 1e-12 {
        assert_eq!(v, expected < 1.0, "{what}: verdict at μ² = {expected}");
    }
}

/// μ² is invariant under r12 → ν r12, Q → ν² Q, and scales as s² under r12 → s r12: with powers
/// of two both are exact, so every finite double gives the unscaled pair's bits (scaled), or
/// +∞ / a subnormal where the true μ² leaves the double range. Uniform scalings across
/// 2^±500 (ν² = 2^±1000), r12 alone across 2^±1000, both matrices alone across 2^±1000; the
/// scalar, overlap, 2D and batch forms.
#[test]
fn every_power_of_two_scaling_across_the_double_range_is_exact() {
    let mut rng = Rng::new(0x0E87_E0E5);
    let mut pairs = Vec::new();
    let mut pairs_2d = Vec::new();
    for i in 0..120 {
        let decades = [0.5, 2.0, 4.0][i % 3];
        let (q1, q2, r) = random_pair(&mut rng, decades, (0.05, 5.0));
        let base = contact_function(&r, &q1, &q2).unwrap();
        let angle = rng.range(0.0, 6.3);
        let e1 = from_axes_angle_2d(&[1.0, 10f64.powf(-decades)], angle).unwrap();
        let e2 = from_axes_angle_2d(&[0.3, 0.2], -angle).unwrap();
        let r2 = [r[0], r[1]];
        let base_2d = contact_function(&r2, &e1, &e2).unwrap();
        for k in [
            -500, -400, -300, -241, -200, -120, 120, 200, 241, 300, 400, 500,
        ] {
            let exact = exactly_scaled(&r, k)
                && exactly_scaled(&q1, 2 * k)
                && exactly_scaled(&q2, 2 * k)
                && exactly_scaled(&e1, 2 * k)
                && exactly_scaled(&e2, 2 * k);
            if !exact {
                continue;
            }
            let nu = times_power_of_two(1.0, k);
            let (rs, a, b) = scaled(nu, r, q1, q2);
            let what = format!("pair {i}, ν = 2^{k}");
            assert_scaled(
                &what,
                base,
                0,
                contact_function(&rs, &a, &b),
                overlap(&rs, &a, &b),
            );
            let (rs2, a2, b2) = scaled(nu, r2, e1, e2);
            assert_scaled(
                &format!("2D {what}"),
                base_2d,
                0,
                contact_function(&rs2, &a2, &b2),
                overlap(&rs2, &a2, &b2),
            );
            pairs.push(pw85::batch::Pair {
                r12: rs,
                q1: a,
                q2: b,
            });
            pairs_2d.push(pw85::batch::Pair2d {
                r12: rs2,
                q1: a2,
                q2: b2,
            });
        }
        for k in [
            -1000, -700, -540, -300, -100, 100, 300, 511, 512, 513, 700, 1000,
        ] {
            if !(exactly_scaled(&r, k)
                && exactly_scaled(&q1, k)
                && exactly_scaled(&q2, k)
                && exactly_scaled(&r2, k))
            {
                continue;
            }
            let rs = r.map(|x| times_power_of_two(x, k));
            let what = format!("pair {i}, r12 · 2^{k}");
            assert_scaled(
                &what,
                base,
                2 * k,
                contact_function(&rs, &q1, &q2),
                overlap(&rs, &q1, &q2),
            );
            let (a, b) = (
                q1.map(|x| times_power_of_two(x, k)),
                q2.map(|x| times_power_of_two(x, k)),
            );
            let what = format!("pair {i}, Q · 2^{k}");
            assert_scaled(
                &what,
                base,
                -k,
                contact_function(&r, &a, &b),
                overlap(&r, &a, &b),
            );
            let rs2 = r2.map(|x| times_power_of_two(x, k));
            assert_scaled(
                &format!("2D {what}"),
                base_2d,
                2 * k,
                contact_function(&rs2, &e1, &e2),
                overlap(&rs2, &e1, &e2),
            );
            pairs.push(pw85::batch::Pair { r12: rs, q1, q2 });
            pairs_2d.push(pw85::batch::Pair2d {
                r12: rs2,
                q1: e1,
                q2: e2,
            });
        }
    }
    // Most scalings keep every input bit (the others are skipped above).
    assert!(pairs.len() > 2000, "{} scaled pairs", pairs.len());
    // The batches: the scalar function's bits, lane by lane, whatever their neighbours.
    let batch = contacts(&pairs);
    let batch_2d = contacts(&pairs_2d);
    let verdicts = verdicts(&pairs);
    for (k, p) in pairs.iter().enumerate() {
        let scalar = contact_function(&p.r12, &p.q1, &p.q2).unwrap();
        let lane = batch[k].unwrap();
        assert_eq!(lane.mu2.to_bits(), scalar.mu2.to_bits(), "batch lane {k}");
        assert_eq!(
            lane.lambda.to_bits(),
            scalar.lambda.to_bits(),
            "batch lane {k}"
        );
        assert_eq!(
            verdicts[k],
            overlap(&p.r12, &p.q1, &p.q2),
            "batch verdict {k}"
        );
        let p2 = &pairs_2d[k];
        let scalar_2d = contact_function(&p2.r12, &p2.q1, &p2.q2).unwrap();
        assert_eq!(
            batch_2d[k].unwrap().mu2.to_bits(),
            scalar_2d.mu2.to_bits(),
            "2D lane {k}"
        );
    }
}

/// The cases of the issue that found the double range's edges, with their closed forms: unit
/// spheres 1e155·√2 apart (μ² beyond the double range: +∞, apart), spheres of radius 1e-52 at
/// 3e-52, and spheres whose Q is 1e±104, 1e±110, 1e±308 times the identity.
#[test]
fn spheres_at_the_edges_of_the_double_range() {
    let sphere = |q: f64| [q, 0.0, 0.0, q, 0.0, q];
    let unit = sphere(1.0);
    for r in [
        [1e155, 1e155, 0.0],
        [1e155, 0.0, 0.0],
        [1e300, 0.0, 0.0],
        [f64::MAX, f64::MAX, f64::MAX],
    ] {
        let c = contact_function(&r, &unit, &unit).unwrap();
        assert_eq!(c.mu2, f64::INFINITY, "{r:?}");
        assert!(!overlap(&r, &unit, &unit).unwrap(), "{r:?}");
    }
    for (radius, distance) in [
        (1e-52, 3e-52),
        (1e52, 3e52),
        (1e-154, 3e-154),
        (1e154, 3e154),
        (1e-160, 1e-161),
    ] {
        let q = sphere(radius * radius);
        let r = [distance, 0.0, 0.0];
        // From the stored Q (a subnormal radius² keeps only part of its digits).
        let exact = (distance / (2.0 * q[0].sqrt())).powi(2);
        let c = contact_function(&r, &q, &q).unwrap();
        assert!(
            rel(c.mu2, exact) < 1e-13,
            "radius {radius:e}: μ² = {} vs {exact}",
            c.mu2
        );
        assert_eq!(overlap(&r, &q, &q).unwrap(), exact < 1.0);
        let q2d = [q[0], 0.0, q[0]];
        let c = contact_function(&[distance, 0.0], &q2d, &q2d).unwrap();
        assert!(
            rel(c.mu2, exact) < 1e-13,
            "2D radius {radius:e}: μ² = {}",
            c.mu2
        );
    }
    for s in [1e104, 1e-110, 1e308, 1e-308, f64::MAX, f64::MIN_POSITIVE] {
        let q = sphere(s);
        let r = [3.0 * s.sqrt(), 0.0, 0.0];
        let c = contact_function(&r, &q, &q).unwrap_or_else(|e| panic!("Q = {s:e} I: {e}"));
        assert!(rel(c.mu2, 2.25) < 1e-13, "Q = {s:e} I: μ² = {}", c.mu2);
        assert!(!overlap(&r, &q, &q).unwrap());
    }
}

/// A second ellipsoid 10^k times smaller than the first, k up to 150 (and the first one
/// smaller): μ² = d² / (R1 + R2)² to 1e-13 at every ratio. The λ iteration used to start from
/// λ = 1 / (1 + ρ) rounded to 1 and stopped at λ = 1 − 2⁻²⁷ from k = 16 on.
#[test]
fn size_ratios_up_to_1e150_keep_mu2_exact() {
    for k in 0..=150 {
        let rho = 10f64.powi(-k);
        let (big, small) = (
            [1.0, 0.0, 0.0, 1.0, 0.0, 1.0],
            [rho * rho, 0.0, 0.0, rho * rho, 0.0, rho * rho],
        );
        let exact = 9.0 / ((1.0 + rho) * (1.0 + rho));
        let r = [3.0, 0.0, 0.0];
        for (what, q1, q2) in [("small second", big, small), ("small first", small, big)] {
            let c = contact_function(&r, &q1, &q2).unwrap_or_else(|e| panic!("10^-{k}: {e}"));
            assert!(
                rel(c.mu2, exact) < 1e-13,
                "{what}, 10^-{k}: μ² = {} vs {exact}",
                c.mu2
            );
            assert!(!overlap(&r, &q1, &q2).unwrap());
        }
        let (b2, s2) = ([1.0, 0.0, 1.0], [rho * rho, 0.0, rho * rho]);
        let c = contact_function(&[3.0, 0.0], &b2, &s2).unwrap();
        assert!(rel(c.mu2, exact) < 1e-13, "2D 10^-{k}: μ² = {}", c.mu2);
    }
}

/// Valid matrices whose determinants leave the double range are not refused: positive
/// definiteness is decided on each matrix balanced by its own diagonal. A matrix that is not
/// positive definite is still refused at every scale, naming the failing minor.
#[test]
fn positive_definiteness_is_decided_whatever_the_units() {
    let r = [1.0, 0.5, 0.25];
    for e in [-1000, -600, -300, 300, 600, 1000] {
        let s = times_power_of_two(1.0, e);
        let q: Sym3 = [2.0, 0.5, 0.1, 1.0, 0.2, 3.0].map(|x| x * s);
        let rs = r.map(|x| x * times_power_of_two(1.0, e / 2));
        let c = contact_function(&rs, &q, &q).unwrap_or_else(|err| panic!("2^{e}: {err}"));
        assert!(c.mu2.is_finite() && c.mu2 > 0.0, "2^{e}");
        let not: Sym3 = [1.0, 2.0, 0.0, 1.0, 0.0, 1.0].map(|x| x * s);
        let err = contact_function(&rs, &q, &not).unwrap_err();
        assert!(
            matches!(
                err,
                Error::NotPositiveDefinite {
                    argument: Argument::Q2,
                    minor: 2,
                    ..
                }
            ),
            "2^{e}: {err}"
        );
        assert_eq!(overlap(&rs, &q, &not).unwrap_err(), err);
    }
    // Axes 2^±300 apart on the axes: det Q = 2^−1200 · … underflows, the matrix is valid.
    let q: Sym3 = [
        times_power_of_two(1.0, 600),
        0.0,
        0.0,
        times_power_of_two(1.0, -600),
        0.0,
        1.0,
    ];
    let c = contact_function(&[0.0, 0.0, 4.0], &q, &q).unwrap();
    assert!(rel(c.mu2, 4.0) < 1e-13, "μ² = {}", c.mu2);
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 3000, failure_persistence: None, ..ProptestConfig::default() })]

    /// Random finite doubles of every exponent into every entry: never a panic, never NaN;
    /// an answer or a typed refusal, the verdict agreeing with μ², and the answer unchanged
    /// (to the bit) under a uniform power-of-two rescaling that keeps the pair representable.
    #[test]
    fn finite_doubles_of_every_exponent(
        mantissas in prop::array::uniform15(-1.0f64..1.0),
        exponents in prop::array::uniform15(-340i32..340),
        shift in -120i32..120,
    ) {
        let x: [f64; 15] = core::array::from_fn(|i| times_power_of_two(mantissas[i], exponents[i]));
        let r = [x[0], x[1], x[2]];
        let q1: Sym3 = core::array::from_fn(|i| x[3 + i]);
        let q2: Sym3 = core::array::from_fn(|i| x[9 + i]);
        let c = contact_function(&r, &q1, &q2);
        let v = overlap(&r, &q1, &q2);
        prop_assert_eq!(c.is_ok(), v.is_ok());
        if let (Ok(c), Ok(v)) = (c, v) {
            prop_assert!(c.mu2 >= 0.0, "μ² = {}", c.mu2);
            prop_assert!((0.0..=1.0).contains(&c.lambda));
            if (c.mu2 - 1.0).abs() > 1e-9 {
                prop_assert_eq!(v, c.mu2 < 1.0);
            }
            let (rs, a, b) = scaled(times_power_of_two(1.0, shift), r, q1, q2);
            let s = contact_function(&rs, &a, &b).unwrap();
            if c.mu2 >= f64::MIN_POSITIVE && c.mu2 < f64::INFINITY {
                prop_assert!(rel(s.mu2, c.mu2) < 1e-13, "2^{}: {} vs {}", shift, s.mu2, c.mu2);
            }
        }
        let r2 = [x[0], x[1]];
        let (e1, e2) = ([x[3], x[4], x[5]], [x[9], x[10], x[11]]);
        if let Ok(c) = contact_function(&r2, &e1, &e2) {
            prop_assert!(c.mu2 >= 0.0 && (0.0..=1.0).contains(&c.lambda));
        }
    }

    /// Valid ellipsoids of every size: axes 2^[−330, 330) each, any orientation, any
    /// separation: always an answer, never a refusal.
    #[test]
    fn valid_ellipsoids_of_every_size_are_answered(
        e1 in prop::array::uniform3(-100i32..100),
        e2 in prop::array::uniform3(-100i32..100),
        size in prop::array::uniform2(-230i32..230),
        quat1 in prop::array::uniform4(-1f64..1.0),
        quat2 in prop::array::uniform4(-1f64..1.0),
        r in prop::array::uniform3(-1f64..1.0),
        r_exponent in -600i32..600,
    ) {
        prop_assume!(quat1.iter().any(|x| x.abs() > 1e-3) && quat2.iter().any(|x| x.abs() > 1e-3));
        // Aspect ratios up to 2^20 within an ellipsoid (beyond, the rounded Q may not be
        // positive definite), any size ratio.
        let axes = |e: [i32; 3], s: i32| e.map(|k| times_power_of_two(1.0, k / 10 + s));
        let q1 = from_axes_quaternion(&axes(e1, size[0]), &quat1).unwrap();
        let q2 = from_axes_quaternion(&axes(e2, size[1]), &quat2).unwrap();
        let rs = r.map(|x| times_power_of_two(x, r_exponent));
        let c = contact_function(&rs, &q1, &q2);
        prop_assert!(c.is_ok(), "{:?}", c);
        let c = c.unwrap();
        prop_assert!(c.mu2 >= 0.0 && !c.mu2.is_nan());
        let v = overlap(&rs, &q1, &q2).unwrap();
        if (c.mu2 - 1.0).abs() > 1e-9 {
            prop_assert_eq!(v, c.mu2 < 1.0);
        }
    }
}

/// The batch's contact functions of `pairs` (on the calling thread).
fn contacts<P: pw85::batch::BatchPair>(pairs: &[P]) -> Vec<Result<pw85::Contact, Error>> {
    let mut out = vec![Ok(pw85::batch::EMPTY_CONTACT); pairs.len()];
    pw85::batch::contact_functions(pairs, &mut out, pw85::batch::Parallelism::Serial);
    out
}

/// The batch's verdicts of `pairs` (on the calling thread).
fn verdicts<P: pw85::batch::BatchPair>(pairs: &[P]) -> Vec<Result<bool, Error>> {
    let mut out = vec![Ok(false); pairs.len()];
    pw85::batch::overlaps(pairs, &mut out, pw85::batch::Parallelism::Serial);
    out
}
