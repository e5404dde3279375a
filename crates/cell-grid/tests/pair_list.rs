//! The Verlet list against brute force and against a fresh grid, along random walks.

mod common;

use cell_grid::{Error, Grid, GridBuilder, PairList};
use common::{Box, brute_pairs};
use proptest::prelude::*;
use testkit::Rng;

/// The list's pairs at `pts`, in the order it reports them, with their deltas and distances.
type Reported<const D: usize> = Vec<(usize, usize, [f64; D], f64)>;

fn reported<const D: usize>(list: &mut PairList<D>, pts: &[[f64; D]]) -> Reported<D> {
    let mut out = Vec::new();
    list.for_each_close_pair(pts, |i, j, d, d2| out.push((i, j, d, d2)))
        .expect("valid points");
    out
}

/// A random walk of `steps` moves of up to `step` per coordinate: after each, the list must
/// give exactly the brute-force pairs, ascending, and on open axes the same deltas and
/// distances, bit for bit, as a grid built afresh at the new positions.
fn walk<const D: usize>(
    mut pts: Vec<[f64; D]>,
    radii: Option<Vec<f64>>,
    cutoff: f64,
    bx: Box<D>,
    (skin, step, steps): (f64, f64, usize),
    rng: &mut Rng,
) -> Result<usize, TestCaseError> {
    let periodic = bx.periodic.iter().any(|&p| p);
    let builder = |r: &Option<Vec<f64>>| {
        let b = match r {
            Some(r) => GridBuilder::<D>::with_radii(r),
            None => GridBuilder::<D>::with_cutoff(cutoff),
        };
        if periodic {
            let hi = std::array::from_fn(|k| bx.lo[k] + bx.len[k]);
            b.domain(bx.lo, hi).periodic(bx.periodic)
        } else {
            b
        }
    };
    let mut list = PairList::new(builder(&radii), skin).expect("valid skin");
    for _ in 0..steps {
        let mut got = Vec::new();
        match list.for_each_close_pair(&pts, |i, j, d, d2| got.push((i, j, d, d2))) {
            Ok(()) => {}
            Err(Error::CutoffTooLargeForBox { .. }) => return Ok(list.builds()),
            Err(e) => return Err(TestCaseError::fail(format!("{e}"))),
        }
        let expected = match &radii {
            Some(r) => brute_pairs(&pts, |i, j| r[i] + r[j], &bx),
            None => brute_pairs(&pts, |_, _| cutoff, &bx),
        };
        let pairs: Vec<_> = got.iter().map(|&(i, j, _, _)| (i, j)).collect();
        prop_assert_eq!(&pairs, &expected, "pairs after {} builds", list.builds());
        if !periodic {
            let mut fresh: Reported<D> = Vec::new();
            builder(&radii)
                .build(&pts)
                .expect("valid points")
                .for_each_close_pair(|i, j, d, d2| fresh.push((i, j, d, d2)));
            fresh.sort_by_key(|&(i, j, _, _)| (i, j));
            for (a, b) in got.iter().zip(&fresh) {
                prop_assert_eq!(a.2.map(f64::to_bits), b.2.map(f64::to_bits));
                prop_assert_eq!(a.3.to_bits(), b.3.to_bits());
            }
        }
        for p in &mut pts {
            for c in p.iter_mut() {
                *c += rng.range(-step, step);
            }
        }
    }
    Ok(list.builds())
}

fn cloud<const D: usize>(rng: &mut Rng, n: usize, side: f64) -> Vec<[f64; D]> {
    (0..n).map(|_| rng.point(0.0, side)).collect()
}

#[test]
fn a_walk_with_small_steps_reuses_the_list_and_stays_exact() {
    let mut rng = Rng::new(7);
    let pts = cloud::<3>(&mut rng, 400, 8.0);
    let radii: Vec<f64> = (0..400).map(|_| rng.range(0.3, 0.6)).collect();
    // Steps of up to 0.01 per coordinate: a skin of 0.2 (0.1 per item) lasts at least 5
    // moves, and as a random walk about 25 for the farthest walker of 400.
    let builds = walk(
        pts,
        Some(radii),
        0.0,
        Box::open(),
        (0.2, 0.01, 120),
        &mut rng,
    )
    .expect("exact");
    assert!((2..=24).contains(&builds), "{builds} builds in 120 moves");
}

#[test]
fn without_a_skin_every_query_rebuilds() {
    let mut rng = Rng::new(8);
    let pts = cloud::<2>(&mut rng, 200, 5.0);
    let builds = walk(pts, None, 0.7, Box::open(), (0.0, 0.01, 10), &mut rng).expect("exact");
    assert_eq!(builds, 10);
}

#[test]
fn a_periodic_box_uses_the_minimum_image() {
    let mut rng = Rng::new(9);
    let pts = cloud::<3>(&mut rng, 300, 6.0);
    let bx = Box {
        lo: [0.0; 3],
        len: [6.0; 3],
        periodic: [true, false, true],
    };
    // Points leave the box through the periodic faces and are not wrapped back.
    let builds = walk(pts, None, 0.9, bx, (0.3, 0.02, 60), &mut rng).expect("exact");
    assert!(builds >= 2, "the walk should outrun the skin");
}

#[test]
fn the_list_is_the_pairs_in_ascending_order_with_the_grids_bits() {
    list_matches_the_grid(2000, 12.0, 10);
}

/// Enough rows for the rows to be sorted by blocks on several threads (feature `rayon`).
#[test]
fn a_long_list_sorted_by_blocks_of_rows_is_the_same() {
    list_matches_the_grid(40_000, 35.0, 11);
}

/// The list of `n` random balls in a cube of edge `side` has the fresh grid's pairs, sorted,
/// with their bits.
fn list_matches_the_grid(n: usize, side: f64, seed: u64) {
    let mut rng = Rng::new(seed);
    let pts = cloud::<3>(&mut rng, n, side);
    let radii: Vec<f64> = (0..n).map(|_| rng.range(0.2, 0.5)).collect();
    let mut list = PairList::new(GridBuilder::with_radii(&radii), 0.1).expect("valid skin");
    let got = reported(&mut list, &pts);
    let grid = Grid::<3>::with_radii(&radii).build(&pts).expect("valid");
    let mut want = Vec::new();
    grid.for_each_close_pair(|i, j, d, d2| want.push((i, j, d, d2)));
    want.sort_by_key(|&(i, j, _, _)| (i, j));
    assert!(!want.is_empty());
    assert_eq!(got.len(), want.len());
    for (a, b) in got.iter().zip(&want) {
        assert_eq!((a.0, a.1), (b.0, b.1));
        assert_eq!(a.2.map(f64::to_bits), b.2.map(f64::to_bits));
        assert_eq!(a.3.to_bits(), b.3.to_bits());
    }
    // The list holds the pairs within the enlarged reach, a superset.
    assert!(list.len() > want.len());
}

#[test]
fn bad_input_is_reported_and_the_list_recovers() {
    assert_eq!(
        PairList::new(GridBuilder::<3>::with_cutoff(1.0), -0.1).err(),
        Some(Error::InvalidSkin { value: -0.1 })
    );
    assert!(matches!(
        PairList::new(GridBuilder::<3>::with_cutoff(1.0), f64::NAN),
        Err(Error::InvalidSkin { .. })
    ));
    assert_eq!(
        PairList::new(GridBuilder::<3>::with_cutoff(1.0), 1e200).err(),
        Some(Error::InvalidSkin { value: 1e200 })
    );
    assert_eq!(
        PairList::new(GridBuilder::<3>::with_cutoff(0.0), 0.1).err(),
        Some(Error::InvalidCutoff { value: 0.0 })
    );
    assert_eq!(
        PairList::new(GridBuilder::<2>::with_radii(&[0.5, -1.0]), 0.1).err(),
        Some(Error::InvalidRadius {
            index: 1,
            value: -1.0
        })
    );

    let radii = [0.5; 3];
    let mut list = PairList::new(GridBuilder::<2>::with_radii(&radii), 0.2).expect("valid");
    let good = [[0.0, 0.0], [0.8, 0.0], [3.0, 0.0]];
    assert_eq!(reported(&mut list, &good).len(), 1);
    // A NaN within the allowed displacement must not pass as "not moved".
    let mut bad = good;
    bad[1][1] = f64::NAN;
    let mut called = false;
    let e = list.for_each_close_pair(&bad, |_, _, _, _| called = true);
    assert!(!called);
    assert!(matches!(
        e,
        Err(Error::NonFiniteCoordinate {
            index: 1,
            axis: 1,
            ..
        })
    ));
    // A point count that does not match the radii.
    assert!(matches!(
        list.refresh(&good[..2]),
        Err(Error::RadiiCountMismatch { .. })
    ));
    // Good points again: rebuilt and exact.
    assert_eq!(reported(&mut list, &good).len(), 1);

    // An empty scene has no pairs, with or without a skin.
    let mut empty = PairList::new(GridBuilder::<3>::with_cutoff(1.0), 0.1).expect("valid");
    assert_eq!(reported(&mut empty, &[]).len(), 0);
    assert!(empty.is_empty());
    let mut none = PairList::new(GridBuilder::<3>::with_radii(&[]), 0.0).expect("valid");
    assert_eq!(reported(&mut none, &[]).len(), 0);
}

#[cfg(feature = "rayon")]
#[test]
fn the_parallel_fold_gives_the_serial_pairs_in_order() {
    let mut rng = Rng::new(11);
    let pts = cloud::<3>(&mut rng, 20_000, 30.0);
    let mut list = PairList::new(GridBuilder::with_cutoff(1.1), 0.1).expect("valid");
    let serial = reported(&mut list, &pts);
    let folded = list
        .par_fold_close_pairs(
            &pts,
            Vec::new,
            |acc, i, j, d, d2| acc.push((i, j, d, d2)),
            |mut a, mut b| {
                a.append(&mut b);
                a
            },
        )
        .expect("valid");
    assert!(serial.len() > 20_000);
    assert_eq!(serial, folded);

    // Into kept states: the same pairs, in order across the states; a second call with the
    // states already full starts each over.
    let mut states = vec![vec![(0, 0, [0.0; 3], 0.0)]];
    for _ in 0..2 {
        list.par_fold_close_pairs_into(
            &pts,
            0..pts.len(),
            &mut states,
            Vec::clear,
            |acc, i, j, d, d2| acc.push((i, j, d, d2)),
        )
        .expect("valid");
        assert!(states.len() > 1);
        assert_eq!(serial, states.concat());
    }

    // From a range of rows: the serial pairs of those rows, cut the same way on one thread
    // as on two.
    let rows = 5_000..12_000;
    let mut from = Vec::new();
    list.for_each_close_pair_from(&pts, rows.clone(), |i, j, d, d2| from.push((i, j, d, d2)))
        .expect("valid");
    assert!(!from.is_empty() && from.iter().all(|p| rows.contains(&p.0)));
    let cut_on = |threads: usize, list: &mut PairList<3>| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("a pool");
        let mut states: Vec<Reported<3>> = Vec::new();
        pool.install(|| {
            list.par_fold_close_pairs_into(
                &pts,
                rows.clone(),
                &mut states,
                Vec::clear,
                |acc, i, j, d, d2| acc.push((i, j, d, d2)),
            )
        })
        .expect("valid");
        states
    };
    let (one, two) = (cut_on(1, &mut list), cut_on(2, &mut list));
    assert!(one.len() > 1);
    assert_eq!(one, two);
    assert_eq!(from, one.concat());
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    #[test]
    fn random_walks_match_brute_force(
        seed in any::<u64>(),
        n in 0usize..120,
        radii in proptest::bool::ANY,
        periodic in proptest::bool::ANY,
        skin in 0.0f64..0.5,
        step in 0.0f64..0.1,
    ) {
        let mut rng = Rng::new(seed);
        let side = 4.0;
        let pts = cloud::<3>(&mut rng, n, side);
        let r = radii.then(|| (0..n).map(|_| rng.range(0.05, 0.5)).collect());
        let bx = Box { lo: [0.0; 3], len: [side; 3], periodic: [periodic, periodic, false] };
        walk(pts, r, 0.6, bx, (skin, step, 12), &mut rng)?;
    }
}
