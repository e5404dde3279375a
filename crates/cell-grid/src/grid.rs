//! The grid itself: geometry of the cells, counting sort of the items, accessors.

use crate::builder::{GridBuilder, Reach};
use crate::error::Error;
use crate::hash::{CellKey, CellMap};

/// Largest number of cells along one axis. The edge margin below already keeps the count
/// under `1 / (16 eps) = 2^48` (the edge is at least `32 eps max|x|` and the side at most
/// `2 max|x|`), which also keeps the integer cell coordinates exact; the clamp only guards
/// that reasoning.
const MAX_CELLS_PER_AXIS: f64 = 281_474_976_710_656.0; // 2^48

/// Default floor of the cap on dense cells: below it the array is small whatever `m` is.
const DEFAULT_MIN_CELLS: usize = 1 << 16;

/// Default dense cells allowed per item before switching to hashed cells.
const DEFAULT_CELLS_PER_ITEM: usize = 16;

/// Relative safety margin on the cell edge, in units of the machine epsilon. The cell index
/// `floor((x - lo) / l)` is computed in floating point; the margin makes sure that two points
/// whose *computed* distance is below the cutoff never land two cells apart, even after the
/// rounding of the subtraction, the division and the distance itself.
const EDGE_MARGIN_ULPS: f64 = 16.0;

/// Radius buckets of the split decision: binary orders of magnitude below the largest.
pub(crate) const SIZE_BUCKETS: usize = 64;

/// From this many items on, the dense counting sort goes through cache-sized blocks of cells
/// (see `sort_blocked`); below it every array fits in cache anyway.
const BLOCKED_MIN_ITEMS: usize = 1 << 15;

/// Number of blocks of the blocked counting sort: few enough that one open cache line per
/// block stays in L1, many enough that a block's cells and items fit in L2.
const SORT_BLOCKS: usize = 256;

/// Slot recorded for an item kept out of the cells (see `Grid::rank`).
const NO_CELL: u32 = u32::MAX;

/// Largest number of items: item ranks and cell slots are `u32` (`NO_CELL` excluded), which
/// halves the bytes the sort writes per item against `usize`.
const MAX_ITEMS: usize = u32::MAX as usize - 1;

/// Bucket of radius `r`: how many binary orders of magnitude it lies below `r_max`
/// (difference of the exponents, capped).
fn size_bucket(r: f64, r_max: f64) -> usize {
    let e = |x: f64| ((x.to_bits() >> 52) & 0x7ff) as i64;
    (e(r_max) - e(r)).clamp(0, SIZE_BUCKETS as i64 - 1) as usize
}

/// Exclusive upper bound of the radii in bucket `b`: `2^(E - b + 1)` where `2^E <= r_max`.
/// Radii are valid (normal squares), so the exponent stays in range.
fn bucket_top(r_max: f64, b: usize) -> f64 {
    let biased = ((r_max.to_bits() >> 52) & 0x7ff) as i64 - b as i64 + 1;
    f64::from_bits((biased.clamp(1, 2046) as u64) << 52)
}

/// How the cell offsets are stored.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Layout {
    /// A flat array over all cells plus one layer of empty ghost cells around them, so a
    /// neighbouring cell is a fixed offset away and needs no bounds check.
    Dense,
    /// Only the non-empty cells, found through a hash map from cell coordinates. Used when
    /// the dense array would exceed the cap on cells ([`GridBuilder::max_cells`]).
    Hashed,
}

/// A non-empty cell and the items in it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Cell<'a, const D: usize> {
    /// Integer coordinates of the cell, `0 <= coords[a] < cells_per_axis()[a]`.
    pub coords: [usize; D],
    /// Indices of the items in the cell, ascending.
    pub items: &'a [usize],
}

/// A uniform grid of square (2D) or cubic (3D) cells over the item centres, for finding all
/// pairs closer than a cutoff in `O(m)` time (paper Section 5.2).
///
/// # The grid
/// The domain `[lo, hi]` (given, or the bounding box of the points) is cut into
/// `N_a = max(1, floor(L_a / l))` cells along each axis `a`, with `L_a = hi_a - lo_a` and
/// `l` the reach: the cutoff, or `2 max_i r_i` for per-item radii (the paper's `l = 2R`;
/// twice the largest radius left in the cells when the largest items are split off, see the
/// crate documentation). The
/// cell edge `L_a / N_a` is then at least `l`, so two items closer than `l` lie in the same
/// or in adjacent cells (cells that share at least a vertex). An item at `x` goes into the
/// cell `p(x_a) = min(max(0, floor((x_a - lo_a) N_a / L_a)), N_a - 1)` along each axis: the
/// clamp of the paper with 0-based indices, which sends points outside the domain to the
/// border cells. On a periodic axis the coordinate is first wrapped into the box.
///
/// The edge gets a margin of a few ulps of the largest coordinate so that the rounding of
/// `floor` cannot separate two points whose computed distance is below the cutoff.
///
/// # Layout
/// Items are counting-sorted by cell (`O(m + cells)`): `order` holds the item indices cell
/// after cell, each cell's items ascending, and cell `c` owns `order[start[c]..start[c+1]]`.
/// The positions (and radii) are copied into the same order so the pair loop reads memory
/// sequentially. The number of cells is capped (see [`GridBuilder::max_cells`]); above the
/// cap only non-empty cells are kept, in a hash map ([`Layout::Hashed`]).
///
/// A build touches few bytes per item, because a fresh build pays a page fault (and the
/// kernel's zeroing) for every page of new buffer: `8 D` for the position, 8 for the index,
/// 4 for the item's rank (`u32`, which limits a grid to fewer than `u32::MAX` items), 8
/// more with radii, and 8 per cell of the dense array. Large inputs are sorted in
/// cache-sized blocks inside the final arrays, with no temporary of the size of the input.
///
/// # Pairs
/// Each non-empty cell is paired with itself and with the half of its `3^D - 1` neighbours
/// that come later in cell order (13 in 3D, 4 in 2D), so every pair of items in the same or
/// adjacent cells is visited exactly once, without a test on `i < j` to reject duplicates.
/// In the dense layout those 13 cells form 4 rows of 3 consecutive cells plus the next cell
/// along x, i.e. 5 contiguous runs of the cell-ordered arrays (2 in 2D).
///
/// # References
/// E. G. Birgin, R. D. Lobato, J. M. Martínez, *A nonlinear programming model with implicit
/// variables for packing ellipsoids*, preprint of March 2016
/// (`shared/papers/birgin-lobato-martinez-implicit-variables-packing.md`), Section 5.2
/// "Efficient evaluation of the constraints".
#[derive(Debug, Clone)]
pub struct Grid<const D: usize> {
    // --- configuration, fixed at construction ---
    pub(crate) cutoff: f64,
    pub(crate) radii_mode: bool,
    pub(crate) radii: Vec<f64>,
    pub(crate) r_max: f64,
    /// Whether items much larger than the rest may be kept out of the cells.
    pub(crate) split: bool,
    /// Number of radii per binary order of magnitude below the largest (bucket
    /// `e(r_max) - e(r)` for the exponent `e`), the input of the split decision.
    pub(crate) size_hist: [usize; SIZE_BUCKETS],
    /// Largest radius in each bucket (0 for an empty bucket).
    pub(crate) bucket_max: [f64; SIZE_BUCKETS],
    pub(crate) fixed_domain: Option<([f64; D], [f64; D])>,
    pub(crate) periodic: [bool; D],
    pub(crate) max_cells: Option<usize>,
    /// All `3^D - 1` non-zero offsets of the neighbourhood.
    pub(crate) stencil: Vec<[i64; D]>,

    // --- geometry of the last build ---
    pub(crate) reach: f64,
    pub(crate) lo: [f64; D],
    pub(crate) extent: [f64; D],
    /// `L_a` and `1 / L_a` on periodic axes, 0 elsewhere: the minimum-image shift
    /// `L_a round(d_a / L_a)` then vanishes on non-periodic axes without a branch (and
    /// without `inf * 0` when a bounding box is wider than the largest `f64`).
    pub(crate) period: [f64; D],
    pub(crate) inv_period: [f64; D],
    pub(crate) edge: [f64; D],
    pub(crate) inv_edge: [f64; D],
    pub(crate) dims: [usize; D],
    /// Strides of the padded dense array (`N_a + 2` cells per axis).
    pub(crate) strides: [usize; D],
    pub(crate) layout: Layout,
    pub(crate) any_periodic: bool,

    // --- buffers, reused by `rebuild` ---
    /// Blocked counting sort without `pack_slots`: slot of each item of `order`, while the
    /// items are only grouped by block of cells.
    pub(crate) tmp_slots: Vec<u32>,
    /// Blocked counting sort: whether the slot of an item travels in the high half of its
    /// `order` entry (64-bit `usize`) instead of in `tmp_slots`, which saves 4 bytes of
    /// fresh memory per item. A field so that tests can run the other path.
    pub(crate) pack_slots: bool,
    /// Blocked counting sort: one block's items, copied out of the final arrays so that they
    /// can be sorted back into the same range (sized for one block, which fits in cache).
    pub(crate) scratch_ids: Vec<usize>,
    pub(crate) scratch_slots: Vec<u32>,
    pub(crate) scratch_pos: Vec<[f64; D]>,
    pub(crate) scratch_r: Vec<f64>,
    /// Item count from which the blocked sort is used (a field so tests can lower it).
    pub(crate) blocked_min: usize,
    /// Largest number of items accepted (`MAX_ITEMS`; a field so tests can lower it).
    pub(crate) max_items: usize,
    pub(crate) start: Vec<usize>,
    pub(crate) order: Vec<usize>,
    /// Position in cell order of each item (`u32`: see `MAX_ITEMS`). During the sort it first
    /// holds each item's slot (or `NO_CELL`): one buffer instead of two, each entry read as
    /// a slot before it is overwritten as a position.
    pub(crate) rank: Vec<u32>,
    pub(crate) sorted: Vec<[f64; D]>,
    pub(crate) sorted_r: Vec<f64>,
    /// Number of items, in cells or not.
    pub(crate) n_items: usize,
    /// Items with radius at least `r_cut` live outside the cells, in these three arrays
    /// (ascending item index). The cells hold the items with radius below `r_cut`, the
    /// largest of which is `r_small` (`r_max` without a split): cells and searches are sized
    /// by `r_small`, which can be up to twice smaller than the power of two `r_cut`.
    pub(crate) r_cut: f64,
    pub(crate) r_small: f64,
    pub(crate) split_active: bool,
    pub(crate) large_ids: Vec<usize>,
    pub(crate) large_pos: Vec<[f64; D]>,
    pub(crate) large_r: Vec<f64>,
    /// Forward row offsets in the padded dense array: the positive linear offsets of the
    /// stencil with no x component (each stands for the three cells `h - 1, h, h + 1`).
    pub(crate) rows: Vec<usize>,
    pub(crate) map: CellMap<D>,
    pub(crate) slot_coords: Vec<[i64; D]>,
}

impl<const D: usize> GridBuilder<D> {
    /// Validates the configuration and builds the grid over `points`.
    ///
    /// # Errors
    /// Any [`Error`] about the configuration, and those of [`Grid::rebuild`].
    pub fn build(self, points: &[[f64; D]]) -> Result<Grid<D>, Error> {
        Grid::from_builder(self, points)
    }
}

impl<const D: usize> Grid<D> {
    /// Builds a grid over `points` where pairs are the points closer than `cutoff`.
    ///
    /// The domain is the bounding box of the points. An empty slice gives an empty grid
    /// (no pairs), not an error.
    ///
    /// # Errors
    /// [`Error::InvalidCutoff`] if `cutoff` is not finite and positive,
    /// [`Error::NonFiniteCoordinate`] for a NaN or infinite coordinate,
    /// [`Error::UnsupportedDimension`] unless `1 <= D <= 3`,
    /// [`Error::TooManyItems`] for `u32::MAX` points or more.
    pub fn build(points: &[[f64; D]], cutoff: f64) -> Result<Self, Error> {
        GridBuilder::with_cutoff(cutoff).build(points)
    }

    /// Starts a configuration with a global cutoff (same as [`GridBuilder::with_cutoff`]).
    pub fn with_cutoff(cutoff: f64) -> GridBuilder<D> {
        GridBuilder::with_cutoff(cutoff)
    }

    /// Starts a configuration with per-item radii (same as [`GridBuilder::with_radii`]).
    pub fn with_radii(radii: &[f64]) -> GridBuilder<D> {
        GridBuilder::with_radii(radii)
    }

    fn from_builder(b: GridBuilder<D>, points: &[[f64; D]]) -> Result<Self, Error> {
        if D == 0 || D > 3 {
            return Err(Error::UnsupportedDimension { dim: D });
        }
        let (cutoff, radii_mode, radii) = match b.reach {
            Reach::Cutoff(c) => {
                if !valid_reach(c) {
                    return Err(Error::InvalidCutoff { value: c });
                }
                (c, false, Vec::new())
            }
            Reach::Radii(r) => (0.0, true, r),
        };
        if let Some((lo, hi)) = b.domain {
            for a in 0..D {
                // The side must be finite too: `1e308 - (-1e308)` is not, and a box side
                // enters the minimum image.
                let ok = lo[a].is_finite()
                    && hi[a].is_finite()
                    && (hi[a] - lo[a]).is_finite()
                    && if b.periodic[a] {
                        lo[a] < hi[a]
                    } else {
                        lo[a] <= hi[a]
                    };
                if !ok {
                    return Err(Error::InvalidDomain {
                        axis: a,
                        lo: lo[a],
                        hi: hi[a],
                    });
                }
            }
        } else if let Some(axis) = b.periodic.iter().position(|&p| p) {
            return Err(Error::PeriodicWithoutDomain { axis });
        }
        let mut grid = Grid {
            cutoff,
            radii_mode,
            radii: Vec::new(),
            r_max: 0.0,
            split: b.split,
            size_hist: [0; SIZE_BUCKETS],
            bucket_max: [0.0; SIZE_BUCKETS],
            fixed_domain: b.domain,
            periodic: b.periodic,
            max_cells: b.max_cells,
            stencil: full_stencil::<D>(),
            reach: cutoff,
            lo: [0.0; D],
            extent: [0.0; D],
            period: [0.0; D],
            inv_period: [0.0; D],
            edge: [1.0; D],
            inv_edge: [1.0; D],
            dims: [1; D],
            strides: [1; D],
            layout: Layout::Dense,
            any_periodic: b.periodic.iter().any(|&p| p),
            tmp_slots: Vec::new(),
            pack_slots: usize::BITS >= 64,
            scratch_ids: Vec::new(),
            scratch_slots: Vec::new(),
            scratch_pos: Vec::new(),
            scratch_r: Vec::new(),
            blocked_min: BLOCKED_MIN_ITEMS,
            max_items: MAX_ITEMS,
            start: Vec::new(),
            order: Vec::new(),
            rank: Vec::new(),
            sorted: Vec::new(),
            sorted_r: Vec::new(),
            rows: Vec::new(),
            n_items: 0,
            r_cut: 0.0,
            r_small: 0.0,
            split_active: false,
            large_ids: Vec::new(),
            large_pos: Vec::new(),
            large_r: Vec::new(),
            map: CellMap::default(),
            slot_coords: Vec::new(),
        };
        if radii_mode {
            grid.rebuild_with_radii(points, &radii)?;
        } else {
            grid.rebuild(points)?;
        }
        Ok(grid)
    }

    /// Re-sorts the items after their positions changed, keeping the configuration (cutoff or
    /// radii, domain, periodic axes, cap on cells).
    ///
    /// No memory is allocated unless the number of points grows beyond what an earlier build
    /// saw, or the dense cell array grows by more than one cell per axis (the headroom kept
    /// for a bounding-box domain that widens as points move). On error the grid keeps its
    /// previous state.
    ///
    /// # Errors
    /// [`Error::NonFiniteCoordinate`] for a NaN or infinite coordinate,
    /// [`Error::RadiiCountMismatch`] if the grid has per-item radii and the number of points
    /// changed (use [`rebuild_with_radii`](Self::rebuild_with_radii)),
    /// [`Error::TooManyItems`] for `u32::MAX` points or more.
    pub fn rebuild(&mut self, points: &[[f64; D]]) -> Result<(), Error> {
        if self.radii_mode && self.radii.len() != points.len() {
            return Err(Error::RadiiCountMismatch {
                radii: self.radii.len(),
                points: points.len(),
            });
        }
        let (lo, hi) = self.check_points(points)?;
        self.layout_cells(points.len(), lo, hi)?;
        self.sort_items(points);
        Ok(())
    }

    /// Replaces the per-item radii and rebuilds. On a grid built with a global cutoff this
    /// switches it to per-item radii.
    ///
    /// # Errors
    /// [`Error::InvalidRadius`], [`Error::RadiiCountMismatch`], and those of
    /// [`rebuild`](Self::rebuild). On error the grid keeps its previous state.
    pub fn rebuild_with_radii(&mut self, points: &[[f64; D]], radii: &[f64]) -> Result<(), Error> {
        if radii.len() != points.len() {
            return Err(Error::RadiiCountMismatch {
                radii: radii.len(),
                points: points.len(),
            });
        }
        let mut r_max = 0.0_f64;
        for (index, &value) in radii.iter().enumerate() {
            if !valid_reach(2.0 * value) {
                return Err(Error::InvalidRadius { index, value });
            }
            r_max = r_max.max(value);
        }
        let mut hist = [0usize; SIZE_BUCKETS];
        let mut top = [0.0f64; SIZE_BUCKETS];
        for &r in radii {
            let b = size_bucket(r, r_max);
            hist[b] += 1;
            top[b] = top[b].max(r);
        }
        let (lo, hi) = self.check_points(points)?;
        let saved = (self.radii_mode, self.r_max, self.size_hist, self.bucket_max);
        self.radii_mode = true;
        self.r_max = r_max;
        self.size_hist = hist;
        self.bucket_max = top;
        if let Err(e) = self.layout_cells(points.len(), lo, hi) {
            (self.radii_mode, self.r_max, self.size_hist, self.bucket_max) = saved;
            return Err(e);
        }
        self.radii.clear();
        self.radii.extend_from_slice(radii);
        self.sort_items(points);
        Ok(())
    }

    /// Checks every coordinate and returns the domain of this build.
    fn check_points(&self, points: &[[f64; D]]) -> Result<([f64; D], [f64; D]), Error> {
        if points.len() > self.max_items {
            return Err(Error::TooManyItems {
                count: points.len(),
                max: self.max_items,
            });
        }
        let mut lo = [f64::INFINITY; D];
        let mut hi = [f64::NEG_INFINITY; D];
        for (index, p) in points.iter().enumerate() {
            for axis in 0..D {
                let value = p[axis];
                if !value.is_finite() {
                    return Err(Error::NonFiniteCoordinate { index, axis, value });
                }
                lo[axis] = lo[axis].min(value);
                hi[axis] = hi[axis].max(value);
            }
        }
        match self.fixed_domain {
            Some(d) => Ok(d),
            None if points.is_empty() => Ok(([0.0; D], [0.0; D])),
            None => Ok((lo, hi)),
        }
    }

    /// Chooses the cells for `m` items over `[lo, hi]`: count per axis, edge, layout.
    fn layout_cells(&mut self, m: usize, lo: [f64; D], hi: [f64; D]) -> Result<(), Error> {
        let reach = if self.radii_mode {
            2.0 * self.r_max
        } else {
            self.cutoff
        };
        // The largest coordinate magnitude (not |lo| + |hi|, which may overflow).
        let mut scale = 0.0_f64;
        for a in 0..D {
            scale = scale.max(lo[a].abs()).max(hi[a].abs());
            if self.periodic[a] && m > 0 && reach > 0.5 * (hi[a] - lo[a]) {
                return Err(Error::CutoffTooLargeForBox {
                    axis: a,
                    reach,
                    box_length: hi[a] - lo[a],
                });
            }
        }
        let (r_cut, r_small, split_active) = if self.radii_mode && self.split && m > 0 {
            self.choose_split(m, &lo, &hi)
        } else {
            (self.r_max, self.r_max, false)
        };
        // Two items in cells have radii of at most `r_small`.
        let cell_reach = if self.radii_mode {
            2.0 * r_small
        } else {
            reach
        };
        // With no items the reach of radii is 0; any positive edge will do.
        let base = if cell_reach > 0.0 { cell_reach } else { 1.0 };
        let safe = base * (1.0 + EDGE_MARGIN_ULPS * f64::EPSILON)
            + 2.0 * EDGE_MARGIN_ULPS * f64::EPSILON * scale;

        let mut dims = [1usize; D];
        let mut edge = [safe; D];
        let mut padded_cells = 1.0_f64;
        for a in 0..D {
            let len = hi[a] - lo[a];
            // Fewer, larger cells are always correct: clamping the count is safe. A side
            // that overflows to infinity gets cells of infinite edge: every point lands in
            // cell 0 along that axis, which is coarse but exact.
            let n = (len / safe).floor().clamp(1.0, MAX_CELLS_PER_AXIS);
            if len > 0.0 {
                edge[a] = len / n;
            }
            dims[a] = n as usize;
            padded_cells *= n + 2.0;
        }
        let cap = self
            .max_cells
            .unwrap_or_else(|| DEFAULT_MIN_CELLS.max(DEFAULT_CELLS_PER_ITEM.saturating_mul(m)));

        self.reach = reach;
        self.r_cut = r_cut;
        self.r_small = r_small;
        self.split_active = split_active;
        self.lo = lo;
        for a in 0..D {
            self.extent[a] = hi[a] - lo[a];
            (self.period[a], self.inv_period[a]) = if self.periodic[a] {
                (self.extent[a], 1.0 / self.extent[a])
            } else {
                (0.0, 0.0)
            };
            self.edge[a] = edge[a];
            self.inv_edge[a] = 1.0 / edge[a];
        }
        self.dims = dims;
        // Dense slots are `u32` too (`NO_CELL` excluded); a cap above that is not honoured.
        self.layout = if padded_cells <= cap as f64 && padded_cells < NO_CELL as f64 {
            Layout::Dense
        } else {
            Layout::Hashed
        };
        if self.layout == Layout::Dense {
            let mut s = 1usize;
            for a in 0..D {
                self.strides[a] = s;
                s *= dims[a] + 2;
            }
            self.rows.clear();
            for o in &self.stencil {
                let lin: i64 = (0..D).map(|a| o[a] * self.strides[a] as i64).sum();
                if o[0] == 0 && lin > 0 {
                    self.rows.push(lin as usize);
                }
            }
        }
        Ok(())
    }

    /// Decides whether to keep the largest items out of the cells, and below which radius
    /// `r_cut` items stay in them.
    ///
    /// With cells sized for `r_max`, an item of radius `r` meets about
    /// `rho (3 * 2 r_max)^D / 2` candidates (density `rho`), which is `(r_max / r)^D` times
    /// more than it would with cells sized for its own kind. Splitting at `r_cut` costs
    /// instead, per item in the cells, `rho (3 * 2 r_s)^D / 2` with `r_s` the largest radius
    /// left in the cells; per large item of radius `r`, a box search of side about
    /// `2 (r + r_s) + 4 r_s`; and `L^2 / 2` for the pairs of the `L` large items. The radii
    /// are bucketed by binary order of magnitude, every power of two is tried as `r_cut`,
    /// and the cheapest estimate wins (no split on ties).
    ///
    /// Returns `(r_cut, r_s, split)`.
    fn choose_split(&self, m: usize, lo: &[f64; D], hi: &[f64; D]) -> (f64, f64, bool) {
        let r_max = self.r_max;
        let mut vol = 1.0;
        for a in 0..D {
            vol *= (hi[a] - lo[a]).max(2.0 * r_max);
        }
        let rho = m as f64 / vol;
        let half_stencil = 3f64.powi(D as i32) / 2.0;
        let d = D as i32;
        let cost_cells = |n_small: f64, r_small: f64| {
            let e = 2.0 * r_small;
            // The last term is the per-cell work of the counting sort.
            n_small * rho * e.powi(d) * half_stencil + 0.25 * vol / e.powi(d)
        };
        // (cost, r_cut, r_small, split)
        let mut best = (cost_cells(m as f64, r_max), r_max, r_max, false);
        let mut n_large = 0usize;
        for k in 1..SIZE_BUCKETS {
            n_large += self.size_hist[k - 1];
            if n_large >= m {
                break;
            }
            if self.size_hist[k] == 0 {
                // Same items in the cells as the next k, with a larger r_cut: not better.
                continue;
            }
            let r_cut = bucket_top(r_max, k);
            let r_small = self.bucket_max[k..].iter().fold(0.0f64, |a, &b| a.max(b));
            let e = 2.0 * r_small;
            let mut cost = cost_cells((m - n_large) as f64, r_small);
            for b in 0..k {
                let r = self.bucket_max[b];
                cost += self.size_hist[b] as f64 * rho * (2.0 * (r + r_small) + 2.0 * e).powi(d);
            }
            cost += 0.5 * (n_large as f64).powi(2);
            if cost < best.0 {
                best = (cost, r_cut, r_small, true);
            }
        }
        (best.1, best.2, best.3)
    }

    /// Wraps `x` into the box on periodic axes and returns it with its cell coordinates.
    #[inline]
    pub(crate) fn locate(&self, x: &[f64; D]) -> ([f64; D], [i64; D]) {
        let mut w = *x;
        let mut k = [0i64; D];
        for a in 0..D {
            if self.periodic[a] {
                let t = (x[a] - self.lo[a]).rem_euclid(self.extent[a]);
                // rem_euclid may round up to the period itself.
                w[a] = if t < self.extent[a] {
                    self.lo[a] + t
                } else {
                    self.lo[a]
                };
            }
            let t = (w[a] - self.lo[a]) * self.inv_edge[a];
            let top = (self.dims[a] - 1) as f64;
            // Clamp in f64 before the cast: far-away points would saturate the integer. On
            // the clamped range `[0, top]` the cast's truncation is `floor`, which without
            // SSE4.1 is a library call per coordinate (measured: 2 % of a rebuild + pairs).
            k[a] = t.clamp(0.0, top) as i64;
        }
        (w, k)
    }

    /// Slot of cell `k` in the dense array (with the ghost layer).
    #[inline]
    pub(crate) fn dense_slot(&self, k: &[i64; D]) -> usize {
        let mut s = 0usize;
        for a in 0..D {
            s += (k[a] + 1) as usize * self.strides[a];
        }
        s
    }

    /// Cell coordinates of a dense slot.
    #[inline]
    pub(crate) fn dense_coords(&self, slot: usize) -> [i64; D] {
        let mut k = [0i64; D];
        for a in 0..D {
            k[a] = ((slot / self.strides[a]) % (self.dims[a] + 2)) as i64 - 1;
        }
        k
    }

    /// Cell coordinates of any slot.
    #[inline]
    pub(crate) fn slot_coords_of(&self, slot: usize) -> [i64; D] {
        match self.layout {
            Layout::Dense => self.dense_coords(slot),
            Layout::Hashed => self.slot_coords[slot],
        }
    }

    /// Slot of the cell with coordinates `k`, if it exists and holds items. Coordinates must
    /// already be wrapped on periodic axes.
    #[inline]
    pub(crate) fn find_slot(&self, k: &[i64; D]) -> Option<usize> {
        for a in 0..D {
            if k[a] < 0 || k[a] >= self.dims[a] as i64 {
                return None;
            }
        }
        let s = match self.layout {
            Layout::Dense => self.dense_slot(k),
            Layout::Hashed => *self.map.get(&CellKey(*k))?,
        };
        (self.start[s] < self.start[s + 1]).then_some(s)
    }

    /// Turns the per-cell counts in `start[..nslots]` into inclusive prefix sums (each cell's
    /// end, which the backward scatter decrements to its start), sets the sentinel, and sizes
    /// the sorted buffers for the counted items (no allocation once large enough).
    /// Returns the number of items in cells.
    fn end_offsets_and_buffers(&mut self, nslots: usize) -> usize {
        let mut acc = 0usize;
        for c in &mut self.start[..nslots] {
            acc += *c;
            *c = acc;
        }
        self.start[nslots] = acc;
        self.size_sorted_buffers(acc);
        acc
    }

    /// Sets the length of the cell-ordered arrays to `n` items. Their old contents are kept,
    /// not zeroed: the sort writes every entry exactly once, and on a rebuild a fill would
    /// be one more pass over all of them for nothing.
    fn size_sorted_buffers(&mut self, n: usize) {
        self.order.resize(n, 0);
        self.sorted.resize(n, [0.0; D]);
        self.sorted_r
            .resize(if self.radii_mode { n } else { 0 }, 0.0);
    }

    /// The counting sort: items into slots, then positions into cell order. Items at or
    /// above the split radius go to the separate large-item arrays instead.
    fn sort_items(&mut self, points: &[[f64; D]]) {
        let m = points.len();
        if self.layout == Layout::Dense && m >= self.blocked_min {
            self.sort_blocked(points);
            return;
        }
        // The items are visited in index order: the caller's points are then read
        // sequentially and only stores land at random. Visiting them in the previous cell
        // order instead (sequential stores, random loads) was measured 2x slower on shuffled
        // input at m = 1e6: a store that misses the cache retires at once, a load stalls.
        self.n_items = m;
        // The slot of each item goes into `rank`, pushed in turn: no zero-fill of fresh
        // memory first.
        self.rank.clear();
        self.rank.reserve(m);
        self.large_ids.clear();
        self.large_pos.clear();
        self.large_r.clear();
        let split = self.split_active;
        let r_cut = self.r_cut;
        let nslots = match self.layout {
            Layout::Dense => {
                let ncells = self.dense_cell_count();
                self.reset_dense_starts(ncells);
                for (i, p) in points.iter().enumerate() {
                    let s = if split && self.radii[i] >= r_cut {
                        NO_CELL
                    } else {
                        let s = self.dense_slot(&self.locate(p).1);
                        self.start[s] += 1;
                        s as u32
                    };
                    self.rank.push(s);
                }
                ncells
            }
            Layout::Hashed => {
                self.map.clear();
                self.slot_coords.clear();
                // There are never more non-empty cells than items: sized for m once, the
                // map and the slot arrays do not grow when moves spread the items over more
                // cells.
                self.map.reserve(m);
                self.slot_coords.reserve(m);
                self.start.clear();
                self.start.reserve(m + 1);
                for (i, p) in points.iter().enumerate() {
                    let s = if split && self.radii[i] >= r_cut {
                        NO_CELL
                    } else {
                        let (_, c) = self.locate(p);
                        let next = self.slot_coords.len();
                        let s = *self.map.entry(CellKey(c)).or_insert(next);
                        if s == next {
                            self.slot_coords.push(c);
                        }
                        // Fewer slots than items, and items are fewer than `NO_CELL`.
                        s as u32
                    };
                    self.rank.push(s);
                }
                let n = self.slot_coords.len();
                self.start.clear();
                self.start.resize(n + 1, 0);
                for &s in &self.rank {
                    if s != NO_CELL {
                        self.start[s as usize] += 1;
                    }
                }
                n
            }
        };
        // Inclusive prefix sums give each cell's end; the backward scatter below decrements
        // them to the starts and keeps each cell's items in ascending index order.
        let in_cells = self.end_offsets_and_buffers(nslots);
        for i in (0..m).rev() {
            let s = self.rank[i];
            if s == NO_CELL {
                continue;
            }
            let s = s as usize;
            self.start[s] -= 1;
            let pos = self.start[s];
            self.order[pos] = i;
            self.rank[i] = pos as u32;
            self.sorted[pos] = if self.any_periodic {
                self.locate(&points[i]).0
            } else {
                points[i]
            };
            if self.radii_mode {
                self.sorted_r[pos] = self.radii[i];
            }
        }
        self.place_large_items(points, in_cells);
    }

    /// Number of slots of the padded dense array.
    fn dense_cell_count(&self) -> usize {
        self.strides[D - 1] * (self.dims[D - 1] + 2)
    }

    /// Zeroes the dense per-cell counts (`ncells` slots and the sentinel).
    fn reset_dense_starts(&mut self, ncells: usize) {
        if self.start.capacity() <= ncells {
            // A bounding-box domain gains a cell along an axis as soon as the points
            // spread a little: leave room for one more cell per axis so that the next
            // small moves do not reallocate.
            let roomy: usize = self.dims.iter().map(|&n| n + 3).product();
            self.start.reserve_exact(roomy + 1 - self.start.len());
        }
        self.start.clear();
        self.start.resize(ncells + 1, 0);
    }

    /// Appends the items at or above the split radius to the large-item arrays, in index
    /// order (the large-large loop relies on it for `i < j`), ranked after the `in_cells`
    /// items of the cells.
    fn place_large_items(&mut self, points: &[[f64; D]], in_cells: usize) {
        if !self.split_active {
            return;
        }
        for i in 0..points.len() {
            if self.radii[i] >= self.r_cut {
                self.rank[i] = (in_cells + self.large_ids.len()) as u32;
                self.large_ids.push(i);
                self.large_pos.push(self.locate(&points[i]).0);
                self.large_r.push(self.radii[i]);
            }
        }
    }

    /// The counting sort of [`sort_items`] for large inputs in the dense layout.
    ///
    /// A one-pass scatter sends every item to a random place of arrays much larger than the
    /// cache (on shuffled input: three cache misses per item, measured 3x slower per item at
    /// m = 1e6 than at 1e4). Here the items are first distributed, in index order, into
    /// `SORT_BLOCKS` contiguous ranges of cells (one write stream per block, cache-friendly),
    /// straight into the final arrays: a block of cells owns one contiguous range of them.
    /// Each block is then copied to a cache-sized scratch and counting-sorted back into its
    /// own range. No full-size temporary is needed, which matters for a fresh build: every
    /// byte of a new buffer costs a page fault and the kernel's zeroing on first touch.
    /// The result is identical to the one-pass sort: cell order, ascending items per cell.
    fn sort_blocked(&mut self, points: &[[f64; D]]) {
        let m = points.len();
        self.n_items = m;
        self.large_ids.clear();
        self.large_pos.clear();
        self.large_r.clear();
        let split = self.split_active;
        let r_cut = self.r_cut;
        let ncells = self.dense_cell_count();
        // Blocks of a power-of-two number of cells: the block of a slot is a shift, not a
        // division. At most SORT_BLOCKS of them.
        let shift = ncells
            .div_ceil(SORT_BLOCKS)
            .next_power_of_two()
            .trailing_zeros();

        // Pass 1: slot of every item (into `rank`), count per block.
        let mut blk = [0usize; SORT_BLOCKS + 1];
        self.rank.clear();
        self.rank.reserve(m);
        for (i, p) in points.iter().enumerate() {
            let s = if split && self.radii[i] >= r_cut {
                NO_CELL
            } else {
                let s = self.dense_slot(&self.locate(p).1);
                blk[s >> shift] += 1;
                s as u32
            };
            self.rank.push(s);
        }
        let mut acc = 0usize;
        for b in blk.iter_mut() {
            let c = *b;
            *b = acc;
            acc += c;
        }
        let in_cells = acc;
        // `blk[b]` is now the start of block b; the distribution below moves each to its end.
        let bounds = blk;

        // Pass 2: items into their block's range of the final arrays, in index order.
        self.size_sorted_buffers(in_cells);
        let pack = self.pack_slots;
        // Every entry is written below, as in `size_sorted_buffers`.
        self.tmp_slots.resize(if pack { 0 } else { in_cells }, 0);
        for (i, p) in points.iter().enumerate() {
            let s = self.rank[i];
            if s == NO_CELL {
                continue;
            }
            let q = &mut blk[(s as usize) >> shift];
            if pack {
                // Both fit in 32 bits (`MAX_ITEMS`, and dense slots below `NO_CELL`).
                self.order[*q] = (u64::from(s) << 32 | i as u64) as usize;
            } else {
                self.order[*q] = i;
                self.tmp_slots[*q] = s;
            }
            self.sorted[*q] = if self.any_periodic {
                self.locate(p).0
            } else {
                *p
            };
            if self.radii_mode {
                self.sorted_r[*q] = self.radii[i];
            }
            *q += 1;
        }

        // Pass 3: each block through the scratch and back, counting-sorted by cell.
        self.reset_dense_starts(ncells);
        // Capacity for every item, so that a rebuild never reallocates; only the pages of
        // the largest block are ever touched. (Cleared first: `reserve` counts from the
        // length, which the last block of the previous build left behind.)
        self.scratch_ids.clear();
        self.scratch_slots.clear();
        self.scratch_pos.clear();
        self.scratch_r.clear();
        self.scratch_ids.reserve(in_cells);
        if !pack {
            self.scratch_slots.reserve(in_cells);
        }
        self.scratch_pos.reserve(in_cells);
        if self.radii_mode {
            self.scratch_r.reserve(in_cells);
        }
        let mut end = 0usize;
        for b in 0..SORT_BLOCKS {
            let cells = (b << shift).min(ncells)..((b + 1) << shift).min(ncells);
            if cells.is_empty() {
                break;
            }
            let (q0, q1) = (bounds[b], bounds[b + 1]);
            self.scratch_ids.clear();
            self.scratch_ids.extend_from_slice(&self.order[q0..q1]);
            self.scratch_slots.clear();
            if pack {
                for &v in &self.scratch_ids {
                    self.start[(v as u64 >> 32) as usize] += 1;
                }
            } else {
                self.scratch_slots
                    .extend_from_slice(&self.tmp_slots[q0..q1]);
                for &s in &self.scratch_slots {
                    self.start[s as usize] += 1;
                }
            }
            self.scratch_pos.clear();
            self.scratch_pos.extend_from_slice(&self.sorted[q0..q1]);
            self.scratch_r.clear();
            if self.radii_mode {
                self.scratch_r.extend_from_slice(&self.sorted_r[q0..q1]);
            }
            // Inclusive prefix sums (each cell's end), carried over from the earlier blocks.
            for s in cells {
                end += self.start[s];
                self.start[s] = end;
            }
            for k in (0..q1 - q0).rev() {
                let (s, i) = if pack {
                    let v = self.scratch_ids[k] as u64;
                    ((v >> 32) as usize, (v & 0xffff_ffff) as usize)
                } else {
                    (self.scratch_slots[k] as usize, self.scratch_ids[k])
                };
                self.start[s] -= 1;
                let pos = self.start[s];
                self.order[pos] = i;
                self.rank[i] = pos as u32;
                self.sorted[pos] = self.scratch_pos[k];
                if self.radii_mode {
                    self.sorted_r[pos] = self.scratch_r[k];
                }
            }
        }
        debug_assert_eq!(end, in_cells);
        self.start[ncells] = end;
        self.place_large_items(points, in_cells);
    }

    /// Number of items.
    pub fn len(&self) -> usize {
        self.n_items
    }

    /// Whether the grid holds no item.
    pub fn is_empty(&self) -> bool {
        self.n_items == 0
    }

    /// The global cutoff, or `None` for per-item radii.
    pub fn cutoff(&self) -> Option<f64> {
        (!self.radii_mode).then_some(self.cutoff)
    }

    /// The per-item radii (empty for a global cutoff).
    pub fn radii(&self) -> &[f64] {
        if self.radii_mode { &self.radii } else { &[] }
    }

    /// The distance below which two items may pair: the cutoff, or `2 max r_i` (the paper's
    /// `l = 2R`). The cell edge is at least this.
    pub fn reach(&self) -> f64 {
        self.reach
    }

    /// The domain `(lo, hi)` of the last build.
    pub fn domain(&self) -> ([f64; D], [f64; D]) {
        let mut hi = self.lo;
        for a in 0..D {
            hi[a] += self.extent[a];
        }
        (self.lo, hi)
    }

    /// Which axes are periodic.
    pub fn periodic(&self) -> [bool; D] {
        self.periodic
    }

    /// Cell edge along each axis: at least the cutoff, or `2 r_max` with per-item radii, or
    /// `2` × [`split_radius`](Self::split_radius) when large items are kept apart.
    pub fn cell_edge(&self) -> [f64; D] {
        self.edge
    }

    /// Number of cells along each axis.
    pub fn cells_per_axis(&self) -> [usize; D] {
        self.dims
    }

    /// Whether the cells live in a dense array or a hash map.
    pub fn layout(&self) -> Layout {
        self.layout
    }

    /// Number of non-empty cells.
    pub fn nonempty_cell_count(&self) -> usize {
        self.nonempty_slots().count()
    }

    /// Number of slots: every cell of the padded dense array, or the hashed cells (all of
    /// which are non-empty).
    #[inline]
    pub(crate) fn slot_count(&self) -> usize {
        self.start.len().saturating_sub(1)
    }

    /// The non-empty slots, ascending. No list of them is stored: at packing density
    /// nearly every cell holds an item, and the list cost a push per cell and 8 bytes per
    /// cell of fresh memory at each build, more than skipping the empty ones costs.
    pub(crate) fn nonempty_slots(&self) -> impl Iterator<Item = usize> + '_ {
        (0..self.slot_count()).filter(move |&s| self.start[s] < self.start[s + 1])
    }

    /// The non-empty cells with their items (in the dense layout, in increasing linear
    /// cell order with x fastest; in the hashed layout, in order of first appearance).
    /// Items kept out of the cells by the size split are in [`large_items`](Self::large_items).
    pub fn cells(&self) -> impl Iterator<Item = Cell<'_, D>> + '_ {
        self.nonempty_slots().map(move |s| {
            let k = self.slot_coords_of(s);
            Cell {
                coords: k.map(|c| c as usize),
                items: &self.order[self.start[s]..self.start[s + 1]],
            }
        })
    }

    /// Item indices in cell order: the items of each non-empty cell are contiguous.
    pub fn sorted_items(&self) -> &[usize] {
        &self.order
    }

    /// Items kept out of the cells because their radius is at least
    /// [`split_radius`](Self::split_radius) (ascending; empty without a split).
    pub fn large_items(&self) -> &[usize] {
        &self.large_ids
    }

    /// With per-item radii and a size split: the radius from which items are kept out of the
    /// cells and searched individually (see the crate documentation on mixed sizes). `None`
    /// when every item is in a cell.
    pub fn split_radius(&self) -> Option<f64> {
        self.split_active.then_some(self.r_cut)
    }

    /// Cell coordinates of a point under the clamp `p(x)` (wrapped on periodic axes).
    ///
    /// # Errors
    /// [`Error::NonFiniteQueryPoint`] for a NaN or infinite coordinate.
    pub fn cell_of_point(&self, x: [f64; D]) -> Result<[usize; D], Error> {
        check_query_point(&x)?;
        Ok(self.locate(&x).1.map(|c| c as usize))
    }

    /// Cell coordinates of item `i`.
    ///
    /// # Errors
    /// [`Error::ItemOutOfRange`] if `i >= len()`.
    pub fn cell_of_item(&self, i: usize) -> Result<[usize; D], Error> {
        if i >= self.len() {
            return Err(Error::ItemOutOfRange {
                index: i,
                len: self.len(),
            });
        }
        let pos = self.rank[i] as usize;
        if pos >= self.order.len() {
            // A large item: the cell its centre falls in, though it is not listed there.
            return Ok(self.locate(&self.item_point(i).0).1.map(|c| c as usize));
        }
        // The starts are ascending (an empty cell starts where the next one does) and the
        // sentinel `start[slots] = order.len()` is beyond `pos`: the last slot starting at or
        // before `pos` is the non-empty cell that holds it.
        let s = self.start.partition_point(|&x| x <= pos) - 1;
        Ok(self.slot_coords_of(s).map(|c| c as usize))
    }

    /// Position of item `i` as stored at the last build (wrapped into the box on periodic
    /// axes).
    ///
    /// # Errors
    /// [`Error::ItemOutOfRange`] if `i >= len()`.
    pub fn position(&self, i: usize) -> Result<[f64; D], Error> {
        if i >= self.len() {
            return Err(Error::ItemOutOfRange {
                index: i,
                len: self.len(),
            });
        }
        Ok(self.item_point(i).0)
    }

    /// Stored position and radius (0 without radii) of item `i < len()`.
    #[inline]
    pub(crate) fn item_point(&self, i: usize) -> ([f64; D], f64) {
        let pos = self.rank[i] as usize;
        let in_cells = self.order.len();
        if pos < in_cells {
            let r = if self.radii_mode {
                self.sorted_r[pos]
            } else {
                0.0
            };
            (self.sorted[pos], r)
        } else {
            (self.large_pos[pos - in_cells], self.large_r[pos - in_cells])
        }
    }

    /// Minimum-image difference `b - a`: on each periodic axis the shortest of the vectors
    /// `b - a + n L` over integers `n`.
    pub fn min_image(&self, a: [f64; D], b: [f64; D]) -> [f64; D] {
        let mut d = [0.0; D];
        for k in 0..D {
            let t = b[k] - a[k];
            d[k] = if self.periodic[k] {
                t - self.period[k] * (t * self.inv_period[k]).round()
            } else {
                t
            };
        }
        d
    }

    /// [`min_image`](Self::min_image) for two points already wrapped into the box, where
    /// `|b - a| < L`: one conditional shift instead of a rounding, which without SSE4.1 is
    /// a library call. `period` is 0 on open axes, where neither test fires.
    #[inline(always)]
    pub(crate) fn min_image_wrapped(&self, a: &[f64; D], b: &[f64; D]) -> [f64; D] {
        let mut d = [0.0; D];
        for k in 0..D {
            let mut t = b[k] - a[k];
            let l = self.period[k];
            if t > 0.5 * l {
                t -= l;
            } else if t < -0.5 * l {
                t += l;
            }
            d[k] = t;
        }
        d
    }
}

/// Distances are compared squared, `|d|^2 < l^2`: a reach whose square underflows to a
/// subnormal or zero (below about `1.5e-154`) or overflows (above about `1.3e154`) would turn
/// that comparison into nonsense, so it is refused.
pub(crate) fn valid_reach(l: f64) -> bool {
    l > 0.0 && (l * l).is_normal()
}

pub(crate) fn check_query_point<const D: usize>(x: &[f64; D]) -> Result<(), Error> {
    for (axis, &value) in x.iter().enumerate() {
        if !value.is_finite() {
            return Err(Error::NonFiniteQueryPoint { axis, value });
        }
    }
    Ok(())
}

/// The `3^D - 1` non-zero offsets in `{-1, 0, 1}^D`.
fn full_stencil<const D: usize>() -> Vec<[i64; D]> {
    let total = 3usize.pow(D as u32);
    let mut out = Vec::with_capacity(total.saturating_sub(1));
    for code in 0..total {
        let mut o = [0i64; D];
        let mut c = code;
        for v in &mut o {
            *v = (c % 3) as i64 - 1;
            c /= 3;
        }
        if o.iter().any(|&v| v != 0) {
            out.push(o);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stencil_has_every_neighbour_once() {
        let s2 = full_stencil::<2>();
        assert_eq!(s2.len(), 8);
        let s3 = full_stencil::<3>();
        assert_eq!(s3.len(), 26);
        let mut sorted = s3.clone();
        sorted.sort_unstable();
        sorted.dedup();
        assert_eq!(sorted.len(), 26);
        assert!(s3.iter().all(|o| o.iter().all(|&v| (-1..=1).contains(&v))));
        assert!(!s3.contains(&[0, 0, 0]));
    }

    #[test]
    fn forward_rows_cover_half_the_stencil() {
        // 1 (next cell along x) + 3 per row must be the 13 forward cells in 3D, 4 in 2D.
        let g = Grid::<3>::build(&[[0.0; 3], [10.0; 3]], 1.0).unwrap();
        assert_eq!(1 + 3 * g.rows.len(), 13);
        let g = Grid::<2>::build(&[[0.0; 2], [10.0; 2]], 1.0).unwrap();
        assert_eq!(1 + 3 * g.rows.len(), 4);
    }

    #[test]
    fn size_buckets_follow_binary_orders_of_magnitude() {
        let r_max = 3.0; // 2^1 <= 3 < 2^2
        assert_eq!(size_bucket(3.0, r_max), 0);
        assert_eq!(size_bucket(2.0, r_max), 0);
        assert_eq!(size_bucket(1.99, r_max), 1);
        assert_eq!(size_bucket(1.0, r_max), 1);
        assert_eq!(size_bucket(0.5, r_max), 2);
        assert_eq!(size_bucket(1e-30, r_max), SIZE_BUCKETS - 1);
        // Radii of bucket b lie below bucket_top(b) and at or above bucket_top(b + 1).
        for r in [3.0, 2.0, 1.5, 1.0, 0.75, 0.3, 0.01] {
            let b = size_bucket(r, r_max);
            assert!(r < bucket_top(r_max, b), "{r}");
            assert!(r >= bucket_top(r_max, b + 1), "{r}");
        }
    }

    #[test]
    fn reach_must_have_a_normal_square() {
        assert!(valid_reach(1.0));
        assert!(valid_reach(1e-150));
        assert!(!valid_reach(1e-160));
        assert!(!valid_reach(1e160));
        assert!(!valid_reach(0.0));
        assert!(!valid_reach(-1.0));
        assert!(!valid_reach(f64::NAN));
    }

    /// The blocked counting sort must give exactly the arrays of the one-pass sort, with the
    /// slots packed into `order` or kept apart.
    fn same_sort<const D: usize>(b: GridBuilder<D>, pts: &[[f64; D]]) {
        same_sort_packed(b.clone(), pts, true);
        same_sort_packed(b, pts, false);
    }

    fn same_sort_packed<const D: usize>(b: GridBuilder<D>, pts: &[[f64; D]], pack: bool) {
        let b = b.max_cells(1 << 22);
        let mut one = b.clone().build(&[]).unwrap();
        one.blocked_min = usize::MAX;
        let mut blocked = b.build(&[]).unwrap();
        blocked.blocked_min = 0;
        blocked.pack_slots = pack;
        let radii = one.radii_mode.then(|| {
            (0..pts.len())
                .map(|i| {
                    if i % 97 == 5 {
                        1.5
                    } else {
                        0.1 + 0.01 * (i % 7) as f64
                    }
                })
                .collect::<Vec<_>>()
        });
        for g in [&mut one, &mut blocked] {
            match &radii {
                Some(r) => g.rebuild_with_radii(pts, r).unwrap(),
                None => g.rebuild(pts).unwrap(),
            }
            assert_eq!(g.layout, Layout::Dense);
        }
        assert_eq!(one.split_active, blocked.split_active);
        assert_eq!(one.order, blocked.order);
        assert_eq!(one.rank, blocked.rank);
        assert_eq!(one.sorted, blocked.sorted);
        assert_eq!(one.sorted_r, blocked.sorted_r);
        assert_eq!(one.start, blocked.start);
        assert_eq!(one.large_ids, blocked.large_ids);
        assert_eq!(one.large_pos, blocked.large_pos);
    }

    #[test]
    fn blocked_sort_equals_one_pass_sort() {
        let mut x = 0x2545_f491_4f6c_dd1d_u64;
        let mut unif = move || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            (x >> 11) as f64 / (1u64 << 53) as f64
        };
        let p3: Vec<[f64; 3]> = (0..3000)
            .map(|_| [unif() * 20.0, unif() * 20.0, unif() * 5.0 - 7.0])
            .collect();
        let p2: Vec<[f64; 2]> = p3.iter().map(|p| [p[0] * 3.0, p[1]]).collect();
        same_sort(GridBuilder::<3>::with_cutoff(0.7), &p3);
        same_sort(GridBuilder::<3>::with_radii(&[]), &p3);
        same_sort(
            GridBuilder::<3>::with_cutoff(0.7).periodic_box([0.0; 3], [20.0; 3]),
            &p3,
        );
        same_sort(
            GridBuilder::<3>::with_radii(&[]).domain([2.0; 3], [9.0; 3]),
            &p3,
        );
        same_sort(GridBuilder::<2>::with_cutoff(0.3), &p2);
        same_sort(
            GridBuilder::<2>::with_radii(&[]).periodic_box([0.0; 2], [60.0, 20.0]),
            &p2,
        );
        same_sort(
            GridBuilder::<1>::with_cutoff(0.01),
            &[[0.5], [0.2], [0.51], [3.0]],
        );
    }

    #[test]
    fn too_many_items_is_an_error_and_keeps_the_grid() {
        let mut g = Grid::<2>::build(&[[0.0; 2], [0.5, 0.0]], 1.0).unwrap();
        // The real limit (u32::MAX - 1 items) is out of reach of a test: lower it.
        g.max_items = 2;
        let err = Error::TooManyItems { count: 3, max: 2 };
        assert_eq!(g.rebuild(&[[0.0; 2]; 3]), Err(err.clone()));
        assert_eq!(g.rebuild_with_radii(&[[0.0; 2]; 3], &[0.1; 3]), Err(err));
        assert_eq!((g.len(), g.close_pairs()), (2, vec![(0, 1)]));
        g.rebuild(&[[0.0; 2], [2.0, 0.0]]).unwrap();
        assert_eq!(g.count_close_pairs(), 0);
    }

    #[test]
    fn wrapping_never_reaches_the_top_of_the_box() {
        let g = GridBuilder::<1>::with_cutoff(0.1)
            .periodic_box([0.0], [1.0])
            .build(&[[0.5]])
            .unwrap();
        // -1e-17 wraps to 1 - 1e-17, which rounds to 1.0: must come back as 0.
        for x in [-1e-17, 1.0, 2.0, -3.0, 1.0 - 1e-17] {
            let (w, k) = g.locate(&[x]);
            assert!(w[0] >= 0.0 && w[0] < 1.0, "{x} -> {w:?}");
            assert!(k[0] >= 0 && (k[0] as usize) < g.dims[0]);
        }
    }
}
