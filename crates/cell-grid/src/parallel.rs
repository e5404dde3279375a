//! Parallel pair enumeration (feature `rayon`): the cells (slots) are split into
//! contiguous ranges and each range runs the serial stencil. A pair of cells is visited
//! from the earlier of the two, so the ranges never visit a pair twice.

use rayon::prelude::*;

use crate::error::Error;
use crate::grid::Grid;
use crate::pair_list::PairList;
use crate::pairs::Candidates;

impl<const D: usize> Grid<D> {
    /// Cells per task: enough pairs to amortise a task, enough tasks to balance the load.
    fn chunk_len(&self) -> usize {
        let threads = rayon::current_num_threads().max(1);
        (self.slot_count() / (8 * threads)).max(64)
    }

    /// The slots cut into consecutive ranges of `chunk_len` slots, as a parallel iterator.
    fn slot_chunks(&self) -> impl IndexedParallelIterator<Item = std::ops::Range<usize>> + '_ {
        let n = self.slot_count();
        let len = self.chunk_len();
        (0..n.div_ceil(len))
            .into_par_iter()
            .map(move |c| c * len..((c + 1) * len).min(n))
    }

    /// Parallel [`for_each_candidate_pair`](Self::for_each_candidate_pair): `f(i, j)` for
    /// every candidate pair `i < j`, exactly once, from several threads in no fixed order.
    pub fn par_for_each_candidate_pair<F>(&self, f: F)
    where
        F: Fn(usize, usize) + Sync,
    {
        self.slot_chunks()
            .for_each(|slots| self.drive(slots, &mut Candidates { f: &f }));
        (0..self.large_ids.len())
            .into_par_iter()
            .for_each(|k| self.large_candidates(k..k + 1, &mut &f));
    }

    /// Parallel [`for_each_close_pair`](Self::for_each_close_pair): `f(i, j, delta, dist2)`
    /// for every pair `i < j` closer than the reach, exactly once, in no fixed order.
    pub fn par_for_each_close_pair<F>(&self, f: F)
    where
        F: Fn(usize, usize, [f64; D], f64) + Sync,
    {
        self.slot_chunks()
            .for_each(|slots| self.close_pairs_over(slots, &f));
        (0..self.large_ids.len())
            .into_par_iter()
            .for_each(|k| self.large_close(k..k + 1, &mut &f));
    }

    /// Folds the close pairs in parallel: each task folds its pairs into its own `init()`
    /// accumulator, and the accumulators are merged with `reduce`. Use it to collect pairs
    /// or sum a pair energy without locks.
    pub fn par_fold_close_pairs<T, I, G, R>(&self, init: I, fold: G, reduce: R) -> T
    where
        T: Send,
        I: Fn() -> T + Sync + Send,
        G: Fn(&mut T, usize, usize, [f64; D], f64) + Sync + Send,
        R: Fn(T, T) -> T + Sync + Send,
    {
        let cells = self
            .slot_chunks()
            .map(|slots| {
                let mut acc = init();
                self.close_pairs_over(slots, |i, j, d, d2| fold(&mut acc, i, j, d, d2));
                acc
            })
            .reduce(&init, &reduce);
        let large = (0..self.large_ids.len())
            .into_par_iter()
            .map(|k| {
                let mut acc = init();
                self.large_close(k..k + 1, &mut |i, j, d, d2| fold(&mut acc, i, j, d, d2));
                acc
            })
            .reduce(&init, &reduce);
        reduce(cells, large)
    }
}

/// Ranges of rows a pair list's parallel folds cut the list into (fewer when it holds under
/// 4 096 pairs a range): a constant, so that the grouping of the folds — and a sum over the
/// ranges — depends on the list alone, never on the number of threads. Sixty-four keep eight
/// threads busy with the ranges of unequal cost.
const ROW_RANGES: usize = 64;

impl<const D: usize> PairList<D> {
    /// Parallel [`for_each_close_pair`](Self::for_each_close_pair) as a fold: the rows of the
    /// list are cut into consecutive ranges of about equal numbers of pairs, each task folds
    /// its pairs (in ascending `(i, j)` order) into its own `init()` accumulator, and the
    /// accumulators are merged with `reduce` in the order of the ranges.
    ///
    /// # Errors
    /// Those of [`refresh`](Self::refresh); nothing is folded then.
    pub fn par_fold_close_pairs<T, I, G, R>(
        &mut self,
        points: &[[f64; D]],
        init: I,
        fold: G,
        reduce: R,
    ) -> Result<T, Error>
    where
        T: Send,
        I: Fn() -> T + Sync + Send,
        G: Fn(&mut T, usize, usize, [f64; D], f64) + Sync + Send,
        R: Fn(T, T) -> T + Sync + Send,
    {
        self.refresh(points)?;
        let chunks = self.row_chunks(0..points.len(), ROW_RANGES);
        let list = &*self;
        Ok(chunks
            .into_par_iter()
            .map(|rows| {
                let mut acc = init();
                list.close_pairs_in(points, rows, &mut |i, j, d, d2| fold(&mut acc, i, j, d, d2));
                acc
            })
            .reduce(&init, &reduce))
    }

    /// Parallel [`for_each_close_pair`](Self::for_each_close_pair) into states the caller
    /// keeps: the rows are cut into consecutive ranges of about equal numbers of listed pairs,
    /// `states` is resized to one per range (new ones `T::default()`), and range `k` folds
    /// its pairs, in ascending `(i, j)` order, into `states[k]` after `start(&mut states[k])`.
    ///
    /// Read in the order of `states`, the pairs come in the order of the serial scan, whatever
    /// the scheduling, and the cut depends on the list alone: a sum over the states in order
    /// is the same on every run, with any number of threads. The states keep their memory from
    /// call to call, so a state that collects pairs allocates only when a range holds more of
    /// them than ever before.
    ///
    /// `rows` is `0..points.len()` for all pairs, else the range of first items `i` whose pairs
    /// are wanted (as [`for_each_close_pair_from`](Self::for_each_close_pair_from)).
    ///
    /// # Errors
    /// Those of [`refresh`](Self::refresh); `states` is left as it was then.
    pub fn par_fold_close_pairs_into<T, S, G>(
        &mut self,
        points: &[[f64; D]],
        rows: std::ops::Range<usize>,
        states: &mut Vec<T>,
        start: S,
        fold: G,
    ) -> Result<(), Error>
    where
        T: Send + Default,
        S: Fn(&mut T) + Sync + Send,
        G: Fn(&mut T, usize, usize, [f64; D], f64) + Sync + Send,
    {
        self.refresh(points)?;
        let chunks = self.row_chunks(rows, ROW_RANGES);
        states.resize_with(chunks.len(), T::default);
        let list = &*self;
        chunks
            .into_par_iter()
            .zip(states.par_iter_mut())
            .for_each(|(rows, state)| {
                start(state);
                list.close_pairs_in(points, rows, &mut |i, j, d, d2| fold(state, i, j, d, d2));
            });
        Ok(())
    }
}
