//! `pw85::objective`, the f(λ) whose maximum is μ².

use pw85::shape::from_axes_quaternion;
use pw85::{Error, contact_function, objective};

#[test]
fn the_objective_peaks_at_the_contact_function() {
    let q1 = from_axes_quaternion(&[1.0, 0.75, 0.5], &[1.0, 0.0, 0.0, 0.0]).unwrap();
    let s = std::f64::consts::FRAC_1_SQRT_2;
    let q2 = from_axes_quaternion(&[2.0, 0.3, 0.3], &[s, s, 0.0, 0.0]).unwrap();
    let r12 = [1.6, 0.3, -0.4];
    let c = contact_function(&r12, &q1, &q2).unwrap();
    let at_max = objective(c.lambda, &r12, &q1, &q2).unwrap();
    assert!(
        (at_max - c.mu2).abs() <= 1e-14 * c.mu2,
        "{at_max} against {}",
        c.mu2
    );
    for k in 0..=20 {
        let lambda = f64::from(k) / 20.0;
        assert!(objective(lambda, &r12, &q1, &q2).unwrap() <= c.mu2 * (1.0 + 1e-14));
    }
    assert_eq!(objective(0.0, &r12, &q1, &q2).unwrap(), 0.0);
    assert_eq!(objective(1.0, &r12, &q1, &q2).unwrap(), 0.0);
    // Invariant under a uniform change of units, far outside the ordinary range.
    for e in [-400, 400] {
        let t = 2f64.powi(e);
        let f = objective(
            0.3,
            &r12.map(|x| x * t),
            &q1.map(|x| x * t * t),
            &q2.map(|x| x * t * t),
        );
        assert_eq!(
            f.unwrap(),
            objective(0.3, &r12, &q1, &q2).unwrap(),
            "units 2^{e}"
        );
    }
}

#[test]
fn bad_input_is_refused_with_the_argument_named() {
    let q = [1.0, 0.0, 0.0, 1.0, 0.0, 1.0];
    let r = [3.0, 0.0, 0.0];
    assert!(matches!(
        objective(1.5, &r, &q, &q),
        Err(Error::LambdaOutOfRange { value }) if value == 1.5
    ));
    assert!(matches!(
        objective(f64::NAN, &r, &q, &q),
        Err(Error::LambdaOutOfRange { .. })
    ));
    assert!(matches!(
        objective(0.5, &[f64::INFINITY, 0.0, 0.0], &q, &q),
        Err(Error::NonFinite { index: 0, .. })
    ));
    assert!(matches!(
        objective(0.5, &r, &q, &[1.0, 0.0, 0.0, -1.0, 0.0, 1.0]),
        Err(Error::NotPositiveDefinite { .. })
    ));
}
