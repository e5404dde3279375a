//! Variable periodic cells find the densest lattice packings from loose, perturbed starts:
//! discs and ellipses (2, 1) 0.9069 (π/√12, the hexagonal packing and its affine images),
//! spheres 0.7405 (π/√18, FCC/HCP), with 1, 2 and 4 items per cell.

use ellipsoid_packer::local::{LocalSettings, local_minimisation};
use ellipsoid_packer::starts::periodic_lattice_start;
use implicit_packing::containment::ContainerShape;
use implicit_packing::model::Model;

/// The packing fraction at `x` of the model's `m` items of semi-axes `axes`.
fn density<const N: usize>(model: &mut Model<N>, x: &[f64], m: usize, axes: &[f64; N]) -> f64 {
    let unit = if N == 2 {
        std::f64::consts::PI
    } else {
        4.0 / 3.0 * std::f64::consts::PI
    };
    m as f64 * unit * axes.iter().product::<f64>() / model.evaluate(x, None).unwrap().objective
}

/// The lattice start with `per_cell` items, loosened by `loose` (the cell dilated, the items
/// turned and moved a little, deterministically), minimised.
fn densest<const N: usize>(axes: [f64; N], per_cell: usize, loose: f64) -> (f64, f64) {
    let mut model = Model::<N>::new(vec![axes; per_cell], ContainerShape::Periodic).unwrap();
    let x0 = periodic_lattice_start(&model, per_cell, &[0.0; N]);
    let mut x = model.dilated(&x0, loose);
    let nb = model.layout().item_variables();
    for (k, v) in x[..nb].iter_mut().enumerate() {
        *v += 0.05 * (((k * 7919) % 13) as f64 / 6.0 - 1.0);
    }
    let start_cert = model.certify(&x).unwrap();
    assert!(start_cert.is_feasible(), "{start_cert:?}");
    let settings = LocalSettings::default()
        .with_feasibility_tolerance(1e-10)
        .with_optimality_tolerance(1e-8);
    let r = local_minimisation(&mut model, &x, &settings, &mut |_| false).unwrap();
    assert!(r.certificate.is_feasible());
    let start = density(&mut model, &x, per_cell, &axes);
    (r.density, start)
}

#[test]
fn discs_and_ellipses_reach_the_hexagonal_density() {
    let hexagonal = std::f64::consts::PI / 12f64.sqrt();
    for axes in [[1.0, 1.0], [2.0, 1.0]] {
        for per_cell in [1, 2, 4] {
            let (density, start) = densest::<2>(axes, per_cell, 1.4);
            eprintln!("{axes:?} x{per_cell}: {start:.4} -> {density:.6}");
            assert!(
                density <= hexagonal * (1.0 + 1e-9),
                "{density} beats the optimum"
            );
            assert!(
                density >= hexagonal * (1.0 - 1e-3),
                "{axes:?}, {per_cell} per cell: {density} from {start}"
            );
        }
    }
}

#[test]
fn spheres_reach_the_fcc_density() {
    let fcc = std::f64::consts::PI / 18f64.sqrt();
    for per_cell in [1, 2, 4] {
        let (density, start) = densest::<3>([1.0, 1.0, 1.0], per_cell, 1.3);
        eprintln!("spheres x{per_cell}: {start:.4} -> {density:.6}");
        assert!(density <= fcc * (1.0 + 1e-9), "{density} beats the optimum");
        assert!(
            density >= fcc * (1.0 - 1e-3),
            "{per_cell} per cell: {density} from {start}"
        );
    }
}

/// Every periodic lattice start is a packing at the lattice's density (π/√12 or π/√18 when
/// the sites are all filled), whatever the number of items.
#[test]
fn periodic_lattice_starts_are_certified() {
    fn check<const N: usize>(axes: [f64; N], m: usize, per_cell: usize, optimum: f64) {
        let mut model = Model::<N>::new(vec![axes; m], ContainerShape::Periodic).unwrap();
        let shift = [0.25 * (m % 2) as f64; N];
        let x = periodic_lattice_start(&model, per_cell, &shift);
        let cert = model.certify(&x).unwrap();
        assert!(
            cert.is_feasible(),
            "{N}D, m = {m}, {per_cell} per cell: {cert:?}"
        );
        let density = density(&mut model, &x, m, &axes);
        assert!(density <= optimum * (1.0 + 1e-12), "{density}");
        // One unit cell, or 10 × 10 × 10: every site filled.
        if m == per_cell || m == 1000 {
            assert!(
                density >= optimum * (1.0 - 1e-8),
                "{N}D, m = {m}: {density}"
            );
        }
    }
    let (hex, fcc) = (
        std::f64::consts::PI / 12f64.sqrt(),
        std::f64::consts::PI / 18f64.sqrt(),
    );
    for per_cell in [1, 2, 4] {
        for m in [1, 2, 4, 7, 16, 64] {
            check([2.0, 1.0], m, per_cell, hex);
            check([1.0, 0.75, 0.5], m, per_cell, fcc);
        }
    }
    check([1.0, 0.75, 0.5], 1000, 1, fcc);
}

/// The densest small cell tiled: 8 ellipses (2, 1) get the hexagonal density from a tiling of
/// a small cell, certified, their cell the small cell's repeated.
#[test]
fn small_cells_tile_into_a_certified_start_at_their_density() {
    use ellipsoid_packer::multistart::MultiStartSettings;
    use ellipsoid_packer::tiling::tiled_start;
    let mut model = Model::<2>::new(vec![[2.0, 1.0]; 8], ContainerShape::Periodic).unwrap();
    // Bounded by its local minimisations; the time is only a ceiling.
    let settings = MultiStartSettings::paper(2, 1)
        .with_lattice_starts(4)
        .with_max_local_minimisations(7);
    let (x, density) = tiled_start(
        &mut model,
        &settings,
        std::time::Duration::from_secs(600),
        &(),
    )
    .unwrap()
    .expect("identical items in a periodic cell");
    assert!(model.certify(&x).unwrap().is_feasible());
    let hexagonal = std::f64::consts::PI / 12f64.sqrt();
    assert!((density - hexagonal).abs() < 1e-4 * hexagonal, "{density}");
    // Mixed items are not tiled.
    let mut mixed =
        Model::<2>::new(vec![[2.0, 1.0], [1.0, 1.0]], ContainerShape::Periodic).unwrap();
    assert!(
        tiled_start(
            &mut mixed,
            &settings,
            std::time::Duration::from_millis(100),
            &()
        )
        .unwrap()
        .is_none()
    );
}
