//! The parallel enumeration gives the same pairs as the serial one (feature `rayon`).
#![cfg(feature = "rayon")]

mod common;

use std::sync::Mutex;

use cell_grid::GridBuilder;
use testkit::Rng;

fn sorted(mut v: Vec<(usize, usize)>) -> Vec<(usize, usize)> {
    v.sort_unstable();
    v
}

#[test]
fn parallel_pairs_equal_serial_pairs() {
    let mut rng = Rng::new(21);
    let pts: Vec<[f64; 3]> = (0..20_000).map(|_| rng.point::<3>(0.0, 25.0)).collect();
    let radii: Vec<f64> = (0..pts.len()).map(|_| rng.range(0.2, 0.7)).collect();
    // A few items 20x larger than the rest: kept out of the cells.
    let giants: Vec<f64> = (0..pts.len())
        .map(|i| if i % 1000 == 3 { 4.0 } else { 0.2 })
        .collect();
    let grids = [
        GridBuilder::<3>::with_cutoff(1.0).build(&pts).unwrap(),
        GridBuilder::<3>::with_cutoff(1.0)
            .max_cells(0)
            .build(&pts)
            .unwrap(),
        GridBuilder::<3>::with_radii(&radii)
            .periodic_box([0.0; 3], [25.0; 3])
            .build(&pts)
            .unwrap(),
        GridBuilder::<3>::with_radii(&giants).build(&pts).unwrap(),
    ];
    assert!(grids[3].split_radius().is_some());
    for g in &grids {
        let serial = sorted(g.close_pairs());
        assert!(serial.len() > 10_000);

        let collected = Mutex::new(Vec::new());
        g.par_for_each_close_pair(|i, j, _, _| collected.lock().unwrap().push((i, j)));
        assert_eq!(sorted(collected.into_inner().unwrap()), serial);

        let folded = g.par_fold_close_pairs(
            Vec::new,
            |acc, i, j, _, _| acc.push((i, j)),
            |mut a, b| {
                a.extend(b);
                a
            },
        );
        assert_eq!(sorted(folded), serial);

        let mut serial_cand = Vec::new();
        g.for_each_candidate_pair(|i, j| serial_cand.push((i, j)));
        let cand = Mutex::new(Vec::new());
        g.par_for_each_candidate_pair(|i, j| cand.lock().unwrap().push((i, j)));
        assert_eq!(sorted(cand.into_inner().unwrap()), sorted(serial_cand));
    }
}
