//! The periodic cell against the box: one evaluation with gradient of the same configuration
//! (m ellipsoids (1, 0.75, 0.5) scaled by [0.9, 1.1], jittered cubic lattice at volume fraction
//! 0.6, random angles) in a box of side L and in the periodic cube of side L, m = 1e3, 1e4,
//! 1e5, the two timed in turn (best of 12 rounds). Prints the time per ellipsoid and the
//! ratio periodic / box, with the number of images and pairs.

use implicit_packing::containment::ContainerShape;
use implicit_packing::model::{Model, ModelGradient};
use std::hint::black_box;
use std::time::Instant;

mod common;

/// Semi-axes, the box variables and the periodic variables of one configuration.
fn configuration(m: usize) -> (Vec<[f64; 3]>, Vec<f64>, Vec<f64>) {
    let (axes, mut boxed, side) = common::configuration(m, 0.6, |rng| {
        std::array::from_fn(|_| 6.0 * rng.uniform() - 3.0)
    });
    // The same centres in fractions of the periodic cube, which starts at the box's corner.
    let mut periodic = boxed.clone();
    for item in periodic.chunks_mut(6) {
        for c in &mut item[..3] {
            *c = *c / side + 0.5;
        }
    }
    boxed.extend_from_slice(&[0.5 * side; 3]);
    periodic.extend_from_slice(&[side, side, side, 0.0, 0.0, 0.0]);
    (axes, boxed, periodic)
}

fn main() {
    println!("m        box (ns/item)  periodic (ns/item)  periodic/box  pairs box/periodic");
    for m in [1_000, 10_000, 100_000] {
        let (axes, xb, xp) = configuration(m);
        let mut in_box = Model::<3>::new(axes.clone(), ContainerShape::Box).expect("valid");
        let mut in_cell = Model::<3>::new(axes, ContainerShape::Periodic).expect("valid");
        let mut g = ModelGradient::default();
        let (mut tb, mut tp) = (f64::INFINITY, f64::INFINITY);
        let (mut pb, mut pp) = (0, 0);
        let passes = (20_000 / m).max(1);
        for _ in 0..12 {
            for _ in 0..passes {
                let t = Instant::now();
                pb = black_box(in_box.evaluate(&xb, Some(&mut g)).expect("evaluates")).pairs;
                tb = tb.min(t.elapsed().as_secs_f64());
                let t = Instant::now();
                pp = black_box(in_cell.evaluate(&xp, Some(&mut g)).expect("evaluates")).pairs;
                tp = tp.min(t.elapsed().as_secs_f64());
            }
        }
        println!(
            "{m:<8} {:>13.1}  {:>18.1}  {:>12.2}  {pb}/{pp}",
            tb / m as f64 * 1e9,
            tp / m as f64 * 1e9,
            tp / tb
        );
    }
}
