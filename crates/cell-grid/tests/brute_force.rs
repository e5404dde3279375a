//! The grid against the O(m^2) reference on the configurations of issue 3.

mod common;

use cell_grid::{Grid, GridBuilder, Layout};
use common::{Box, brute_pairs, check_grid, neighbour_lists};
use testkit::Rng;

/// Builds with a global cutoff, dense and hashed, and checks both against brute force.
fn check_cutoff<const D: usize>(pts: &[[f64; D]], cutoff: f64) -> usize {
    let bx = Box::<D>::open();
    let expected = brute_pairs(pts, |_, _| cutoff, &bx);
    let dense = Grid::<D>::build(pts, cutoff).unwrap();
    check_grid(&dense, pts, &expected, &bx);
    let hashed = GridBuilder::<D>::with_cutoff(cutoff)
        .max_cells(0)
        .build(pts)
        .unwrap();
    assert_eq!(hashed.layout(), Layout::Hashed);
    check_grid(&hashed, pts, &expected, &bx);
    check_neighbours(&dense, pts, &expected);
    check_neighbours(&hashed, pts, &expected);
    expected.len()
}

fn check_neighbours<const D: usize>(g: &Grid<D>, pts: &[[f64; D]], pairs: &[(usize, usize)]) {
    let lists = neighbour_lists(pts.len(), pairs);
    for (i, want) in lists.iter().enumerate() {
        assert_eq!(&g.neighbours(i).unwrap(), want, "neighbours of item {i}");
    }
}

fn uniform<const D: usize>(rng: &mut Rng, m: usize, side: f64) -> Vec<[f64; D]> {
    (0..m).map(|_| rng.point::<D>(0.0, side)).collect()
}

fn clustered<const D: usize>(rng: &mut Rng, m: usize) -> Vec<[f64; D]> {
    // A few tight blobs far apart plus scattered points: very uneven cell occupancy.
    let centres: Vec<[f64; D]> = (0..4).map(|_| rng.point::<D>(0.0, 50.0)).collect();
    (0..m)
        .map(|i| {
            if i % 5 == 0 {
                rng.point::<D>(0.0, 50.0)
            } else {
                let c = centres[i % centres.len()];
                std::array::from_fn(|k| c[k] + rng.range(-0.8, 0.8))
            }
        })
        .collect()
}

#[test]
fn uniform_random_2d_and_3d() {
    let mut rng = Rng::new(1);
    for &(m, side) in &[(2usize, 1.0), (50, 3.0), (400, 10.0), (1500, 20.0)] {
        let p2 = uniform::<2>(&mut rng, m, side);
        check_cutoff(&p2, 1.0);
        let p3 = uniform::<3>(&mut rng, m, side / 2.0);
        check_cutoff(&p3, 1.0);
    }
    // Enough pairs that the comparison means something.
    let p3 = uniform::<3>(&mut rng, 1500, 8.0);
    assert!(check_cutoff(&p3, 1.0) > 1000);
}

#[test]
fn clustered_points() {
    let mut rng = Rng::new(2);
    let p2 = clustered::<2>(&mut rng, 800);
    assert!(check_cutoff(&p2, 0.3) > 1000);
    let p3 = clustered::<3>(&mut rng, 800);
    assert!(check_cutoff(&p3, 0.3) > 1000);
}

#[test]
fn all_points_identical() {
    let p2 = vec![[1.5, -2.0]; 150];
    assert_eq!(check_cutoff(&p2, 0.1), 150 * 149 / 2);
    let p3 = vec![[1e6, 3.0, -7.0]; 40];
    assert_eq!(check_cutoff(&p3, 0.1), 40 * 39 / 2);
    let g = Grid::<3>::build(&p3, 0.1).unwrap();
    assert_eq!(g.cells_per_axis(), [1, 1, 1]);
    assert_eq!(g.nonempty_cell_count(), 1);
}

/// A cell of 3 + 4k mutually close points, k = 16 … 18: the first point's candidates fill the
/// hit buffer with whole quads of four (64 hits) and leave one to three for the scalar loop,
/// which must flush the full buffer first.
#[test]
fn quads_that_fill_the_hit_buffer_exactly() {
    let mut rng = Rng::new(11);
    for m in [67, 68, 69, 70, 71, 131] {
        let pts: Vec<[f64; 3]> = (0..m).map(|_| rng.point(0.0, 0.01)).collect();
        assert_eq!(check_cutoff(&pts, 1.0), m * (m - 1) / 2, "m = {m}");
        let radii = vec![1.0; m];
        check_radii(&pts, &radii);
    }
}

#[test]
fn points_on_a_line() {
    let mut rng = Rng::new(3);
    let p2: Vec<[f64; 2]> = (0..300).map(|_| [rng.range(0.0, 30.0), 4.0]).collect();
    check_cutoff(&p2, 0.5);
    // A diagonal line in 3D: degenerate in none of the axes but sparse in the volume.
    let p3: Vec<[f64; 3]> = (0..300)
        .map(|_| {
            let t = rng.range(0.0, 30.0);
            [t, 2.0 * t, -t]
        })
        .collect();
    check_cutoff(&p3, 1.5);
    // Along z only.
    let p3z: Vec<[f64; 3]> = (0..300).map(|_| [0.0, 0.0, rng.range(0.0, 30.0)]).collect();
    check_cutoff(&p3z, 0.5);
}

#[test]
fn points_outside_a_given_domain_go_to_border_cells() {
    let mut rng = Rng::new(4);
    for layout_cap in [None, Some(0)] {
        let pts: Vec<[f64; 3]> = (0..700).map(|_| rng.point::<3>(-5.0, 15.0)).collect();
        let mut b = GridBuilder::<3>::with_cutoff(1.0).domain([0.0; 3], [10.0; 3]);
        if let Some(c) = layout_cap {
            b = b.max_cells(c);
        }
        let g = b.build(&pts).unwrap();
        assert_eq!(g.domain(), ([0.0; 3], [10.0; 3]));
        let bx = Box::<3>::open();
        let expected = brute_pairs(&pts, |_, _| 1.0, &bx);
        check_grid(&g, &pts, &expected, &bx);
        let dims = g.cells_per_axis();
        for (i, p) in pts.iter().enumerate() {
            let c = g.cell_of_item(i).unwrap();
            for a in 0..3 {
                if p[a] < 0.0 {
                    assert_eq!(c[a], 0, "point {i} axis {a}");
                }
                if p[a] > 10.0 {
                    assert_eq!(c[a], dims[a] - 1, "point {i} axis {a}");
                }
            }
        }
    }
    // 2D, far outside.
    let pts = [[-1e9, 0.5], [-1e9 + 0.5, 0.5], [0.5, 0.5], [1e9, 1e9]];
    let g = GridBuilder::<2>::with_cutoff(1.0)
        .domain([0.0; 2], [4.0; 2])
        .build(&pts)
        .unwrap();
    assert_eq!(g.close_pairs(), vec![(0, 1)]);
}

#[test]
fn polydisperse_radii_spanning_100x() {
    let mut rng = Rng::new(5);
    for _ in 0..2 {
        let m = 600;
        let pts3: Vec<[f64; 3]> = (0..m).map(|_| rng.point::<3>(0.0, 20.0)).collect();
        // Log-uniform over [0.01, 1]: 100x between smallest and largest.
        let mut radii: Vec<f64> = (0..m).map(|_| 0.01 * 100f64.powf(rng.uniform())).collect();
        radii[0] = 0.01;
        radii[1] = 1.0;
        check_radii(&pts3, &radii);
        let pts2: Vec<[f64; 2]> = (0..m).map(|_| rng.point::<2>(0.0, 20.0)).collect();
        check_radii(&pts2, &radii);
    }
}

fn check_radii<const D: usize>(pts: &[[f64; D]], radii: &[f64]) {
    let bx = Box::<D>::open();
    let expected = brute_pairs(pts, |i, j| radii[i] + radii[j], &bx);
    assert!(!expected.is_empty());
    for cap in [None, Some(0)] {
        for split in [true, false] {
            let mut b = GridBuilder::<D>::with_radii(radii).split_large_items(split);
            if let Some(c) = cap {
                b = b.max_cells(c);
            }
            let g = b.build(pts).unwrap();
            assert_eq!(g.reach(), 2.0 * 1.0);
            check_grid(&g, pts, &expected, &bx);
            check_neighbours(&g, pts, &expected);
        }
    }
}

/// Many small items and a few giant ones: the case where cells sized for the largest
/// radius degenerate towards brute force, and the size split pays.
fn bimodal<const D: usize>(rng: &mut Rng, m: usize, side: f64) -> (Vec<[f64; D]>, Vec<f64>) {
    let pts: Vec<[f64; D]> = (0..m).map(|_| rng.point::<D>(0.0, side)).collect();
    let radii = giants_among_small(rng, m, |i| i % 400 == 7, 2.0, (0.02, 0.05));
    (pts, radii)
}

/// `m` radii: `giant` where `is_giant(i)`, elsewhere drawn uniformly from `small`.
fn giants_among_small(
    rng: &mut Rng,
    m: usize,
    is_giant: impl Fn(usize) -> bool,
    giant: f64,
    small: (f64, f64),
) -> Vec<f64> {
    (0..m)
        .map(|i| {
            if is_giant(i) {
                giant
            } else {
                rng.range(small.0, small.1)
            }
        })
        .collect()
}

#[test]
fn size_split_keeps_pairs_exact_and_cuts_candidates() {
    let mut rng = Rng::new(13);
    let (pts, radii) = bimodal::<3>(&mut rng, 2400, 6.0);
    let bx = Box::<3>::open();
    let expected = brute_pairs(&pts, |i, j| radii[i] + radii[j], &bx);
    let split = GridBuilder::<3>::with_radii(&radii).build(&pts).unwrap();
    let plain = GridBuilder::<3>::with_radii(&radii)
        .split_large_items(false)
        .build(&pts)
        .unwrap();
    assert_eq!(plain.split_radius(), None);
    let r_cut = split
        .split_radius()
        .expect("a 40x size gap should be split");
    assert!(r_cut > 0.05 && r_cut <= 2.0, "split radius {r_cut}");
    assert_eq!(split.large_items().len(), 6);
    assert!(split.large_items().iter().all(|&i| radii[i] == 2.0));
    let cells: usize = split.cells().map(|c| c.items.len()).sum();
    assert_eq!(cells + split.large_items().len(), pts.len());
    for g in [&split, &plain] {
        check_grid(g, &pts, &expected, &bx);
        check_neighbours(g, &pts, &expected);
    }
    let count = |g: &Grid<3>| {
        let mut n = 0usize;
        g.for_each_candidate_pair(|_, _| n += 1);
        n
    };
    let (n_split, n_plain) = (count(&split), count(&plain));
    assert!(
        n_split * 10 < n_plain,
        "split {n_split} candidates, plain {n_plain}"
    );
    for i in [7, 8, 407] {
        let c = split.cell_of_item(i).unwrap();
        assert_eq!(c, split.cell_of_point(pts[i]).unwrap());
        assert_eq!(split.position(i).unwrap(), pts[i]);
    }

    // Periodic, hashed, 2D, and after a rebuild with moved points and new radii.
    let (mut pts2, mut radii2) = bimodal::<2>(&mut rng, 2400, 30.0);
    let bx2 = Box {
        lo: [0.0; 2],
        len: [30.0; 2],
        periodic: [true; 2],
    };
    let mut g = GridBuilder::<2>::with_radii(&radii2)
        .periodic_box([0.0; 2], [30.0; 2])
        .max_cells(0)
        .build(&pts2)
        .unwrap();
    assert!(g.split_radius().is_some());
    check_grid(
        &g,
        &pts2,
        &brute_pairs(&pts2, |i, j| radii2[i] + radii2[j], &bx2),
        &bx2,
    );
    for p in &mut pts2 {
        p[0] += rng.range(-1.0, 1.0);
    }
    radii2[1] = 3.0;
    g.rebuild_with_radii(&pts2, &radii2).unwrap();
    assert!(g.large_items().contains(&1));
    let want = brute_pairs(&pts2, |i, j| radii2[i] + radii2[j], &bx2);
    check_grid(&g, &pts2, &want, &bx2);
    check_neighbours(&g, &pts2, &want);
}

fn check_periodic<const D: usize>(
    pts: &[[f64; D]],
    lo: [f64; D],
    hi: [f64; D],
    periodic: [bool; D],
    cutoff: f64,
) -> Vec<(usize, usize)> {
    let bx = Box {
        lo,
        len: std::array::from_fn(|k| hi[k] - lo[k]),
        periodic,
    };
    let expected = brute_pairs(pts, |_, _| cutoff, &bx);
    for cap in [None, Some(0)] {
        let mut b = GridBuilder::<D>::with_cutoff(cutoff)
            .domain(lo, hi)
            .periodic(periodic);
        if let Some(c) = cap {
            b = b.max_cells(c);
        }
        let g = b.build(pts).unwrap();
        check_grid(&g, pts, &expected, &bx);
        check_neighbours(&g, pts, &expected);
    }
    expected
}

#[test]
fn periodic_pairs_across_faces_and_corners() {
    // 3D: one pair across each kind of boundary element.
    let pts = [
        [0.1, 5.0, 5.0],  // 0: across the x face with 1
        [9.8, 5.0, 5.0],  // 1
        [0.2, 0.2, 5.0],  // 2: across the xy edge with 3
        [9.9, 9.9, 5.0],  // 3
        [0.1, 0.1, 0.1],  // 4: across the corner with 5
        [9.9, 9.9, 9.95], // 5
        [5.0, 5.0, 5.0],  // 6: alone
        [15.0, 5.0, 5.0], // 7: outside the box, wraps onto 6
    ];
    let got = check_periodic(&pts, [0.0; 3], [10.0; 3], [true; 3], 0.5);
    assert_eq!(got, vec![(0, 1), (2, 3), (4, 5), (6, 7)]);
    // Same points, z not periodic: the corner pair through z is lost, the others stay.
    let got = check_periodic(&pts, [0.0; 3], [10.0; 3], [true, true, false], 0.5);
    assert!(!got.contains(&(4, 5)) && got.contains(&(0, 1)) && got.contains(&(2, 3)));

    let mut rng = Rng::new(6);
    let pts: Vec<[f64; 3]> = (0..800).map(|_| rng.point::<3>(-2.0, 8.0)).collect();
    let got = check_periodic(&pts, [-2.0; 3], [8.0; 3], [true; 3], 1.0);
    assert!(got.len() > 500);
    let pts: Vec<[f64; 2]> = (0..800).map(|_| rng.point::<2>(0.0, 7.0)).collect();
    let got = check_periodic(&pts, [0.0, 0.0], [7.0, 5.0], [true, true], 0.5);
    assert!(got.len() > 300);
    // Points given far outside the box are wrapped before binning.
    let pts: Vec<[f64; 2]> = (0..300).map(|_| rng.point::<2>(-100.0, 100.0)).collect();
    check_periodic(&pts, [0.0, 0.0], [6.0, 6.0], [true, false], 0.5);
}

#[test]
fn periodic_boxes_with_one_or_two_cells_per_axis() {
    let mut rng = Rng::new(7);
    // cutoff = L/2 exactly: one cell along the axis (edge carries a margin above cutoff).
    for &(side, cutoff) in &[(2.0, 1.0), (2.5, 1.0), (3.1, 1.0), (4.0, 1.3)] {
        let pts: Vec<[f64; 3]> = (0..120).map(|_| rng.point::<3>(0.0, side)).collect();
        check_periodic(&pts, [0.0; 3], [side; 3], [true; 3], cutoff);
        let g = GridBuilder::<3>::with_cutoff(cutoff)
            .periodic_box([0.0; 3], [side; 3])
            .build(&pts)
            .unwrap();
        assert!(g.cells_per_axis()[0] <= 3);
        let pts: Vec<[f64; 2]> = (0..120).map(|_| rng.point::<2>(0.0, side)).collect();
        check_periodic(&pts, [0.0; 2], [side; 2], [true; 2], cutoff);
    }
}

#[test]
fn pairs_exactly_at_the_cutoff_and_on_cell_boundaries() {
    // Square lattice of unit spacing (exact in floating point). With cutoff 1 no pair
    // (strict <); with cutoff one ulp above 1 every lattice edge is a pair.
    for cutoff in [1.0, 1.0 + f64::EPSILON] {
        let mut pts = Vec::new();
        for x in 0..12 {
            for y in 0..12 {
                pts.push([x as f64, y as f64]);
            }
        }
        let n = check_cutoff(&pts, cutoff);
        assert_eq!(n, if cutoff > 1.0 { 2 * 12 * 11 } else { 0 });
        let p3: Vec<[f64; 3]> = pts.iter().map(|p| [p[0], p[1], 7.0]).collect();
        check_cutoff(&p3, cutoff);
    }
    // A domain whose cell faces (edge exactly 1) carry half of the points.
    let mut pts = Vec::new();
    for x in 0..12 {
        for y in 0..12 {
            pts.push([x as f64, y as f64]);
            pts.push([x as f64 + 0.94, y as f64]);
        }
    }
    let g = GridBuilder::<2>::with_cutoff(0.95)
        .domain([0.0; 2], [12.0; 2])
        .build(&pts)
        .unwrap();
    assert_eq!(g.cell_edge(), [1.0, 1.0]);
    let bx = Box::<2>::open();
    let want = brute_pairs(&pts, |_, _| 0.95, &bx);
    assert!(want.len() > 250);
    check_grid(&g, &pts, &want, &bx);
    // Large offsets: the cell index is computed from coordinates near 1e8.
    let base = 1e8;
    let pts: Vec<[f64; 3]> = (0..60)
        .map(|k| [base + 0.999_999 * k as f64, base, base])
        .collect();
    assert_eq!(check_cutoff(&pts, 1.0), 59);
}

#[test]
fn tiny_cutoff_against_a_huge_domain_uses_hashed_cells() {
    let mut rng = Rng::new(8);
    // 1e12 cells per axis would be needed: the dense array is refused by the default cap.
    let mut pts: Vec<[f64; 3]> = (0..500).map(|_| rng.point::<3>(0.0, 1e12)).collect();
    for k in 0..100 {
        let p = pts[k];
        pts.push([p[0] + 0.3, p[1], p[2] - 0.2]);
    }
    let g = Grid::<3>::build(&pts, 1.0).unwrap();
    assert_eq!(g.layout(), Layout::Hashed);
    assert!(g.nonempty_cell_count() <= pts.len());
    let bx = Box::<3>::open();
    let expected = brute_pairs(&pts, |_, _| 1.0, &bx);
    assert!(expected.len() >= 100);
    check_grid(&g, &pts, &expected, &bx);
    // Extreme ratios: cells cannot be finer than a few ulps of the coordinates; still exact.
    let pts = [[0.0, 0.0], [1e300, 0.0], [1e300, 0.5], [-1e300, 1e300]];
    let g = Grid::<2>::build(&pts, 1e-150).unwrap();
    assert_eq!(g.close_pairs(), Vec::<(usize, usize)>::new());
    let g = Grid::<2>::build(&pts, 1.0).unwrap();
    assert_eq!(g.close_pairs(), vec![(1, 2)]);
}

#[test]
fn one_dimensional_grid() {
    let mut rng = Rng::new(9);
    let pts: Vec<[f64; 1]> = (0..400).map(|_| [rng.range(0.0, 100.0)]).collect();
    check_cutoff(&pts, 0.7);
}

#[test]
fn rebuild_matches_a_fresh_build() {
    let mut rng = Rng::new(10);
    let mut pts: Vec<[f64; 3]> = (0..600).map(|_| rng.point::<3>(0.0, 9.0)).collect();
    let radii: Vec<f64> = (0..600).map(|_| rng.range(0.2, 0.6)).collect();
    let mut g = Grid::<3>::build(&pts, 1.0).unwrap();
    let mut gr = GridBuilder::<3>::with_radii(&radii).build(&pts).unwrap();
    for step in 0..4 {
        for p in &mut pts {
            for c in p.iter_mut() {
                *c += rng.range(-0.5, 0.5) * (step as f64 + 1.0);
            }
        }
        if step == 3 {
            pts.truncate(500); // fewer points
        }
        g.rebuild(&pts).unwrap();
        let fresh = Grid::<3>::build(&pts, 1.0).unwrap();
        let mut a = g.close_pairs();
        let mut b = fresh.close_pairs();
        a.sort_unstable();
        b.sort_unstable();
        assert_eq!(a, b, "step {step}");
        let bx = Box::<3>::open();
        check_grid(&g, &pts, &brute_pairs(&pts, |_, _| 1.0, &bx), &bx);
        if step < 3 {
            gr.rebuild(&pts).unwrap();
            let want = brute_pairs(&pts, |i, j| radii[i] + radii[j], &bx);
            check_grid(&gr, &pts, &want, &bx);
        } else {
            assert!(gr.rebuild(&pts).is_err());
            gr.rebuild_with_radii(&pts, &radii[..500]).unwrap();
            let want = brute_pairs(&pts, |i, j| radii[i] + radii[j], &bx);
            check_grid(&gr, &pts, &want, &bx);
        }
    }
}

#[test]
fn near_point_queries_match_brute_force() {
    let mut rng = Rng::new(11);
    let pts: Vec<[f64; 3]> = (0..500).map(|_| rng.point::<3>(0.0, 10.0)).collect();
    let radii: Vec<f64> = (0..500).map(|_| rng.range(0.05, 0.5)).collect();
    let open = GridBuilder::<3>::with_cutoff(0.8).build(&pts).unwrap();
    let periodic = GridBuilder::<3>::with_cutoff(0.8)
        .periodic_box([0.0; 3], [10.0; 3])
        .build(&pts)
        .unwrap();
    let with_r = GridBuilder::<3>::with_radii(&radii).build(&pts).unwrap();
    let hashed = GridBuilder::<3>::with_cutoff(0.8)
        .max_cells(0)
        .build(&pts)
        .unwrap();
    let obox = Box::<3>::open();
    let pbox = Box {
        lo: [0.0; 3],
        len: [10.0; 3],
        periodic: [true; 3],
    };
    for q in 0..40 {
        let x = rng.point::<3>(-2.0, 12.0);
        // Small, cell-sized and many-cell radii.
        let radius = [0.3, 0.8, 2.5, 7.0][q % 4];
        for (g, bx) in [(&open, obox), (&periodic, pbox), (&hashed, obox)] {
            let mut got = Vec::new();
            g.for_each_near_point(x, radius, |j, d, d2| {
                let dd: f64 = d.iter().map(|t| t * t).sum();
                assert!((dd - d2).abs() < 1e-12);
                got.push(j)
            })
            .unwrap();
            got.sort_unstable();
            let want: Vec<usize> = (0..pts.len())
                .filter(|&j| bx.dist2(&x, &pts[j]) < radius * radius)
                .collect();
            assert_eq!(got, want, "query {q} radius {radius}");
        }
        let mut got = Vec::new();
        with_r
            .for_each_near_point(x, radius, |j, _, _| got.push(j))
            .unwrap();
        got.sort_unstable();
        let want: Vec<usize> = (0..pts.len())
            .filter(|&j| {
                let s = radius + radii[j];
                obox.dist2(&x, &pts[j]) < s * s
            })
            .collect();
        assert_eq!(got, want, "radii query {q}");
    }
}

#[test]
fn cells_partition_the_items() {
    let mut rng = Rng::new(12);
    let pts: Vec<[f64; 2]> = (0..500).map(|_| rng.point::<2>(0.0, 10.0)).collect();
    for cap in [None, Some(0)] {
        let mut b = GridBuilder::<2>::with_cutoff(0.7);
        if let Some(c) = cap {
            b = b.max_cells(c);
        }
        let g = b.build(&pts).unwrap();
        let mut seen = vec![0; pts.len()];
        let mut cells = 0;
        for cell in g.cells() {
            assert!(!cell.items.is_empty());
            for &i in cell.items {
                seen[i] += 1;
                assert_eq!(g.cell_of_item(i).unwrap(), cell.coords);
                assert_eq!(g.cell_of_point(pts[i]).unwrap(), cell.coords);
                let e = g.cell_edge();
                let origin = g.domain().0;
                for a in 0..2 {
                    let lo = origin[a] + cell.coords[a] as f64 * e[a];
                    assert!(pts[i][a] >= lo - 1e-12 && pts[i][a] <= lo + e[a] + 1e-12);
                }
            }
            cells += 1;
        }
        assert_eq!(cells, g.nonempty_cell_count());
        assert!(seen.iter().all(|&c| c == 1));
        let e = g.cell_edge();
        assert!(e[0] >= 0.7 && e[1] >= 0.7);
    }
}

#[test]
fn large_inputs_match_the_hashed_layout_and_sampled_brute_force() {
    // Above 2^15 items the dense layout sorts through blocks of cells; the hashed layout
    // never does, so the two are independent computations of the same pairs.
    let mut rng = Rng::new(14);
    let pts: Vec<[f64; 3]> = (0..40_000).map(|_| rng.point::<3>(0.0, 30.0)).collect();
    let radii = giants_among_small(&mut rng, pts.len(), |i| i % 3000 == 0, 2.5, (0.2, 0.5));
    for b in [
        GridBuilder::<3>::with_cutoff(0.9),
        GridBuilder::<3>::with_radii(&radii),
        GridBuilder::<3>::with_cutoff(0.9).periodic_box([0.0; 3], [30.0; 3]),
    ] {
        let dense = b.clone().build(&pts).unwrap();
        let hashed = b.max_cells(0).build(&pts).unwrap();
        assert_eq!(dense.layout(), Layout::Dense);
        let (mut a, mut h) = (dense.close_pairs(), hashed.close_pairs());
        a.sort_unstable();
        h.sort_unstable();
        assert_eq!(a, h);
        assert!(a.len() > 10_000);
        let periodic = dense.periodic()[0];
        let bx = Box {
            lo: [0.0; 3],
            len: [30.0; 3],
            periodic: [periodic; 3],
        };
        for i in (0..pts.len()).step_by(199) {
            let want: Vec<usize> = (0..pts.len())
                .filter(|&j| {
                    let r = match dense.cutoff() {
                        Some(c) => c,
                        None => radii[i] + radii[j],
                    };
                    j != i && bx.dist2(&pts[i], &pts[j]) < r * r
                })
                .collect();
            assert_eq!(dense.neighbours(i).unwrap(), want, "item {i}");
        }
    }
}

#[test]
fn coordinates_near_the_largest_float() {
    // The bounding box side overflows to infinity; the pairs must still be exact and no
    // distance may turn into NaN.
    let big = f64::MAX / 2.0;
    let pts2 = [[-big, 0.0], [big, 0.0], [big, 0.5], [0.0, 0.0], [0.25, 0.0]];
    let bx = Box::<2>::open();
    let want = brute_pairs(&pts2, |_, _| 1.0, &bx);
    assert_eq!(want, vec![(1, 2), (3, 4)]);
    let g = Grid::<2>::build(&pts2, 1.0).unwrap();
    check_grid(&g, &pts2, &want, &bx);
    check_neighbours(&g, &pts2, &want);
    let pts3 = [
        [-big, -big, 1.0],
        [big, big, 1.0],
        [big, big, 1.5],
        [1.0, 2.0, 3.0],
    ];
    let want = brute_pairs(&pts3, |_, _| 1.0, &Box::<3>::open());
    assert_eq!(want, vec![(1, 2)]);
    let g = GridBuilder::<3>::with_radii(&[0.5; 4])
        .build(&pts3)
        .unwrap();
    check_grid(&g, &pts3, &want, &Box::<3>::open());
    // A domain whose side is not finite is refused.
    assert!(matches!(
        GridBuilder::<2>::with_cutoff(1.0)
            .domain([-big * 1.5, 0.0], [big * 1.5, 1.0])
            .build(&pts2),
        Err(cell_grid::Error::InvalidDomain { axis: 0, .. })
    ));
}

#[test]
fn sparse_points_skip_the_empty_cells() {
    // Few points over many cells: nearly every slot of the dense array is empty, and the
    // enumeration, `cells`, `nonempty_cell_count` and `cell_of_item` (which find the cells
    // by skipping empty slots, not from a stored list) must still see each cell once.
    let mut rng = Rng::new(5);
    let pts: Vec<[f64; 3]> = uniform(&mut rng, 300, 25.0);
    let n = check_cutoff(&pts, 1.5);
    assert!(n > 0, "the test needs some pairs");
    let g = Grid::<3>::build(&pts, 1.5).unwrap();
    assert_eq!(g.layout(), Layout::Dense);
    let mut distinct: Vec<[usize; 3]> = pts.iter().map(|&p| g.cell_of_point(p).unwrap()).collect();
    distinct.sort_unstable();
    distinct.dedup();
    let listed: Vec<[usize; 3]> = g.cells().map(|c| c.coords).collect();
    // Increasing linear order, x fastest.
    let key = |c: &[usize; 3]| (c[2], c[1], c[0]);
    assert!(listed.windows(2).all(|w| key(&w[0]) < key(&w[1])));
    let mut sorted = listed.clone();
    sorted.sort_unstable();
    assert_eq!(sorted, distinct);
    assert_eq!(g.nonempty_cell_count(), distinct.len());
    for (i, &p) in pts.iter().enumerate() {
        assert_eq!(g.cell_of_item(i).unwrap(), g.cell_of_point(p).unwrap());
    }
}
