//! The starts of local minimisations: the paper's first initial solution ([`lattice_start`]),
//! dense lattice starts ([`LatticeStart`], [`lattice_start_of`]) and random perturbations of a
//! packing ([`perturb`]).
//!
//! The paper's first initial solution ([`lattice_start`]) puts the
//! items, unrotated, on the affine image of the hexagonal circle lattice in 2D but of the
//! *simple cubic* lattice in 3D, whose density is π/6 ≈ 0.52 of the items' bounding boxes. Its
//! single start also fixes the container's aspect ratio to that of a round cluster. A box
//! holding 100 ellipsoids at the paper's density 0.64 is neither round nor cubic-packed.
//!
//! With every item unrotated and `l` the largest semi-axis of each direction over all items,
//! the map `x ↦ diag(l)⁻¹ x` sends every item into a unit ball. Unit balls centred on a lattice
//! with minimum distance 2 are disjoint, and so are their images under `diag(l)`; the densest
//! such lattices are the hexagonal one in 2D (density π/√12 ≈ 0.907) and the face-centred
//! cubic one in 3D (π/√18 ≈ 0.740). A [`LatticeStart`] chooses
//!
//! * the lattice's orientation ([`LatticeStart::orientation`]): rows along x or y in 2D; in 3D
//!   the cubic axes along the coordinate axes, or close-packed hexagonal layers stacked along
//!   x, y or z;
//! * a shift of the lattice against the origin (in lattice units), which changes which points
//!   sit on the boundary;
//! * the container's aspect (relative semi-axes or half-sides; a ball ignores it);
//!
//! and keeps the `m` lattice points deepest inside the container's gauge — the smallest
//! container of that aspect holding each item's enclosing ball or box (in a box, the points are
//! centred on their bounding box). Many such starts differ in the structure the local solver
//! refines, which the paper's perturbations of one solution rarely change.
//! [`tightest_lattice_starts`] ranks a grid of orientations, shifts and aspects by the measure
//! of their containers: the few blocks of the lattice that fill their container best, which a
//! multi-start tries first.
//!
//! # References
//! - E. G. Birgin, R. D. Lobato, J. M. Martínez, *A nonlinear programming model with implicit
//!   variables for packing ellipsoids*, J. Global Optim. 68 (2017), Section 6 (the initial
//!   solutions this module generalises).
//! - J. H. Conway, N. J. A. Sloane, *Sphere Packings, Lattices and Groups*, 3rd ed., Springer
//!   1999, chapter 1 (the hexagonal and face-centred cubic lattices).

use crate::Error;
use implicit_packing::Layout;
use implicit_packing::containment::ContainerShape;
use implicit_packing::model::Model;

/// One dense lattice start: which lattice orientation, shifted by how much, cut to which
/// container aspect.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LatticeStart<const N: usize> {
    /// 2D: 0 rows along x, 1 rows along y. 3D: 0 cubic axes along the coordinate axes (FCC),
    /// 1–3 close-packed layers stacked along x, y, z. Taken modulo the number of orientations.
    pub orientation: usize,
    /// Shift of the lattice against the origin, in units of the minimum distance.
    pub shift: [f64; N],
    /// Relative semi-axes (ellipsoid) or half-sides (box) of the container; ignored by a ball.
    /// Positive; only ratios matter.
    pub aspect: [f64; N],
}

impl<const N: usize> LatticeStart<N> {
    /// Number of distinct orientations in dimension `N`.
    pub const ORIENTATIONS: usize = if N == 2 { 2 } else { 4 };

    /// The round, unshifted start with the first orientation.
    pub fn centred() -> Self {
        Self {
            orientation: 0,
            shift: [0.0; N],
            aspect: [1.0; N],
        }
    }

    /// The start number `k` of a deterministic sequence that runs through every orientation,
    /// then varies the shift and (for non-ball containers) the aspect by a low-discrepancy
    /// sequence: aspect ratios spread over [1/4, 4] per axis and shifts over the unit cell.
    /// Start 0 is [`LatticeStart::centred`].
    pub fn sequence(k: usize) -> Self {
        let orientation = k % Self::ORIENTATIONS;
        let round = k / Self::ORIENTATIONS;
        if round == 0 {
            return Self {
                orientation,
                ..Self::centred()
            };
        }
        // Additive recurrence with the square roots of the first primes as steps (a Kronecker
        // sequence: rationally independent steps fill the unit cube evenly) over 2N coordinates.
        let mut unit = [0.0; 6];
        for (u, p) in unit.iter_mut().zip([2.0_f64, 3.0, 5.0, 7.0, 11.0, 13.0]) {
            let step = p.sqrt().fract();
            *u = (round as f64 * step).fract();
        }
        let mut shift = [0.0; N];
        let mut aspect = [1.0; N];
        for a in 0..N {
            shift[a] = unit[a];
            // Log-uniform on [1/4, 4], relative to axis 0: the best boxes for 100 ellipses
            // (2, 1) are long and flat (aspect 0.2–0.3 gave 0.872–0.874, aspects in [1/2, 2]
            // at most 0.870).
            aspect[a] = if a == 0 {
                1.0
            } else {
                4f64.powf(2.0 * unit[N + a] - 1.0)
            };
        }
        Self {
            orientation,
            shift,
            aspect,
        }
    }

    /// Basis vectors (rows) of the lattice with minimum distance 2.
    fn basis(&self) -> [[f64; N]; N] {
        let mut b = [[0.0; N]; N];
        if N == 2 {
            let rows = [[2.0, 0.0], [1.0, 3f64.sqrt()]];
            let swap = self.orientation % 2 == 1;
            for (r, row) in rows.iter().enumerate() {
                b[r][0] = if swap { row[1] } else { row[0] };
                b[r][1] = if swap { row[0] } else { row[1] };
            }
        } else if self.orientation.is_multiple_of(4) {
            // FCC with its cubic axes along x, y, z: √2 (1,1,0), √2 (1,0,1), √2 (0,1,1).
            let s = std::f64::consts::SQRT_2;
            let rows = [[s, s, 0.0], [s, 0.0, s], [0.0, s, s]];
            for (r, row) in rows.iter().enumerate() {
                b[r][..3].copy_from_slice(row);
            }
        } else {
            // Hexagonal layers (two in-plane vectors) stacked ABC (the third), i.e. FCC seen
            // along a body diagonal; the stacking axis is x, y or z.
            let h = 3f64.sqrt();
            let rows = [
                [2.0, 0.0, 0.0],
                [1.0, h, 0.0],
                [1.0, 1.0 / h, 2.0 * (2.0f64 / 3.0).sqrt()],
            ];
            let stack = self.orientation % 4 - 1;
            for (r, row) in rows.iter().enumerate() {
                for k in 0..3 {
                    // In-plane axes follow the stacking axis cyclically.
                    b[r][(stack + 1 + k) % 3] = row[k];
                }
            }
        }
        b
    }
}

/// The variables of a [`LatticeStart`] for `problem`: items unrotated on the lattice, and the
/// smallest container of the start's aspect holding every item's enclosing ball (a ball or an
/// ellipsoid) or box (a box), so the start is feasible.
pub fn lattice_start_of<const N: usize>(problem: &Model<N>, start: &LatticeStart<N>) -> Vec<f64> {
    let m = problem.len();
    if problem.container_kind() == ContainerShape::Periodic {
        let per_cell = PER_CELL[start.orientation % PER_CELL.len()];
        return periodic_lattice_start(problem, per_cell, &start.shift);
    }
    let (points, dims) = lattice_cut(problem, start);
    let layout = problem.layout();
    let mut x = vec![0.0; problem.var_count()];
    for (i, p) in points.iter().enumerate().take(m) {
        let at = layout.start(i);
        x[at..at + N].copy_from_slice(p);
    }
    let nb = layout.item_variables();
    x[nb..].copy_from_slice(&dims[..problem.var_count() - nb]);
    x
}

/// The `m` lattice points of a [`LatticeStart`] (not periodic) and the dimensions of the
/// smallest container of its aspect holding them. In a box the points are centred on their
/// bounding box, which the container then fits exactly on every side.
fn lattice_cut<const N: usize>(
    problem: &Model<N>,
    start: &LatticeStart<N>,
) -> (Vec<[f64; N]>, [f64; N]) {
    let kind = problem.container_kind();
    let l = lattice_semi_axes(problem);
    let reach = l.iter().fold(0.0_f64, |a, &b| a.max(b));
    let aspect = if kind == ContainerShape::Ball {
        [1.0; N]
    } else {
        start
            .aspect
            .map(|a| if a > 0.0 && a.is_finite() { a } else { 1.0 })
    };
    let gauge = |p: &[f64; N]| match kind {
        ContainerShape::Ball => p.iter().map(|v| v * v).sum::<f64>().sqrt(),
        ContainerShape::Ellipsoid => (0..N)
            .map(|k| (p[k] / aspect[k]).powi(2))
            .sum::<f64>()
            .sqrt(),
        ContainerShape::Box => (0..N)
            .map(|k| (p[k].abs() + l[k]) / aspect[k])
            .fold(0.0, f64::max),
        ContainerShape::Periodic => 0.0,
    };
    let mut points = deepest_points(
        problem.len(),
        &start.basis(),
        &start.shift,
        &l,
        &aspect,
        gauge,
    );
    if kind == ContainerShape::Box {
        centre_on_bounding_box(&mut points);
    }
    let dims = container_holding(&points, kind, &l, reach, &aspect);
    (points, dims)
}

/// Translates `points` so that their bounding box is centred on the origin.
fn centre_on_bounding_box<const N: usize>(points: &mut [[f64; N]]) {
    for k in 0..N {
        let (low, high) = points
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
                (a.min(p[k]), b.max(p[k]))
            });
        let middle = 0.5 * (low + high);
        for p in points.iter_mut() {
            p[k] -= middle;
        }
    }
}

/// Lattice points (summed over the cuts) that [`tightest_lattice_starts`] examines at most.
/// A cut of `m` points examines a cube of `(2R + 1)ᴺ` lattice points, `R ≈ spread · m^(1/N)`;
/// up to a second or two on one core.
const CUT_WORK: f64 = 1e8;

/// Container aspects per axis that [`tightest_lattice_starts`] tries: log-spaced over
/// `[1/4, 4]`, the range [`LatticeStart::sequence`] draws from.
const CUT_ASPECTS: [usize; 2] = [64, 12];

/// Shifts per orientation that [`tightest_lattice_starts`] tries (Kronecker points of the
/// unit cell, the first the unshifted lattice).
const CUT_SHIFTS: usize = 4;

/// The `count` [`LatticeStart`]s (at most) whose containers are smallest: every orientation,
/// several shifts and, but for a ball, container aspects on a log-spaced grid over `[1/4, 4]`
/// are cut to `m` points ([`lattice_start_of`]); the cuts are ranked by container area or
/// volume, and cuts of equal measure and dimensions (the same block of the lattice) are kept
/// once. Empty for a periodic cell, which has its own lattice starts.
///
/// The aspects drawn by [`LatticeStart::sequence`] seldom hit one of the few blocks of the
/// lattice that fill their container well: for 1000 ellipses (2, 1) in a rectangle the 16
/// tightest cuts fill 0.886–0.891 of their boxes, the first 64 starts of the sequence
/// 0.838–0.891 (median 0.874). When all cuts together would examine more than 10⁸ lattice
/// points (large `m`, mostly in 3D), an evenly spread subset of them is cut.
pub fn tightest_lattice_starts<const N: usize>(
    problem: &Model<N>,
    count: usize,
) -> Vec<LatticeStart<N>> {
    let kind = problem.container_kind();
    if count == 0 || kind == ContainerShape::Periodic {
        return Vec::new();
    }
    let candidates = cut_candidates::<N>(kind);
    let cost = |s: &LatticeStart<N>| {
        let spread = s.aspect.iter().fold(0.0_f64, |a, &b| a.max(b))
            / s.aspect.iter().fold(f64::INFINITY, |a, &b| a.min(b));
        let radius = spread.min(4.0) * (problem.len() as f64).powf(1.0 / N as f64) + 3.0;
        (2.0 * radius.ceil() + 1.0).powi(N as i32)
    };
    let total: f64 = candidates.iter().map(cost).sum();
    let kept = (CUT_WORK / total).min(1.0);
    // Golden-ratio sampling keeps an even spread of orientations, shifts and aspects.
    let golden = (5f64.sqrt() - 1.0) / 2.0;
    let mut ranked: Vec<(f64, [f64; N], LatticeStart<N>)> = candidates
        .into_iter()
        .enumerate()
        .filter(|(i, _)| (*i as f64 * golden).fract() < kept)
        .map(|(_, s)| {
            let (_, dims) = lattice_cut(problem, &s);
            (dims.iter().product::<f64>(), dims, s)
        })
        .collect();
    // A stable sort: equal measures keep the candidates' order, so the ranking is
    // deterministic.
    ranked.sort_by(|a, b| a.0.total_cmp(&b.0));
    let same = |a: &[f64; N], b: &[f64; N]| {
        a.iter()
            .zip(b)
            .all(|(x, y)| (x - y).abs() <= 1e-9 * x.abs().max(y.abs()))
    };
    let mut starts: Vec<(f64, [f64; N], LatticeStart<N>)> = Vec::with_capacity(count);
    for cut in ranked {
        if starts.len() == count {
            break;
        }
        if !starts.iter().any(|kept| same(&kept.1, &cut.1)) {
            starts.push(cut);
        }
    }
    starts.into_iter().map(|(_, _, s)| s).collect()
}

/// The cuts [`tightest_lattice_starts`] may try: orientations innermost, then shifts, then
/// aspects (one per direction after the first, relative to it; none for a ball).
fn cut_candidates<const N: usize>(kind: ContainerShape) -> Vec<LatticeStart<N>> {
    let per_axis = if kind == ContainerShape::Ball {
        1
    } else {
        CUT_ASPECTS[N - 2]
    };
    let ratio = |i: usize| {
        if per_axis == 1 {
            1.0
        } else {
            4f64.powf(2.0 * i as f64 / (per_axis - 1) as f64 - 1.0)
        }
    };
    let mut candidates = Vec::new();
    for a in 0..per_axis.pow(N as u32 - 1) {
        let mut aspect = [1.0; N];
        let mut rest = a;
        for v in aspect.iter_mut().skip(1) {
            *v = ratio(rest % per_axis);
            rest /= per_axis;
        }
        for s in 0..CUT_SHIFTS {
            let mut shift = [0.0; N];
            for (k, v) in shift.iter_mut().enumerate() {
                *v = (s as f64 * [2.0_f64, 3.0, 5.0][k].sqrt()).fract();
            }
            for orientation in 0..LatticeStart::<N>::ORIENTATIONS {
                candidates.push(LatticeStart {
                    orientation,
                    shift,
                    aspect,
                });
            }
        }
    }
    candidates
}

/// A start that fills a fixed container: the [`LatticeStart`] (with the container's aspect
/// when it has one semi-axis or half side per direction) dilated about the centre
/// ([`Model::dilated`]) until its container has the fixed container's area or volume, and then
/// given the fixed container's variables `container` (those of the model after the items').
/// Items keep their size, so above the lattice's density they overlap and the solver
/// separates them. A periodic cell is filled by a lattice fitted to its shape instead
/// (`periodic_fill_start`).
///
/// # Errors
/// [`Error::Model`] when `container` is not a valid container of the problem's kind (wrong
/// length, a value that is not positive and finite).
pub fn fill_start<const N: usize>(
    problem: &mut Model<N>,
    start: &LatticeStart<N>,
    container: &[f64],
) -> Result<Vec<f64>, Error> {
    let body_variables = problem.layout().item_variables();
    if container.len() != problem.var_count() - body_variables {
        return Err(implicit_packing::Error::LengthMismatch {
            what: "container variables",
            expected: problem.var_count() - body_variables,
            found: container.len(),
        }
        .into());
    }
    if problem.container_kind() == ContainerShape::Periodic {
        return Ok(periodic_fill_start(problem, start, container));
    }
    let start = LatticeStart {
        aspect: if container.len() == N {
            std::array::from_fn(|k| container[k])
        } else {
            start.aspect
        },
        ..*start
    };
    let lattice = lattice_start_of(problem, &start);
    let lattice_measure = problem.evaluate(&lattice, None)?.objective;
    let mut fixed = lattice.clone();
    fixed[body_variables..].copy_from_slice(container);
    let fixed_measure = problem.evaluate(&fixed, None)?.objective;
    let s = (fixed_measure / lattice_measure).powf(1.0 / N as f64);
    let mut x = problem.dilated(&lattice, s);
    x[body_variables..].copy_from_slice(container);
    Ok(x)
}

/// The `m` points `diag(l) (shift·B + n·B)`, `n ∈ ℤᴺ`, of smallest gauge (ties broken by the
/// lattice index, so the start is deterministic).
fn deepest_points<const N: usize>(
    m: usize,
    basis: &[[f64; N]; N],
    shift: &[f64; N],
    l: &[f64; N],
    aspect: &[f64; N],
    gauge: impl Fn(&[f64; N]) -> f64,
) -> Vec<[f64; N]> {
    // The lattice has one point per cell of volume |det B| ≥ 2ᴺ·(√3/2 or 1/√2); a cube of index
    // radius R holds (2R+1)ᴺ points, covering any container of aspect spread ≤ 4 holding m
    // points when R exceeds the spread times m^(1/N) plus a margin. Beyond a spread of 4 the
    // cube is capped (its size grows as spreadᴺ m): the start is then the m deepest points of
    // the cube, a container less elongated than asked but still feasible and deterministic.
    let spread = aspect.iter().fold(0.0_f64, |a, &b| a.max(b))
        / aspect.iter().fold(f64::INFINITY, |a, &b| a.min(b));
    let radius = (spread.min(4.0) * (m as f64).powf(1.0 / N as f64) + 3.0).ceil() as i64;
    let mut candidates: Vec<(f64, [i64; N], [f64; N])> = Vec::new();
    let mut index = [-radius; N];
    loop {
        let mut p = [0.0; N];
        for r in 0..N {
            let coefficient = index[r] as f64 + shift[r];
            for k in 0..N {
                p[k] += coefficient * basis[r][k];
            }
        }
        let p = std::array::from_fn(|k| p[k] * l[k]);
        candidates.push((gauge(&p), index, p));
        let mut k = 0;
        loop {
            if k == N {
                let cmp = |a: &(f64, [i64; N], [f64; N]), b: &(f64, [i64; N], [f64; N])| {
                    a.0.total_cmp(&b.0).then(a.1.cmp(&b.1))
                };
                if m < candidates.len() {
                    candidates.select_nth_unstable_by(m, cmp);
                    candidates.truncate(m);
                }
                candidates.sort_by(cmp);
                return candidates.into_iter().map(|c| c.2).collect();
            }
            index[k] += 1;
            if index[k] <= radius {
                break;
            }
            index[k] = -radius;
            k += 1;
        }
    }
}

/// The smallest container of the given aspect that holds every item's enclosing ball (radius
/// `reach`) about each point — for a box, the exact bounding box of the unrotated items.
fn container_holding<const N: usize>(
    points: &[[f64; N]],
    kind: ContainerShape,
    l: &[f64; N],
    reach: f64,
    aspect: &[f64; N],
) -> [f64; N] {
    let grow = 1.0 + 1e-9;
    match kind {
        ContainerShape::Ball => {
            let r = points
                .iter()
                .map(|p| p.iter().map(|v| v * v).sum::<f64>().sqrt())
                .fold(0.0, f64::max);
            [(r + reach) * grow; N]
        }
        ContainerShape::Ellipsoid => {
            // E(a t) contains the points; E(a t) + E(a s) = E(a (t + s)) for homothetic
            // ellipsoids, and E(a s) ⊇ B(reach) when s = reach / min a.
            let t = points
                .iter()
                .map(|p| {
                    (0..N)
                        .map(|k| (p[k] / aspect[k]).powi(2))
                        .sum::<f64>()
                        .sqrt()
                })
                .fold(0.0, f64::max);
            let a_min = aspect.iter().fold(f64::INFINITY, |a, &b| a.min(b));
            let s = t + reach / a_min;
            aspect.map(|a| a * s * grow)
        }
        ContainerShape::Box => {
            let mut half = [0.0; N];
            for p in points {
                for k in 0..N {
                    half[k] = f64::max(half[k], p[k].abs() + l[k]);
                }
            }
            half.map(|h| h * grow)
        }
        // Never asked: periodic starts are built by `periodic_lattice_start`.
        ContainerShape::Periodic => [reach; N],
    }
}

/// The paper's first initial solution: items not rotated, centres on a lattice nearest the
/// origin — the affine image of the hexagonal circle packing in 2D (rows `2 a` apart in x,
/// `√3 b` in y, alternate rows shifted by `a`), the points `(2δ₁ l₁, 2δ₂ l₂, 2δ₃ l₃)`, δ ∈ ℤ³,
/// in 3D (`l` the largest semi-axis of each direction over all items, so nothing overlaps) —
/// and the smallest container of the problem's kind that holds every item's enclosing ball.
pub fn lattice_start<const N: usize>(problem: &Model<N>) -> Vec<f64> {
    let m = problem.len();
    let spacing = lattice_semi_axes(problem);
    let points = lattice_points::<N>(m, &spacing);
    let layout = problem.layout();
    let mut x = vec![0.0; problem.var_count()];
    let mut reach = [0.0_f64; N];
    let mut radius = 0.0_f64;
    for (i, (p, l)) in points.iter().zip(problem.semi_axes()).enumerate() {
        let at = layout.start(i);
        x[at..at + N].copy_from_slice(p);
        let r = l.iter().fold(0.0_f64, |a, &b| a.max(b));
        let norm = p.iter().map(|v| v * v).sum::<f64>().sqrt();
        radius = radius.max(norm + r);
        for k in 0..N {
            reach[k] = reach[k].max(p[k].abs() + r);
        }
    }
    // The enclosing balls touch the container; the same relative gap as the lattice.
    let (radius, reach) = (radius * (1.0 + 1e-9), reach.map(|r| r * (1.0 + 1e-9)));
    let dims = &mut x[layout.item_variables()..];
    match problem.container_kind() {
        ContainerShape::Ball => dims[0] = radius,
        ContainerShape::Ellipsoid => dims.fill(radius),
        ContainerShape::Box => dims.copy_from_slice(&reach),
        ContainerShape::Periodic => return periodic_lattice_start(problem, 1, &[0.0; N]),
    }
    x
}

/// The items per unit cell of the periodic lattice starts, by [`LatticeStart::orientation`].
pub const PER_CELL: [usize; 3] = [1, 2, 4];

/// A unit cell of a densest lattice packing of balls of radius 1 (upper-triangular `H`,
/// columns the lattice vectors) and its sites (fractional coordinates): with 1 site, the
/// hexagonal (2D) or face-centred cubic primitive cell (3D); with 2, the centred rectangular
/// cell (2D) or the hexagonal close-packed cell (3D); with 4, the rectangular cell of four
/// rows (2D) or the cubic FCC cell (3D). All have density π/√12 (2D) or π/√18 (3D), HCP too.
fn unit_cell<const N: usize>(per_cell: usize) -> ([[f64; N]; N], Vec<[f64; N]>) {
    let h = 3f64.sqrt();
    let pick = |rows: &[&[f64]]| -> [[f64; N]; N] {
        std::array::from_fn(|r| std::array::from_fn(|c| rows[r][c]))
    };
    let sites = |list: &[&[f64]]| -> Vec<[f64; N]> {
        list.iter().map(|s| std::array::from_fn(|k| s[k])).collect()
    };
    if N == 2 {
        match per_cell {
            1 => (pick(&[&[2.0, 1.0], &[0.0, h]]), sites(&[&[0.0, 0.0]])),
            2 => (
                pick(&[&[2.0, 0.0], &[0.0, 2.0 * h]]),
                sites(&[&[0.0, 0.0], &[0.5, 0.5]]),
            ),
            _ => (
                pick(&[&[4.0, 0.0], &[0.0, 2.0 * h]]),
                sites(&[&[0.0, 0.0], &[0.5, 0.0], &[0.25, 0.5], &[0.75, 0.5]]),
            ),
        }
    } else {
        let z = (8.0f64 / 3.0).sqrt();
        let a = 2.0 * std::f64::consts::SQRT_2;
        match per_cell {
            1 => (
                pick(&[&[2.0, 1.0, 1.0], &[0.0, h, 1.0 / h], &[0.0, 0.0, z]]),
                sites(&[&[0.0, 0.0, 0.0]]),
            ),
            2 => (
                pick(&[&[2.0, 1.0, 0.0], &[0.0, h, 0.0], &[0.0, 0.0, 2.0 * z]]),
                sites(&[&[0.0, 0.0, 0.0], &[1.0 / 3.0, 1.0 / 3.0, 0.5]]),
            ),
            _ => (
                pick(&[&[a, 0.0, 0.0], &[0.0, a, 0.0], &[0.0, 0.0, a]]),
                sites(&[
                    &[0.0, 0.0, 0.0],
                    &[0.5, 0.5, 0.0],
                    &[0.5, 0.0, 0.5],
                    &[0.0, 0.5, 0.5],
                ]),
            ),
        }
    }
}

/// The numbers of unit cells `c_k` along each axis for `m` items, `per_cell` sites per unit
/// cell of heights `h_k`: the fewest empty sites among the supercells whose heights `c_k h_k`
/// differ by at most a factor 4, then the least spread of the heights.
pub(crate) fn supercell<const N: usize>(m: usize, per_cell: usize, h: &[f64; N]) -> [usize; N] {
    let cells = m.div_ceil(per_cell).max(1);
    let cost = |c: &[usize; N]| {
        let sites = per_cell * c.iter().product::<usize>();
        let widths: Vec<f64> = (0..N).map(|k| c[k] as f64 * h[k]).collect();
        let spread = widths.iter().fold(0.0f64, |a, &b| a.max(b))
            / widths.iter().fold(f64::INFINITY, |a, &b| a.min(b));
        (spread > 4.0, sites - m, spread)
    };
    least_cost_counts(cells, cost)
}

/// The numbers of unit cells `c_k` along each axis that hold `cells` unit cells at the least
/// `cost` (the first found among equal costs): every `(c_1, …, c_{N−1})` whose product is at
/// most `cells`, with the least `c_N` that makes up `cells`.
fn least_cost_counts<const N: usize, C: PartialOrd>(
    cells: usize,
    cost: impl Fn(&[usize; N]) -> C,
) -> [usize; N] {
    let mut best = [1usize; N];
    best[N - 1] = cells;
    let mut best_cost = cost(&best);
    let mut c = [1usize; N];
    loop {
        // The increments below keep this product at most `cells`.
        let partial: usize = c[..N - 1].iter().product();
        c[N - 1] = cells.div_ceil(partial);
        let value = cost(&c);
        if value.partial_cmp(&best_cost) == Some(std::cmp::Ordering::Less) {
            (best, best_cost) = (c, value);
        }
        let mut k = 0;
        while k < N - 1 {
            c[k] += 1;
            if c[..N - 1].iter().product::<usize>() <= cells {
                break;
            }
            c[k] = 1;
            k += 1;
        }
        if k == N - 1 {
            return best;
        }
    }
}

/// A periodic lattice start: the items unrotated on a densest lattice of unit balls mapped by
/// `diag(l)` (so that items do not overlap, as in [`LatticeStart`]), in a periodic cell made of
/// `c_1 × … × c_N` unit cells of `per_cell` sites (1, 2 or 4), the `c_k` chosen for the fewest
/// empty sites and then the most isotropic cell; the first `m` sites are taken and the rest
/// left empty. `shift` moves every site (in units of the unit cell).
pub fn periodic_lattice_start<const N: usize>(
    problem: &Model<N>,
    per_cell: usize,
    shift: &[f64; N],
) -> Vec<f64> {
    let m = problem.len();
    let l = lattice_semi_axes(problem);
    let (unit, sites) = unit_cell::<N>(per_cell);
    let unit: [[f64; N]; N] = std::array::from_fn(|r| unit[r].map(|v| v * l[r]));
    let counts = supercell::<N>(m, sites.len(), &std::array::from_fn(|k| unit[k][k]));
    let mut x = vec![0.0; problem.var_count()];
    place_on_sites(&mut x, problem.layout(), &sites, &counts, shift);
    let nb = problem.layout().item_variables();
    // The supercell H diag(c), with the same relative gap as the lattice.
    for k in 0..N * (N + 1) / 2 {
        let (r, c) = implicit_packing::periodic::entry::<N>(k);
        x[nb + k] = unit[r][c] * counts[c] as f64 * (1.0 + 1e-9);
    }
    x
}

/// Writes the fractional centres of the first `m` sites of a supercell of `counts` unit cells
/// (each with `sites`, moved by `shift`) into the variables `x`; the angles stay as they are.
fn place_on_sites<const N: usize>(
    x: &mut [f64],
    layout: &Layout,
    sites: &[[f64; N]],
    counts: &[usize; N],
    shift: &[f64; N],
) {
    let m = layout.items();
    let mut item = 0;
    let mut n = [0usize; N];
    loop {
        for site in sites {
            if item == m {
                return;
            }
            for k in 0..N {
                x[layout.start(item) + k] = (n[k] as f64 + site[k] + shift[k]) / counts[k] as f64;
            }
            item += 1;
        }
        if !next_cell(&mut n, counts) {
            return;
        }
    }
}

/// Steps the unit cell `n` of a supercell of `counts` cells to the next one, the first axis
/// fastest; `false` after the last.
pub(crate) fn next_cell<const N: usize>(n: &mut [usize; N], counts: &[usize; N]) -> bool {
    for k in 0..N {
        n[k] += 1;
        if n[k] < counts[k] {
            return true;
        }
        n[k] = 0;
    }
    false
}

/// A start that fills a fixed periodic cell with diagonal `heights` (`l_x, l_y, l_z`): items
/// unrotated on a lattice of unit balls with an orthogonal conventional cell
/// ([`orthogonal_cells`]: square and hexagonal in 2D; simple cubic, body-centred cubic,
/// face-centred cubic and hexagonal close-packed in 3D), mapped by `diag(l)`, its cells counted
/// along each axis. Each (lattice, counts) is compressed by the largest ratio of its natural
/// height to the cell's, `max_k c_k h_k l_k / L_k`; at most 1, no two items overlap (a stretch
/// by factors ≥ 1 along each axis shortens no distance), so every fraction one of these
/// lattices reaches in the cell's shape starts as a packing, before any solver work. The
/// candidates are ranked by that compression, then by their empty sites;
/// [`LatticeStart::orientation`] picks the rank (0: the least compressed), so a multi-start
/// tries the others. The centres are fractional, so the lattice takes the cell's shape.
/// A lattice filling a fixed periodic cell: (compression, empty sites), the counts of its
/// conventional cells along each axis, and their sites.
type RankedFill<const N: usize> = ((f64, usize), [usize; N], Vec<[f64; N]>);

fn periodic_fill_start<const N: usize>(
    problem: &Model<N>,
    start: &LatticeStart<N>,
    container: &[f64],
) -> Vec<f64> {
    let m = problem.len();
    let l = lattice_semi_axes(problem);
    let heights: [f64; N] = std::array::from_fn(|k| container[k]);
    let mut ranked: Vec<RankedFill<N>> = orthogonal_cells::<N>()
        .into_iter()
        .map(|(natural, sites)| {
            let compression = |c: &[usize; N]| {
                (0..N)
                    .map(|k| c[k] as f64 * natural[k] * l[k] / heights[k])
                    .fold(0.0, f64::max)
            };
            let cells = m.div_ceil(sites.len()).max(1);
            let cost = |c: &[usize; N]| (compression(c), sites.len() * c.iter().product::<usize>());
            let counts = least_cost_counts(cells, cost);
            let (compression, occupied) = cost(&counts);
            ((compression, occupied - m), counts, sites)
        })
        .collect();
    ranked.sort_by(|a, b| a.0.0.total_cmp(&b.0.0).then(a.0.1.cmp(&b.0.1)));
    let (_, counts, sites) = &ranked[start.orientation % ranked.len()];
    let mut x = vec![0.0; problem.var_count()];
    place_on_sites(&mut x, problem.layout(), sites, counts, &start.shift);
    x[problem.layout().item_variables()..].copy_from_slice(container);
    x
}

/// The orthogonal conventional cells of lattices of unit balls (minimum distance 2) that fill
/// a fixed periodic cell: each cell's side lengths and its sites in fractional coordinates.
/// 2D: the square lattice (density π/4) and the hexagonal one (π/√12) in its centred
/// rectangular cell, alone and doubled along x. 3D: simple cubic (π/6), body-centred cubic
/// (π√3/8), face-centred cubic and hexagonal close-packed (π/√18) in its orthohexagonal cell.
///
/// # References
/// - N. W. Ashcroft, N. D. Mermin, *Solid State Physics*, Saunders 1976, chapter 4 (the cubic
///   and hexagonal close-packed structures and their conventional cells).
fn orthogonal_cells<const N: usize>() -> Vec<([f64; N], Vec<[f64; N]>)> {
    let h = 3f64.sqrt();
    let cell = |sides: &[f64], sites: &[&[f64]]| -> ([f64; N], Vec<[f64; N]>) {
        (
            std::array::from_fn(|k| sides[k]),
            sites
                .iter()
                .map(|s| std::array::from_fn(|k| s[k]))
                .collect(),
        )
    };
    if N == 2 {
        vec![
            cell(&[2.0, 2.0], &[&[0.0, 0.0]]),
            cell(&[2.0, 2.0 * h], &[&[0.0, 0.0], &[0.5, 0.5]]),
            cell(
                &[4.0, 2.0 * h],
                &[&[0.0, 0.0], &[0.5, 0.0], &[0.25, 0.5], &[0.75, 0.5]],
            ),
        ]
    } else {
        let fcc = 2.0 * std::f64::consts::SQRT_2;
        let layers = 2.0 * (8.0f64 / 3.0).sqrt();
        vec![
            cell(&[2.0, 2.0, 2.0], &[&[0.0, 0.0, 0.0]]),
            cell(&[4.0 / h; 3], &[&[0.0, 0.0, 0.0], &[0.5, 0.5, 0.5]]),
            cell(
                &[fcc; 3],
                &[
                    &[0.0, 0.0, 0.0],
                    &[0.5, 0.5, 0.0],
                    &[0.5, 0.0, 0.5],
                    &[0.0, 0.5, 0.5],
                ],
            ),
            cell(
                &[2.0, 2.0 * h, layers],
                &[
                    &[0.0, 0.0, 0.0],
                    &[0.5, 0.5, 0.0],
                    &[0.5, 1.0 / 6.0, 0.5],
                    &[0.0, 2.0 / 3.0, 0.5],
                ],
            ),
        ]
    }
}

/// The largest semi-axis of each direction over all items, which unrotated items on a lattice
/// scaled by it never exceed. Lattice neighbours are then exactly tangent; a relative gap of
/// 1e-9 keeps lattice starts certified under rounding.
pub(crate) fn lattice_semi_axes<const N: usize>(problem: &Model<N>) -> [f64; N] {
    let mut l = [0.0_f64; N];
    for axes in problem.semi_axes() {
        for k in 0..N {
            l[k] = l[k].max(axes[k]);
        }
    }
    l.map(|v| v * (1.0 + 1e-9))
}

/// The `m` lattice points nearest the origin (ties broken by coordinates, so the start is
/// deterministic).
fn lattice_points<const N: usize>(m: usize, l: &[f64; N]) -> Vec<[f64; N]> {
    // Enough shells that the m nearest points are among the candidates.
    let reach = ((m as f64).powf(1.0 / N as f64) + 2.0).ceil() as i64;
    let mut candidates: Vec<([f64; N], [i64; N])> = Vec::new();
    let mut index = [-reach; N];
    loop {
        let mut p = [0.0; N];
        if N == 2 {
            // Hexagonal: row j at height √3 b j, shifted by a on odd rows.
            let row = index[1];
            p[0] = 2.0 * l[0] * index[0] as f64 + if row.rem_euclid(2) == 1 { l[0] } else { 0.0 };
            p[1] = 3f64.sqrt() * l[1] * row as f64;
        } else {
            for k in 0..N {
                p[k] = 2.0 * l[k] * index[k] as f64;
            }
        }
        candidates.push((p, index));
        // Next multi-index.
        let mut k = 0;
        loop {
            if k == N {
                candidates.sort_by(|a, b| {
                    let na: f64 = a.0.iter().map(|v| v * v).sum();
                    let nb: f64 = b.0.iter().map(|v| v * v).sum();
                    na.total_cmp(&nb).then(a.1.cmp(&b.1))
                });
                return candidates.into_iter().take(m).map(|c| c.0).collect();
            }
            index[k] += 1;
            if index[k] <= reach {
                break;
            }
            index[k] = -reach;
            k += 1;
        }
    }
}

/// The start `index` of a run: `x` with every centre coordinate moved by up to
/// `fraction × extent` (the container's half-extent along that axis) and every angle by up to
/// `fraction × π`, from a generator seeded by `(seed, index)`.
pub fn perturb<const N: usize>(
    x: &[f64],
    layout: &Layout,
    fraction: f64,
    seed: u64,
    index: u64,
) -> Vec<f64> {
    let dims = &x[layout.item_variables()..];
    // A periodic cell is the only container with N (N + 1) / 2 dimensions; its centres are
    // fractional, so the half-cell is 1/2.
    let periodic = dims.len() == N * (N + 1) / 2;
    let extent = |k: usize| {
        if periodic {
            0.5
        } else {
            dims.get(k).or(dims.first()).copied().unwrap_or(1.0)
        }
    };
    jittered::<N>(x, layout, (seed, index), |v| {
        Some(
            fraction
                * if v < N {
                    extent(v)
                } else {
                    std::f64::consts::PI
                },
        )
    })
}

/// `x` with every item's angles moved by up to `amplitude` radians, from a generator seeded by
/// `(seed, index)`; centres and container stay.
///
/// On a lattice start every item is unrotated in a mirror-symmetric arrangement, where the
/// model's derivatives in the angles cancel, and a local minimisation can end with the
/// lattice barely changed. For 1000 ellipses (2, 1) in a rectangle, rows along x in a
/// 162 × 43.6 box: 0.89181 from the start as cut, 0.89549 with every angle turned by up to
/// 0.01 rad; the cuts with rows along y end alike either way (0.89293 and 0.89263, 0.89352
/// twice).
pub fn turned<const N: usize>(
    x: &[f64],
    layout: &Layout,
    amplitude: f64,
    seed: u64,
    index: u64,
) -> Vec<f64> {
    jittered::<N>(x, layout, (seed, index), |v| (v >= N).then_some(amplitude))
}

/// `x` with item variable `v` of every item moved by a uniform draw in `±amplitude(v)`
/// (`None`: left, and no draw made), from a generator seeded by `(seed, index)`, item by item.
fn jittered<const N: usize>(
    x: &[f64],
    layout: &Layout,
    (seed, index): (u64, u64),
    amplitude: impl Fn(usize) -> Option<f64>,
) -> Vec<f64> {
    let mut rng = SplitMix64::stream(seed, index);
    let mut y = x.to_vec();
    for i in 0..layout.items() {
        for (v, at) in layout.range(i).enumerate() {
            if let Some(a) = amplitude(v) {
                y[at] += a * (2.0 * rng.uniform() - 1.0);
            }
        }
    }
    y
}

/// SplitMix64 (Steele, Lea, Flood 2014): small, fast and good enough to place perturbations;
/// kept here so that runs are reproducible without a random-number dependency (the crate's
/// tests draw from it too).
pub(crate) struct SplitMix64(u64);

impl SplitMix64 {
    pub(crate) fn new(seed: u64) -> Self {
        Self(seed)
    }

    /// The generator of stream `index` of a run seeded by `seed`.
    pub(crate) fn stream(seed: u64, index: u64) -> Self {
        Self::new(seed ^ index.wrapping_mul(0x9E37_79B9_7F4A_7C15))
    }

    /// Uniform in `[0, 1)`.
    pub(crate) fn uniform(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// The paper's first initial solution for these items ([`lattice_start`]).
///
/// # Errors
/// Errors of [`Model::new`] (no items, invalid semi-axes).
pub fn paper_start<const N: usize>(
    semi_axes: &[[f64; N]],
    kind: ContainerShape,
) -> Result<Vec<f64>, Error> {
    Ok(lattice_start(&Model::<N>::new(semi_axes.to_vec(), kind)?))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn certified<const N: usize>(axes: [f64; N], m: usize, kind: ContainerShape, k: usize) -> f64 {
        let mut p = Model::<N>::new(vec![axes; m], kind).unwrap();
        let x = lattice_start_of(&p, &LatticeStart::sequence(k));
        let c = p.certify(&x).unwrap();
        assert!(c.is_feasible(), "start {k} of {kind:?}: {c:?}");
        crate::local::item_measure(&p) / p.evaluate(&x, None).unwrap().objective
    }

    #[test]
    fn every_start_is_feasible() {
        for kind in [
            ContainerShape::Ball,
            ContainerShape::Ellipsoid,
            ContainerShape::Box,
        ] {
            for k in 0..12 {
                certified([2.0, 1.0], 40, kind, k);
                certified([1.0, 0.75, 0.5], 60, kind, k);
            }
        }
    }

    #[test]
    fn fcc_starts_are_denser_than_the_papers_cubic_start_in_a_box() {
        let m = 100;
        let mut p = Model::<3>::new(vec![[1.0, 0.75, 0.5]; m], ContainerShape::Box).unwrap();
        let paper = crate::starts::lattice_start(&p);
        let paper = crate::local::item_measure(&p) / p.evaluate(&paper, None).unwrap().objective;
        let best = (0..16)
            .map(|k| certified([1.0, 0.75, 0.5], m, ContainerShape::Box, k))
            .fold(0.0, f64::max);
        assert!(best > paper * 1.1, "FCC {best} against cubic {paper}");
    }

    fn cut_density<const N: usize>(p: &mut Model<N>, start: &LatticeStart<N>) -> f64 {
        let x = lattice_start_of(p, start);
        assert!(p.certify(&x).unwrap().is_feasible(), "{start:?}");
        crate::local::item_measure(p) / p.evaluate(&x, None).unwrap().objective
    }

    #[test]
    fn the_tightest_cuts_are_feasible_ranked_distinct_and_beat_the_sequence() {
        let mut p = Model::<2>::new(vec![[2.0, 1.0]; 200], ContainerShape::Box).unwrap();
        let tightest = tightest_lattice_starts(&p, 8);
        assert_eq!(tightest.len(), 8);
        let ranked: Vec<f64> = tightest.iter().map(|s| cut_density(&mut p, s)).collect();
        assert!(ranked.windows(2).all(|w| w[0] >= w[1]), "{ranked:?}");
        let containers: Vec<Vec<f64>> = tightest
            .iter()
            .map(|s| lattice_start_of(&p, s)[200 * 3..].to_vec())
            .collect();
        for (i, a) in containers.iter().enumerate() {
            assert!(
                containers[..i].iter().all(|b| b != a),
                "cut {i} repeats {a:?}"
            );
        }
        let sequence = (0..32)
            .map(|k| cut_density(&mut p, &LatticeStart::sequence(k)))
            .fold(0.0, f64::max);
        assert!(ranked[0] > sequence, "{} against {sequence}", ranked[0]);
    }

    #[test]
    fn a_ball_ranks_orientations_and_shifts_and_a_periodic_cell_nothing() {
        let p = Model::<3>::new(vec![[1.0, 0.75, 0.5]; 50], ContainerShape::Ball).unwrap();
        let tightest = tightest_lattice_starts(&p, 100);
        assert!(!tightest.is_empty() && tightest.len() <= 4 * CUT_SHIFTS);
        assert!(tightest.iter().all(|s| s.aspect == [1.0; 3]));
        assert!(tightest_lattice_starts(&p, 0).is_empty());
        let cell = Model::<2>::new(vec![[2.0, 1.0]; 8], ContainerShape::Periodic).unwrap();
        assert!(tightest_lattice_starts(&cell, 4).is_empty());
    }

    #[test]
    fn a_box_cut_touches_every_wall() {
        let p = Model::<2>::new(vec![[2.0, 1.0]; 37], ContainerShape::Box).unwrap();
        for k in 0..8 {
            let x = lattice_start_of(&p, &LatticeStart::sequence(k));
            let l = lattice_semi_axes(&p);
            for axis in 0..2 {
                let half = x[37 * 3 + axis];
                let (low, high) = (0..37).fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), i| {
                    let c = x[i * 3 + axis];
                    (a.min(c - l[axis]), b.max(c + l[axis]))
                });
                assert!(
                    (high - half).abs() < 1e-6 && (low + half).abs() < 1e-6,
                    "{k}: {low} {high} {half}"
                );
            }
        }
    }

    #[test]
    fn turning_moves_only_angles_within_the_amplitude_and_reproducibly() {
        let p = Model::<3>::new(vec![[1.0, 0.75, 0.5]; 20], ContainerShape::Box).unwrap();
        let x = lattice_start_of(&p, &LatticeStart::sequence(1));
        let y = turned::<3>(&x, p.layout(), 0.01, 7, 3);
        assert_eq!(y, turned::<3>(&x, p.layout(), 0.01, 7, 3));
        assert_ne!(y, turned::<3>(&x, p.layout(), 0.01, 7, 4));
        for (i, (a, b)) in x.iter().zip(&y).enumerate() {
            let angle = i < 20 * 6 && i % 6 >= 3;
            assert!(
                if angle {
                    (a - b).abs() <= 0.01 && a != b
                } else {
                    a == b
                },
                "{i}"
            );
        }
    }

    #[test]
    fn lattice_points_keep_the_minimum_distance() {
        for orientation in 0..4 {
            let s = LatticeStart::<3> {
                orientation,
                ..LatticeStart::centred()
            };
            let b = s.basis();
            for n in [
                [1, 0, 0],
                [0, 1, 0],
                [0, 0, 1],
                [1, -1, 0],
                [1, 0, -1],
                [0, 1, -1],
            ] {
                let v: [f64; 3] =
                    std::array::from_fn(|k| (0..3).map(|r| n[r] as f64 * b[r][k]).sum());
                let d = v.iter().map(|x| x * x).sum::<f64>().sqrt();
                assert!(
                    (d - 2.0).abs() < 1e-12,
                    "orientation {orientation}: {n:?} has {d}"
                );
            }
        }
    }
}
