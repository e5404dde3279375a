//! `rebuild` after small moves must not touch the allocator. A counting global allocator
//! (per thread, so the test harness's own threads do not interfere) checks it.

mod common;

use std::alloc::{GlobalAlloc, Layout as AllocLayout, System};
use std::cell::Cell;

use cell_grid::{Grid, GridBuilder, Layout};
use testkit::Rng;

struct Counting;

thread_local! {
    static ALLOCS: Cell<usize> = const { Cell::new(0) };
}

// SAFETY: forwards every call to the system allocator unchanged; only counts.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: AllocLayout) -> *mut u8 {
        ALLOCS.with(|c| c.set(c.get() + 1));
        // SAFETY: same contract as our caller's.
        unsafe { System.alloc(layout) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: AllocLayout) {
        // SAFETY: same contract as our caller's.
        unsafe { System.dealloc(ptr, layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: AllocLayout, new_size: usize) -> *mut u8 {
        ALLOCS.with(|c| c.set(c.get() + 1));
        // SAFETY: same contract as our caller's.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

fn allocations_during(f: impl FnOnce()) -> usize {
    let before = ALLOCS.with(Cell::get);
    f();
    ALLOCS.with(Cell::get) - before
}

fn jiggle<const D: usize>(rng: &mut Rng, pts: &mut [[f64; D]], step: f64) {
    for p in pts.iter_mut() {
        for c in p.iter_mut() {
            *c += rng.range(-step, step);
        }
    }
}

#[test]
fn rebuild_after_small_moves_allocates_nothing() {
    let mut rng = Rng::new(42);
    let side = 12.0;
    let mut pts: Vec<[f64; 3]> = (0..3000).map(|_| rng.point::<3>(0.0, side)).collect();
    let radii: Vec<f64> = (0..3000).map(|_| rng.range(0.1, 0.5)).collect();

    let mut dense = Grid::<3>::build(&pts, 1.0).unwrap();
    assert_eq!(dense.layout(), Layout::Dense);
    let mut hashed = GridBuilder::<3>::with_cutoff(1.0)
        .max_cells(0)
        .build(&pts)
        .unwrap();
    let mut periodic = GridBuilder::<3>::with_radii(&radii)
        .periodic_box([0.0; 3], [side; 3])
        .build(&pts)
        .unwrap();
    let giants: Vec<f64> = (0..3000)
        .map(|i| if i % 500 == 1 { 3.0 } else { 0.1 })
        .collect();
    let mut split = GridBuilder::<3>::with_radii(&giants).build(&pts).unwrap();
    assert!(split.split_radius().is_some());
    let mut two_d =
        Grid::<2>::build(&pts.iter().map(|p| [p[0], p[1]]).collect::<Vec<_>>(), 0.3).unwrap();

    let mut pts2: Vec<[f64; 2]> = pts.iter().map(|p| [p[0], p[1]]).collect();
    // The first enumeration detects the processor's instruction set, once per process: that
    // reads the environment (`ELLIPACK_DISABLE_AVX2`), which allocates when the variable is
    // set. What is counted below is the steady state.
    dense.for_each_close_pair(|_, _, _, _| {});
    for round in 0..5 {
        jiggle(&mut rng, &mut pts, 0.01);
        jiggle(&mut rng, &mut pts2, 0.01);
        let n = [
            allocations_during(|| dense.rebuild(&pts).unwrap()),
            allocations_during(|| periodic.rebuild(&pts).unwrap()),
            allocations_during(|| two_d.rebuild(&pts2).unwrap()),
            allocations_during(|| hashed.rebuild(&pts).unwrap()),
            allocations_during(|| split.rebuild(&pts).unwrap()),
        ];
        assert_eq!(
            n, [0; 5],
            "round {round}: allocations by dense, periodic, 2D, hashed, split"
        );
        // Enumeration allocates nothing either.
        let mut count = 0usize;
        let n = allocations_during(|| {
            dense.for_each_close_pair(|_, _, _, _| count += 1);
            periodic.for_each_close_pair(|_, _, _, _| count += 1);
            dense.for_each_candidate_pair(|_, _| count += 1);
            dense
                .for_each_pair_within(&pts, |_, _, _| count += 1)
                .unwrap();
            dense.for_each_neighbour(7, |_, _, _| count += 1).unwrap();
            split.for_each_close_pair(|_, _, _, _| count += 1);
            split.for_each_neighbour(1, |_, _, _| count += 1).unwrap();
        });
        assert_eq!(n, 0);
        assert!(count > 0);
    }
    // Fewer points: still no allocation. More points than ever: allocation is allowed.
    pts.truncate(2000);
    assert_eq!(allocations_during(|| dense.rebuild(&pts).unwrap()), 0);
}

#[test]
fn blocked_rebuild_of_a_large_input_allocates_nothing() {
    // 40 000 points take the blocked counting sort (from 2^15 items on).
    let mut rng = Rng::new(43);
    let mut pts: Vec<[f64; 3]> = (0..40_000).map(|_| rng.point::<3>(0.0, 30.0)).collect();
    let radii: Vec<f64> = (0..pts.len())
        .map(|i| if i % 4000 == 0 { 3.0 } else { 0.3 })
        .collect();
    let mut g = Grid::<3>::build(&pts, 0.8).unwrap();
    let mut gr = GridBuilder::<3>::with_radii(&radii).build(&pts).unwrap();
    assert!(gr.split_radius().is_some());
    // Points along a line: the last block of cells holds items (in a cube it holds only
    // the ghost layer), so the sort's per-block scratch ends a build non-empty.
    let mut line: Vec<[f64; 3]> = (0..40_000).map(|i| [0.0, 0.0, i as f64 * 0.025]).collect();
    let mut gl = Grid::<3>::build(&line, 0.8).unwrap();
    for _ in 0..3 {
        jiggle(&mut rng, &mut pts, 0.01);
        jiggle(&mut rng, &mut line, 0.001);
        let n = allocations_during(|| {
            g.rebuild(&pts).unwrap();
            gr.rebuild(&pts).unwrap();
            gl.rebuild(&line).unwrap();
        });
        assert_eq!(n, 0);
    }
}

#[test]
fn the_counter_sees_allocations() {
    // Guards the test above against a counter that never counts.
    let n = allocations_during(|| {
        let v: Vec<u64> = Vec::with_capacity(10);
        std::hint::black_box(v);
    });
    assert_eq!(n, 1);
    let mut rng = Rng::new(1);
    let pts: Vec<[f64; 3]> = (0..100).map(|_| rng.point::<3>(0.0, 5.0)).collect();
    let mut g = Grid::<3>::build(&pts[..10], 1.0).unwrap();
    assert!(allocations_during(|| g.rebuild(&pts).unwrap()) > 0);
}
