//! Neighbour pairs of random points, as a user's simulation would ask for them: every pair
//! closer than a cutoff in a periodic box, from the grid, checked against the all-pairs
//! count.
//!
//! Run with `cargo run --release -p ellipack-cell-grid --example neighbour_pairs`.

use cell_grid::Grid;

const POINTS: usize = 2000;
const SIDE: f64 = 10.0;
const CUTOFF: f64 = 0.8;

fn main() -> Result<(), cell_grid::Error> {
    // A 64-bit linear congruential generator (Knuth's MMIX constants) is enough to scatter
    // points; its top 53 bits give a uniform double in [0, 1).
    let mut state = 2024_u64;
    let mut uniform = move || {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (state >> 11) as f64 / (1_u64 << 53) as f64
    };
    let points: Vec<[f64; 3]> = (0..POINTS)
        .map(|_| [uniform() * SIDE, uniform() * SIDE, uniform() * SIDE])
        .collect();

    let grid = Grid::with_cutoff(CUTOFF)
        .periodic_box([0.0; 3], [SIDE; 3])
        .build(&points)?;
    let mut pairs = Vec::new();
    grid.for_each_close_pair(|i, j, _delta, dist2| pairs.push((i, j, dist2.sqrt())));
    println!(
        "{POINTS} points in a periodic box of side {SIDE}, cutoff {CUTOFF}: {} pairs \
         ({} non-empty cells)",
        pairs.len(),
        grid.nonempty_cell_count()
    );
    let mean = 2.0 * pairs.len() as f64 / POINTS as f64;
    let ideal = (POINTS as f64 / SIDE.powi(3)) * 4.0 / 3.0 * std::f64::consts::PI * CUTOFF.powi(3);
    println!("neighbours per point: {mean:.2} (an ideal gas expects {ideal:.2})");
    if let Some(&(i, j, d)) = pairs.iter().min_by(|a, b| a.2.total_cmp(&b.2)) {
        println!("closest pair: {i} and {j}, {d:.4} apart");
    }

    // The same pairs by brute force, with the minimum-image convention.
    let mut brute = 0;
    for i in 0..POINTS {
        for j in i + 1..POINTS {
            let d2: f64 = (0..3)
                .map(|k| {
                    let d = points[j][k] - points[i][k];
                    let d = d - SIDE * (d / SIDE).round();
                    d * d
                })
                .sum();
            if d2 < CUTOFF * CUTOFF {
                brute += 1;
            }
        }
    }
    assert_eq!(
        brute,
        pairs.len(),
        "the grid and the all-pairs count disagree"
    );
    println!("all-pairs check: {brute} pairs, the same");
    Ok(())
}
