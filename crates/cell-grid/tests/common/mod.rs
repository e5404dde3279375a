//! Shared helpers: the O(m^2) reference.
#![allow(dead_code)]

use cell_grid::Grid;

/// The reference: how a pair is judged close, independent of the grid's code.
#[derive(Clone, Copy)]
pub struct Box<const D: usize> {
    pub lo: [f64; D],
    pub len: [f64; D],
    pub periodic: [bool; D],
}

impl<const D: usize> Box<D> {
    pub fn open() -> Self {
        Box {
            lo: [0.0; D],
            len: [1.0; D],
            periodic: [false; D],
        }
    }

    /// Minimum image by trying every shift in {-1, 0, 1} box lengths after reducing into
    /// the box: deliberately a different computation from the grid's rounding.
    pub fn dist2(&self, a: &[f64; D], b: &[f64; D]) -> f64 {
        let mut s = 0.0;
        for k in 0..D {
            let mut t = b[k] - a[k];
            if self.periodic[k] {
                let l = self.len[k];
                let wa = (a[k] - self.lo[k]).rem_euclid(l);
                let wb = (b[k] - self.lo[k]).rem_euclid(l);
                let base = wb - wa;
                t = [base - l, base, base + l]
                    .into_iter()
                    .min_by(|x, y| x.abs().total_cmp(&y.abs()))
                    .unwrap();
            }
            s += t * t;
        }
        s
    }
}

/// All pairs i < j with dist < reach_ij, by brute force, sorted.
pub fn brute_pairs<const D: usize>(
    pts: &[[f64; D]],
    reach: impl Fn(usize, usize) -> f64,
    bx: &Box<D>,
) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    for i in 0..pts.len() {
        for j in i + 1..pts.len() {
            let r = reach(i, j);
            if bx.dist2(&pts[i], &pts[j]) < r * r {
                out.push((i, j));
            }
        }
    }
    out
}

/// Checks every pair query of `grid` against the brute-force pairs `expected`.
pub fn check_grid<const D: usize>(
    grid: &Grid<D>,
    pts: &[[f64; D]],
    expected: &[(usize, usize)],
    bx: &Box<D>,
) {
    // Candidates: each once, i < j, a superset of the close pairs.
    let mut cand = Vec::new();
    grid.for_each_candidate_pair(|i, j| cand.push((i, j)));
    assert!(cand.iter().all(|&(i, j)| i < j), "candidate with i >= j");
    cand.sort_unstable();
    let n_cand = cand.len();
    cand.dedup();
    assert_eq!(cand.len(), n_cand, "duplicate candidate pair");
    for p in expected {
        assert!(cand.binary_search(p).is_ok(), "candidates miss {p:?}");
    }

    // Fast path with deltas.
    let mut close = Vec::new();
    grid.for_each_close_pair(|i, j, d, d2| {
        assert!(i < j);
        let want = bx.dist2(&pts[i], &pts[j]);
        assert!(
            (d2 - want).abs() <= 1e-12 * (1.0 + want),
            "dist2 of ({i},{j}): {d2} vs {want}"
        );
        let dd: f64 = d.iter().map(|t| t * t).sum();
        assert!((dd - d2).abs() <= 1e-12 * (1.0 + d2));
        close.push((i, j));
    });
    close.sort_unstable();
    assert_eq!(close, expected, "close pairs differ from brute force");

    // Caller's points.
    let mut within = Vec::new();
    grid.for_each_pair_within(pts, |i, j, _| within.push((i, j)))
        .unwrap();
    within.sort_unstable();
    assert_eq!(within, expected, "pairs within differ from brute force");
}

/// Neighbour lists from the brute-force pairs.
pub fn neighbour_lists(n: usize, pairs: &[(usize, usize)]) -> Vec<Vec<usize>> {
    let mut out = vec![Vec::new(); n];
    for &(i, j) in pairs {
        out[i].push(j);
        out[j].push(i);
    }
    for l in &mut out {
        l.sort_unstable();
    }
    out
}
