//! Property tests: random sets, cutoffs, boxes and layouts against brute force.

mod common;

use cell_grid::GridBuilder;
use common::{Box, brute_pairs, check_grid};
use proptest::prelude::*;

fn run<const D: usize>(
    pts: Vec<[f64; D]>,
    radii: Option<Vec<f64>>,
    cutoff: f64,
    periodic: [bool; D],
    side: f64,
    (hashed, split): (bool, bool),
) -> Result<(), TestCaseError> {
    let bx = Box {
        lo: [0.0; D],
        len: [side; D],
        periodic,
    };
    let mut b = match &radii {
        Some(r) => GridBuilder::<D>::with_radii(r),
        None => GridBuilder::<D>::with_cutoff(cutoff),
    };
    if periodic.iter().any(|&p| p) {
        b = b.domain([0.0; D], [side; D]).periodic(periodic);
    }
    if hashed {
        b = b.max_cells(0);
    }
    b = b.split_large_items(split);
    let grid = match b.build(&pts) {
        Ok(g) => g,
        Err(cell_grid::Error::CutoffTooLargeForBox {
            reach, box_length, ..
        }) => {
            prop_assert!(reach > 0.5 * box_length);
            return Ok(());
        }
        Err(e) => return Err(TestCaseError::fail(format!("{e}"))),
    };
    let expected = match &radii {
        Some(r) => brute_pairs(&pts, |i, j| r[i] + r[j], &bx),
        None => brute_pairs(&pts, |_, _| cutoff, &bx),
    };
    check_grid(&grid, &pts, &expected, &bx);

    // Rebuild after moving every point: the sort now visits items in the previous cell
    // order, so the items of a cell are no longer by index.
    let mut grid = grid;
    let moved: Vec<[f64; D]> = pts
        .iter()
        .enumerate()
        .map(|(i, p)| {
            std::array::from_fn(|k| p[k] + 0.37 * cutoff * (((i * 7 + k * 3) % 5) as f64 - 2.0))
        })
        .collect();
    grid.rebuild(&moved)
        .map_err(|e| TestCaseError::fail(format!("{e}")))?;
    let expected = match &radii {
        Some(r) => brute_pairs(&moved, |i, j| r[i] + r[j], &bx),
        None => brute_pairs(&moved, |_, _| cutoff, &bx),
    };
    check_grid(&grid, &moved, &expected, &bx);
    Ok(())
}

fn coords(side: f64) -> impl Strategy<Value = f64> {
    // Mostly inside the box, some outside (wrapped or clamped), some snapped to a coarse
    // lattice so that exact ties and coincident points occur.
    prop_oneof![
        4 => -0.2 * side..1.2 * side,
        1 => (0i32..8).prop_map(move |k| k as f64 * side / 8.0),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn grid_3d_matches_brute_force(
        (side, pts) in (1.0f64..20.0).prop_flat_map(|s| {
            (Just(s), prop::collection::vec(prop::array::uniform3(coords(s)), 0..120))
        }),
        cutoff_frac in 0.01f64..0.5,
        periodic in prop::array::uniform3(any::<bool>()),
        use_radii in any::<bool>(),
        hashed in any::<bool>(),
        split in any::<bool>(),
        radius_seed in prop::collection::vec(0.0f64..1.0, 120),
    ) {
        let cutoff = cutoff_frac * side;
        let radii = use_radii.then(|| {
            // Log-uniform over two decades: the split between sizes is exercised.
            (0..pts.len()).map(|i| cutoff * 0.5 * 100f64.powf(radius_seed[i] - 1.0)).collect()
        });
        run::<3>(pts, radii, cutoff, periodic, side, (hashed, split))?;
    }

    #[test]
    fn grid_2d_matches_brute_force(
        (side, pts) in (1.0f64..20.0).prop_flat_map(|s| {
            (Just(s), prop::collection::vec(prop::array::uniform2(coords(s)), 0..150))
        }),
        cutoff_frac in 0.01f64..0.5,
        periodic in prop::array::uniform2(any::<bool>()),
        use_radii in any::<bool>(),
        hashed in any::<bool>(),
        split in any::<bool>(),
        radius_seed in prop::collection::vec(0.0f64..1.0, 150),
    ) {
        let cutoff = cutoff_frac * side;
        let radii = use_radii.then(|| {
            // Log-uniform over two decades: the split between sizes is exercised.
            (0..pts.len()).map(|i| cutoff * 0.5 * 100f64.powf(radius_seed[i] - 1.0)).collect()
        });
        run::<2>(pts, radii, cutoff, periodic, side, (hashed, split))?;
    }

    #[test]
    fn build_never_panics_on_arbitrary_floats(
        pts in prop::collection::vec(prop::array::uniform3(any::<f64>()), 0..20),
        cutoff in any::<f64>(),
    ) {
        if let Ok(g) = cell_grid::Grid::<3>::build(&pts, cutoff) {
            // Every coordinate was finite and the cutoff positive; pairs must then be exact.
            let bx = Box::<3>::open();
            let expected = brute_pairs(&pts, |_, _| cutoff, &bx);
            let mut got = g.close_pairs();
            got.sort_unstable();
            prop_assert_eq!(&got, &expected);
            let mut within = Vec::new();
            g.for_each_pair_within(&pts, |i, j, _| within.push((i, j))).unwrap();
            within.sort_unstable();
            prop_assert_eq!(&within, &expected);
            for i in 0..pts.len() {
                let n = g.neighbours(i).unwrap();
                prop_assert!(n.iter().all(|&j| got.contains(&(i.min(j), i.max(j)))));
            }
        }
    }
}
