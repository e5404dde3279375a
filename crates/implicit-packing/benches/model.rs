//! The whole model, value and gradient, for m = 1e3, 1e4, 1e5 ellipsoids at density ≈ 0.6, and
//! the all-pairs sum at m = 1e4 for comparison.
//!
//! Configuration: semi-axes (1, 0.75, 0.5) scaled by a factor in [0.9, 1.1], centres on a
//! jittered cubic lattice sized for a volume fraction of 0.6, random angles, box container.
//! Prints the time per ellipsoid (best of several passes) and the ratios asked for, and where
//! the time goes (variables, the scan of the pair list, separation certificate, pair kernel four
//! pairs at a time as the model runs it, and one at a time for comparison), and what a rebuild
//! of the pair list costs (the model's evaluations at a fixed point reuse it; in a solve it is
//! rebuilt about once every few hundred evaluations, see `model::PAIR_LIST_SKIN`); and balls of
//! the same volumes against the ellipsoids (no angles, the closed-form pair term).
#![allow(clippy::needless_range_loop)]

use implicit_packing::batch::pair_gradients;
use implicit_packing::containment::ContainerShape;
use implicit_packing::derivatives::{PairGradient, pair_gradient};
use implicit_packing::model::{Model, ModelGradient, PAIR_LIST_SKIN};
use implicit_packing::pair::separated_along_centre_line;
use std::hint::black_box;
use std::time::Instant;

mod common;

fn configuration(m: usize, density: f64) -> (Vec<[f64; 3]>, Vec<f64>) {
    let (axes, mut x, side) = common::configuration(m, density, |rng| {
        [
            6.0 * rng.uniform() - 3.0,
            3.0 * rng.uniform() - 1.5,
            6.0 * rng.uniform() - 3.0,
        ]
    });
    x.extend_from_slice(&[0.5 * side; 3]);
    (axes, x)
}

fn best<F: FnMut()>(passes: usize, mut f: F) -> f64 {
    let mut t_best = f64::INFINITY;
    for _ in 0..passes {
        let t = Instant::now();
        f();
        t_best = t_best.min(t.elapsed().as_secs_f64());
    }
    t_best
}

/// Time per ellipsoid of one evaluation with gradient at each size, the sizes timed in turn
/// for 12 rounds (best of all rounds): on this shared virtual machine the speed of a run
/// drifts by up to 40 % over seconds, and timing the sizes one after the other put that drift
/// into their ratio (m = 1e3 came out at 343 or 486 ns per ellipsoid from run to run).
fn interleaved(sizes: &[usize]) -> Vec<f64> {
    let mut cases: Vec<_> = sizes
        .iter()
        .map(|&m| {
            let (axes, x) = configuration(m, 0.6);
            let p = Model::<3>::new(axes, ContainerShape::Box).expect("valid problem");
            (m, p, x, ModelGradient::default(), f64::INFINITY)
        })
        .collect();
    for _ in 0..12 {
        for (m, p, x, g, t_best) in cases.iter_mut() {
            // About 5 ms per turn whatever the size.
            let passes = (10_000 / *m).max(1);
            let t = best(passes, || {
                black_box(p.evaluate(x, Some(g)).expect("evaluates"));
            });
            *t_best = t_best.min(t / *m as f64);
        }
    }
    cases.iter().map(|c| c.4).collect()
}

fn main() {
    for &m in &[1_000usize, 10_000, 100_000] {
        let (axes, x) = configuration(m, 0.6);
        let mut p = Model::<3>::new(axes, ContainerShape::Box).expect("valid problem");
        let mut g = ModelGradient::default();
        let ev = p.evaluate(&x, Some(&mut g)).expect("evaluates");
        let passes = if m >= 100_000 { 5 } else { 20 };
        let t_grad = best(passes, || {
            black_box(p.evaluate(&x, Some(&mut g)).expect("evaluates"));
        });
        let t_val = best(passes, || {
            black_box(p.evaluate(&x, None).expect("evaluates"));
        });
        println!(
            "m = {m:6}: value+gradient {:8.3} ms ({:6.0} ns/ellipsoid), value {:8.3} ms ({:6.0} ns/ellipsoid); {} pairs evaluated, overlap {:.3e}",
            t_grad * 1e3,
            t_grad * 1e9 / m as f64,
            t_val * 1e3,
            t_val * 1e9 / m as f64,
            ev.pairs,
            ev.overlap
        );
        // Where the time goes, per ellipsoid: reading the variables (rotations, bodies), the
        // scan of a valid pair list (the displacement test and the exact bounding-sphere
        // test), the separation certificate on every candidate pair, and the pair kernel on
        // the candidates the certificate leaves; and a rebuild of the pair list.
        {
            let pb = if m >= 100_000 { 3 } else { 10 };
            let t_load = best(pb, || {
                black_box(p.bodies_at(&x).expect("evaluates").len());
            });
            let bodies = p.bodies().to_vec();
            let centres: Vec<[f64; 3]> = bodies.iter().map(|b| b.centre()).collect();
            let radii: Vec<f64> = bodies.iter().map(|b| b.bounding_radius()).collect();
            let r_min = radii.iter().fold(f64::INFINITY, |a, &b| a.min(b));
            let builder = || cell_grid::GridBuilder::<3>::with_radii(&radii);
            let mut list =
                cell_grid::PairList::new(builder(), PAIR_LIST_SKIN * r_min).expect("pair list");
            let mut pairs = Vec::new();
            list.for_each_close_pair(&centres, |i, j, _, _| pairs.push((i, j)))
                .expect("valid centres");
            let t_pairs = best(pb, || {
                let mut c = 0usize;
                list.for_each_close_pair(&centres, |i, j, _, _| c += i ^ j)
                    .expect("valid centres");
                black_box(c);
            });
            let t_rebuild = best(pb, || {
                let mut fresh =
                    cell_grid::PairList::new(builder(), PAIR_LIST_SKIN * r_min).expect("pair list");
                black_box(fresh.refresh(&centres).expect("valid centres"));
            });
            let t_sep = best(pb, || {
                let c = pairs
                    .iter()
                    .filter(|&&(i, j)| separated_along_centre_line(&bodies[i], &bodies[j]))
                    .count();
                black_box(c);
            });
            let kernel: Vec<(usize, usize)> = pairs
                .iter()
                .copied()
                .filter(|&(i, j)| !separated_along_centre_line(&bodies[i], &bodies[j]))
                .collect();
            let t_kernel = best(pb, || {
                let mut c = 0.0;
                for &(i, j) in &kernel {
                    c += pair_gradient(&bodies[i], &bodies[j]).1.centre_i[0];
                }
                black_box(c);
            });
            // The same pairs four at a time, as the model solves them.
            let mut terms = vec![(0.0, PairGradient::ZERO); kernel.len()];
            let t_four = best(pb, || {
                pair_gradients(&bodies, &kernel, &mut terms).expect("valid pairs");
                black_box(terms[0].0);
            });
            let per = |t: f64| t * 1e9 / m as f64;
            let per_pair = |t: f64| t * 1e9 / kernel.len().max(1) as f64;
            println!(
                "           per ellipsoid: variables {:.0} ns, pair list scan {:.0} ns ({} listed for {} close pairs; a rebuild from scratch {:.0} ns), certificate {:.0} ns, kernel with gradient {:.0} ns four pairs at a time ({:.1} ns per pair; one at a time {:.1} ns, {:.2}x); the certificate rejects {} of {} candidate pairs ({:.1} %)",
                per(t_load),
                per(t_pairs),
                list.len(),
                pairs.len(),
                per(t_rebuild),
                per(t_sep),
                per(t_four),
                per_pair(t_four),
                per_pair(t_kernel),
                t_kernel / t_four,
                pairs.len() - kernel.len(),
                pairs.len(),
                100.0 * (pairs.len() - kernel.len()) as f64 / pairs.len() as f64
            );
        }
        if m == 10_000 {
            // (a) All m(m−1)/2 pairs, each with the bounding-sphere exit of the pair term.
            let t_all = best(2, || {
                black_box(p.overlap_all_pairs(&x).expect("evaluates"));
            });
            println!(
                "m = {m:6}: all pairs with bounding-sphere exit (value only) {:8.1} ms: {:.1}x the grid value, {:.1}x the grid value+gradient",
                t_all * 1e3,
                t_all / t_val,
                t_all / t_grad
            );
            // (b) The O(m²) model proper: the pair term with its gradient solved for every pair
            // (no pair skipped), timed on 200 000 pairs and scaled to m(m−1)/2.
            let bodies = p.bodies().to_vec();
            let sample: Vec<(usize, usize)> = (0..200_000)
                .map(|k| ((k * 7919) % m, (k * 104_729 + 1) % m))
                .filter(|(a, b)| a != b)
                .collect();
            let t_sample = best(3, || {
                let mut acc = 0.0;
                for &(a, b) in &sample {
                    acc +=
                        implicit_packing::derivatives::pair_derivatives(&bodies[a], &bodies[b]).f;
                }
                black_box(acc);
            });
            let t_full = t_sample / sample.len() as f64 * (m * (m - 1) / 2) as f64;
            println!(
                "m = {m:6}: every pair solved, with gradient (extrapolated from {} pairs): {:8.1} s: {:.0}x the grid value+gradient",
                sample.len(),
                t_full,
                t_full / t_grad
            );
        }
    }
    let per_body = interleaved(&[1_000, 10_000, 100_000]);
    println!(
        "value+gradient, sizes timed in turn: {:.0} / {:.0} / {:.0} ns per ellipsoid at m = 1e3 / 1e4 / 1e5; time per ellipsoid at 1e5 / at 1e3: {:.2}",
        per_body[0] * 1e9,
        per_body[1] * 1e9,
        per_body[2] * 1e9,
        per_body[2] / per_body[0]
    );
    for m in [10_000, 100_000] {
        balls_against_ellipsoids(m);
    }
    #[cfg(feature = "rayon")]
    for m in [10_000, 100_000] {
        threads::compare(m);
    }
}

/// The configuration of [`configuration`] with every ellipsoid replaced by the ball of its
/// volume at its centre: no angles, and every pair in the closed form of module `round`.
fn balls(m: usize, density: f64) -> (Vec<[f64; 3]>, Vec<f64>) {
    let (axes, x) = configuration(m, density);
    let balls: Vec<[f64; 3]> = axes
        .iter()
        .map(|l| [(l[0] * l[1] * l[2]).cbrt(); 3])
        .collect();
    let mut y = Vec::with_capacity(3 * m + 3);
    for i in 0..m {
        y.extend_from_slice(&x[6 * i..6 * i + 3]);
    }
    y.extend_from_slice(&x[6 * m..]);
    (balls, y)
}

/// Value and gradient of `m` balls against `m` ellipsoids of the same volumes and centres,
/// timed in turn (best of 12 rounds): what a scene of balls costs against one of ellipsoids.
fn balls_against_ellipsoids(m: usize) {
    let mut cases: Vec<(Model<3>, Vec<f64>, ModelGradient, f64)> =
        [configuration(m, 0.6), balls(m, 0.6)]
            .into_iter()
            .map(|(axes, x)| {
                let p = Model::<3>::new(axes, ContainerShape::Box).expect("valid problem");
                (p, x, ModelGradient::default(), f64::INFINITY)
            })
            .collect();
    for _ in 0..12 {
        for (p, x, g, t_best) in cases.iter_mut() {
            let passes = if m >= 100_000 { 2 } else { 10 };
            let t = best(passes, || {
                black_box(p.evaluate(x, Some(g)).expect("evaluates"));
            });
            *t_best = t_best.min(t);
        }
    }
    let per = |t: f64| t * 1e9 / m as f64;
    let (ellipsoids, balls) = (cases[0].3, cases[1].3);
    println!(
        "m = {m:6}: value+gradient of balls {:.0} ns per item, of ellipsoids {:.0} ns: {:.2}x; variables {} against {}",
        per(balls),
        per(ellipsoids),
        ellipsoids / balls,
        cases[1].1.len(),
        cases[0].1.len()
    );
}

/// Value and gradient on pools of one and two threads, in a box and in the periodic cube of
/// the same side, the two pools timed in turn (best of 12 rounds), with the check that both
/// give the same bits.
#[cfg(feature = "rayon")]
mod threads {
    use super::*;

    /// The box configuration's centres as fractions of the periodic cube of its side.
    fn periodic(x: &[f64]) -> Vec<f64> {
        let side = 2.0 * x[x.len() - 1];
        let mut cell: Vec<f64> = x[..x.len() - 3].to_vec();
        for item in cell.chunks_mut(6) {
            for c in &mut item[..3] {
                *c = *c / side + 0.5;
            }
        }
        cell.extend_from_slice(&[side, side, side, 0.0, 0.0, 0.0]);
        cell
    }

    pub(super) fn compare(m: usize) {
        let (axes, x) = configuration(m, 0.6);
        let xp = periodic(&x);
        for (kind, x) in [(ContainerShape::Box, x), (ContainerShape::Periodic, xp)] {
            let pools = [1, 2].map(|t| {
                rayon::ThreadPoolBuilder::new()
                    .num_threads(t)
                    .build()
                    .expect("pool")
            });
            let mut models = [0, 1].map(|_| Model::<3>::new(axes.clone(), kind).expect("valid"));
            let mut grads = [0, 1].map(|_| ModelGradient::default());
            let mut best_t = [f64::INFINITY; 2];
            let passes = (20_000 / m).max(1);
            for _ in 0..12 {
                for k in 0..2 {
                    let (model, g) = (&mut models[k], &mut grads[k]);
                    let t = pools[k].install(|| {
                        best(passes, || {
                            black_box(model.evaluate(&x, Some(g)).expect("evaluates"));
                        })
                    });
                    best_t[k] = best_t[k].min(t);
                }
            }
            let same = grads[0].overlap == grads[1].overlap;
            println!(
                "m = {m:6}, {kind:?}: value+gradient on 1 thread {:.0} ns, on 2 threads {:.0} ns per ellipsoid: {:.2}x; same bits: {same}",
                best_t[0] * 1e9 / m as f64,
                best_t[1] * 1e9 / m as f64,
                best_t[0] / best_t[1]
            );
        }
    }
}
