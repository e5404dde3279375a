//! The whole model: grid sum equals the all-pairs sum, gradients against finite differences,
//! value-only calls agree with gradient calls, bad variables are named.
#![allow(clippy::needless_range_loop)]

use implicit_packing::Error;
use implicit_packing::containment::ContainerShape;
use implicit_packing::model::{Model, ModelGradient};
use testkit::Rng;

/// m ellipsoids on a jittered cubic lattice at about the given volume fraction, random angles;
/// container dimensions last.
fn config3(
    rng: &mut Rng,
    m: usize,
    density: f64,
    kind: ContainerShape,
) -> (Vec<[f64; 3]>, Vec<f64>) {
    let axes: Vec<[f64; 3]> = (0..m)
        .map(|_| {
            [
                rng.range(0.8, 1.2),
                rng.range(0.6, 0.9),
                rng.range(0.4, 0.6),
            ]
        })
        .collect();
    let x = placed3(rng, &axes, |_| 3, density, kind);
    (axes, x)
}

/// The variables of items with semi-axes `axes`, the last `angles(i)` of eq. 2's angles each
/// (random), on a jittered cubic lattice at about the given volume fraction; container
/// dimensions last.
fn placed3(
    rng: &mut Rng,
    axes: &[[f64; 3]],
    angles: impl Fn(usize) -> usize,
    density: f64,
    kind: ContainerShape,
) -> Vec<f64> {
    let m = axes.len();
    let vol: f64 = axes
        .iter()
        .map(|l| 4.0 / 3.0 * std::f64::consts::PI * l[0] * l[1] * l[2])
        .sum();
    let (side, per, h) = lattice::<3>(vol, density, m);
    let mut x = Vec::new();
    let ranges = [(-3.0, 3.0), (-1.4, 1.4), (-3.0, 3.0)];
    for i in 0..m {
        let (a, b, c) = (i % per, (i / per) % per, i / (per * per));
        for idx in [a, b, c] {
            x.push(jittered(idx, h, side, rng));
        }
        for &(lo, hi) in &ranges[3 - angles(i)..] {
            x.push(rng.range(lo, hi));
        }
    }
    match kind {
        ContainerShape::Ball => x.push(0.45 * side * 3f64.sqrt()),
        _ => x.extend_from_slice(&[0.45 * side, 0.5 * side, 0.55 * side]),
    }
    x
}

/// For `m` items of total area or volume `measure` at `density`: the side of their square or
/// cube, the lattice cells per side and the cell size.
fn lattice<const D: usize>(measure: f64, density: f64, m: usize) -> (f64, usize, f64) {
    let root = |v: f64| if D == 3 { v.cbrt() } else { v.sqrt() };
    let side = root(measure / density);
    let per = root(m as f64).ceil() as usize;
    (side, per, side / per as f64)
}

/// Coordinate of lattice index `idx` (spacing `h`, the lattice centred on a square or cube of
/// `side`), moved at random by up to a fifth of the spacing.
fn jittered(idx: usize, h: f64, side: f64, rng: &mut Rng) -> f64 {
    (idx as f64 + 0.5) * h - side / 2.0 + rng.range(-0.2, 0.2) * h
}

fn config2(rng: &mut Rng, m: usize, density: f64) -> (Vec<[f64; 2]>, Vec<f64>) {
    let axes: Vec<[f64; 2]> = (0..m)
        .map(|_| [rng.range(0.8, 1.2), rng.range(0.4, 0.7)])
        .collect();
    let x = placed2(rng, &axes, density);
    (axes, x)
}

/// The variables of ellipses and circles with semi-axes `axes` (an angle for each ellipse,
/// random; none for a circle) on a jittered square lattice at about the given area fraction,
/// then a box's half-sides.
fn placed2(rng: &mut Rng, axes: &[[f64; 2]], density: f64) -> Vec<f64> {
    let m = axes.len();
    let area: f64 = axes
        .iter()
        .map(|l| std::f64::consts::PI * l[0] * l[1])
        .sum();
    let (side, per, h) = lattice::<2>(area, density, m);
    let mut x = Vec::new();
    for (i, l) in axes.iter().enumerate() {
        x.push(jittered(i % per, h, side, rng));
        x.push(jittered(i / per, h, side, rng));
        if l[0] != l[1] {
            x.push(rng.range(-3.0, 3.0));
        }
    }
    x.extend_from_slice(&[0.45 * side, 0.48 * side]);
    x
}

/// Every kind of container.
const KINDS: [ContainerShape; 3] = [
    ContainerShape::Ball,
    ContainerShape::Ellipsoid,
    ContainerShape::Box,
];

#[test]
fn grid_sum_equals_all_pairs_sum() {
    let mut rng = Rng::new(21);
    for &(m, density) in &[(200usize, 0.6), (343, 0.3), (50, 0.7)] {
        let (axes, x) = config3(&mut rng, m, density, ContainerShape::Box);
        let mut p = Model::<3>::new(axes, ContainerShape::Box).unwrap();
        let ev = p.evaluate(&x, None).unwrap();
        let all = p.overlap_all_pairs(&x).unwrap();
        assert!(ev.overlap > 0.0);
        // The same terms added in the same (i, j) order: the same bits, however the kernel
        // queue groups and delays the pairs.
        assert_same_bits(ev.overlap, all);
        assert!(ev.pairs < m * (m - 1) / 2);
    }
    let (axes, x) = config2(&mut rng, 400, 0.6);
    let mut p = Model::<2>::new(axes, ContainerShape::Ellipsoid).unwrap();
    let ev = p.evaluate(&x, None).unwrap();
    let all = p.overlap_all_pairs(&x).unwrap();
    assert_same_bits(ev.overlap, all);
}

/// With the `rayon` feature the pair sums run in ranges of the pair list on rayon's pool:
/// the gradient terms are added item by item in the order of the pairs (the items cut into
/// one block per thread), and `Σf` summed range by range over ranges cut from the list alone,
/// so one, two and three threads give the same bits (and the serial sum to rounding), in a
/// container and in a periodic cell.
#[cfg(feature = "rayon")]
#[test]
fn two_threads_give_the_gradient_of_one() {
    let mut rng = Rng::new(5);
    let (axes, in_ball) = config3(&mut rng, 4000, 0.6, ContainerShape::Ball);
    let (_, in_box) = config3(&mut rng, 4000, 0.6, ContainerShape::Box);
    // The box's centres as fractions of the periodic cube of the same side.
    let side = in_box[in_box.len() - 2] / 0.5;
    let mut in_cell: Vec<f64> = in_box[..in_box.len() - 3].to_vec();
    for item in in_cell.chunks_mut(6) {
        for c in &mut item[..3] {
            *c = *c / side + 0.5;
        }
    }
    in_cell.extend_from_slice(&[side, side, side, 0.0, 0.0, 0.0]);
    for (kind, x) in [
        (ContainerShape::Ball, in_ball),
        (ContainerShape::Periodic, in_cell),
    ] {
        let run = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| {
                let mut p = Model::<3>::new(axes.clone(), kind).unwrap();
                let mut g = ModelGradient::default();
                // Twice on one model: the second call reuses the ranges' vectors.
                let first = p.evaluate(&x, Some(&mut g)).unwrap();
                let first_g = g.overlap.clone();
                let again = p.evaluate(&x, Some(&mut g)).unwrap();
                assert_eq!(first, again);
                assert_eq!(first_g, g.overlap);
                let value = p.evaluate(&x, None).unwrap();
                (again, g, value)
            })
        };
        let (one, g1, v1) = run(1);
        assert!(
            one.pairs > 20_000,
            "{kind:?}: {} pairs: too few for several ranges",
            one.pairs
        );
        assert!(
            g1.overlap.iter().filter(|&&d| d != 0.0).count() > 10_000,
            "{kind:?}: too few overlapping items to test the scatter"
        );
        for threads in [2, 3] {
            let (more, g, v) = run(threads);
            assert_eq!(one, more, "{kind:?} on {threads} threads");
            assert_eq!(v1, v, "{kind:?} on {threads} threads");
            assert_eq!(g1.overlap, g.overlap, "{kind:?} on {threads} threads");
            assert_eq!(
                g1.containment, g.containment,
                "{kind:?} on {threads} threads"
            );
        }
        if kind == ContainerShape::Ball {
            let all = Model::<3>::new(axes.clone(), kind)
                .unwrap()
                .overlap_all_pairs(&x)
                .unwrap();
            for ev in [one, v1] {
                assert!(
                    (ev.overlap - all).abs() <= 1e-13 * all,
                    "{} {all}",
                    ev.overlap
                );
            }
        }
    }
}

#[track_caller]
fn assert_same_bits(grid: f64, all_pairs: f64) {
    assert_eq!(grid.to_bits(), all_pairs.to_bits(), "{grid} {all_pairs}");
}

fn fd_check(
    p_eval: &mut dyn FnMut(
        &[f64],
        Option<&mut ModelGradient>,
    ) -> implicit_packing::model::Evaluation,
    x: &[f64],
) {
    let mut g = ModelGradient::default();
    let ev = p_eval(x, Some(&mut g));
    let ev0 = p_eval(x, None);
    assert_eq!(ev.overlap, ev0.overlap);
    assert_eq!(ev.containment, ev0.containment);
    assert_eq!(ev.objective, ev0.objective);
    assert!(ev.overlap > 0.0 && ev.containment > 0.0);
    let h = 1e-6;
    let mut worst = [0.0f64; 3];
    let scales = [
        g.overlap.iter().fold(0.0f64, |m, v| m.max(v.abs())),
        g.containment.iter().fold(0.0f64, |m, v| m.max(v.abs())),
        g.objective.iter().fold(0.0f64, |m, v| m.max(v.abs())),
    ];
    for k in 0..x.len() {
        let mut xp = x.to_vec();
        xp[k] += h;
        let mut xm = x.to_vec();
        xm[k] -= h;
        let ep = p_eval(&xp, None);
        let em = p_eval(&xm, None);
        let fd = [
            (ep.overlap - em.overlap) / (2.0 * h),
            (ep.containment - em.containment) / (2.0 * h),
            (ep.objective - em.objective) / (2.0 * h),
        ];
        let an = [g.overlap[k], g.containment[k], g.objective[k]];
        for q in 0..3 {
            worst[q] = worst[q].max((fd[q] - an[q]).abs() / scales[q]);
        }
    }
    println!(
        "model gradient vs FD: overlap {:.2e}, containment {:.2e}, objective {:.2e}",
        worst[0], worst[1], worst[2]
    );
    assert!(worst.iter().all(|&w| w <= 1e-6), "{worst:?}");
}

#[test]
fn model_gradient_matches_finite_differences() {
    let mut rng = Rng::new(33);
    for kind in KINDS {
        let (axes, x) = config3(&mut rng, 27, 0.55, kind);
        let mut p = Model::<3>::new(axes, kind).unwrap();
        fd_check(&mut |x, g| p.evaluate(x, g).unwrap(), &x);
    }
    let (axes, x) = config2(&mut rng, 25, 0.6);
    let mut p = Model::<2>::new(axes, ContainerShape::Box).unwrap();
    fd_check(&mut |x, g| p.evaluate(x, g).unwrap(), &x);
}

/// Among several bad variables of a large model (checked in groups of items, in parallel with
/// the `rayon` feature) the first is named: a centre beyond 1e30 in a late group, a NaN angle
/// in an earlier one, an infinite container dimension.
#[test]
fn the_first_bad_variable_of_many_items_is_named() {
    let m = 10_000;
    let mut p = Model::<3>::new(vec![[1.0, 0.5, 0.25]; m], ContainerShape::Box).unwrap();
    let mut x = vec![0.0; p.var_count()];
    let n = x.len();
    // Apart, on a cubic lattice of spacing 3.
    for (i, item) in x[..6 * m].chunks_mut(6).enumerate() {
        item[..3].copy_from_slice(&[(i % 22) as f64, (i / 22 % 22) as f64, (i / 484) as f64]);
        item[..3].iter_mut().for_each(|c| *c = 3.0 * *c - 30.0);
    }
    x[n - 3..].copy_from_slice(&[100.0, 100.0, 100.0]);
    assert!(p.evaluate(&x, None).is_ok());
    x[n - 2] = f64::INFINITY;
    assert!(matches!(
        p.evaluate(&x, None),
        Err(Error::NonFiniteVariable { index, .. }) if index == n - 2
    ));
    x[6 * 9_000 + 1] = 2e30;
    x[6 * 4_000 + 4] = f64::NAN;
    assert!(matches!(
        p.evaluate(&x, None),
        Err(Error::NonFiniteVariable { index, .. }) if index == 6 * 4_000 + 4
    ));
    x[6 * 4_000 + 4] = 0.0;
    assert!(matches!(
        p.evaluate(&x, None),
        Err(Error::NonFiniteVariable { index, .. }) if index == 6 * 9_000 + 1
    ));
    // An angle may be large: only centres are bounded.
    x[6 * 9_000 + 1] = 0.0;
    x[n - 2] = 100.0;
    x[6 * 7_000 + 5] = 2e30;
    assert!(p.evaluate(&x, None).is_ok());
}

#[test]
fn bad_variables_are_reported_by_index() {
    let mut p = Model::<3>::new(vec![[1.0, 0.5, 0.25]; 3], ContainerShape::Ball).unwrap();
    let mut x = vec![0.0; p.var_count()];
    x[0] = 3.0;
    x[6] = -3.0;
    x[18] = 10.0;
    assert!(p.evaluate(&x, None).is_ok());
    x[7] = f64::NAN;
    assert!(matches!(
        p.evaluate(&x, None),
        Err(Error::NonFiniteVariable { index: 7, .. })
    ));
    x[7] = 0.0;
    x[18] = -1.0;
    assert!(matches!(
        p.evaluate(&x, None),
        Err(Error::InvalidContainer { dimension: 0, .. })
    ));
    assert!(matches!(
        p.evaluate(&x[..5], None),
        Err(Error::LengthMismatch { .. })
    ));
    assert!(matches!(
        Model::<2>::new(vec![[1.0, 1.0], [1.0, 0.0]], ContainerShape::Box),
        Err(Error::InvalidSemiAxis {
            item: Some(1),
            axis: 1,
            ..
        })
    ));
}

/// `(x, v, out)`: a Hessian–vector product.
type Hvp<'a> = &'a mut dyn FnMut(&[f64], &[f64], &mut ModelGradient);
/// `(x, out)`: a gradient.
type Grad<'a> = &'a mut dyn FnMut(&[f64], &mut ModelGradient);

/// Hessian–vector products of the model against central differences of its exact gradient,
/// and symmetric (uᵀHv = vᵀHu), for the three containers in 3D and a box in 2D.
#[test]
fn hessian_vector_products_match_finite_differences() {
    let mut rng = Rng::new(55);
    for kind in KINDS {
        let (axes, x) = config3(&mut rng, 27, 0.55, kind);
        on_two_copies(axes, kind, &x, &mut rng, hvp_check);
    }
    let (axes, x) = config2(&mut rng, 25, 0.6);
    on_two_copies(axes, ContainerShape::Box, &x, &mut rng, hvp_check);
}

/// The Hessian–vector products `p` against central differences of the gradient `grad` along
/// random directions, and their symmetry `uᵀHv = vᵀHu`.
fn hvp_check(p: Hvp<'_>, grad: Grad<'_>, x: &[f64], rng: &mut Rng) {
    let n = x.len();
    let (mut hu, mut hv) = (ModelGradient::default(), ModelGradient::default());
    let (mut gp, mut gm) = (ModelGradient::default(), ModelGradient::default());
    let mut worst = [0.0f64; 3];
    let mut worst_sym = 0.0f64;
    for _ in 0..5 {
        let u: Vec<f64> = (0..n).map(|_| rng.range(-1.0, 1.0)).collect();
        let v: Vec<f64> = (0..n).map(|_| rng.range(-1.0, 1.0)).collect();
        p(x, &u, &mut hu);
        p(x, &v, &mut hv);
        let h = 1e-6;
        let xp: Vec<f64> = x.iter().zip(&v).map(|(a, b)| a + h * b).collect();
        let xm: Vec<f64> = x.iter().zip(&v).map(|(a, b)| a - h * b).collect();
        grad(&xp, &mut gp);
        grad(&xm, &mut gm);
        for (q, (an, (pp, mm))) in [
            (&hv.overlap, (&gp.overlap, &gm.overlap)),
            (&hv.containment, (&gp.containment, &gm.containment)),
            (&hv.objective, (&gp.objective, &gm.objective)),
        ]
        .into_iter()
        .enumerate()
        {
            let scale = an.iter().fold(0.0f64, |m, a| m.max(a.abs()));
            for k in 0..n {
                let fd = (pp[k] - mm[k]) / (2.0 * h);
                worst[q] = worst[q].max((fd - an[k]).abs() / scale.max(1e-300));
            }
        }
        let uhv: f64 = u.iter().zip(&hv.overlap).map(|(a, b)| a * b).sum();
        let vhu: f64 = v.iter().zip(&hu.overlap).map(|(a, b)| a * b).sum();
        worst_sym = worst_sym.max((uhv - vhu).abs() / uhv.abs().max(vhu.abs()));
    }
    println!(
        "model HVP vs FD of the gradient: overlap {:.2e}, containment {:.2e}, objective {:.2e}; asymmetry {worst_sym:.2e}",
        worst[0], worst[1], worst[2]
    );
    assert!(
        worst.iter().all(|&w| w <= 1e-6) && worst_sym <= 1e-9,
        "{worst:?} {worst_sym}"
    );
}

/// Runs `check` with the Hessian–vector products of one model of `axes` in a container of
/// `kind` and the gradients of another (two models, as each closure borrows its own mutably).
fn on_two_copies<const N: usize>(
    axes: Vec<[f64; N]>,
    kind: ContainerShape,
    x: &[f64],
    rng: &mut Rng,
    check: impl Fn(Hvp<'_>, Grad<'_>, &[f64], &mut Rng),
) {
    let mut p = Model::<N>::new(axes.clone(), kind).unwrap();
    let mut q = Model::<N>::new(axes, kind).unwrap();
    check(
        &mut |x, v, out| p.hessian_vector_product(x, v, out).unwrap(),
        &mut |x, g| {
            q.evaluate(x, Some(g)).unwrap();
        },
        x,
        rng,
    );
}

/// Certification by PW85 agrees with the model: a pair has f > 0 exactly when PW85 says it
/// overlaps, and an ellipsoid is reported outside exactly when its residual is positive.
#[test]
fn certification_agrees_with_the_model() {
    let mut rng = Rng::new(66);
    for &density in &[0.3, 0.6] {
        let (axes, x) = config3(&mut rng, 125, density, ContainerShape::Box);
        let mut p = Model::<3>::new(axes, ContainerShape::Box).unwrap();
        let cert = p.certify(&x).unwrap();
        let b = p.bodies().to_vec();
        let mut expect = Vec::new();
        for i in 0..b.len() {
            for j in i + 1..b.len() {
                if implicit_packing::overlap_measure(&b[i], &b[j]) > 0.0 {
                    expect.push((i, j));
                }
            }
        }
        assert_eq!(cert.overlapping_pairs(), expect);
        for o in &cert.overlapping {
            let (i, j) = o.items;
            let mu2 = implicit_packing::certificate::contact(&b[i], &b[j])
                .unwrap()
                .mu2;
            assert_eq!(o.mu2, mu2);
            assert!(mu2 < 1.0);
        }
        let least = cert
            .overlapping
            .iter()
            .map(|o| o.mu2)
            .fold(f64::INFINITY, f64::min);
        assert_eq!(
            cert.min_mu2,
            Some(least),
            "the overlapping pairs hold the least μ²"
        );
        assert!(!cert.is_feasible());
    }
    // Two separated ellipses well inside a disc: feasible.
    let mut p = Model::<2>::new(vec![[1.0, 0.5], [1.0, 0.5]], ContainerShape::Ball).unwrap();
    let cert = p.certify(&[-1.5, 0.0, 0.0, 1.5, 0.0, 0.3, 4.0]).unwrap();
    assert!(cert.is_feasible(), "{cert:?}");
    let cert = p.certify(&[-0.5, 0.0, 0.0, 0.5, 0.0, 0.3, 1.2]).unwrap();
    assert_eq!(cert.overlapping_pairs(), vec![(0, 1)]);
    assert_eq!(cert.outside_items(), vec![0, 1]);
    assert!(cert.outside.iter().all(|o| o.scale > 1.0), "{cert:?}");
}

/// Coincident centres put the pair in the hard case (no Hessian): the Hessian–vector product
/// falls back to a difference of gradients and stays finite.
#[test]
fn hessian_vector_product_in_the_hard_case_is_finite() {
    let mut p = Model::<3>::new(
        vec![[1.0, 0.5, 0.25], [0.8, 0.6, 0.3]],
        ContainerShape::Ball,
    )
    .unwrap();
    let x = [
        0.0, 0.0, 0.0, 0.1, 0.2, 0.3, 0.0, 0.0, 0.0, -0.3, 0.1, 0.2, 3.0,
    ];
    let v: Vec<f64> = (0..x.len()).map(|k| 0.1 * (k as f64 + 1.0)).collect();
    let mut out = ModelGradient::default();
    p.hessian_vector_product(&x, &v, &mut out).unwrap();
    assert!(
        out.overlap
            .iter()
            .chain(&out.containment)
            .chain(&out.objective)
            .all(|a| a.is_finite())
    );
    assert!(out.overlap.iter().any(|&a| a != 0.0));
}

/// Bodies → variables → bodies is the identity (up to rounding of the angle recovery), for
/// ellipsoids, balls (no angles) and spheroids (the direction of the distinct axis), and a
/// spheroid at zero angles is unrotated.
#[test]
fn pack_variables_round_trips() {
    let mut rng = Rng::new(77);
    let general = config3(&mut rng, 8, 0.4, ContainerShape::Ball);
    for (axes, x) in [general, mixed3(&mut rng, 10, 0.4, ContainerShape::Ball)] {
        let mut p = Model::<3>::new(axes, ContainerShape::Ball).unwrap();
        let bodies = p.bodies_at(&x).unwrap().to_vec();
        let y = p.pack_variables(&bodies, &x[x.len() - 1..]).unwrap();
        assert_eq!(y.len(), x.len());
        let again = p.bodies_at(&y).unwrap().to_vec();
        for (a, b) in bodies.iter().zip(&again) {
            let (sa, sb) = (a.shape_matrix(), b.shape_matrix());
            for r in 0..3 {
                assert_eq!(a.centre()[r], b.centre()[r]);
                for c in 0..3 {
                    assert!((sa[r][c] - sb[r][c]).abs() < 1e-13, "{sa:?} {sb:?}");
                }
            }
        }
    }
    let spheroids = vec![[1.0, 1.0, 2.0], [1.0, 2.0, 1.0]];
    let mut q = Model::<3>::new(spheroids, ContainerShape::Ball).unwrap();
    let at_zero = [0.0, 0.0, 0.0, 0.0, 0.0, 5.0, 0.0, 0.0, 0.0, 0.0, 9.0];
    for b in q.bodies_at(&at_zero).unwrap() {
        assert_eq!(
            b.rotation(),
            [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
        );
    }
    let q = Model::<2>::new(vec![[1.0, 0.5]], ContainerShape::Box).unwrap();
    let e = implicit_packing::Ellipse::ellipse([0.3, -0.2], [1.0, 0.5], 2.5).unwrap();
    let y = q.pack_variables(&[e], &[2.0, 3.0]).unwrap();
    assert_eq!((y[0], y[1], y[3], y[4]), (0.3, -0.2, 2.0, 3.0));
    assert!((y[2] - 2.5).abs() < 1e-14);
    let wrong = implicit_packing::Ellipse::ellipse([0.3, -0.2], [1.0, 0.6], 2.5).unwrap();
    assert!(matches!(
        q.pack_variables(&[wrong], &[2.0, 3.0]),
        Err(Error::InvalidSemiAxis {
            item: Some(0),
            axis: 1,
            ..
        })
    ));
}

/// A spheroid centred on the container's centre and sticking out has a circle of farthest
/// points (hard case, no Hessian): the Hessian–vector product falls back to a difference of
/// gradients and stays finite.
#[test]
fn containment_hessian_in_the_hard_case_is_finite() {
    let mut p = Model::<3>::new(vec![[1.0, 1.0, 0.25]], ContainerShape::Ball).unwrap();
    // A spheroid: its centre, the two angles of its axis, the radius.
    let x = [0.0, 0.0, 0.0, 0.2, 0.3, 0.8];
    let v = [0.1, -0.2, 0.3, -0.5, 0.6, 0.7];
    let mut out = ModelGradient::default();
    p.hessian_vector_product(&x, &v, &mut out).unwrap();
    assert!(out.containment.iter().all(|a| a.is_finite()));
    assert!(out.containment.iter().any(|&a| a != 0.0));
}

/// Aligned items whose centres differ along a short axis only, overlapping from barely to
/// deeply: the pair's secular equation has a term without weight, whose pole sits at the end
/// of the bracket. Every overlap is finite and positive.
#[test]
fn centres_along_a_short_axis_give_finite_overlaps() {
    fn overlaps<const N: usize>(axes: [f64; N], along: usize) -> Vec<f64> {
        let mut model = Model::<N>::new(vec![axes; 2], ContainerShape::Box).unwrap();
        let stride = model.layout().range(0).len();
        (1..2000)
            .map(|k| {
                let mut x = vec![0.0; 2 * stride + N];
                x[stride + along] = axes[along] * 2.0 * k as f64 / 2000.0;
                x[2 * stride..].fill(10.0);
                model.evaluate(&x, None).unwrap().overlap
            })
            .collect()
    }
    for (name, v) in [
        ("2D", overlaps([2.0, 1.0], 1)),
        ("3D, middle axis", overlaps([1.0, 0.75, 0.5], 1)),
        ("3D, short axis", overlaps([1.0, 0.75, 0.5], 2)),
    ] {
        assert!(v.iter().all(|o| o.is_finite() && *o > 0.0), "{name}: {v:?}");
    }
}

/// A run on the model's threads is a task of a pool: of the number asked, of the caller's pool
/// when it runs in one and asks for 0, of rayon's global pool's size otherwise.
#[cfg(feature = "rayon")]
#[test]
fn runs_are_placed_inside_a_pool_of_the_threads_asked() {
    use implicit_packing::model::on_threads;
    let inside = || {
        (
            rayon::current_thread_index().is_some(),
            rayon::current_num_threads(),
        )
    };
    assert_eq!(on_threads(3, inside).unwrap(), (true, 3));
    assert_eq!(
        on_threads(0, inside).unwrap(),
        (true, rayon::current_num_threads())
    );
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap();
    let nested = pool.install(|| on_threads(0, inside).unwrap());
    assert_eq!(nested, (true, 2));
}

/// The semi-axes of `m` items of every kind that carries its own angles (module `layout`):
/// balls, spheroids whose distinct axis is each of the three, general ellipsoids, of sizes
/// near 1.
fn mixed_axes3(rng: &mut Rng, m: usize) -> Vec<[f64; 3]> {
    (0..m)
        .map(|i| {
            let (a, c) = (rng.range(0.7, 0.9), rng.range(0.4, 0.6));
            match i % 5 {
                0 => [a; 3],
                1 => [a, a, c],
                2 => [a, c, a],
                3 => [c, a, a],
                _ => [a, rng.range(0.55, 0.65), c],
            }
        })
        .collect()
}

/// Items of [`mixed_axes3`] placed with the angles each carries; container dimensions last.
fn mixed3(
    rng: &mut Rng,
    m: usize,
    density: f64,
    kind: ContainerShape,
) -> (Vec<[f64; 3]>, Vec<f64>) {
    let axes = mixed_axes3(rng, m);
    let layout = implicit_packing::Layout::of(&axes);
    let x = placed3(rng, &axes, |i| layout.angles(i), density, kind);
    assert_eq!(x.len(), layout.item_variables() + kind.dimension_count(3));
    (axes, x)
}

/// A ball has no angles and a spheroid two: the layout's variables, the gradient (against
/// central differences) and the Hessian–vector products (against differences of the
/// gradient) of scenes mixing them with general ellipsoids, in every container, and of
/// circles with ellipses; the grid sum is still the all-pairs sum.
#[test]
fn round_items_and_spheroids_carry_only_their_angles() {
    let mut rng = Rng::new(88);
    for kind in KINDS {
        let (axes, x) = mixed3(&mut rng, 30, 0.55, kind);
        let mut p = Model::<3>::new(axes.clone(), kind).unwrap();
        assert_eq!(p.var_count(), x.len());
        // 6 balls (3 variables), 18 spheroids (5), 6 ellipsoids (6).
        assert_eq!(
            p.var_count(),
            6 * 3 + 18 * 5 + 6 * 6 + kind.dimension_count(3)
        );
        fd_check(&mut |x, g| p.evaluate(x, g).unwrap(), &x);
        let ev = p.evaluate(&x, None).unwrap();
        assert_same_bits(ev.overlap, p.overlap_all_pairs(&x).unwrap());
        on_two_copies(axes, kind, &x, &mut rng, hvp_check);
    }
    // Circles (no angle) and ellipses in a box.
    let axes: Vec<[f64; 2]> = (0..30)
        .map(|i| [1.0, if i % 2 == 0 { 1.0 } else { 0.5 }])
        .collect();
    let x = placed2(&mut rng, &axes, 0.6);
    assert_eq!(x.len(), 15 * 2 + 15 * 3 + 2);
    let mut p = Model::<2>::new(axes.clone(), ContainerShape::Box).unwrap();
    fd_check(&mut |x, g| p.evaluate(x, g).unwrap(), &x);
    on_two_copies(axes, ContainerShape::Box, &x, &mut rng, hvp_check);
}

/// Two balls by the closed form of module `round` and by the general solution of eq. 35
/// (`pair_term`): the same `f`, and the closed-form gradient against central differences.
#[test]
fn the_closed_form_of_two_balls_is_the_general_pair_term() {
    let mut rng = Rng::new(90);
    let mut worst = 0.0f64;
    for _ in 0..2000 {
        let (ri, rj) = (rng.range(0.2, 2.0), rng.range(0.2, 2.0));
        let dist = rng.range(0.01, 1.0) * (ri + rj);
        let dir = [
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
        ];
        let n = dir.iter().map(|v| v * v).sum::<f64>().sqrt();
        let cj: [f64; 3] = std::array::from_fn(|k| dist * dir[k] / n);
        let bi = implicit_packing::Body::from_angles([0.0; 3], [ri; 3], [0.0; 3]).unwrap();
        let bj = implicit_packing::Body::from_angles(cj, [rj; 3], [0.3, 0.2, 0.1]).unwrap();
        let closed = implicit_packing::round::round_overlap_measure(&bi, &bj);
        let general = implicit_packing::pair_term(&bi, &bj).f;
        assert_eq!(closed, implicit_packing::overlap_measure(&bi, &bj));
        worst = worst.max((closed - general).abs() / (1.0 + general));
        let (f, g) = implicit_packing::derivatives::round_pair_gradient(&bi, &bj);
        assert_eq!(f, closed);
        let h = 1e-7;
        for k in 0..3 {
            let mut cp = cj;
            cp[k] += h;
            let mut cm = cj;
            cm[k] -= h;
            let at = |c: [f64; 3]| {
                let b = implicit_packing::Body::from_angles(c, [rj; 3], [0.0; 3]).unwrap();
                implicit_packing::round::round_overlap_measure(&bi, &b)
            };
            let fd = (at(cp) - at(cm)) / (2.0 * h);
            assert!(
                (fd - g.centre_j[k]).abs() <= 1e-6 * (1.0 + fd.abs()),
                "{fd} {:?}",
                g
            );
        }
    }
    println!("two balls, closed form against eq. 35: worst |difference| / (1 + f) {worst:.2e}");
    assert!(worst < 1e-12, "{worst}");
}
