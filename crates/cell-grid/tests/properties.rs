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

/// A random case in `D` dimensions: (box side, points), cutoff as a fraction of the side,
/// periodic axes, whether items have radii, (hashed, split) layout, and the seeds of the radii.
type Case<const D: usize> = (
    (f64, Vec<[f64; D]>),
    f64,
    [bool; D],
    bool,
    bool,
    bool,
    Vec<f64>,
);

/// Cases of up to `max` points.
fn case<const D: usize>(max: usize) -> impl Strategy<Value = Case<D>> {
    (
        (1.0f64..20.0).prop_flat_map(move |s| {
            (
                Just(s),
                prop::collection::vec(prop::array::uniform(coords(s)), 0..max),
            )
        }),
        0.01f64..0.5,
        prop::array::uniform(any::<bool>()),
        any::<bool>(),
        any::<bool>(),
        any::<bool>(),
        prop::collection::vec(0.0f64..1.0, max),
    )
}

fn matches_brute_force<const D: usize>(
    ((side, pts), cutoff_frac, periodic, use_radii, hashed, split, radius_seed): Case<D>,
) -> Result<(), TestCaseError> {
    let cutoff = cutoff_frac * side;
    let radii = use_radii.then(|| {
        // Log-uniform over two decades: the split between sizes is exercised.
        (0..pts.len())
            .map(|i| cutoff * 0.5 * 100f64.powf(radius_seed[i] - 1.0))
            .collect()
    });
    run::<D>(pts, radii, cutoff, periodic, side, (hashed, split))
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn grid_3d_matches_brute_force(case in case::<3>(120)) {
        matches_brute_force(case)?;
    }

    #[test]
    fn grid_2d_matches_brute_force(case in case::<2>(150)) {
        matches_brute_force(case)?;
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
