//! Containment: exact values (KKT, closed forms, dense sampling as a lower bound) and gradients
//! against central finite differences.
#![allow(clippy::needless_range_loop)]

use implicit_packing::containment::{
    Container, ContainerShape, containment_gradient, containment_residual, farthest_point,
};
use implicit_packing::derivatives::angle_gradient_3d;
use implicit_packing::model::Model;
use implicit_packing::{Body, Ellipsoid};
use testkit::Rng;

fn random_body(rng: &mut Rng, spread: f64) -> ([f64; 3], [f64; 3], [f64; 3]) {
    let c = rng.point::<3>(-spread, spread);
    let l = rng.point::<3>(0.2, 2.0);
    let a = [
        rng.range(-3.0, 3.0),
        rng.range(-1.4, 1.4),
        rng.range(-3.0, 3.0),
    ];
    (c, l, a)
}

/// Every kind of container.
const KINDS: [ContainerShape; 3] = [
    ContainerShape::Ball,
    ContainerShape::Ellipsoid,
    ContainerShape::Box,
];

/// Container dimensions of `kind` in `d` dimensions, each in [2, 4).
fn random_dimensions(rng: &mut Rng, kind: ContainerShape, d: usize) -> Vec<f64> {
    (0..kind.dimension_count(d))
        .map(|_| rng.range(2.0, 4.0))
        .collect()
}

/// Central differences of `eval` at `v`, variable by variable, with step `h`.
fn central_differences(v: &[f64], h: f64, eval: impl Fn(&[f64]) -> f64) -> Vec<f64> {
    (0..v.len())
        .map(|k| {
            let mut vp = v.to_vec();
            vp[k] += h;
            let mut vm = v.to_vec();
            vm[k] -= h;
            (eval(&vp) - eval(&vm)) / (2.0 * h)
        })
        .collect()
}

/// A 3D containment gradient in the variables (centre, angles, the first `nd` container
/// dimensions).
fn in_angles_3d(
    g: &implicit_packing::containment::ContainmentGradient<3>,
    ang: [f64; 3],
    nd: usize,
) -> Vec<f64> {
    let mut out = vec![g.centre[0], g.centre[1], g.centre[2]];
    out.extend_from_slice(&angle_gradient_3d(ang, &g.torque));
    out.extend_from_slice(&g.container[..nd]);
    out
}

#[test]
fn farthest_point_is_a_kkt_point_and_beats_sampling() {
    let mut rng = Rng::new(5);
    for _ in 0..200 {
        let (c, l, ang) = random_body(&mut rng, 3.0);
        let body = Ellipsoid::from_angles(c, l, ang).unwrap();
        let a = rng.point::<3>(1.0, 5.0);
        let (h, p) = farthest_point(&body, &a);
        let q = body.rotation();
        // p* on the surface of E.
        let d = [p[0] - c[0], p[1] - c[1], p[2] - c[2]];
        let mut body_coords = [0.0; 3];
        for k in 0..3 {
            body_coords[k] = (0..3).map(|m| q[m][k] * d[m]).sum::<f64>() / l[k];
        }
        let on = body_coords.iter().map(|x| x * x).sum::<f64>();
        assert!((on - 1.0).abs() < 1e-12, "{on}");
        let hp: f64 = (0..3).map(|k| (p[k] / a[k]).powi(2)).sum();
        assert!((hp - h).abs() <= 1e-12 * h, "{hp} {h}");
        // Sampling gives a lower bound that comes close.
        let mut best = 0.0f64;
        let n = 120;
        for it in 0..n {
            let th = std::f64::consts::PI * (it as f64 + 0.5) / n as f64;
            for ip in 0..2 * n {
                let ph = std::f64::consts::PI * ip as f64 / n as f64;
                let u = [th.sin() * ph.cos(), th.sin() * ph.sin(), th.cos()];
                let mut pt = c;
                for r in 0..3 {
                    for k in 0..3 {
                        pt[r] += q[r][k] * l[k] * u[k];
                    }
                }
                best = best.max((0..3).map(|k| (pt[k] / a[k]).powi(2)).sum());
            }
        }
        assert!(best <= h * (1.0 + 1e-14), "sampled {best} > exact {h}");
        assert!(h - best <= 2e-3 * h, "sampled {best} far below exact {h}");
    }
}

/// A centre orthogonal to the longest axis but off the container's centre (a lattice start
/// shrunk by compression): the secular equation's top term has no weight, and its bracket
/// starts at τ = 0, where that term once gave 0/0 and the model's containment NaN.
#[test]
fn centre_orthogonal_to_the_longest_axis_gives_a_finite_residual() {
    let mut model = Model::<3>::new(vec![[1.0, 0.75, 0.5]], ContainerShape::Ball).unwrap();
    let mut containment = |x: f64| {
        let point = [
            x,
            0.4022467762180378,
            1.0765969675575129,
            0.004391924789480385,
            0.0,
            0.0,
            2.1329680307096353,
        ];
        model.evaluate(&point, None).unwrap().containment
    };
    let (on, near) = (containment(0.0), containment(1e-9));
    assert!(on.is_finite(), "{on}");
    // Continuous in the centre: the same as a hair off the orthogonal plane.
    assert!((on - near).abs() <= 1e-6 * near, "{on} against {near}");
}

#[test]
fn closed_forms_sphere_in_ball_and_box_support() {
    let s = Ellipsoid::from_angles([1.0, -2.0, 0.5], [0.7, 0.7, 0.7], [0.3, 0.2, 0.1]).unwrap();
    let (h, _) = farthest_point(&s, &[4.0; 3]);
    let cn = (1.0f64 + 4.0 + 0.25).sqrt();
    let expect = ((cn + 0.7) / 4.0).powi(2);
    assert!((h - expect).abs() <= 4e-16 * expect, "{h} {expect}");
    // Coincident centre (hard case): the farthest distance is the largest semi-axis.
    let e = Ellipsoid::from_angles([0.0; 3], [0.5, 1.5, 0.9], [0.4, -0.3, 1.0]).unwrap();
    let (h, _) = farthest_point(&e, &[3.0; 3]);
    assert!((h - 0.25).abs() < 1e-15, "{h}");
    // Box: an axis-aligned ellipsoid touching the walls exactly has zero residual, and just over.
    let b = Ellipsoid::from_angles([0.5, 0.0, 0.0], [1.0, 2.0, 3.0], [0.0; 3]).unwrap();
    let inside = Container::Box {
        half_sides: [1.5, 2.0, 3.0],
    };
    assert_eq!(containment_residual(&b, &inside), 0.0);
    let over = Container::Box {
        half_sides: [1.5 * (1.0 - 1e-9), 2.0, 3.0],
    };
    assert!(containment_residual(&b, &over) > 0.0);
}

#[test]
fn containment_gradients_match_finite_differences() {
    let mut rng = Rng::new(9);
    for kind in KINDS {
        let mut checked = 0;
        let mut worst = 0.0f64;
        while checked < 300 {
            let (c, l, ang) = random_body(&mut rng, 2.5);
            let dims = random_dimensions(&mut rng, kind, 3);
            let eval = |v: &[f64]| -> f64 {
                let b = Ellipsoid::from_angles([v[0], v[1], v[2]], l, [v[3], v[4], v[5]]).unwrap();
                let cont = Container::<3>::from_dimensions(kind, &v[6..]).unwrap();
                containment_residual(&b, &cont)
            };
            let mut v = vec![c[0], c[1], c[2], ang[0], ang[1], ang[2]];
            v.extend_from_slice(&dims);
            let f0 = eval(&v);
            if f0 < 1e-6 {
                continue;
            }
            let b = Body::from_angles(c, l, ang).unwrap();
            let cont = Container::<3>::from_dimensions(kind, &dims).unwrap();
            let (f, g) = containment_gradient(&b, &cont);
            assert_eq!(f, f0);
            let an = in_angles_3d(&g, ang, dims.len());
            let mut err = 0.0f64;
            let scale = an.iter().fold(0.0f64, |m, x| m.max(x.abs()));
            for (k, fd) in central_differences(&v, 1e-6, eval).into_iter().enumerate() {
                err = err.max((fd - an[k]).abs() / scale);
            }
            // Kinks of max{0, g}² (box: several constraints) are C¹: allow the O(h) there.
            assert!(err <= 1e-6, "{kind:?}: rel err {err:e} at {v:?}: {an:?}");
            worst = worst.max(err);
            checked += 1;
        }
        println!("{kind:?}: {checked} cases, worst relative error {worst:.2e}");
    }
}

#[test]
fn containment_gradients_match_finite_differences_2d() {
    use implicit_packing::Ellipse;
    let mut rng = Rng::new(10);
    for kind in KINDS {
        let mut checked = 0;
        while checked < 300 {
            let c = [rng.range(-2.5, 2.5), rng.range(-2.5, 2.5)];
            let l = [rng.range(0.2, 2.0), rng.range(0.2, 2.0)];
            let theta = rng.range(-3.0, 3.0);
            let dims = random_dimensions(&mut rng, kind, 2);
            let eval = |v: &[f64]| -> f64 {
                let b = Ellipse::ellipse([v[0], v[1]], l, v[2]).unwrap();
                containment_residual(&b, &Container::<2>::from_dimensions(kind, &v[3..]).unwrap())
            };
            let mut v = vec![c[0], c[1], theta];
            v.extend_from_slice(&dims);
            if eval(&v) < 1e-6 {
                continue;
            }
            let b = Ellipse::ellipse(c, l, theta).unwrap();
            let (_, g) =
                containment_gradient(&b, &Container::<2>::from_dimensions(kind, &dims).unwrap());
            let mut an = vec![g.centre[0], g.centre[1], g.torque[2]];
            an.extend_from_slice(&g.container[..dims.len()]);
            let scale = an.iter().fold(0.0f64, |m, x| m.max(x.abs()));
            for (k, fd) in central_differences(&v, 1e-6, eval).into_iter().enumerate() {
                assert!(
                    (fd - an[k]).abs() <= 1e-6 * scale,
                    "{kind:?} var {k}: fd {fd} analytic {}",
                    an[k]
                );
            }
            checked += 1;
        }
    }
}

/// Exact Hessian–vector products of the containment residual against central differences of
/// its exact gradient (centre, angles of eq. 2 including their own curvature, container).
#[test]
fn containment_hessian_vector_products_match_finite_differences() {
    use implicit_packing::containment::{ContainmentDirection, containment_gradient_derivative};
    use implicit_packing::derivatives::angular_velocity_derivatives_3d;
    use implicit_packing::shape::angular_velocities_3d;
    let mut rng = Rng::new(12);
    for kind in KINDS {
        let nd = kind.dimension_count(3);
        let grad_at = |v: &[f64], l: [f64; 3]| -> Vec<f64> {
            let b = Ellipsoid::from_angles([v[0], v[1], v[2]], l, [v[3], v[4], v[5]]).unwrap();
            let (_, g) =
                containment_gradient(&b, &Container::<3>::from_dimensions(kind, &v[6..]).unwrap());
            in_angles_3d(&g, [v[3], v[4], v[5]], nd)
        };
        let (mut checked, mut worst) = (0, 0.0f64);
        while checked < 300 {
            let (c, l, ang) = random_body(&mut rng, 2.5);
            let dims = random_dimensions(&mut rng, kind, 3);
            let mut v = vec![c[0], c[1], c[2], ang[0], ang[1], ang[2]];
            v.extend_from_slice(&dims);
            let b = Body::from_angles(c, l, ang).unwrap();
            let cont = Container::<3>::from_dimensions(kind, &dims).unwrap();
            if containment_residual(&b, &cont) < 1e-4 {
                continue;
            }
            let dv: Vec<f64> = (0..v.len()).map(|_| rng.range(-1.0, 1.0)).collect();
            let wv = angular_velocities_3d(ang);
            let mut spin = [0.0; 3];
            for a in 0..3 {
                for k in 0..3 {
                    spin[k] += wv[a][k] * dv[3 + a];
                }
            }
            let mut dcont = [0.0; 3];
            dcont[..nd].copy_from_slice(&dv[6..]);
            let dir = ContainmentDirection {
                centre: [dv[0], dv[1], dv[2]],
                spin,
                container: dcont,
            };
            let (_, g, hv) =
                containment_gradient_derivative(&b, &cont, &dir).expect("not the hard case");
            let dw = angular_velocity_derivatives_3d(ang);
            let mut exact = vec![hv.centre[0], hv.centre[1], hv.centre[2]];
            for a in 0..3 {
                let mut e = (0..3).map(|k| wv[a][k] * hv.torque[k]).sum::<f64>();
                for bb in 0..3 {
                    e += (0..3).map(|k| dw[a][bb][k] * g.torque[k]).sum::<f64>() * dv[3 + bb];
                }
                exact.push(e);
            }
            exact.extend_from_slice(&hv.container[..nd]);
            let h = 1e-6;
            let vp: Vec<f64> = v.iter().zip(&dv).map(|(a, b)| a + h * b).collect();
            let vm: Vec<f64> = v.iter().zip(&dv).map(|(a, b)| a - h * b).collect();
            let (gp, gm) = (grad_at(&vp, l), grad_at(&vm, l));
            let scale = exact.iter().fold(0.0f64, |m, x| m.max(x.abs()));
            let mut err = 0.0f64;
            for k in 0..v.len() {
                err = err.max(((gp[k] - gm[k]) / (2.0 * h) - exact[k]).abs() / scale);
            }
            assert!(err <= 1e-6, "{kind:?}: rel err {err:e}\nexact {exact:?}");
            worst = worst.max(err);
            checked += 1;
        }
        println!("{kind:?} containment HVP: {checked} cases, worst relative error {worst:.2e}");
    }
}
