//! Periodic cells: the lattice, fractional coordinates, and the images of the items that a
//! pair term can reach.
//!
//! The cell matrix `H` is upper triangular with a positive diagonal; its columns are the
//! lattice vectors (the triclinic convention of LAMMPS, `a = (l_x, 0, 0)`, `b = (xy, l_y, 0)`,
//! `c = (xz, yz, l_z)`):
//!
//! ```text
//! 2D: H = [[l_x, xy], [0, l_y]]        3D: H = [[l_x, xy, xz], [0, l_y, yz], [0, 0, l_z]]
//! container variables: [l_x, l_y, xy]   or   [l_x, l_y, l_z, xy, xz, yz]
//! ```
//!
//! Every sheared lattice has such a cell (a rotation of space brings any cell to it), so the
//! `N (N + 1) / 2` entries are the lattice's degrees of freedom up to rotation, and the cell's
//! area or volume is `det H = Π H_kk`.
//!
//! An item with fractional coordinates `s` is at `c = H s`, and its images at `H (s + n)`,
//! `n ∈ Zᴺ`. The non-overlap sum of eq. 19 becomes the sum over the distinct pairs of the
//! infinite packing, one per lattice translation class:
//!
//! ```text
//! overlap = Σ_{i<j} Σ_{n ∈ Zᴺ} f(c_i, c_j + H n)  +  Σ_i Σ_{n ≻ 0} f(c_i, c_i + H n)
//! ```
//!
//! (`n ≻ 0`: lexicographically positive, so that an item and its image `−n` count once). A
//! term is zero unless the enclosing balls meet (eq. 37). Those images are found without any
//! minimum-image assumption, so that a cell narrower than an item (one item per cell, a
//! strongly sheared cell) is summed exactly: the width of the cell across its lattice planes
//! `k` is `w_k = 1 / |row k of H⁻¹|`, so a point within distance `d` of the cell has its
//! fractional coordinate `k` within `d / w_k` of `[0, 1]`. Each item's images in that padded
//! cell join the items (ghosts, as in molecular dynamics), and one neighbour grid over items
//! and ghosts lists every pair of an item with an item or a ghost; a pair is kept when it is
//! the representative of its class above. The number of ghosts is that of the items in a
//! shell of width `2 r_max` around the cell: the evaluation stays linear in `m`.
//!
//! Derivatives: `f` depends on the centres through `c_j + H n − c_i` only; with the Cartesian
//! force `F_e` on every item or ghost `e` (at fractional position `u_e`, the owner's `s` plus
//! its integer shift), the chain rule gives
//!
//! ```text
//! ∂/∂s_i = Hᵀ Σ_{e of item i} F_e,        ∂/∂H_ab = Σ_e F_e,a u_e,b   (a ≤ b)
//! ```
//!
//! # References
//! - S. Torquato, Y. Jiao, *Dense packings of polyhedra: Platonic and Archimedean solids*,
//!   Phys. Rev. E 80, 041104 (2009): the adaptive shrinking cell (a deforming lattice as
//!   variables, fractional coordinates, volume as objective).
//! - A. Donev, F. H. Stillinger, P. M. Chaikin, S. Torquato, *Unusually dense crystal packings
//!   of ellipsoids*, Phys. Rev. Lett. 92, 255506 (2004).
//! - M. P. Allen, D. J. Tildesley, *Computer Simulation of Liquids* (2nd ed., 2017),
//!   Section 1.6 (periodic images) and 5.3 (neighbour lists).

use crate::error::Error;
use crate::shape::Body;

/// The cell matrix of the container variables `[l_x, l_y, (l_z,) xy, (xz, yz)]`.
///
/// # Errors
/// [`Error::LengthMismatch`] for a wrong count, [`Error::InvalidContainer`] naming the variable
/// for a diagonal entry that is not positive and finite or a tilt that is not finite.
pub(crate) fn cell_from_dimensions<const N: usize>(dims: &[f64]) -> Result<[[f64; N]; N], Error> {
    Error::check_length("cell entries", N * (N + 1) / 2, dims.len())?;
    let mut cell = [[0.0; N]; N];
    for (dimension, &value) in dims.iter().enumerate() {
        let diagonal = dimension < N;
        if !(value.is_finite() && (!diagonal || value > 0.0)) {
            return Err(Error::InvalidContainer { dimension, value });
        }
        let (r, c) = entry::<N>(dimension);
        cell[r][c] = value;
    }
    Ok(cell)
}

/// The container variables of a cell, the inverse of [`cell_from_dimensions`].
pub(crate) fn cell_dimensions<const N: usize>(cell: &[[f64; N]; N]) -> Vec<f64> {
    (0..N * (N + 1) / 2)
        .map(|k| {
            let (r, c) = entry::<N>(k);
            cell[r][c]
        })
        .collect()
}

/// The matrix entry `(row, column)` of container variable `k`: the diagonal first, then
/// `xy`, `xz`, `yz`.
pub fn entry<const N: usize>(k: usize) -> (usize, usize) {
    const ENTRIES_3D: [(usize, usize); 6] = [(0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2)];
    const ENTRIES_2D: [(usize, usize); 3] = [(0, 0), (1, 1), (0, 1)];
    if N == 2 { ENTRIES_2D[k] } else { ENTRIES_3D[k] }
}

/// The same lattice with its tilts reduced: `c − k b`, `c − k a`, `b − k a` with the nearest
/// integers `k`, so that `|yz| ≤ l_y / 2`, `|xz| ≤ l_x / 2`, `|xy| ≤ l_x / 2` (the limits
/// LAMMPS asks of a triclinic box). The cell stays upper triangular with the same diagonal,
/// so the same volume; the items keep their Cartesian positions (the caller wraps them into
/// the new cell).
pub fn reduced<const N: usize>(cell: &[[f64; N]; N]) -> [[f64; N]; N] {
    let mut h = *cell;
    // Column j −= k · column i, for the pairs (i, j) = (1, 2), (0, 2), (0, 1) in 3D; (0, 1) in 2D.
    let steps: &[(usize, usize)] = if N == 3 {
        &[(1, 2), (0, 2), (0, 1)]
    } else {
        &[(0, 1)]
    };
    for &(i, j) in steps {
        let k = (h[i][j] / h[i][i]).round();
        for r in 0..N {
            h[r][j] -= k * h[r][i];
        }
    }
    h
}

/// `H⁻¹`, upper triangular, by back substitution.
pub fn inverse<const N: usize>(cell: &[[f64; N]; N]) -> [[f64; N]; N] {
    let mut inv = [[0.0; N]; N];
    for c in 0..N {
        for r in (0..=c).rev() {
            let mut v = if r == c { 1.0 } else { 0.0 };
            for k in r + 1..=c {
                v -= cell[r][k] * inv[k][c];
            }
            inv[r][c] = v / cell[r][r];
        }
    }
    inv
}

/// The widths of the cell across its lattice planes, `w_k = 1 / |row k of H⁻¹|`: the distance
/// between the two faces of the cell where fractional coordinate `k` is 0 and 1.
pub fn widths<const N: usize>(cell: &[[f64; N]; N]) -> [f64; N] {
    let inv = inverse(cell);
    std::array::from_fn(|k| 1.0 / inv[k].iter().map(|v| v * v).sum::<f64>().sqrt())
}

/// `H s`.
pub fn to_cartesian<const N: usize>(cell: &[[f64; N]; N], s: &[f64; N]) -> [f64; N] {
    std::array::from_fn(|r| (r..N).map(|c| cell[r][c] * s[c]).sum())
}

/// `H⁻¹ c`.
pub fn to_fractional<const N: usize>(cell: &[[f64; N]; N], c: &[f64; N]) -> [f64; N] {
    to_cartesian(&inverse(cell), c)
}

/// Images per item at most, and close pairs of images per item at most (beyond a spare
/// allowance of [`IMAGE_ALLOWANCE`] for cells of few items): a cell so thin or so small that
/// its items need more is refused ([`Error::PeriodicImages`], [`Error::CellCrowded`]) rather
/// than filling the memory.
pub const MAX_IMAGES_PER_ITEM: usize = 4096;

/// Points and pairs of images any cell may use whatever its number of items: a single
/// elongated item in a sheared cell of its own (a needle's small cell) needs about 10⁴.
pub const IMAGE_ALLOWANCE: usize = 1 << 16;

/// The most points (items and images) the image set of `m` items may hold.
pub(crate) fn image_limit(m: usize) -> usize {
    MAX_IMAGES_PER_ITEM.saturating_mul(m).max(IMAGE_ALLOWANCE)
}

/// Refuses, before anything is allocated, a cell far smaller than its items: with `r_i` the
/// enclosing radii, the balls cover the cell `ρ = Σ_i |B(r_i)| / |det H|` times over, and the
/// pairs of points whose balls meet number about `2^(N−1) m ρ` (`|B(r_i + r_j)| ≤
/// 2^(N−1) (|B(r_i)| + |B(r_j)|)` by convexity). More than `MAX_IMAGES_PER_ITEM · m +
/// IMAGE_ALLOWANCE` is [`Error::CellCrowded`] — typically a cell given in the wrong units.
pub(crate) fn check_crowding<const N: usize>(
    cell: &[[f64; N]; N],
    radii: impl Iterator<Item = f64>,
) -> Result<(), Error> {
    let det: f64 = (0..N).map(|k| cell[k][k]).product::<f64>().abs();
    let ball = if N == 2 {
        std::f64::consts::PI
    } else {
        4.0 / 3.0 * std::f64::consts::PI
    };
    let (mut m, mut covered) = (0usize, 0.0f64);
    for r in radii {
        m += 1;
        covered += ball * r.powi(N as i32);
    }
    let cover = covered / det;
    let pairs = 2f64.powi(N as i32 - 1) * m as f64 * cover;
    let limit = MAX_IMAGES_PER_ITEM
        .saturating_mul(m)
        .saturating_add(IMAGE_ALLOWANCE);
    if pairs > limit as f64 || !cover.is_finite() {
        return Err(Error::CellCrowded {
            cover,
            pairs,
            limit,
        });
    }
    Ok(())
}

/// Whether a lattice translation `n` is the representative of `{n, −n}`: its first non-zero
/// component is positive.
fn lexicographically_positive<const N: usize>(n: &[i32; N]) -> bool {
    n.iter().find(|&&v| v != 0).is_some_and(|&v| v > 0)
}

/// The items and their ghosts: every image of an item whose fractional coordinates lie in the
/// cell padded by `pad` (Cartesian distance) on every side. Items come first, each at the
/// image `s − ⌊s⌋` inside the cell, then the ghosts, by item and then by translation.
#[derive(Debug, Clone, Default)]
pub(crate) struct ImageSet<const N: usize> {
    /// The item each point is an image of.
    pub(crate) owner: Vec<u32>,
    /// The integer shift of each point: it lies at fractional position `s_owner + shift`.
    pub(crate) shift: Vec<[i32; N]>,
    /// The number of items (the first points).
    pub(crate) items: usize,
}

impl<const N: usize> ImageSet<N> {
    /// The set for the items at fractional positions `fractional` in `cell`.
    ///
    /// # Errors
    /// [`Error::PeriodicImages`] when more than `max_points` points would be needed (a cell
    /// far too thin for its items).
    pub(crate) fn new(
        cell: &[[f64; N]; N],
        fractional: &[[f64; N]],
        pad: f64,
        max_points: usize,
    ) -> Result<Self, Error> {
        let w = widths(cell);
        let pad_frac: [f64; N] = std::array::from_fn(|k| pad / w[k]);
        let m = fractional.len();
        let mut set = ImageSet {
            owner: (0..m as u32).collect(),
            shift: Vec::with_capacity(m),
            items: m,
        };
        for s in fractional {
            set.shift
                .push(std::array::from_fn(|k| -(s[k].floor() as i32)));
        }
        for (i, s) in fractional.iter().enumerate() {
            let base = set.shift[i];
            // Wrapped coordinate u_k ∈ [0, 1); images u_k + n_k ∈ [−pad_k, 1 + pad_k].
            let u: [f64; N] = std::array::from_fn(|k| s[k] + f64::from(base[k]));
            let lo: [i32; N] = std::array::from_fn(|k| (-pad_frac[k] - u[k]).ceil() as i32);
            let hi: [i32; N] = std::array::from_fn(|k| (1.0 + pad_frac[k] - u[k]).floor() as i32);
            let mut n = lo;
            loop {
                if n.iter().any(|&v| v != 0) {
                    if set.owner.len() >= max_points {
                        return Err(Error::PeriodicImages {
                            points: max_points,
                            width: w.iter().fold(f64::INFINITY, |a, &b| a.min(b)),
                            reach: pad,
                        });
                    }
                    set.owner.push(i as u32);
                    set.shift.push(std::array::from_fn(|k| base[k] + n[k]));
                }
                if !next_in_box(&mut n, &lo, &hi) {
                    break;
                }
            }
        }
        Ok(set)
    }

    /// The index of the first ghost of item `i` or of a later item (the ghosts follow the
    /// items, grouped by owner in item order).
    pub(crate) fn first_ghost(&self, i: usize) -> usize {
        self.items + self.owner[self.items..].partition_point(|&o| (o as usize) < i)
    }

    /// Fractional position of point `e`: its owner's `s` plus its shift.
    pub(crate) fn fractional(&self, e: usize, fractional: &[[f64; N]]) -> [f64; N] {
        let s = &fractional[self.owner[e] as usize];
        std::array::from_fn(|k| s[k] + f64::from(self.shift[e][k]))
    }

    /// Whether the pair of points `(a, b)`, `a < b`, is the representative of its class (see
    /// the module documentation): `a` is an item, and `b` an image of a later item, or of `a`
    /// itself by a lexicographically positive translation.
    pub(crate) fn is_representative(&self, a: usize, b: usize) -> bool {
        if a >= self.items {
            return false;
        }
        let owner = self.owner[b] as usize;
        owner > a
            || (owner == a && {
                let n: [i32; N] = std::array::from_fn(|k| self.shift[b][k] - self.shift[a][k]);
                lexicographically_positive(&n)
            })
    }
}

/// Advances `n` to the next integer point of the box `lo..=hi` (first axis fastest); false
/// after the last.
fn next_in_box<const N: usize>(n: &mut [i32; N], lo: &[i32; N], hi: &[i32; N]) -> bool {
    for k in 0..N {
        if n[k] < hi[k] {
            n[k] += 1;
            return true;
        }
        n[k] = lo[k];
    }
    false
}

/// Points (items and images) placed per rayon task at least.
#[cfg(feature = "rayon")]
const POINTS_PER_TASK: usize = 4096;

/// The model's workspace in a periodic cell: the items' fractional positions, their images,
/// the bodies at every point and a Verlet list over them.
///
/// The image set is rebuilt (and the list with it) when an item has moved by half the skin
/// since the last build, or when the cell has changed enough to bring an image that was not
/// kept within reach: images are kept within `2 r_max + 2 s` of the cell, and a change `ΔH`
/// moves the image at fractional offset `t` by `ΔH t`, so `|ΔH|_F · T ≤ s / 2` (with `T`
/// bounding `|t|` over the kept images and one cell beyond) keeps every pair within reach in
/// the list. Between builds the list itself is rebuilt, over the same points, when they move
/// by half the skin (cell-grid's rule).
#[derive(Debug, Clone)]
pub(crate) struct Lattice<const N: usize> {
    /// Fractional positions of the items, `H⁻¹ c`, from the variables.
    pub(crate) fractional: Vec<[f64; N]>,
    /// The items and their images.
    pub(crate) images: ImageSet<N>,
    /// The bodies at the points of `images`.
    pub(crate) extended: Vec<Body<N>>,
    points: Vec<[f64; N]>,
    list: Option<cell_grid::PairList<N>>,
    reference: Vec<[f64; N]>,
    cell_at_build: [[f64; N]; N],
    far: f64,
    reach: f64,
    skin: f64,
    builds: usize,
}

impl<const N: usize> Lattice<N> {
    /// An empty workspace for items whose enclosing radii reach at most `r_max`.
    pub(crate) fn new(r_max: f64, skin: f64) -> Self {
        Self {
            fractional: Vec::new(),
            images: ImageSet::default(),
            extended: Vec::new(),
            points: Vec::new(),
            list: None,
            reference: Vec::new(),
            cell_at_build: [[0.0; N]; N],
            far: 0.0,
            reach: 2.0 * r_max,
            skin,
            builds: 0,
        }
    }

    /// How many times the image set has been built.
    pub(crate) fn builds(&self) -> usize {
        self.builds
    }

    /// Places the images of `bodies` (at `H s`, `s` in `self.fractional`) for `cell`,
    /// rebuilding the image set when it may have become incomplete.
    pub(crate) fn update(&mut self, cell: &[[f64; N]; N], bodies: &[Body<N>]) -> Result<(), Error> {
        if self.needs_build(cell, bodies) {
            self.build(cell, bodies)?;
        }
        let (images, fractional) = (&self.images, &self.fractional);
        let point = |e: usize| {
            let b = &bodies[images.owner[e] as usize];
            let c = to_cartesian(cell, &images.fractional(e, fractional));
            (
                Body::from_parts_unchecked(c, b.semi_axes(), b.rotation()),
                c,
            )
        };
        #[cfg(feature = "rayon")]
        {
            use rayon::prelude::*;
            (0..images.owner.len())
                .into_par_iter()
                .with_min_len(POINTS_PER_TASK)
                .map(point)
                .unzip_into_vecs(&mut self.extended, &mut self.points);
        }
        #[cfg(not(feature = "rayon"))]
        {
            self.extended.clear();
            self.points.clear();
            for (body, c) in (0..images.owner.len()).map(point) {
                self.extended.push(body);
                self.points.push(c);
            }
        }
        Ok(())
    }

    fn needs_build(&self, cell: &[[f64; N]; N], bodies: &[Body<N>]) -> bool {
        if self.list.is_none() || self.reference.len() != bodies.len() {
            return true;
        }
        let mut dh2 = 0.0;
        for r in 0..N {
            for c in 0..N {
                dh2 += (cell[r][c] - self.cell_at_build[r][c]).powi(2);
            }
        }
        let half = 0.5 * self.skin;
        if dh2.sqrt() * self.far > half {
            return true;
        }
        bodies.iter().zip(&self.reference).any(|(b, r)| {
            let c = b.centre();
            (0..N).map(|k| (c[k] - r[k]).powi(2)).sum::<f64>() > half * half
        })
    }

    fn build(&mut self, cell: &[[f64; N]; N], bodies: &[Body<N>]) -> Result<(), Error> {
        let pad = self.reach + 2.0 * self.skin;
        check_crowding(cell, bodies.iter().map(Body::bounding_radius))?;
        self.images = ImageSet::new(cell, &self.fractional, pad, image_limit(bodies.len()))?;
        let w = widths(cell);
        let t = (0..N).map(|k| (pad / w[k] + 3.0).powi(2)).sum::<f64>();
        self.far = t.sqrt();
        let radii: Vec<f64> = self
            .images
            .owner
            .iter()
            .map(|&o| bodies[o as usize].bounding_radius())
            .collect();
        self.list = Some(
            cell_grid::PairList::new(cell_grid::GridBuilder::with_radii(&radii), self.skin)
                .map_err(Error::Grid)?,
        );
        self.reference.clear();
        self.reference.extend(bodies.iter().map(Body::centre));
        self.cell_at_build = *cell;
        self.builds += 1;
        Ok(())
    }

    /// Calls `f(points, a, b)` for every representative pair of points `(a, b)` whose
    /// enclosing balls meet (see the module documentation), in ascending `(a, b)`, with the
    /// bodies and owners of the points.
    #[cfg(not(feature = "rayon"))]
    pub(crate) fn for_each_pair(
        &mut self,
        mut f: impl FnMut(Points<'_, N>, usize, usize),
    ) -> Result<(), Error> {
        let (images, points, bodies) = (&self.images, &self.points, &self.extended);
        // Only pairs whose first point is an item can be representatives.
        match &mut self.list {
            Some(list) => list
                .for_each_close_pair_from(points, 0..images.items, |a, b, _, _| {
                    if images.is_representative(a, b) {
                        f((bodies, &images.owner), a, b);
                    }
                })
                .map_err(Error::Grid),
            None => Ok(()),
        }
    }

    /// [`Lattice::for_each_pair`] on rayon's pool: the item rows of the list cut into ranges
    /// (cell-grid's `par_fold_close_pairs_into`, a cut that depends on the list alone),
    /// range `k` folding its representative pairs, in ascending `(a, b)`, into `states[k]`
    /// after `start(&mut states[k])`. Read in the order of `states`, the pairs come in the
    /// order of [`Lattice::for_each_pair`], on any number of threads.
    #[cfg(feature = "rayon")]
    pub(crate) fn par_fold_pairs_into<T: Send + Default>(
        &mut self,
        states: &mut Vec<T>,
        start: impl Fn(&mut T) + Sync + Send,
        fold: impl Fn(&mut T, Points<'_, N>, usize, usize) + Sync + Send,
    ) -> Result<(), Error> {
        let (images, points, bodies) = (&self.images, &self.points, &self.extended);
        match &mut self.list {
            Some(list) => list
                .par_fold_close_pairs_into(
                    points,
                    0..images.items,
                    states,
                    start,
                    |state, a, b, _, _| {
                        if images.is_representative(a, b) {
                            fold(state, (bodies, &images.owner), a, b);
                        }
                    },
                )
                .map_err(Error::Grid),
            None => {
                states.clear();
                Ok(())
            }
        }
    }

    /// The bodies and owners of the points.
    pub(crate) fn points(&self) -> Points<'_, N> {
        (&self.extended, &self.images.owner)
    }
}

/// The bodies at the points of an image set, and the item each point is an image of.
pub(crate) type Points<'a, const N: usize> = (&'a [Body<N>], &'a [u32]);

impl<const N: usize> Lattice<N> {}
