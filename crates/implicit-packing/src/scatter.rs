//! Pair gradients added to their items on every thread, each item's terms in the order of the
//! serial scan: the same bits on any number of threads.
//!
//! The pair sums keep, range by range of the pair list's rows, the non-zero pair gradients
//! `(i, j, ∂f_ij)` in ascending `(i, j)`. Adding them to the items is a scatter: a term lands on
//! `i` and on `j`, anywhere in the gradient. Instead of splitting the *terms* over the threads
//! (two threads would then add to one item in an order that depends on the scheduling), the
//! *items* are split: the items are cut into consecutive blocks, one task each, and a task scans
//! the terms in their order and adds only those that land on its block. Every item then receives
//! its terms in the order of the serial scan, whatever the cut, so the gradient has the bits of
//! the serial path for any number of threads.
//!
//! A task can stop at the first term whose `i` is past its block (`j > i`), so the first block
//! reads the fewest terms. With the items in no particular spatial order the later item of a
//! pair is the larger index three times in four, and the work of a block ending at the fraction
//! `c` of the terms is about `c + c²` of a total 2 (its `i` sides, and the `j` sides of the pairs
//! with both ends in it). The cuts even that out: block `t` of `T` ends where
//! `c + c² = 2 (t + 1) / T`.

use crate::derivatives::PairGradient;
use crate::periodic::ImageSet;
use rayon::prelude::*;

/// A kept pair term's gradient: the pair `(i, j)`, `i < j`, and its derivatives.
pub(crate) type Entry<const N: usize> = (usize, usize, PairGradient<N>);

/// Fewer terms than this are added on the calling thread: waking the pool would cost more.
const TERMS_PER_TASK: usize = 4096;

/// Item indices `0 = b_0 ≤ b_1 ≤ … ≤ b_T = items` cutting the items into blocks of about equal
/// scatter work for the terms `lists` (in order, ascending `i`): one block per thread of the
/// current pool, one when there are few terms.
fn block_bounds<const N: usize>(lists: &[&[Entry<N>]], items: usize) -> Vec<usize> {
    let total: usize = lists.iter().map(|l| l.len()).sum();
    let blocks = if total < 2 * TERMS_PER_TASK {
        1
    } else {
        rayon::current_num_threads().min(total / TERMS_PER_TASK)
    };
    let mut bounds = Vec::with_capacity(blocks + 1);
    bounds.push(0);
    for t in 1..blocks {
        let c = ((1.0 + 8.0 * t as f64 / blocks as f64).sqrt() - 1.0) / 2.0;
        let at = (c * total as f64) as usize;
        let cut = entry_at(lists, at).map_or(items, |e| e.0);
        let last = bounds[bounds.len() - 1];
        bounds.push(cut.clamp(last, items));
    }
    bounds.push(items);
    bounds
}

/// The `k`-th term of the concatenated lists.
fn entry_at<'a, const N: usize>(lists: &[&'a [Entry<N>]], mut k: usize) -> Option<&'a Entry<N>> {
    for l in lists {
        if k < l.len() {
            return Some(&l[k]);
        }
        k -= l.len();
    }
    None
}

/// Calls `add(i, j, g)` for the terms in order while `i < end`.
fn scan_until<const N: usize>(
    lists: &[&[Entry<N>]],
    end: usize,
    mut add: impl FnMut(usize, usize, &PairGradient<N>),
) {
    for list in lists {
        for (i, j, g) in *list {
            if *i >= end {
                return;
            }
            add(*i, *j, g);
        }
    }
}

/// `f` on every block: on rayon's pool when there are several.
fn for_each_block<T: Send>(blocks: Vec<T>, f: impl Fn(T) + Sync + Send) {
    if blocks.len() == 1 {
        blocks.into_iter().for_each(f);
    } else {
        blocks.into_par_iter().for_each(f);
    }
}

/// Splits `v` at the item bounds `bounds`, `width` entries per item.
fn split_at_bounds<'a, T>(mut v: &'a mut [T], bounds: &[usize], width: usize) -> Vec<&'a mut [T]> {
    let mut out = Vec::with_capacity(bounds.len());
    for w in bounds.windows(2) {
        let (head, tail) = v.split_at_mut((w[1] - w[0]) * width);
        out.push(head);
        v = tail;
    }
    out
}

/// Adds the terms `lists` of items in a container to the centres' derivatives in `out` (item
/// `i`'s variables from `starts[i]`, the centre first) and to the per-item `torques`, on
/// rayon's pool, each item's terms in the order of `lists`.
pub(crate) fn add_to_items<const N: usize>(
    lists: &[&[Entry<N>]],
    starts: &[usize],
    out: &mut [f64],
    torques: &mut [[f64; 3]],
) {
    let items = torques.len();
    let bounds = block_bounds(lists, items);
    let var_bounds: Vec<usize> = bounds.iter().map(|&b| starts[b]).collect();
    let outs = split_at_bounds(&mut out[..starts[items]], &var_bounds, 1);
    let taus = split_at_bounds(torques, &bounds, 1);
    let blocks: Vec<_> = (bounds.windows(2).map(|w| w[0]..w[1]))
        .zip(outs)
        .zip(taus)
        .collect();
    for_each_block(blocks, |((block, out), tau)| {
        let base = starts[block.start];
        let mut add = |item: usize, centre: &[f64; N], torque: &[f64; 3]| {
            let at = starts[item] - base;
            for (o, c) in out[at..at + N].iter_mut().zip(centre) {
                *o += c;
            }
            for (t, c) in tau[item - block.start].iter_mut().zip(torque) {
                *t += c;
            }
        };
        scan_until(lists, block.end, |i, j, g| {
            if i >= block.start {
                add(i, &g.centre_i, &g.angular_i);
            }
            if block.contains(&j) {
                add(j, &g.centre_j, &g.angular_j);
            }
        });
    });
}

/// Adds the terms `lists` of a periodic cell's points (`i` an item, `j` an item or a ghost) to
/// the forces on the points and the torques on their owners, on rayon's pool, each point's and
/// each item's terms in the order of `lists`.
pub(crate) fn add_to_points<const N: usize>(
    lists: &[&[Entry<N>]],
    owners: &ImageSet<N>,
    forces: &mut [[f64; N]],
    torques: &mut [[f64; 3]],
) {
    let items = owners.items;
    let bounds = block_bounds(lists, items);
    let (item_forces, ghost_forces) = forces.split_at_mut(items);
    let ghost_bounds: Vec<usize> = bounds
        .iter()
        .map(|&b| owners.first_ghost(b) - items)
        .collect();
    let fi = split_at_bounds(item_forces, &bounds, 1);
    let fg = split_at_ghost_bounds(ghost_forces, &ghost_bounds);
    let taus = split_at_bounds(torques, &bounds, 1);
    let blocks: Vec<_> = (bounds.windows(2).zip(ghost_bounds.windows(2)))
        .map(|(w, g)| (w[0]..w[1], items + g[0]))
        .zip(fi)
        .zip(fg)
        .zip(taus)
        .collect();
    for_each_block(blocks, |((((block, ghost0), fi), fg), tau)| {
        let lo = block.start;
        scan_until(lists, block.end, |a, b, g| {
            if a >= lo {
                add(&mut fi[a - lo], &g.centre_i);
                add(&mut tau[a - lo], &g.angular_i);
            }
            let o = owners.owner[b] as usize;
            if block.contains(&o) {
                let f = if b < items {
                    &mut fi[b - lo]
                } else {
                    &mut fg[b - ghost0]
                };
                add(f, &g.centre_j);
                add(&mut tau[o - lo], &g.angular_j);
            }
        });
    });
}

/// Splits `v` at the (ghost) point bounds `bounds`.
fn split_at_ghost_bounds<'a, T>(v: &'a mut [T], bounds: &[usize]) -> Vec<&'a mut [T]> {
    let shifted: Vec<usize> = bounds.iter().map(|b| b - bounds[0]).collect();
    split_at_bounds(&mut v[bounds[0]..], &shifted, 1)
}

#[inline(always)]
fn add<const K: usize>(to: &mut [f64; K], from: &[f64; K]) {
    for (t, f) in to.iter_mut().zip(from) {
        *t += f;
    }
}
