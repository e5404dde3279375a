//! Invariants of the pair term: Lemma 4.4 (scaling), symmetry of the verdict, Lemma 4.3 on
//! separated pairs, no panic and finite output on extreme inputs.
#![allow(clippy::needless_range_loop)]

use implicit_packing::{Body, Ellipse, Ellipsoid, overlap_measure, pair_term};
use proptest::prelude::*;
use testkit::Rng;
use testkit::reference::scaled_error;

/// `x` rounded to 20 significant bits.
fn short(x: f64) -> f64 {
    if x == 0.0 {
        return 0.0;
    }
    let s = 2f64.powi(19 - x.abs().log2().floor() as i32);
    (x * s).round() / s
}

fn random_pair(rng: &mut Rng) -> (Ellipsoid, Ellipsoid) {
    let (i, j) = random_pair_full(rng);
    let sh = |v: [f64; 3]| [short(v[0]), short(v[1]), short(v[2])];
    let i = Body::from_parts(sh(i.centre()), sh(i.semi_axes()), i);
    let j = Body::from_parts(sh(j.centre()), sh(j.semi_axes()), j);
    (i, j)
}

trait FromParts {
    fn from_parts(c: [f64; 3], l: [f64; 3], like: Ellipsoid) -> Ellipsoid;
}

impl FromParts for Ellipsoid {
    fn from_parts(c: [f64; 3], l: [f64; 3], like: Ellipsoid) -> Ellipsoid {
        let a = like.angles();
        Body::from_angles(c, l, a).unwrap()
    }
}

/// Euler angles of eq. 2, the middle one away from the poles.
fn random_angles(rng: &mut Rng) -> [f64; 3] {
    [
        rng.range(-3.0, 3.0),
        rng.range(-1.5, 1.5),
        rng.range(-3.0, 3.0),
    ]
}

/// An ellipsoid at `c` with semi-axes `l` and [`random_angles`].
fn oriented_at_random(rng: &mut Rng, c: [f64; 3], l: [f64; 3]) -> Ellipsoid {
    Body::from_angles(c, l, random_angles(rng)).unwrap()
}

fn random_pair_full(rng: &mut Rng) -> (Ellipsoid, Ellipsoid) {
    let li = rng.point::<3>(0.2, 2.0);
    let lj = rng.point::<3>(0.2, 2.0);
    let r = li.iter().chain(lj.iter()).cloned().fold(0.0, f64::max);
    let dir = rng.direction();
    let d = rng.range(0.0, 2.0) * r;
    let ci = rng.point::<3>(-1.0, 1.0);
    let i = oriented_at_random(rng, ci, li);
    let cj = [ci[0] + d * dir[0], ci[1] + d * dir[1], ci[2] + d * dir[2]];
    let j = oriented_at_random(rng, cj, lj);
    (i, j)
}

/// Lemma 4.4: the function `f` of eq. 34 does not change when both ellipsoids are scaled by `ν`:
/// to 1e-14 relative to `max(1, f)` (`|∂f/∂d²| ≤ 2`, so a relative measure would only amplify
/// the last bits of `1 − d²` near tangency). Centres and semi-axes carry 20 significant bits and
/// so do the factors `ν`, so the scaled inputs are exact: the two problems are the same
/// mathematically and only our own rounding can tell them apart. Powers of two must give
/// bit-identical results. `U` and `d²` (not the subject of the lemma) are checked as well, to a
/// relative 1e-12 (absolute 1e-14 below 1e-2), the accuracy asked against the reference files.
#[test]
fn lemma_4_4_scaling_invariance() {
    let mut rng = Rng::new(44);
    let (mut worst_f, mut worst_ud) = (0.0f64, 0.0f64);
    for n in 0..3000 {
        let (i, j) = random_pair(&mut rng);
        let p = pair_term(&i, &j);
        for nu in [0.125, 1024.0, short(3.0f64.powi(-7)), 1e5, short(0.37), 3.0] {
            let q = pair_term(&i.scaled(nu).unwrap(), &j.scaled(nu).unwrap());
            let eu = scaled_error(q.u, p.u);
            let ed = scaled_error(q.d2, p.d2);
            let ef = (q.f - p.f).abs() / p.f.abs().max(1.0);
            if nu.log2().fract() == 0.0 {
                assert!(
                    eu == 0.0 && ed == 0.0 && ef == 0.0,
                    "pair {n}, nu {nu}: exact scaling changed the result"
                );
            }
            assert!(
                ef <= 1e-14,
                "pair {n}, nu {nu}: f changed by {ef:e} ({} -> {})",
                p.f,
                q.f
            );
            assert!(
                eu.max(ed) <= 1e-12,
                "pair {n}, nu {nu}: U {} -> {}, d2 {} -> {}",
                p.u,
                q.u,
                p.d2,
                q.d2
            );
            assert_eq!(p.f > 0.0, q.f > 0.0);
            worst_f = worst_f.max(ef);
            worst_ud = worst_ud.max(eu.max(ed));
        }
    }
    println!(
        "Lemma 4.4: worst change of f {worst_f:.2e} (relative to max(1, f)); of U, d² {worst_ud:.2e} (relative, absolute ×1e2 below 1e-2)"
    );
}

#[test]
fn verdict_is_symmetric_and_zero_iff_separated() {
    let mut rng = Rng::new(45);
    for _ in 0..5000 {
        let (i, j) = random_pair(&mut rng);
        let a = pair_term(&i, &j);
        let b = pair_term(&j, &i);
        if (a.d2 - 1.0).abs() > 1e-12 && (b.d2 - 1.0).abs() > 1e-12 {
            assert_eq!(a.f > 0.0, b.f > 0.0, "{a:?}\n{b:?}");
        }
        // Lemma 4.3 / Prop. 3.3: a separated pair has U ≥ ε.
        if a.f == 0.0 {
            assert!(a.u >= a.eps && a.d2 >= 1.0);
        }
        assert_eq!(overlap_measure(&i, &j), if a.f > 0.0 { a.f } else { 0.0 });
    }
}

/// The direct route (LDLᵀ Newton) and the SVD route agree on the pairs where the direct route
/// applies (centre outside, axis ratios ≤ 2.8 for each ellipsoid), 2D and 3D.
#[test]
fn direct_and_svd_routes_agree() {
    use implicit_packing::{Route, pair_term_by};
    let mut rng = Rng::new(46);
    let mut worst = 0.0f64;
    let mut n = 0;
    while n < 10_000 {
        let li = rng.point::<3>(0.6, 1.6);
        let lj = rng.point::<3>(0.35, 1.0);
        let dir = rng.direction();
        let d = rng.range(0.5, 4.0);
        let i = oriented_at_random(&mut rng, [0.0; 3], li);
        let j = oriented_at_random(&mut rng, [d * dir[0], d * dir[1], d * dir[2]], lj);
        let a = pair_term_by(&i, &j, Route::Auto);
        let b = pair_term_by(&i, &j, Route::Svd);
        if b.centre_inside {
            continue;
        }
        let e = scaled_error(a.u, b.u).max(scaled_error(a.d2, b.d2));
        let ex = (0..3).map(|k| (a.x[k] - b.x[k]).abs()).fold(0.0, f64::max)
            / b.x.iter().map(|v| v * v).sum::<f64>().sqrt();
        assert!(e <= 1e-13 && ex <= 1e-13, "pair {n}: {a:?}\n{b:?}");
        assert_eq!(a.f > 0.0, b.f > 0.0);
        // The gradient the model uses (direct route where it applies) against the SVD route's.
        let (f, g) = implicit_packing::derivatives::pair_gradient(&i, &j);
        let full = implicit_packing::derivatives::pair_derivatives(&i, &j);
        let ga: Vec<f64> = g
            .centre_i
            .iter()
            .chain(&g.angular_i)
            .chain(&g.centre_j)
            .chain(&g.angular_j)
            .copied()
            .collect();
        let gb: Vec<f64> = full
            .grad_f
            .centre_i
            .iter()
            .chain(&full.grad_f.angular_i)
            .chain(&full.grad_f.centre_j)
            .chain(&full.grad_f.angular_j)
            .copied()
            .collect();
        let scale = gb.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let eg = ga
            .iter()
            .zip(&gb)
            .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
        assert!(
            (f - full.f).abs() <= 1e-13 * full.f.max(1e-2) && eg <= 1e-12 * scale.max(1e-2),
            "pair {n}: {g:?}\n{:?}",
            full.grad_f
        );
        worst = worst.max(e).max(ex);
        n += 1;
    }
    let mut n2 = 0;
    while n2 < 10_000 {
        let li = [rng.range(0.6, 1.6), rng.range(0.6, 1.6)];
        let lj = [rng.range(0.35, 1.0), rng.range(0.35, 1.0)];
        let t = rng.range(0.0, 6.3);
        let d = rng.range(0.5, 4.0);
        let i = Ellipse::ellipse([0.0; 2], li, rng.range(-3.0, 3.0)).unwrap();
        let j = Ellipse::ellipse([d * t.cos(), d * t.sin()], lj, rng.range(-3.0, 3.0)).unwrap();
        let a = pair_term_by(&i, &j, Route::Auto);
        let b = pair_term_by(&i, &j, Route::Svd);
        if b.centre_inside {
            continue;
        }
        let e = scaled_error(a.u, b.u).max(scaled_error(a.d2, b.d2));
        assert!(e <= 1e-13, "pair {n2}: {a:?}\n{b:?}");
        worst = worst.max(e);
        n2 += 1;
    }
    println!("direct vs SVD route: worst difference {worst:.2e} on {n} + {n2} pairs");
}

fn axis() -> impl Strategy<Value = f64> {
    (-30.0f64..30.0).prop_map(|e| 10f64.powf(e).clamp(1e-30, 1e30))
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(3000))]

    /// Any valid input gives finite, consistent output: f ≥ 0, U ≥ −1/λ_max(S), no panic.
    #[test]
    fn extreme_inputs_give_finite_output(
        li in prop::array::uniform3(axis()), lj in prop::array::uniform3(axis()),
        ci in prop::array::uniform3(-1e6f64..1e6), cj in prop::array::uniform3(-1e6f64..1e6),
        qi in prop::array::uniform4(-1.0f64..1.0), qj in prop::array::uniform4(-1.0f64..1.0),
    ) {
        let norm = |q: [f64; 4]| {
            let n = q.iter().map(|v| v * v).sum::<f64>().sqrt();
            if n < 1e-3 { [1.0, 0.0, 0.0, 0.0] } else { [q[0] / n, q[1] / n, q[2] / n, q[3] / n] }
        };
        let i = Body::from_quaternion(ci, li, norm(qi)).unwrap();
        let j = Body::from_quaternion(cj, lj, norm(qj)).unwrap();
        let p = pair_term(&i, &j);
        prop_assert!(p.f.is_finite() && p.f >= 0.0, "{:?}", p);
        prop_assert!(p.u.is_finite() && p.d2.is_finite() && p.d2 >= 0.0, "{:?}", p);
        prop_assert!(p.x.iter().all(|v| v.is_finite()), "{:?}", p);
        let q = implicit_packing::derivatives::pair_derivatives(&i, &j);
        prop_assert!(q.grad_f.centre_i.iter().chain(q.grad_f.angular_i.iter()).all(|v| v.is_finite()), "{:?}", q);
    }

    #[test]
    fn ellipses_give_finite_output(
        li in prop::array::uniform2(axis()), lj in prop::array::uniform2(axis()),
        ci in prop::array::uniform2(-1e6f64..1e6), cj in prop::array::uniform2(-1e6f64..1e6),
        ti in -10.0f64..10.0, tj in -10.0f64..10.0,
    ) {
        let i = Ellipse::ellipse(ci, li, ti).unwrap();
        let j = Ellipse::ellipse(cj, lj, tj).unwrap();
        let p = pair_term(&i, &j);
        prop_assert!(p.f.is_finite() && p.f >= 0.0 && p.u.is_finite() && p.d2.is_finite(), "{:?}", p);
    }
}

/// Pairs with a common rotation, centres along a common principal axis `k`: `c` lies on an
/// eigenvector of `S` and the projection is the vertex, `U = l_jk (D − l_jk) / l_ik²`,
/// `d = (D − l_jk) / l_ik`. The root of the secular equation is then at the end of its initial
/// bracket, `(|b| − 1)/s_k`, where the safeguarded Newton once stopped 1e-9 short (found by
/// the separation-certificate test, `tests/separation.rs`). Both routes, 2D and 3D.
#[test]
fn aligned_pairs_match_the_closed_form() {
    use implicit_packing::{Route, pair_term_by};
    let mut rng = Rng::new(47);
    let mut worst = 0.0f64;
    for n in 0..4000 {
        // j down to 1e-3 times the size of i, where the bracket-end root was found; not much
        // larger than i, where |c| ≫ d and the rounding of the centres alone moves d² by
        // |c| ε (input conditioning, not the solver).
        let size = 10f64.powf(rng.range(-3.0, 0.5));
        let li = rng.point::<3>(0.3, 1.0);
        let lj = [
            size * rng.range(0.3, 1.0),
            size * rng.range(0.3, 1.0),
            size * rng.range(0.3, 1.0),
        ];
        let k = n % 3;
        let dist = (li[k] + lj[k]) * (1.0 + 10f64.powf(rng.range(-12.0, 0.0)));
        let u_exact = lj[k] * (dist - lj[k]) / (li[k] * li[k]);
        let d2_exact = ((dist - lj[k]) / li[k]).powi(2);
        let angles = random_angles(&mut rng);
        let i = Body::from_angles([0.0; 3], li, angles).unwrap();
        let q = i.rotation();
        let j = Body::from_angles([q[0][k] * dist, q[1][k] * dist, q[2][k] * dist], lj, angles)
            .unwrap();
        let i2 = Ellipse::ellipse([0.0; 2], [li[0], li[1]], angles[0]).unwrap();
        let q2 = i2.rotation();
        let k2 = n % 2;
        let dist2 = (li[k2] + lj[k2]) * (1.0 + 10f64.powf(rng.range(-12.0, 0.0)));
        let j2 = Ellipse::ellipse(
            [q2[0][k2] * dist2, q2[1][k2] * dist2],
            [lj[0], lj[1]],
            angles[0],
        )
        .unwrap();
        let u2_exact = lj[k2] * (dist2 - lj[k2]) / (li[k2] * li[k2]);
        let d22_exact = ((dist2 - lj[k2]) / li[k2]).powi(2);
        for route in [Route::Auto, Route::Svd] {
            let t = pair_term_by(&i, &j, route);
            let e = scaled_error(t.u, u_exact).max(scaled_error(t.d2, d2_exact));
            assert!(
                e <= 1e-13,
                "3D {route:?} pair {n}: {t:?}, U {u_exact}, d² {d2_exact}"
            );
            let t2 = pair_term_by(&i2, &j2, route);
            let e2 = scaled_error(t2.u, u2_exact).max(scaled_error(t2.d2, d22_exact));
            assert!(
                e2 <= 1e-13,
                "2D {route:?} pair {n}: {t2:?}, U {u2_exact}, d² {d22_exact}"
            );
            worst = worst.max(e).max(e2);
        }
    }
    println!("aligned pairs: worst error against the closed form {worst:.2e}");
}
