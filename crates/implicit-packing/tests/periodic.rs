//! The periodic cell: the image sum equals a brute-force sum over every image, gradients
//! (fractional centres, angles, the six cell entries) against finite differences, the
//! certificate on images, known lattice packings, bad cells named.
#![allow(clippy::needless_range_loop)]

use implicit_packing::Error;
use implicit_packing::containment::ContainerShape;
use implicit_packing::model::{Model, ModelGradient};
use testkit::Rng;

/// `m` items with random semi-axes (aspect up to `aspect`), random fractional centres (some
/// outside [0, 1), as a solver leaves them), random angles, in a sheared cell of about the
/// given density.
fn config<const N: usize>(
    rng: &mut Rng,
    m: usize,
    density: f64,
    aspect: f64,
) -> (Vec<[f64; N]>, Vec<f64>) {
    let axes: Vec<[f64; N]> = (0..m)
        .map(|_| {
            let a = rng.range(1.0, aspect);
            std::array::from_fn(|k| if k == 0 { a } else { rng.range(0.5, 1.0) })
        })
        .collect();
    let unit = if N == 2 {
        std::f64::consts::PI
    } else {
        4.0 / 3.0 * std::f64::consts::PI
    };
    let measure: f64 = axes.iter().map(|l| unit * l.iter().product::<f64>()).sum();
    let side = (measure / density).powf(1.0 / N as f64);
    let mut x = Vec::new();
    for _ in 0..m {
        for _ in 0..N {
            x.push(rng.range(-0.5, 1.5));
        }
        for _ in 0..N * (N - 1) / 2 {
            x.push(rng.range(-3.0, 3.0));
        }
    }
    let diagonal: Vec<f64> = (0..N).map(|_| side * rng.range(0.8, 1.25)).collect();
    x.extend_from_slice(&diagonal);
    for _ in 0..N * (N - 1) / 2 {
        x.push(side * rng.range(-0.4, 0.4));
    }
    (axes, x)
}

fn relative(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs().max(1e-300)
}

/// The generic check `$check` as two tests, `$check::in_2d` and `$check::in_3d`.
macro_rules! in_2d_and_3d {
    ($check:ident) => {
        mod $check {
            #[test]
            fn in_2d() {
                super::$check::<2>();
            }

            #[test]
            fn in_3d() {
                super::$check::<3>();
            }
        }
    };
}

/// The image sum equals the brute-force sum, also after moves that rebuild the image set and
/// moves that do not; with one item (its own images), a few and many.
fn image_sum_matches_brute_force<const N: usize>() {
    let mut rng = Rng::new(7 + N as u64);
    for (m, density, aspect) in [(1, 0.9, 1.5), (2, 0.8, 2.0), (3, 0.7, 3.0), (40, 0.75, 2.0)] {
        let (axes, mut x) = config::<N>(&mut rng, m, density, aspect);
        let mut model = Model::<N>::new(axes, ContainerShape::Periodic).unwrap();
        for step in 0..12 {
            let value = model.evaluate(&x, None).unwrap();
            let reference = model.overlap_all_pairs(&x).unwrap();
            assert!(
                reference > 0.0,
                "{N}D m = {m}: nothing overlaps, a weak test"
            );
            assert!(
                relative(value.overlap, reference) < 1e-12,
                "{N}D m = {m}, step {step}: {} against {reference}",
                value.overlap
            );
            let mut g = ModelGradient::default();
            let with_gradient = model.evaluate(&x, Some(&mut g)).unwrap();
            assert!(relative(with_gradient.overlap, reference) < 1e-12);
            // Small and large moves of the items and the cell.
            let size = if step % 3 == 2 { 0.3 } else { 0.003 };
            for v in x.iter_mut() {
                *v += size * rng.range(-1.0, 1.0);
            }
        }
    }
}

in_2d_and_3d!(image_sum_matches_brute_force);

/// The gradient with respect to every variable (fractional centres, angles, cell entries)
/// against central differences of the value.
fn gradient_matches_differences<const N: usize>() {
    let mut rng = Rng::new(11 + N as u64);
    for (m, density, aspect) in [(1, 0.95, 1.6), (3, 0.8, 2.5), (12, 0.75, 2.0)] {
        let (axes, x) = config::<N>(&mut rng, m, density, aspect);
        let mut model = Model::<N>::new(axes, ContainerShape::Periodic).unwrap();
        let mut g = ModelGradient::default();
        let ev = model.evaluate(&x, Some(&mut g)).unwrap();
        assert!(ev.overlap > 0.0);
        let scale = g.overlap.iter().fold(0.0f64, |a, b| a.max(b.abs()));
        for k in 0..x.len() {
            let h = 1e-6 * x[k].abs().max(1.0);
            let at = |t: f64, model: &mut Model<N>| {
                let mut y = x.clone();
                y[k] += t;
                model.evaluate(&y, None).unwrap()
            };
            let (p, q) = (at(h, &mut model), at(-h, &mut model));
            let fd = (p.overlap - q.overlap) / (2.0 * h);
            assert!(
                (g.overlap[k] - fd).abs() <= 1e-6 * scale,
                "{N}D m = {m}, variable {k}: {} against {fd}",
                g.overlap[k]
            );
            let fd_objective = (p.objective - q.objective) / (2.0 * h);
            assert!((g.objective[k] - fd_objective).abs() <= 1e-6 * ev.objective.max(1.0));
        }
        assert!(g.containment.iter().all(|&v| v == 0.0));
    }
}

in_2d_and_3d!(gradient_matches_differences);

/// One disc of radius 1 in the hexagonal cell [[2, 1], [0, √3]], the densest packing of
/// discs (π/(2√3) = 0.9069), and its affine image, one ellipse (2, 1) in [[4, 2], [0, √3]]:
/// both are packings, every item touching six images (three classes, μ² = 1), and the cell
/// shrunk by one part in a million overlaps (an item with its own images).
#[test]
fn hexagonal_packings_of_discs_and_ellipses_are_tangent() {
    let hex = 3f64.sqrt();
    for (axes, cell) in [([1.0, 1.0], [2.0, hex, 1.0]), ([2.0, 1.0], [4.0, hex, 2.0])] {
        let mut model = Model::<2>::new(vec![axes], ContainerShape::Periodic).unwrap();
        // A disc has no angle; the ellipse's is 0.
        let mut x = vec![0.3, 0.6];
        x.extend(std::iter::repeat_n(0.0, model.layout().angles(0)));
        let items = x.len();
        x.extend_from_slice(&cell);
        let cert = model.certify(&x).unwrap();
        assert!(cert.is_feasible(), "{axes:?}: {cert:?}");
        if axes[0] != axes[1] {
            // Discs at tangency are not even checked (their enclosing balls only touch).
            let mu2 = cert.min_mu2.unwrap();
            assert!((mu2 - 1.0).abs() < 1e-12, "{mu2}");
        }
        let area = std::f64::consts::PI * axes[0] * axes[1];
        let density = area / model.evaluate(&x, None).unwrap().objective;
        assert!((density - std::f64::consts::PI / (2.0 * hex)).abs() < 1e-15);
        let shrunk = model.dilated(&x, 1.0 - 1e-6);
        assert_eq!(
            &shrunk[..items],
            &x[..items],
            "fractional centres are not dilated"
        );
        let cert = model.certify(&shrunk).unwrap();
        assert_eq!(cert.overlapping_pairs(), vec![(0, 0); 3], "{axes:?}");
        assert!(model.evaluate(&shrunk, None).unwrap().overlap > 0.0);
    }
}

/// Spheres of radius 1 in the FCC cell (four per cubic cell of side 2√2): density
/// π/(3√2) = 0.7405, tangent; the same lattice as one sphere per rhombohedral (sheared) cell.
#[test]
fn face_centred_cubic_spheres_are_tangent_in_both_cells() {
    let a = 2.0 * 2f64.sqrt();
    let mut cubic = Model::<3>::new(vec![[1.0; 3]; 4], ContainerShape::Periodic).unwrap();
    let mut x = Vec::new();
    for s in [
        [0.0, 0.0, 0.0],
        [0.5, 0.5, 0.0],
        [0.5, 0.0, 0.5],
        [0.0, 0.5, 0.5],
    ] {
        // A ball has no angles.
        x.extend_from_slice(&s);
    }
    x.extend_from_slice(&[a, a, a, 0.0, 0.0, 0.0]);
    let cert = cubic.certify(&x).unwrap();
    assert!(cert.is_feasible(), "{cert:?}");
    let cert = cubic.certify(&cubic.dilated(&x, 0.999)).unwrap();
    assert_eq!(
        cert.overlapping.len(),
        4 * 6,
        "twelve neighbours each, six classes"
    );
    let volume = cubic.evaluate(&x, None).unwrap().objective;
    let density = 4.0 * 4.0 / 3.0 * std::f64::consts::PI / volume;
    assert!((density - std::f64::consts::PI / (3.0 * 2f64.sqrt())).abs() < 1e-14);
    // The primitive cell: a = (2, 0, 0), b = (1, √3, 0), c = (1, 1/√3, √(8/3)).
    let mut primitive = Model::<3>::new(vec![[1.0; 3]], ContainerShape::Periodic).unwrap();
    let y = vec![
        0.1,
        0.2,
        0.3,
        2.0,
        3f64.sqrt(),
        (8.0f64 / 3.0).sqrt(),
        1.0,
        1.0,
        1.0 / 3f64.sqrt(),
    ];
    // The cell's irrational entries put some contacts an ulp inside tangency.
    let cert = primitive
        .certify(&primitive.dilated(&y, 1.0 + 1e-12))
        .unwrap();
    assert!(cert.is_feasible(), "{cert:?}");
    assert_eq!(
        primitive
            .evaluate(&primitive.dilated(&y, 1.0 + 1e-12), None)
            .unwrap()
            .overlap,
        0.0
    );
    let cert = primitive.certify(&primitive.dilated(&y, 0.999)).unwrap();
    assert_eq!(cert.overlapping.len(), 6, "twelve neighbours, six classes");
}

#[test]
fn bad_cells_and_far_items_are_named() {
    let mut model = Model::<2>::new(vec![[1.0, 0.5]], ContainerShape::Periodic).unwrap();
    let err = model.evaluate(&[0.0, 0.0, 0.0, -1.0, 2.0, 0.0], None);
    assert_eq!(
        err.unwrap_err(),
        Error::InvalidContainer {
            dimension: 0,
            value: -1.0
        }
    );
    let err = model.evaluate(&[0.0, 0.0, 0.0, 2.0, 2.0, f64::NAN], None);
    assert!(matches!(
        err,
        Err(Error::NonFiniteVariable { index: 5, .. })
    ));
    let err = model.evaluate(&[0.0, 3e9, 0.0, 2.0, 2.0, 0.0], None);
    assert!(matches!(
        err,
        Err(Error::FractionalOutOfRange { index: 1, .. })
    ));
    let err = model.evaluate(&[0.0, 0.0, 0.0, 1e-4, 1e-4, 0.0], None);
    assert!(matches!(err, Err(Error::CellCrowded { .. })), "{err:?}");
    let message = err.unwrap_err().to_string();
    assert!(
        message.contains("cover it 3.14159e8 times over"),
        "{message}"
    );
    // Thin in one direction only, with room along the other: too many images, not pairs.
    let err = model.evaluate(&[0.0, 0.0, 0.0, 1e7, 1e-6, 0.0], None);
    assert!(matches!(err, Err(Error::PeriodicImages { .. })), "{err:?}");
    let message = err.unwrap_err().to_string();
    assert!(message.contains("too thin"), "{message}");
}

/// The reduced cell spans the same lattice: the same packing, value and certificate.
#[test]
fn reduced_cells_hold_the_same_packing() {
    use implicit_packing::periodic::{reduced, to_cartesian, to_fractional};
    let mut rng = Rng::new(5);
    let (axes, mut x) = config::<3>(&mut rng, 20, 0.6, 2.0);
    let n = x.len();
    // Large tilts: several cells of shear.
    x[n - 3] += 2.3 * x[n - 6];
    x[n - 2] -= 1.7 * x[n - 6];
    x[n - 1] += 3.2 * x[n - 5];
    let mut model = Model::<3>::new(axes, ContainerShape::Periodic).unwrap();
    let before = model.evaluate(&x, None).unwrap();
    let cell: [[f64; 3]; 3] = [
        [x[n - 6], x[n - 3], x[n - 2]],
        [0.0, x[n - 5], x[n - 1]],
        [0.0, 0.0, x[n - 4]],
    ];
    let h = reduced(&cell);
    assert!(h[0][1].abs() <= 0.5 * h[0][0] && h[0][2].abs() <= 0.5 * h[0][0]);
    assert!(h[1][2].abs() <= 0.5 * h[1][1]);
    let mut y = x.clone();
    for i in 0..20 {
        let c = to_cartesian(&cell, &[x[6 * i], x[6 * i + 1], x[6 * i + 2]]);
        y[6 * i..6 * i + 3].copy_from_slice(&to_fractional(&h, &c));
    }
    y[n - 3..].copy_from_slice(&[h[0][1], h[0][2], h[1][2]]);
    let after = model.evaluate(&y, None).unwrap();
    assert!(
        relative(after.overlap, before.overlap) < 1e-10,
        "{after:?} {before:?}"
    );
    assert!(relative(after.objective, before.objective) < 1e-15);
    assert_eq!(
        model.certify(&x).unwrap().overlapping.len(),
        model.certify(&y).unwrap().overlapping.len()
    );
}
