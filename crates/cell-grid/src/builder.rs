//! Configuration of a grid: cutoff or radii, domain, periodic axes, cap on cells.

/// How far apart two items may be and still form a pair.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Reach {
    /// One distance for all pairs: `|c_i - c_j| < cutoff` (the paper's `2R`).
    Cutoff(f64),
    /// Per-item radii: `|c_i - c_j| < r_i + r_j`.
    Radii(Vec<f64>),
}

/// Options for a [`Grid`](crate::Grid) beyond the plain [`Grid::build`](crate::Grid::build).
///
/// ```
/// use cell_grid::GridBuilder;
///
/// // Spheres of radius 0.5 and 1.0 in a box periodic along x and y, walls along z.
/// let centres = [[0.2, 0.2, 1.0], [9.9, 9.9, 1.5], [5.0, 5.0, 5.0]];
/// let grid = GridBuilder::<3>::with_radii(&[0.5, 1.0, 0.5])
///     .domain([0.0; 3], [10.0; 3])
///     .periodic([true, true, false])
///     .build(&centres)?;
/// let mut pairs = Vec::new();
/// grid.for_each_close_pair(|i, j, _delta, _dist2| pairs.push((i, j)));
/// assert_eq!(pairs, vec![(0, 1)]); // across the x and y faces at once
/// # Ok::<(), cell_grid::Error>(())
/// ```
#[derive(Debug, Clone)]
pub struct GridBuilder<const D: usize> {
    pub(crate) reach: Reach,
    pub(crate) domain: Option<([f64; D], [f64; D])>,
    pub(crate) periodic: [bool; D],
    pub(crate) max_cells: Option<usize>,
    pub(crate) split: bool,
}

impl<const D: usize> GridBuilder<D> {
    /// Pairs are the items closer than `cutoff` (for the packing model, `cutoff = 2R` with `R`
    /// the largest enclosing-ball radius, paper Eq. (37)).
    pub fn with_cutoff(cutoff: f64) -> Self {
        Self {
            reach: Reach::Cutoff(cutoff),
            domain: None,
            periodic: [false; D],
            max_cells: None,
            split: true,
        }
    }

    /// Pairs are the items `i, j` with `|c_i - c_j| < r_i + r_j` (enclosing balls that
    /// overlap, paper Section 5.2). The cell edge follows the largest radius, see the crate
    /// documentation on mixed sizes.
    pub fn with_radii(radii: &[f64]) -> Self {
        Self {
            reach: Reach::Radii(radii.to_vec()),
            domain: None,
            periodic: [false; D],
            max_cells: None,
            split: true,
        }
    }

    /// Fixes the domain `[lo, hi]` instead of the bounding box of the points.
    ///
    /// On a non-periodic axis a point outside the domain is put into the border cell (the
    /// clamp `p(x)` of paper Section 5.2), so it is still paired correctly; only the work per
    /// border cell grows if many points lie outside. On a periodic axis the domain is the box
    /// and points are wrapped into it.
    pub fn domain(mut self, lo: [f64; D], hi: [f64; D]) -> Self {
        self.domain = Some((lo, hi));
        self
    }

    /// Marks the axes with periodic boundaries (needs [`domain`](Self::domain)). Distances
    /// along those axes follow the minimum-image convention.
    pub fn periodic(mut self, axes: [bool; D]) -> Self {
        self.periodic = axes;
        self
    }

    /// A box `[lo, hi)` periodic along every axis.
    pub fn periodic_box(self, lo: [f64; D], hi: [f64; D]) -> Self {
        self.domain(lo, hi).periodic([true; D])
    }

    /// Caps the number of cells of the dense cell array (ghost layer included).
    ///
    /// Above the cap the grid stores only its non-empty cells in a hash map
    /// ([`Layout::Hashed`](crate::Layout::Hashed)): memory stays `O(m)` however small the
    /// cutoff is against the domain, at the price of a hash lookup per neighbouring cell.
    /// Without this call the cap is `max(65 536, 16 m)` for `m` points, re-evaluated at each
    /// rebuild. `max_cells(0)` always selects the hashed layout. A dense array of `2^32 - 1`
    /// cells or more is never used whatever the cap (cell slots are stored as `u32`).
    pub fn max_cells(mut self, cells: usize) -> Self {
        self.max_cells = Some(cells);
        self
    }

    /// With per-item radii, whether the largest items may be kept out of the cells when a
    /// cost estimate says it pays (default: yes). The pairs found are the same either way;
    /// only the work differs. See the crate documentation on mixed sizes.
    pub fn split_large_items(mut self, split: bool) -> Self {
        self.split = split;
        self
    }
}
