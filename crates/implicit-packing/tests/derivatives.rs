//! Derivatives of the pair term against central finite differences, and the envelope-theorem
//! gradient of d² against the implicit-function system of Appendix A.1.
#![allow(clippy::needless_range_loop)]

use implicit_packing::derivatives::{
    PairGradient, a1_reference, angle_gradient_3d, pair_derivatives,
};
use implicit_packing::pair::{PairTerm, pair_term};
use implicit_packing::shape::angular_velocities_3d;
use implicit_packing::{Body, Ellipse, Ellipsoid};
use testkit::Rng;

/// Variables of a 3D pair: [c_i, angles_i, c_j, angles_j].
fn bodies3(v: &[f64; 12], li: [f64; 3], lj: [f64; 3]) -> (Ellipsoid, Ellipsoid) {
    let i = Body::from_angles([v[0], v[1], v[2]], li, [v[3], v[4], v[5]]).unwrap();
    let j = Body::from_angles([v[6], v[7], v[8]], lj, [v[9], v[10], v[11]]).unwrap();
    (i, j)
}

fn bodies2(v: &[f64; 6], li: [f64; 2], lj: [f64; 2]) -> (Ellipse, Ellipse) {
    let i = Body::ellipse([v[0], v[1]], li, v[2]).unwrap();
    let j = Body::ellipse([v[3], v[4]], lj, v[5]).unwrap();
    (i, j)
}

fn random_pair3(rng: &mut Rng) -> ([f64; 12], [f64; 3], [f64; 3]) {
    let li = rng.point::<3>(0.3, 2.0);
    let lj = rng.point::<3>(0.3, 2.0);
    let ri = li.iter().cloned().fold(0.0, f64::max);
    let rj = lj.iter().cloned().fold(0.0, f64::max);
    let dir = rng.direction();
    let dist = rng.range(0.0, 1.1) * (ri + rj);
    let mut v = [0.0; 12];
    for k in 0..3 {
        v[k] = rng.range(-1.0, 1.0);
        v[6 + k] = v[k] + dist * dir[k];
        v[3 + k] = rng.range(-3.0, 3.0);
        v[9 + k] = rng.range(-3.0, 3.0);
    }
    v[4] = rng.range(-1.4, 1.4);
    v[10] = rng.range(-1.4, 1.4);
    (v, li, lj)
}

/// Whether f is positive and smooth at `p`: away from the kinks of max{0, ·}² and from the
/// hard case (X not unique), the one non-smooth point of U and d² besides those kinks; random
/// pairs never hit it exactly, but are skipped if they do.
fn positive_and_smooth<const N: usize>(p: &PairTerm<N>) -> bool {
    p.f != 0.0 && (1.0 - p.d2).abs() > 1e-3 && (p.eps - p.u).abs() > 1e-3 && p.x_unique
}

/// A random pair from `draw` with its bodies and pair term.
struct Sample<const N: usize, const M: usize> {
    v: [f64; M],
    li: [f64; N],
    lj: [f64; N],
    i: Body<N>,
    j: Body<N>,
    p: PairTerm<N>,
}

/// Draws a pair's variables and the axes of its two bodies (`random_pair3`, `random_pair2`).
type Draw<const N: usize, const M: usize> = fn(&mut Rng) -> ([f64; M], [f64; N], [f64; N]);
/// Builds a pair's bodies from its variables and axes (`bodies3`, `bodies2`).
type Bodies<const N: usize, const M: usize> =
    fn(&[f64; M], [f64; N], [f64; N]) -> (Body<N>, Body<N>);

/// The next pair from `draw` at which f is positive and smooth, skipping those where it is not.
fn smooth_pair<const N: usize, const M: usize>(
    rng: &mut Rng,
    draw: Draw<N, M>,
    bodies: Bodies<N, M>,
) -> Sample<N, M> {
    loop {
        let (v, li, lj) = draw(rng);
        let (i, j) = bodies(&v, li, lj);
        let p = pair_term(&i, &j);
        if positive_and_smooth(&p) {
            return Sample { v, li, lj, i, j, p };
        }
    }
}

/// Runs `check` on the first 1000 pairs from `draw` (seeded with `seed`) at which f is
/// positive and smooth, each with its number from 0; returns how many were checked.
fn check_smooth_pairs<const N: usize, const M: usize>(
    seed: u64,
    draw: Draw<N, M>,
    bodies: Bodies<N, M>,
    mut check: impl FnMut(usize, Sample<N, M>),
) -> usize {
    let mut rng = Rng::new(seed);
    let pairs = 1000;
    for checked in 0..pairs {
        check(checked, smooth_pair(&mut rng, draw, bodies));
    }
    pairs
}

fn rel_err(g: &[f64], fd: &[f64]) -> f64 {
    let scale = g.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let worst = g
        .iter()
        .zip(fd)
        .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
    if scale == 0.0 { worst } else { worst / scale }
}

/// The relative error of the finite differences `fd` against `exact`, which must be at most
/// 1e-6; `case` names the case in the failure message.
fn assert_close(exact: &[f64], fd: &[f64], case: impl FnOnce() -> String) -> f64 {
    let e = rel_err(exact, fd);
    assert!(
        e <= 1e-6,
        "{}: rel err {e:e}\nexact {exact:?}\n   fd {fd:?}",
        case()
    );
    e
}

/// The central difference of `grad` from `v` along `dv`, with step 1e-6.
fn along<const M: usize>(
    v: &[f64; M],
    dv: &[f64; M],
    grad: impl Fn(&[f64; M]) -> [f64; M],
) -> [f64; M] {
    let h = 1e-6;
    let vp: [f64; M] = std::array::from_fn(|k| v[k] + h * dv[k]);
    let vm: [f64; M] = std::array::from_fn(|k| v[k] - h * dv[k]);
    let (gp, gm) = (grad(&vp), grad(&vm));
    std::array::from_fn(|k| (gp[k] - gm[k]) / (2.0 * h))
}

/// Central finite differences of each of `Q` pair-term quantities with respect to each
/// variable in turn: `out[q][k]` ≈ ∂ value_q / ∂ v_k.
fn partials<const M: usize, const Q: usize>(
    v: &[f64; M],
    values: impl Fn(&[f64; M]) -> [f64; Q],
) -> [[f64; M]; Q] {
    let h = 1e-6;
    let mut out = [[0.0; M]; Q];
    for k in 0..M {
        let mut vp = *v;
        vp[k] += h;
        let mut vm = *v;
        vm[k] -= h;
        let (pp, pm) = (values(&vp), values(&vm));
        for q in 0..Q {
            out[q][k] = (pp[q] - pm[q]) / (2.0 * h);
        }
    }
    out
}

/// A 3D pair gradient in the variables of [`bodies3`]: torques become derivatives with
/// respect to the angles `v[3..6]` and `v[9..12]`.
fn in_angles_3d(v: &[f64; 12], g: &PairGradient<3>) -> [f64; 12] {
    let mut out = [0.0; 12];
    out[0..3].copy_from_slice(&g.centre_i);
    out[3..6].copy_from_slice(&angle_gradient_3d([v[3], v[4], v[5]], &g.angular_i));
    out[6..9].copy_from_slice(&g.centre_j);
    out[9..12].copy_from_slice(&angle_gradient_3d([v[9], v[10], v[11]], &g.angular_j));
    out
}

/// A 2D pair gradient in the variables of [`bodies2`]: the torque about z is the derivative
/// with respect to the angle.
fn in_angles_2d(g: &PairGradient<2>) -> [f64; 6] {
    [
        g.centre_i[0],
        g.centre_i[1],
        g.angular_i[2],
        g.centre_j[0],
        g.centre_j[1],
        g.angular_j[2],
    ]
}

/// Two ellipses with semi-axes in [0.3, 2), centres up to 1.1 times the sum of their largest
/// semi-axes apart, as variables of [`bodies2`].
fn random_pair2(rng: &mut Rng) -> ([f64; 6], [f64; 2], [f64; 2]) {
    let li = [rng.range(0.3, 2.0), rng.range(0.3, 2.0)];
    let lj = [rng.range(0.3, 2.0), rng.range(0.3, 2.0)];
    let r = li[0].max(li[1]) + lj[0].max(lj[1]);
    let ang = rng.range(0.0, std::f64::consts::TAU);
    let dist = rng.range(0.0, 1.1) * r;
    let c = [rng.range(-1.0, 1.0), rng.range(-1.0, 1.0)];
    let v = [
        c[0],
        c[1],
        rng.range(-3.0, 3.0),
        c[0] + dist * ang.cos(),
        c[1] + dist * ang.sin(),
        rng.range(-3.0, 3.0),
    ];
    (v, li, lj)
}

#[test]
fn gradient_of_f_matches_finite_differences_3d() {
    let mut worst = 0.0f64;
    let (mut worst_u, mut n_u) = (0.0f64, 0);
    let checked = check_smooth_pairs(7, random_pair3, bodies3, |checked, sample| {
        let Sample { v, li, lj, i, j, p } = sample;
        let d = pair_derivatives(&i, &j);
        let g = in_angles_3d(&v, &d.grad_f);
        let gu = in_angles_3d(&v, &d.grad_u);
        let [fd, fdu] = partials(&v, |x| {
            let (i, j) = bodies3(x, li, lj);
            let p = pair_term(&i, &j);
            [p.f, p.u]
        });
        let e = assert_close(&g, &fd, || {
            format!(
                "pair {checked} (v = {v:?} li {li:?} lj {lj:?} d2 {} u {})",
                p.d2, p.u
            )
        });
        worst = worst.max(e);
        if p.centre_inside || p.u < 1.0 {
            let eu = assert_close(&gu, &fdu, || format!("pair {checked}, ∇U"));
            worst_u = worst_u.max(eu);
            n_u += 1;
        }
    });
    println!(
        "3D: {checked} pairs, worst relative error of ∇f {worst:.2e}; ∇U on {n_u} pairs: {worst_u:.2e}"
    );
}

#[test]
fn gradient_of_f_matches_finite_differences_2d() {
    let mut worst = 0.0f64;
    let checked = check_smooth_pairs(11, random_pair2, bodies2, |checked, sample| {
        let Sample {
            v, li, lj, i, j, ..
        } = sample;
        let d = pair_derivatives(&i, &j);
        let g = in_angles_2d(&d.grad_f);
        let [fd] = partials(&v, |x| {
            let (i, j) = bodies2(x, li, lj);
            [pair_term(&i, &j).f]
        });
        worst = worst.max(assert_close(&g, &fd, || format!("pair {checked}")));
    });
    println!("2D: {checked} pairs, worst relative error of ∇f {worst:.2e}");
}

/// The envelope-theorem gradient of d² and the implicit gradient of U agree with the solution of
/// the (n+1)×(n+1) system of Appendix A.1, parameter by parameter.
#[test]
fn envelope_form_equals_appendix_a1() {
    let mut rng = Rng::new(3);
    let mut worst_d2 = 0.0f64;
    let mut worst_u = 0.0f64;
    let mut n = 0;
    while n < 300 {
        let (v, li, lj) = random_pair3(&mut rng);
        let (i, j) = bodies3(&v, li, lj);
        let p = pair_term(&i, &j);
        if !p.x_unique {
            continue;
        }
        let d = pair_derivatives(&i, &j);
        let wi = angular_velocities_3d([v[3], v[4], v[5]]);
        let wj = angular_velocities_3d([v[9], v[10], v[11]]);
        let gi = angle_gradient_3d([v[3], v[4], v[5]], &d.grad_d2.angular_i);
        let gj = angle_gradient_3d([v[9], v[10], v[11]], &d.grad_d2.angular_j);
        let gui = angle_gradient_3d([v[3], v[4], v[5]], &d.grad_u.angular_i);
        let guj = angle_gradient_3d([v[9], v[10], v[11]], &d.grad_u.angular_j);
        let mut env_d2 = Vec::new();
        let mut env_u = Vec::new();
        let mut a1_d2 = Vec::new();
        let mut a1_u = Vec::new();
        for k in 0..12 {
            let (mut dci, mut dcj, mut w_i, mut w_j) = ([0.0; 3], [0.0; 3], [0.0; 3], [0.0; 3]);
            match k {
                0..=2 => dci[k] = 1.0,
                3..=5 => w_i = wi[k - 3],
                6..=8 => dcj[k - 6] = 1.0,
                _ => w_j = wj[k - 9],
            }
            let (dd2, du) = a1_reference(&i, &j, &dci, &dcj, &w_i, &w_j);
            a1_d2.push(dd2);
            a1_u.push(du);
            let (e2, eu) = match k {
                0..=2 => (d.grad_d2.centre_i[k], d.grad_u.centre_i[k]),
                3..=5 => (gi[k - 3], gui[k - 3]),
                6..=8 => (d.grad_d2.centre_j[k - 6], d.grad_u.centre_j[k - 6]),
                _ => (gj[k - 9], guj[k - 9]),
            };
            env_d2.push(e2);
            env_u.push(eu);
        }
        let e2 = rel_err(&env_d2, &a1_d2);
        let eu = rel_err(&env_u, &a1_u);
        assert!(
            e2 <= 1e-9 && eu <= 1e-9,
            "pair {n}: d2 {e2:e} U {eu:e}\n{env_d2:?}\n{a1_d2:?}\n{env_u:?}\n{a1_u:?}"
        );
        worst_d2 = worst_d2.max(e2);
        worst_u = worst_u.max(eu);
        n += 1;
    }
    println!("envelope vs A.1 on {n} pairs: worst rel diff ∇d² {worst_d2:.2e}, ∇U {worst_u:.2e}");
}

/// Exact directional derivatives of ∇f (Hessian–vector products) against central finite
/// differences of the analytic gradient, 3D (12 variables) and 2D (6 variables).
#[test]
fn hessian_vector_products_match_finite_differences() {
    use implicit_packing::derivatives::{
        PairDirection, angular_velocity_derivatives_3d, pair_gradient_derivative,
    };
    let grad12 = |v: &[f64; 12], li: [f64; 3], lj: [f64; 3]| -> [f64; 12] {
        let (i, j) = bodies3(v, li, lj);
        in_angles_3d(v, &pair_derivatives(&i, &j).grad_f)
    };
    let mut rng = Rng::new(99);
    let (mut checked, mut worst, mut with_u) = (0, 0.0f64, 0);
    while checked < 1000 {
        let Sample { v, li, lj, i, j, p } = smooth_pair(&mut rng, random_pair3, bodies3);
        let dv: [f64; 12] = std::array::from_fn(|_| rng.range(-1.0, 1.0));
        let ai = [v[3], v[4], v[5]];
        let aj = [v[9], v[10], v[11]];
        let wi = angular_velocities_3d(ai);
        let wj = angular_velocities_3d(aj);
        let mut dir = PairDirection {
            centre_i: [dv[0], dv[1], dv[2]],
            centre_j: [dv[6], dv[7], dv[8]],
            angular_i: [0.0; 3],
            angular_j: [0.0; 3],
        };
        for a in 0..3 {
            for k in 0..3 {
                dir.angular_i[k] += wi[a][k] * dv[3 + a];
                dir.angular_j[k] += wj[a][k] * dv[9 + a];
            }
        }
        let (_, grad, hv) = pair_gradient_derivative(&i, &j, &dir).expect("not the hard case");
        let dwi = angular_velocity_derivatives_3d(ai);
        let dwj = angular_velocity_derivatives_3d(aj);
        let mut exact = [0.0; 12];
        exact[0..3].copy_from_slice(&hv.centre_i);
        exact[6..9].copy_from_slice(&hv.centre_j);
        for a in 0..3 {
            let mut e_i = (0..3).map(|k| wi[a][k] * hv.angular_i[k]).sum::<f64>();
            let mut e_j = (0..3).map(|k| wj[a][k] * hv.angular_j[k]).sum::<f64>();
            for b in 0..3 {
                e_i += (0..3)
                    .map(|k| dwi[a][b][k] * grad.angular_i[k])
                    .sum::<f64>()
                    * dv[3 + b];
                e_j += (0..3)
                    .map(|k| dwj[a][b][k] * grad.angular_j[k])
                    .sum::<f64>()
                    * dv[9 + b];
            }
            exact[3 + a] = e_i;
            exact[9 + a] = e_j;
        }
        let fd = along(&v, &dv, |x| grad12(x, li, lj));
        let e = assert_close(&exact, &fd, || {
            format!("pair {checked} (u {} eps {} d2 {})", p.u, p.eps, p.d2)
        });
        worst = worst.max(e);
        with_u += usize::from(p.u < p.eps);
        checked += 1;
    }
    println!(
        "3D Hessian-vector products: {checked} pairs ({with_u} with U < ε), worst relative error {worst:.2e}"
    );

    let grad6 = |v: &[f64; 6], li: [f64; 2], lj: [f64; 2]| -> [f64; 6] {
        let (i, j) = bodies2(v, li, lj);
        in_angles_2d(&pair_derivatives(&i, &j).grad_f)
    };
    let (mut checked, mut worst) = (0, 0.0f64);
    while checked < 1000 {
        let Sample {
            v, li, lj, i, j, ..
        } = smooth_pair(&mut rng, random_pair2, bodies2);
        let dv: [f64; 6] = std::array::from_fn(|_| rng.range(-1.0, 1.0));
        let dir = PairDirection {
            centre_i: [dv[0], dv[1]],
            centre_j: [dv[3], dv[4]],
            angular_i: [0.0, 0.0, dv[2]],
            angular_j: [0.0, 0.0, dv[5]],
        };
        let (_, _, hv) = pair_gradient_derivative(&i, &j, &dir).expect("not the hard case");
        let exact = in_angles_2d(&hv);
        let fd = along(&v, &dv, |x| grad6(x, li, lj));
        worst = worst.max(assert_close(&exact, &fd, || format!("2D pair {checked}")));
        checked += 1;
    }
    println!("2D Hessian-vector products: {checked} pairs, worst relative error {worst:.2e}");
}
