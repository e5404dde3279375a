//! Neighbours of one item or of an arbitrary point.

use crate::error::Error;
use crate::grid::{Grid, Layout, check_query_point, valid_reach};
use crate::pairs::dot;

impl<const D: usize> Grid<D> {
    /// Calls `f(j, delta, dist2)` for every item `j != i` closer to item `i` than the cutoff
    /// (or than `r_i + r_j`), with `delta = p_j - p_i` (minimum image) and `dist2 = |delta|^2`,
    /// from the positions of the last build. Visits the `3^D` cells around item `i`.
    ///
    /// # Errors
    /// [`Error::ItemOutOfRange`] if `i >= len()`.
    pub fn for_each_neighbour<F: FnMut(usize, [f64; D], f64)>(
        &self,
        i: usize,
        mut f: F,
    ) -> Result<(), Error> {
        if i >= self.len() {
            return Err(Error::ItemOutOfRange {
                index: i,
                len: self.len(),
            });
        }
        let (x, ri) = self.item_point(i);
        if self.radii_mode {
            self.search(&x, ri + self.r_small, |p, d, d2| {
                let s = ri + self.sorted_r[p];
                if d2 < s * s && self.order[p] != i {
                    f(self.order[p], d, d2);
                }
            });
        } else {
            let c2 = self.cutoff * self.cutoff;
            self.search(&x, self.cutoff, |p, d, d2| {
                if d2 < c2 && self.order[p] != i {
                    f(self.order[p], d, d2);
                }
            });
        }
        self.scan_large(&x, ri, |j, d, d2| {
            if j != i {
                f(j, d, d2);
            }
        });
        Ok(())
    }

    /// Tests `x` with radius `r` against every large item (radius sum as the threshold).
    fn scan_large<V: FnMut(usize, [f64; D], f64)>(&self, x: &[f64; D], r: f64, mut visit: V) {
        for q in 0..self.large_ids.len() {
            let d = self.min_image_wrapped(x, &self.large_pos[q]);
            let d2 = dot(&d, &d);
            let s = r + self.large_r[q];
            if d2 < s * s {
                visit(self.large_ids[q], d, d2);
            }
        }
    }

    /// The items returned by [`for_each_neighbour`](Self::for_each_neighbour), ascending.
    ///
    /// # Errors
    /// [`Error::ItemOutOfRange`] if `i >= len()`.
    pub fn neighbours(&self, i: usize) -> Result<Vec<usize>, Error> {
        let mut out = Vec::new();
        self.for_each_neighbour(i, |j, _, _| out.push(j))?;
        out.sort_unstable();
        Ok(out)
    }

    /// Calls `f(j, delta, dist2)` for every item `j` with `|x - p_j| < radius` (global
    /// cutoff) or `|x - p_j| < radius + r_j` (per-item radii: the balls of the items that a
    /// ball of `radius` around `x` overlaps). `delta = p_j - x` (minimum image).
    ///
    /// Any radius works: the search covers `ceil(reach / edge)` cells on each side, and falls
    /// back to scanning all items when that box holds more cells than there are items.
    ///
    /// # Errors
    /// [`Error::NonFiniteQueryPoint`], [`Error::InvalidQueryRadius`] (negative, NaN,
    /// infinite, or neither 0 nor of normal square, see [`Error::InvalidCutoff`]).
    pub fn for_each_near_point<F: FnMut(usize, [f64; D], f64)>(
        &self,
        x: [f64; D],
        radius: f64,
        mut f: F,
    ) -> Result<(), Error> {
        check_query_point(&x)?;
        if !(radius == 0.0 || valid_reach(radius)) {
            return Err(Error::InvalidQueryRadius { value: radius });
        }
        let (w, _) = self.locate(&x);
        if self.radii_mode {
            self.scan_large(&w, radius, &mut f);
            self.search(&w, radius + self.r_small, |p, d, d2| {
                let s = radius + self.sorted_r[p];
                if d2 < s * s {
                    f(self.order[p], d, d2);
                }
            });
        } else {
            let r2 = radius * radius;
            self.search(&w, radius, |p, d, d2| {
                if d2 < r2 {
                    f(self.order[p], d, d2);
                }
            });
        }
        Ok(())
    }

    /// Calls `visit(position_in_cell_order, delta, dist2)` for every item in the cells that
    /// can hold an item within `reach` of the (already wrapped) point `x`, each item once.
    pub(crate) fn search<V: FnMut(usize, [f64; D], f64)>(
        &self,
        x: &[f64; D],
        reach: f64,
        mut visit: V,
    ) {
        if self.order.is_empty() {
            return;
        }
        let (_, k) = self.locate(x);
        // Per axis: the range of cell coordinates to scan, wrapped later on periodic axes.
        let mut lo = [0i64; D];
        let mut hi = [0i64; D];
        let mut volume = 1.0_f64;
        for a in 0..D {
            let dims = self.dims[a] as i64;
            // Two points closer than `reach` are at most `floor(reach / edge) + 1` cells
            // apart; unlike `ceil`, this bound survives a quotient that rounds down onto an
            // integer.
            let span = ((reach * self.inv_edge[a]).floor() + 1.0).min(dims as f64) as i64;
            if self.periodic[a] && 2 * span + 1 >= dims {
                // The window covers the whole ring: scan each cell once, not twice.
                lo[a] = 0;
                hi[a] = dims - 1;
            } else if self.periodic[a] {
                lo[a] = k[a] - span;
                hi[a] = k[a] + span;
            } else {
                lo[a] = (k[a] - span).max(0);
                hi[a] = (k[a] + span).min(dims - 1);
            }
            volume *= (hi[a] - lo[a] + 1) as f64;
        }
        let emit = |p: usize, visit: &mut V| {
            let d = self.min_image_wrapped(x, &self.sorted[p]);
            let d2 = dot(&d, &d);
            visit(p, d, d2);
        };
        if volume > self.order.len() as f64 {
            for p in 0..self.order.len() {
                emit(p, &mut visit);
            }
            return;
        }
        // In the dense layout the cells of one x-row of the box are consecutive, and so are
        // their items: one run per row instead of one lookup per cell (a large item's box
        // can span thousands of cells).
        let rows = self.layout == Layout::Dense && !self.periodic[0];
        let first = usize::from(rows);
        let mut c = lo;
        loop {
            let mut w = c;
            for a in 0..D {
                if self.periodic[a] {
                    w[a] = c[a].rem_euclid(self.dims[a] as i64);
                }
            }
            if rows {
                let s0 = self.dense_slot(&w);
                let s1 = s0 + (hi[0] - lo[0]) as usize;
                for p in self.start[s0]..self.start[s1 + 1] {
                    emit(p, &mut visit);
                }
            } else if let Some(s) = self.find_slot(&w) {
                for p in self.start[s]..self.start[s + 1] {
                    emit(p, &mut visit);
                }
            }
            // Odometer increment over the box [lo, hi] (axes from `first` on).
            let mut a = first;
            loop {
                if a == D {
                    return;
                }
                if c[a] < hi[a] {
                    c[a] += 1;
                    break;
                }
                c[a] = lo[a];
                a += 1;
            }
        }
    }
}
