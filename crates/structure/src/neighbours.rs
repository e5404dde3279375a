//! Neighbours of every item: the displacements `d = c_j − c_i` of every item j (in a periodic
//! cell: every image of it, the item's own images included) with `|d| < cutoff`.
//!
//! A cell grid ([`cell_grid::Grid`]) over the centres finds the pairs in O(m). In a periodic
//! cell the grid holds, besides the items wrapped into the cell, their images whose fractional
//! coordinates lie within `cutoff / w_k` of the cell (`w_k` its width across lattice planes
//! k): every image within the cutoff of an item in the cell is then among the points, since a
//! Cartesian distance r has |Δs_k|·w_k ≤ r. An item pairs with an image of j found beside it;
//! the image of the item beside j gives the reverse bond.

use crate::Error;
use implicit_packing::periodic::{to_cartesian, to_fractional, widths};

/// Directed bonds: for each item, its neighbours and their displacements.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Bonds<const N: usize> {
    /// The cutoff they were found within.
    pub cutoff: f64,
    /// Per item `i`, its neighbours `(j, c_j − c_i)`, j's image included.
    pub of_item: Vec<Vec<(usize, [f64; N])>>,
}

/// Images of an item beyond this many per item are refused: the cell is too thin for the
/// cutoff.
pub const MAX_IMAGES_PER_ITEM: usize = 4096;

impl<const N: usize> Bonds<N> {
    /// The bonds of `centres` shorter than `cutoff`, in a periodic cell (columns: lattice
    /// vectors, upper triangular) or in open space.
    ///
    /// # Errors
    /// [`Error::Grid`] when the grid refuses the centres (non-finite values);
    /// [`Error::Settings`] when a periodic cell needs more than [`MAX_IMAGES_PER_ITEM`]
    /// images per item for the cutoff.
    pub fn within(
        centres: &[[f64; N]],
        cell: Option<&[[f64; N]; N]>,
        cutoff: f64,
    ) -> Result<Self, Error> {
        let mut of_item = vec![Vec::new(); centres.len()];
        for_each_bond(centres, cell, cutoff, |i, j, d| of_item[i].push((j, d)))?;
        // The grid's order depends on its cells: sort, so that sums are reproducible.
        for list in &mut of_item {
            list.sort_by(|x, y| x.0.cmp(&y.0).then_with(|| compare(&x.1, &y.1)));
        }
        Ok(Bonds { cutoff, of_item })
    }

    /// Undirected bonds, each once: `(i, j, c_j − c_i)` with `i < j`, or `i == j` (an item
    /// and its own image) with `d` lexicographically positive.
    pub fn pairs(&self) -> impl Iterator<Item = (usize, usize, [f64; N])> + '_ {
        self.of_item.iter().enumerate().flat_map(|(i, list)| {
            list.iter()
                .filter(move |(j, d)| {
                    i < *j || (i == *j && d.iter().find(|v| **v != 0.0).is_some_and(|v| *v > 0.0))
                })
                .map(move |(j, d)| (i, *j, *d))
        })
    }
}

/// Calls `f(i, j, d)` for every directed bond shorter than `cutoff`: j (an image of it) is at
/// `c_i + d`. Each bond comes twice, once from each end; nothing is stored, so a long cutoff
/// (g(r) over several diameters) costs time but no memory per bond.
///
/// # Errors
/// As [`Bonds::within`].
pub fn for_each_bond<const N: usize>(
    centres: &[[f64; N]],
    cell: Option<&[[f64; N]; N]>,
    cutoff: f64,
    mut f: impl FnMut(usize, usize, [f64; N]),
) -> Result<(), Error> {
    let m = centres.len();
    let (points, owner) = match cell {
        None => (centres.to_vec(), (0..m).collect()),
        Some(cell) => images(centres, cell, cutoff)?,
    };
    let grid = cell_grid::Grid::<N>::build(&points, cutoff)?;
    grid.for_each_pair_within(&points, |a, b, _| {
        let d: [f64; N] = std::array::from_fn(|k| points[b][k] - points[a][k]);
        match (a < m, b < m) {
            (true, true) => {
                f(a, b, d);
                f(b, a, d.map(|v| -v));
            }
            (true, false) => f(a, owner[b], d),
            (false, true) => f(b, owner[a], d.map(|v| -v)),
            (false, false) => {}
        }
    })?;
    Ok(())
}

fn compare<const N: usize>(a: &[f64; N], b: &[f64; N]) -> std::cmp::Ordering {
    a.iter()
        .zip(b)
        .map(|(x, y)| x.total_cmp(y))
        .find(|o| o.is_ne())
        .unwrap_or(std::cmp::Ordering::Equal)
}

/// The items wrapped into the cell, then their images within `pad` of it, with the item each
/// point stands for.
fn images<const N: usize>(
    centres: &[[f64; N]],
    cell: &[[f64; N]; N],
    pad: f64,
) -> Result<(Vec<[f64; N]>, Vec<usize>), Error> {
    let w = widths(cell);
    let margin: [f64; N] = std::array::from_fn(|k| pad / w[k]);
    let reach: [i64; N] = std::array::from_fn(|k| margin[k].ceil() as i64);
    let per_item: f64 = reach.iter().map(|&r| (2 * r + 1) as f64).product();
    if per_item > MAX_IMAGES_PER_ITEM as f64 {
        return Err(Error::Settings(format!(
            "a cutoff of {pad} needs {per_item} images of each item in this cell (widths {w:?}); \
             at most {MAX_IMAGES_PER_ITEM}"
        )));
    }
    let wrapped: Vec<[f64; N]> = centres
        .iter()
        .map(|c| to_fractional(cell, c).map(|s| s - s.floor()))
        .collect();
    let mut points: Vec<[f64; N]> = wrapped.iter().map(|s| to_cartesian(cell, s)).collect();
    let mut owner: Vec<usize> = (0..centres.len()).collect();
    for (i, s) in wrapped.iter().enumerate() {
        let mut n = reach.map(|r| -r);
        loop {
            if n.iter().any(|&v| v != 0) {
                let t: [f64; N] = std::array::from_fn(|k| s[k] + n[k] as f64);
                if (0..N).all(|k| t[k] >= -margin[k] && t[k] < 1.0 + margin[k]) {
                    points.push(to_cartesian(cell, &t));
                    owner.push(i);
                }
            }
            let mut k = 0;
            while k < N {
                n[k] += 1;
                if n[k] <= reach[k] {
                    break;
                }
                n[k] = -reach[k];
                k += 1;
            }
            if k == N {
                break;
            }
        }
    }
    Ok((points, owner))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Brute force: every image within the cutoff.
    fn brute<const N: usize>(
        centres: &[[f64; N]],
        cell: &[[f64; N]; N],
        cutoff: f64,
    ) -> Vec<Vec<usize>> {
        let mut out = vec![Vec::new(); centres.len()];
        for (i, ci) in centres.iter().enumerate() {
            for (j, cj) in centres.iter().enumerate() {
                let s = to_fractional(cell, &std::array::from_fn(|k| cj[k] - ci[k]));
                let mut n = [-3i64; N];
                loop {
                    let t: [f64; N] = std::array::from_fn(|k| s[k] + n[k] as f64);
                    let d = to_cartesian(cell, &t);
                    let r2: f64 = d.iter().map(|v| v * v).sum();
                    if r2 < cutoff * cutoff && r2 > 0.0 {
                        out[i].push(j);
                    }
                    let mut k = 0;
                    while k < N {
                        n[k] += 1;
                        if n[k] <= 3 {
                            break;
                        }
                        n[k] = -3;
                        k += 1;
                    }
                    if k == N {
                        break;
                    }
                }
            }
            out[i].sort_unstable();
        }
        out
    }

    #[test]
    fn bonds_in_a_sheared_cell_match_brute_force_over_images() {
        let cell = [[5.0, 2.2, -1.1], [0.0, 4.0, 1.7], [0.0, 0.0, 4.5]];
        let mut rng = testkit::Rng::new(12345);
        let mut next = || rng.uniform();
        let centres: Vec<[f64; 3]> = (0..40)
            .map(|_| [9.0 * next() - 3.0, 9.0 * next() - 3.0, 9.0 * next()])
            .collect();
        for cutoff in [0.8, 1.9, 2.4] {
            let bonds = Bonds::within(&centres, Some(&cell), cutoff).unwrap();
            let found: Vec<Vec<usize>> = bonds
                .of_item
                .iter()
                .map(|l| l.iter().map(|b| b.0).collect())
                .collect();
            assert_eq!(found, brute(&centres, &cell, cutoff), "cutoff {cutoff}");
            let directed: usize = bonds.of_item.iter().map(Vec::len).sum();
            assert_eq!(2 * bonds.pairs().count(), directed);
        }
    }

    #[test]
    fn an_item_alone_in_a_small_cell_sees_its_images() {
        let cell = [[1.0, 0.0], [0.0, 3.0]];
        let bonds = Bonds::within(&[[0.2, 0.5]], Some(&cell), 1.5).unwrap();
        // Images at ±1 and ±2 along x are within 1.5 except ±2.
        assert_eq!(bonds.of_item[0].len(), 2);
        assert_eq!(bonds.pairs().count(), 1);
    }
}
