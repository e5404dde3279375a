//! Where each item's variables lie in the model's vector of variables.
//!
//! Item by item come its `N` centre coordinates, then its angles; the container's dimensions
//! follow the last item. An item carries only the angles that turn it:
//!
//! - a round item (all semi-axes equal: a circle or a ball) is the same set however it is
//!   turned and carries none;
//! - a spheroid (3D, exactly two semi-axes equal) is the same set however it is turned about
//!   its distinct axis `d` and carries two, `[θ, ψ]`: its rotation is `P_dᵀ R(0, θ, ψ) P_d`,
//!   `R` of eq. 2 and `P_d` the fixed rotation taking `e_d` to `e_1` (the axis about which
//!   `R`'s first angle `φ` turns), so that zero angles leave it unrotated, as every item;
//! - any other item carries eq. 1's `θ` in 2D and eq. 2's `[φ, θ, ψ]` in 3D.
//!
//! A scene of balls thus has `3m` variables instead of `6m`, and no angle derivative is
//! computed or carried by the solver for them.

use core::ops::Range;

/// The positions of the items' variables (see the module documentation).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Layout {
    /// `starts[i]` is the first variable of item `i`; `starts[m]` the first of the container.
    starts: Vec<usize>,
    /// The dimension `N` of the items.
    dimension: usize,
}

/// Whether an item with semi-axes `l` is round: all semi-axes equal (exactly), so that a
/// rotation leaves it unchanged.
pub fn is_round<const N: usize>(l: &[f64; N]) -> bool {
    l.iter().all(|&v| v == l[0])
}

/// The distinct axis `d` of a spheroid: in 3D, the semi-axis that differs from the two equal
/// others; `None` for any other item.
pub fn spheroid_axis<const N: usize>(l: &[f64; N]) -> Option<usize> {
    if N != 3 {
        return None;
    }
    match (l[0] == l[1], l[0] == l[2], l[1] == l[2]) {
        (true, false, false) => Some(2),
        (false, true, false) => Some(1),
        (false, false, true) => Some(0),
        _ => None,
    }
}

/// The number of angles of an item with semi-axes `l`: 0 for a round item, 2 for a spheroid,
/// else 1 in 2D and 3 in 3D.
pub fn angles_of<const N: usize>(l: &[f64; N]) -> usize {
    if is_round(l) {
        0
    } else if spheroid_axis(l).is_some() {
        2
    } else {
        N * (N - 1) / 2
    }
}

/// `P_d`: the rotation taking `e_d` to `e_1` (axes counted from 0: the identity for `d = 0`,
/// `R_z(−π/2)` for `d = 1`, `R_y(π/2)` for `d = 2`). Its entries are 0 and ±1, so products with
/// it are exact.
fn frame(d: usize) -> [[f64; 3]; 3] {
    match d {
        1 => [[0.0, 1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, 1.0]],
        2 => [[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]],
        _ => [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
    }
}

/// `Pᵀ v` for `P = P_d`.
fn frame_transposed_times(d: usize, v: &[f64; 3]) -> [f64; 3] {
    let p = frame(d);
    core::array::from_fn(|r| (0..3).map(|k| p[k][r] * v[k]).sum())
}

/// `P v` for `P = P_d`.
pub(crate) fn frame_times(d: usize, v: &[f64; 3]) -> [f64; 3] {
    let p = frame(d);
    core::array::from_fn(|r| (0..3).map(|k| p[r][k] * v[k]).sum())
}

/// A spheroid's rotation `P_dᵀ R P_d` from `R` of eq. 2.
pub(crate) fn spheroid_rotation(d: usize, r: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
    let p = frame(d);
    let rp: [[f64; 3]; 3] =
        core::array::from_fn(|a| core::array::from_fn(|b| (0..3).map(|k| r[a][k] * p[k][b]).sum()));
    core::array::from_fn(|a| core::array::from_fn(|b| (0..3).map(|k| p[k][a] * rp[k][b]).sum()))
}

/// `R = P_d Q P_dᵀ` of a spheroid's rotation `Q`: the inverse of [`spheroid_rotation`].
pub(crate) fn spheroid_frame_rotation(d: usize, q: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
    let p = frame(d);
    let pq: [[f64; 3]; 3] =
        core::array::from_fn(|a| core::array::from_fn(|b| (0..3).map(|k| p[a][k] * q[k][b]).sum()));
    core::array::from_fn(|a| core::array::from_fn(|b| (0..3).map(|k| pq[a][k] * p[b][k]).sum()))
}

/// The world angular velocities of a spheroid's angles from those of `R`'s:
/// `∂Q/∂α = P_dᵀ [ω_α]× R P_d = [P_dᵀ ω_α]× Q`, each row `ω_α` taken to `P_dᵀ ω_α`.
pub(crate) fn spheroid_rows(d: usize, rows: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
    core::array::from_fn(|a| frame_transposed_times(d, &rows[a]))
}

impl Layout {
    /// The layout of items with the semi-axes `semi_axes`.
    pub fn of<const N: usize>(semi_axes: &[[f64; N]]) -> Self {
        let mut starts = Vec::with_capacity(semi_axes.len() + 1);
        let mut next = 0;
        starts.push(next);
        for l in semi_axes {
            next += N + angles_of(l);
            starts.push(next);
        }
        Layout {
            starts,
            dimension: N,
        }
    }

    /// The number of items.
    pub fn items(&self) -> usize {
        self.starts.len() - 1
    }

    /// The variables of item `i`: its centre, then its angles.
    pub fn range(&self, i: usize) -> Range<usize> {
        self.starts[i]..self.starts[i + 1]
    }

    /// The first variable of item `i` (its centre's first coordinate).
    pub fn start(&self, i: usize) -> usize {
        self.starts[i]
    }

    /// The number of angles of item `i`.
    pub fn angles(&self, i: usize) -> usize {
        self.starts[i + 1] - self.starts[i] - self.dimension
    }

    /// The number of the items' variables: the container's dimensions start here.
    pub fn item_variables(&self) -> usize {
        self.starts[self.items()]
    }

    /// `starts[i]` for every item, then the container's start.
    pub(crate) fn starts(&self) -> &[usize] {
        &self.starts
    }

    /// `v` (the items' variables) cut at the items `bounds` (ascending item indices, the first
    /// and last included): one piece per pair of consecutive bounds.
    pub(crate) fn split_mut<'a, T>(
        &self,
        mut v: &'a mut [T],
        bounds: &[usize],
    ) -> Vec<&'a mut [T]> {
        let mut out = Vec::with_capacity(bounds.len().saturating_sub(1));
        for w in bounds.windows(2) {
            let (head, tail) = v.split_at_mut(self.starts[w[1]] - self.starts[w[0]]);
            out.push(head);
            v = tail;
        }
        out
    }

    /// The item bounds `0, g, 2g, …, m` of groups of `g` consecutive items.
    pub(crate) fn groups(&self, g: usize) -> Vec<usize> {
        let m = self.items();
        let mut bounds: Vec<usize> = (0..m).step_by(g.max(1)).collect();
        bounds.push(m);
        bounds
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_items_carry_no_angles() {
        let l = Layout::of(&[[1.0, 1.0, 1.0], [1.0, 0.75, 0.5], [2.0, 2.0, 2.0]]);
        assert_eq!(l.items(), 3);
        assert_eq!((l.range(0), l.range(1), l.range(2)), (0..3, 3..9, 9..12));
        assert_eq!((l.angles(0), l.angles(1), l.angles(2)), (0, 3, 0));
        assert_eq!(l.item_variables(), 12);
        assert_eq!((l.start(0), l.start(1), l.start(2)), (0, 3, 9));
        let circles = Layout::of(&[[1.0, 1.0], [2.0, 1.0]]);
        assert_eq!((circles.range(0), circles.range(1)), (0..2, 2..5));
    }

    #[test]
    fn spheroids_carry_two_angles_and_their_frames_are_rotations() {
        assert_eq!(spheroid_axis(&[1.0, 1.0, 2.0]), Some(2));
        assert_eq!(spheroid_axis(&[1.0, 2.0, 1.0]), Some(1));
        assert_eq!(spheroid_axis(&[2.0, 1.0, 1.0]), Some(0));
        assert_eq!(spheroid_axis(&[1.0, 0.75, 0.5]), None);
        assert_eq!(spheroid_axis(&[1.0, 1.0]), None);
        let l = Layout::of(&[[1.0, 1.0, 2.0], [1.0, 0.75, 0.5], [1.0; 3]]);
        assert_eq!((l.angles(0), l.angles(1), l.angles(2)), (2, 3, 0));
        for d in 0..3 {
            let p = frame(d);
            let mut e = [0.0; 3];
            e[d] = 1.0;
            assert_eq!(frame_times(d, &e), [1.0, 0.0, 0.0], "P_d e_d = e_1");
            let identity = spheroid_rotation(d, &frame(0));
            assert_eq!(identity, frame(0), "P_dᵀ P_d = I");
            let r = [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]];
            assert_eq!(spheroid_frame_rotation(d, &spheroid_rotation(d, &r)), r);
            let det = p[0][0] * (p[1][1] * p[2][2] - p[1][2] * p[2][1])
                - p[0][1] * (p[1][0] * p[2][2] - p[1][2] * p[2][0])
                + p[0][2] * (p[1][0] * p[2][1] - p[1][1] * p[2][0]);
            assert_eq!(det, 1.0);
        }
    }

    #[test]
    fn a_vector_splits_at_item_bounds() {
        let l = Layout::of(&[[1.0, 1.0], [2.0, 1.0], [1.0, 1.0]]);
        let mut v: Vec<usize> = (0..l.item_variables()).collect();
        let bounds = l.groups(2);
        assert_eq!(bounds, vec![0, 2, 3]);
        let pieces = l.split_mut(&mut v, &bounds);
        assert_eq!(pieces[0], &[0, 1, 2, 3, 4][..]);
        assert_eq!(pieces[1], &[5, 6][..]);
    }
}
