//! The whole model: the sum of the pair terms over the grid's candidate pairs (Section 5.2),
//! the containment residuals and the objective, with gradients, in `O(m)` time and memory.
//!
//! Variables, in this order ([`Layout`]):
//!
//! ```text
//! x = [ c_1, Ω_1, c_2, Ω_2, …, c_m, Ω_m, container dimensions ]
//! Ω_i = θ_i (eq. 1) or [φ_i, θ_i, ψ_i] (eq. 2), none for a round item (a circle or a ball);
//! container: [r] or N semi-axes / half-sides.
//! ```
//!
//! Quantities (all ≥ 0):
//!
//! ```text
//! overlap     = Σ_{i<j} f(c_i, c_j, Ω_i, Ω_j; P_i, P_j)      (eq. 19; f of eq. 34)
//! containment = Σ_i Σ max{0, g}²                             (crate::containment)
//! objective   = area or volume of the container
//! ```
//!
//! The sum runs over the pairs whose enclosing balls intersect, `|c_i − c_j| < r_i + r_j`
//! (`r_i = max_k l_ik`), found by a uniform grid of cell edge `2R`, `R = max r_i`
//! ([`cell_grid`]): a pair outside this set has `f = 0` exactly (eq. 37), so the sum is the full
//! `O(m²)` sum of eq. 19, computed in `O(m)`. The grid is not rebuilt at every evaluation: it
//! fills a Verlet list ([`cell_grid::PairList`]) with the pairs within `r_i + r_j + s`, the skin
//! `s` a tenth of the smallest enclosing radius ([`PAIR_LIST_SKIN`]), and the list is scanned
//! with the exact test until some ellipsoid has moved by `s/2` since it was built. The pairs are
//! the same as a fresh grid's and are summed in ascending `(i, j)` order, so the model's values
//! are a function of `x` alone, whatever the history of the list.
//!
//! Evaluation reuses the workspace of the [`Model`] (the bodies and the pair list): after the
//! first call no memory is allocated unless `m` grows or a rebuild of the list finds more pairs
//! than any before. With the `rayon` feature the list's rows are cut into ranges of about equal
//! numbers of pairs, one task each; a range keeps its non-zero pair gradients in a vector of its
//! own (kept from call to call), and they are added to the gradient with the items cut into one
//! block per thread, each block taking the terms that land on it in the order of the pairs
//! (module `scatter`), so the gradient has the same bits on any number of threads. The per-body
//! pass (torques to angle derivatives, containment; in a periodic cell the ghosts' forces and
//! the cell's derivatives) runs in fixed groups of 2048 bodies, summed in order. A value-only
//! call does no gradient work.
//! Pairs are skipped at once when their enclosing balls are apart (the list's exact test) or the
//! plane orthogonal to the centre line separates them with a margin (an exact certificate: the pair
//! term is then exactly zero, value and gradient, see
//! [`crate::pair::separated_along_centre_line`]); the rest take the fast direct solve when it
//! applies ([`crate::pair`]), four pairs at a time in AVX registers (module `batch`; the same
//! bits as one at a time, and added in the same order). Each ellipsoid's rotation and the angular
//! velocities of its angles are computed once per evaluation, from one set of sines and cosines;
//! pair gradients add forces to the centres and torques to a per-ellipsoid buffer, which is turned
//! into angle derivatives once per ellipsoid at the end.
//!
//! # References
//! Birgin, Lobato, Martínez (2016), eqs. (18)–(19), (33)–(34), (37), Section 5.2.
//! L. Verlet, Phys. Rev. 159 (1967) 98–103: the neighbour list with a skin.

use crate::batch::{KernelQueue, Term, ValueOnly, WithGradient};
use crate::containment::{
    Container, ContainerShape, ContainmentDirection, containment_gradient,
    containment_gradient_derivative, containment_residual,
};
use crate::derivatives::{
    PairDirection, PairGradient, angle_gradient_3d, angular_velocity_derivatives_3d, pair_gradient,
    pair_gradient_derivative,
};
use crate::error::Error;
use crate::layout::{
    Layout, frame_times, spheroid_axis, spheroid_frame_rotation, spheroid_rotation, spheroid_rows,
};
use crate::pair::overlap_measure;
use crate::periodic::{ImageSet, Lattice, entry};
#[cfg(feature = "rayon")]
use crate::scatter::Entry;
use crate::shape::{
    Body, MAX_MAGNITUDE, angles_from_rotation, angular_velocities_3d, check_semi_axes, rotation_2d,
    rotation_and_velocities_3d,
};

/// Values of the model at one point.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Evaluation {
    /// `Σ_{i<j} f_ij` (eq. 19).
    pub overlap: f64,
    /// `Σ_i` containment residual.
    pub containment: f64,
    /// Container area (2D) or volume (3D).
    pub objective: f64,
    /// Number of pairs whose term was evaluated (enclosing balls intersect).
    pub pairs: usize,
}

/// Gradients of the three model quantities, each laid out like the variables.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ModelGradient {
    /// `∇ overlap`.
    pub overlap: Vec<f64>,
    /// `∇ containment`.
    pub containment: Vec<f64>,
    /// `∇ objective` (non-zero only on the container variables).
    pub objective: Vec<f64>,
}

impl ModelGradient {
    fn reset(&mut self, n: usize) {
        for v in [
            &mut self.overlap,
            &mut self.containment,
            &mut self.objective,
        ] {
            v.resize(n, 0.0);
            fill(v, 0.0);
        }
    }
}

pub use crate::certificate::Certificate;

/// A packing problem: the semi-axes of the `m` ellipsoids and the kind of container, with the
/// workspace reused by every evaluation.
#[derive(Debug)]
pub struct Model<const N: usize> {
    semi_axes: Vec<[f64; N]>,
    layout: Layout,
    kind: ContainerShape,
    bodies: Vec<Body<N>>,
    centres: Vec<[f64; N]>,
    // Per ellipsoid, computed once per evaluation by `load`: (sin ψ, cos ψ) of eq. 2's third
    // angle, from which `spin_rows` rebuilds the angular velocities ω_α of the angles (row α,
    // world frame) that turn a torque into angle derivatives. The pair gradients only
    // accumulate torques (`torques`), and each ellipsoid's are turned into angle derivatives
    // once, instead of once per pair (that cost two `sin_cos` per side). Two numbers instead
    // of the nine of ω: at m = 1e5 this array is written and read on every evaluation.
    spins: Vec<[f64; 2]>,
    torques: Vec<[f64; 3]>,
    // The summed pair forces on a periodic cell's points (items and ghosts).
    forces: Vec<[f64; N]>,
    // The candidate pairs: a Verlet list over the grid (cell edge 2R plus the skin), rebuilt
    // only when an ellipsoid has moved more than half the skin since the last build.
    pairs: cell_grid::PairList<N>,
    // The pair sums' per-range shares with the `rayon` feature (nothing without it).
    ranges: RangeWork<N>,
    // In a periodic cell: the fractional positions, the images and their own list.
    lattice: Option<Lattice<N>>,
    // The threads of the evaluations (`None`: rayon's global pool, or the caller's).
    #[cfg(feature = "rayon")]
    pool: Option<std::sync::Arc<rayon::ThreadPool>>,
}

/// The skin of the model's pair list, relative to the smallest enclosing radius: pairs
/// with `|c_i − c_j| < r_i + r_j + s` are listed, and the list is rebuilt once an ellipsoid
/// has moved by `s/2`.
///
/// Relative to the smallest radius so that, with mixed sizes, the skin adds at most a tenth
/// of `2 r_min` to any pair's reach (16 % more listed than close pairs in the `model` bench, 3D
/// at density 0.6). In a local minimisation the list is rebuilt once every few hundred
/// evaluations (the `local_minimisation` example prints the count), and a build costs about
/// one evaluation (the `model` bench prints both), so its upkeep is amortised. (Counted on one
/// run with other skins, relative to the largest radius: a twentieth was outrun twice as
/// often, a fifth half as often.)
pub const PAIR_LIST_SKIN: f64 = 0.1;

/// Number of rotation angles in dimension `n` (1 in 2D, 3 in 3D).
pub const fn angle_count(n: usize) -> usize {
    n * (n - 1) / 2
}

impl<const N: usize> Model<N> {
    /// A problem with the given semi-axes (one `[l_1, …, l_N]` per ellipsoid) and container kind.
    ///
    /// # Errors
    /// [`Error::Empty`] without ellipsoids, [`Error::InvalidSemiAxis`] naming the ellipsoid and
    /// the semi-axis that is not in `[1e-30, 1e30]`.
    pub fn new(semi_axes: Vec<[f64; N]>, kind: ContainerShape) -> Result<Self, Error> {
        if semi_axes.is_empty() {
            return Err(Error::Empty);
        }
        for (i, l) in semi_axes.iter().enumerate() {
            check_semi_axes(Some(i), l)?;
        }
        let radii: Vec<f64> = semi_axes
            .iter()
            .map(|l| l.iter().fold(0.0f64, |m, &x| m.max(x)))
            .collect();
        let r_min = radii.iter().fold(f64::INFINITY, |m, &r| m.min(r));
        let pairs = cell_grid::PairList::new(
            cell_grid::GridBuilder::with_radii(&radii),
            PAIR_LIST_SKIN * r_min,
        )
        .map_err(grid_error)?;
        let r_max = radii.iter().fold(0.0f64, |m, &r| m.max(r));
        let lattice =
            (kind == ContainerShape::Periodic).then(|| Lattice::new(r_max, PAIR_LIST_SKIN * r_min));
        Ok(Model {
            layout: Layout::of(&semi_axes),
            semi_axes,
            kind,
            lattice,
            bodies: Vec::new(),
            centres: Vec::new(),
            spins: Vec::new(),
            torques: Vec::new(),
            forces: Vec::new(),
            pairs,
            ranges: RangeWork::default(),
            #[cfg(feature = "rayon")]
            pool: None,
        })
    }

    /// Evaluates on `threads` threads of a pool of the model's own (0: on the caller's pool,
    /// rayon's global one by default: every core). The values and gradients are the same bits
    /// on any number of threads: the pair sums are cut into ranges by the pair list alone and
    /// summed in their order, the gradient scattered in the order of the pairs.
    ///
    /// # Errors
    /// [`Error::ThreadPool`] when the threads cannot be started.
    #[cfg(feature = "rayon")]
    pub fn set_threads(&mut self, threads: usize) -> Result<(), Error> {
        self.pool = match threads {
            0 => None,
            n => Some(std::sync::Arc::new(thread_pool(n)?)),
        };
        Ok(())
    }

    /// Number of ellipsoids `m`.
    pub fn len(&self) -> usize {
        self.semi_axes.len()
    }

    /// Always false: a problem has at least one ellipsoid.
    pub fn is_empty(&self) -> bool {
        self.semi_axes.is_empty()
    }

    /// Where each item's variables are: its centre, then its angles (none for a round item).
    pub fn layout(&self) -> &Layout {
        &self.layout
    }

    /// Total number of variables.
    pub fn var_count(&self) -> usize {
        self.layout.item_variables() + self.kind.dimension_count(N)
    }

    /// The container kind.
    pub fn container_kind(&self) -> ContainerShape {
        self.kind
    }

    /// The semi-axes of the ellipsoids.
    pub fn semi_axes(&self) -> &[[f64; N]] {
        &self.semi_axes
    }

    /// Reads the bodies and the container from `x` into the workspace.
    fn load(&mut self, x: &[f64]) -> Result<Container<N>, Error> {
        let n = self.var_count();
        Error::check_length("variables", n, x.len())?;
        if let Some(index) = first_bad_variable::<N>(x, &self.layout) {
            let value = x[index];
            return Err(Error::NonFiniteVariable { index, value });
        }
        let layout = &self.layout;
        let container = Container::from_dimensions(self.kind, &x[layout.item_variables()..])?;
        self.bodies.clear();
        self.centres.clear();
        self.spins.clear();
        if let (Some(lattice), Container::Periodic { cell }) = (&mut self.lattice, container) {
            // The centre variables are fractional coordinates: the body sits at H s.
            fractional_centres(x, layout, &mut lattice.fractional)?;
            let fractional = &lattice.fractional;
            let body_at = |(i, l): (usize, &[f64; N])| {
                let mut vars = [0.0; 6];
                let own = layout.range(i);
                let width = own.len();
                vars[..width].copy_from_slice(&x[own]);
                vars[..N].copy_from_slice(&crate::periodic::to_cartesian(&cell, &fractional[i]));
                make_body_and_spins(l, &vars[..width])
            };
            make_bodies(&self.semi_axes, body_at, &mut self.bodies, &mut self.spins);
            lattice.update(&cell, &self.bodies)?;
            return Ok(container);
        }
        let body_of = |(i, l): (usize, &[f64; N])| make_body_and_spins(l, &x[layout.range(i)]);
        make_bodies(&self.semi_axes, body_of, &mut self.bodies, &mut self.spins);
        self.centres.extend(self.bodies.iter().map(|b| b.centre()));
        Ok(container)
    }

    /// Evaluates the model at `x`; fills `gradient` (resized to the variable count) when given.
    ///
    /// # Errors
    /// [`Error::LengthMismatch`] if `x` has the wrong length, [`Error::NonFiniteVariable`] for a
    /// NaN or infinite variable (or a centre coordinate beyond `1e30`),
    /// [`Error::InvalidContainer`] for a non-positive container dimension.
    pub fn evaluate(
        &mut self,
        x: &[f64],
        gradient: Option<&mut ModelGradient>,
    ) -> Result<Evaluation, Error> {
        #[cfg(feature = "rayon")]
        if let Some(pool) = self.pool.clone() {
            return pool.install(|| self.evaluate_here(x, gradient));
        }
        self.evaluate_here(x, gradient)
    }

    /// [`Model::evaluate`] on the current thread's pool.
    fn evaluate_here(
        &mut self,
        x: &[f64],
        gradient: Option<&mut ModelGradient>,
    ) -> Result<Evaluation, Error> {
        let container = self.load(x)?;
        if let Container::Periodic { cell } = container {
            return self.evaluate_periodic(&cell, x.len(), gradient);
        }
        let (objective, dobj) = container.measure();
        let mut ev = Evaluation {
            objective,
            ..Evaluation::default()
        };
        let layout = &self.layout;
        let nb = layout.item_variables();
        let (list, centres) = (&mut self.pairs, &self.centres);
        let bodies = &self.bodies;
        let spins = &self.spins;
        match gradient {
            None => {
                let (sum, count) = pair_sum_value((list, centres), bodies, &mut self.ranges)?;
                ev.overlap = sum;
                ev.pairs = count;
                ev.containment = containment_sum(bodies, &container);
            }
            Some(g) => {
                g.reset(x.len());
                let (sum, count) = pair_sum_gradient(
                    (list, centres),
                    (bodies, layout),
                    &mut self.ranges,
                    &mut self.torques,
                    &mut g.overlap,
                )?;
                ev.overlap = sum;
                ev.pairs = count;
                // One pass over the bodies for both: the overlap's torques become angle
                // derivatives, and the containment residuals with their gradients. At m = 1e5
                // the bodies no longer fit in the last-level cache, and each pass over them
                // costs several ns per ellipsoid.
                let (r, dc) = body_terms(
                    (bodies, spins, &self.torques),
                    layout,
                    &container,
                    &mut g.overlap[..nb],
                    &mut g.containment[..nb],
                );
                ev.containment = r;
                for k in 0..self.kind.dimension_count(N) {
                    g.containment[nb + k] += dc[k];
                }
                let nc = self.kind.dimension_count(N);
                g.objective[nb..nb + nc].copy_from_slice(&dobj[..nc]);
            }
        }
        Ok(ev)
    }

    /// Hessian–vector products `H v` of the three model quantities.
    ///
    /// * Overlap: exact, the sum over the pairs with `f > 0` of the directional derivatives of
    ///   the pair gradients ([`pair_gradient_derivative`]: Appendix A.1's implicit derivatives
    ///   differentiated once more, in the form of a product rule through the force/torque
    ///   expressions), plus the curvature of the angle parametrisation
    ///   (`Σ_β ∂ω_α/∂β v_β · torque`). A pair exactly in the hard case (no Hessian there) falls
    ///   back to a central difference of its gradient.
    /// * Containment: exact, body by body ([`containment_gradient_derivative`]). An ellipsoid in
    ///   the hard case of its farthest point (no Hessian there) falls back to a central
    ///   difference of its gradient, `(∇r(x + h v) − ∇r(x − h v)) / 2h`,
    ///   `h = 6e-6 · max(1, |x|∞) / |v|∞` (≈ ε^⅓).
    /// * Objective: exact.
    ///
    /// Serial (also with the `rayon` feature); no allocation once `out` is sized.
    ///
    /// # Errors
    /// Those of [`Model::evaluate`], and [`Error::LengthMismatch`] or
    /// [`Error::NonFiniteVariable`] for a bad direction `v`.
    pub fn hessian_vector_product(
        &mut self,
        x: &[f64],
        v: &[f64],
        out: &mut ModelGradient,
    ) -> Result<(), Error> {
        let n = self.var_count();
        Error::check_length("direction", n, v.len())?;
        if let Some(index) = v.iter().position(|a| !a.is_finite()) {
            return Err(Error::NonFiniteVariable {
                index,
                value: v[index],
            });
        }
        let container = self.load(x)?;
        if let Container::Periodic { .. } = container {
            return self.hessian_product_periodic(x, v, &container, out);
        }
        out.reset(n);
        let layout = &self.layout;
        let nb = layout.item_variables();
        let nc = self.kind.dimension_count(N);
        let (list, centres) = (&mut self.pairs, &self.centres);
        let bodies = &self.bodies;
        let vmax = v.iter().fold(0.0f64, |m, a| m.max(a.abs()));
        if vmax == 0.0 {
            return Ok(());
        }
        let h = 6e-6 * x.iter().fold(1.0f64, |m, a| m.max(a.abs())) / vmax;
        let semi_axes = &self.semi_axes;
        let shifted = |i: usize, sign: f64| -> Body<N> {
            let mut vars = [0.0; 6];
            let own = layout.range(i);
            for (k, at) in own.clone().enumerate() {
                vars[k] = x[at] + sign * h * v[at];
            }
            make_body(&semi_axes[i], &vars[..own.len()])
        };
        {
            let out_overlap = &mut out.overlap;
            list.for_each_close_pair(centres, |i, j, _, _| {
                let dir = direction((x, v), (layout, semi_axes), i, j);
                match pair_gradient_derivative(&bodies[i], &bodies[j], &dir) {
                    Some((f, grad, hv)) => {
                        if f > 0.0 {
                            let (ri, rj) = (layout.range(i), layout.range(j));
                            scatter_second(
                                (&x[ri.clone()], &v[ri.clone()], &mut out_overlap[ri]),
                                &semi_axes[i],
                                &hv.centre_i,
                                &hv.angular_i,
                                &grad.angular_i,
                            );
                            scatter_second(
                                (&x[rj.clone()], &v[rj.clone()], &mut out_overlap[rj]),
                                &semi_axes[j],
                                &hv.centre_j,
                                &hv.angular_j,
                                &grad.angular_j,
                            );
                        }
                    }
                    None => {
                        let (_, gp) = pair_gradient(&shifted(i, 1.0), &shifted(j, 1.0));
                        let (_, gm) = pair_gradient(&shifted(i, -1.0), &shifted(j, -1.0));
                        let xp = shifted_vars(x, v, h);
                        let xm = shifted_vars(x, v, -h);
                        let inv = 0.5 / h;
                        let sides = [
                            (
                                i,
                                (&gp.centre_i, &gp.angular_i),
                                (&gm.centre_i, &gm.angular_i),
                            ),
                            (
                                j,
                                (&gp.centre_j, &gp.angular_j),
                                (&gm.centre_j, &gm.angular_j),
                            ),
                        ];
                        for (b, (fp, tp), (fm, tm)) in sides {
                            let own = layout.range(b);
                            let (mut tmp_p, mut tmp_m) = ([0.0; 6], [0.0; 6]);
                            let width = own.len();
                            let l = &semi_axes[b];
                            body_gradient_into((&xp, own.start), l, fp, tp, &mut tmp_p[..width]);
                            body_gradient_into((&xm, own.start), l, fm, tm, &mut tmp_m[..width]);
                            for (k, at) in own.enumerate() {
                                out_overlap[at] += (tmp_p[k] - tmp_m[k]) * inv;
                            }
                        }
                    }
                }
            })
            .map_err(grid_error)?;
        }
        let mut dims_p = [0.0; N];
        let mut dims_m = [0.0; N];
        for k in 0..nc {
            dims_p[k] = x[nb + k] + h * v[nb + k];
            dims_m[k] = x[nb + k] - h * v[nb + k];
        }
        let cont_p = Container::from_dimensions(self.kind, &dims_p[..nc])?;
        let cont_m = Container::from_dimensions(self.kind, &dims_m[..nc])?;
        let xp = ShiftedVars { x, v, h };
        let xm = ShiftedVars { x, v, h: -h };
        let mut dcont = [0.0; N];
        dcont[..nc].copy_from_slice(&v[nb..nb + nc]);
        for i in 0..self.len() {
            let own = layout.range(i);
            let d = direction((x, v), (layout, semi_axes), i, i);
            let cdir = ContainmentDirection {
                centre: d.centre_i,
                spin: d.angular_i,
                container: dcont,
            };
            if let Some((r, grad, hv)) =
                containment_gradient_derivative(&bodies[i], &container, &cdir)
            {
                if r > 0.0 {
                    scatter_second(
                        (&x[own.clone()], &v[own.clone()], &mut out.containment[own]),
                        &semi_axes[i],
                        &hv.centre,
                        &hv.torque,
                        &grad.torque,
                    );
                    for k in 0..nc {
                        out.containment[nb + k] += hv.container[k];
                    }
                }
                continue;
            }
            // Hard case of the farthest point: a central difference of the exact gradient.
            let (_, gp) = containment_gradient(&shifted(i, 1.0), &cont_p);
            let (_, gm) = containment_gradient(&shifted(i, -1.0), &cont_m);
            let inv = 0.5 / h;
            let mut tp = [0.0; 6];
            let mut tm = [0.0; 6];
            let width = own.len();
            let l = &semi_axes[i];
            body_gradient_into(
                (&xp, own.start),
                l,
                &gp.centre,
                &gp.torque,
                &mut tp[..width],
            );
            body_gradient_into(
                (&xm, own.start),
                l,
                &gm.centre,
                &gm.torque,
                &mut tm[..width],
            );
            for (k, at) in own.enumerate() {
                out.containment[at] += (tp[k] - tm[k]) * inv;
            }
            for k in 0..nc {
                out.containment[nb + k] += (gp.container[k] - gm.container[k]) * inv;
            }
        }
        // Objective: Hessian of the area/volume of the container.
        let hess = container.measure_hessian();
        for r in 0..nc {
            out.objective[nb + r] = (0..nc).map(|c| hess[r][c] * v[nb + c]).sum();
        }
        Ok(())
    }

    /// Certifies a configuration independently of the model ([`crate::certificate::certify`]
    /// on the bodies and the container that `x` stands for).
    ///
    /// # Errors
    /// Those of [`Model::evaluate`], and those of [`crate::certificate::certify`].
    pub fn certify(&mut self, x: &[f64]) -> Result<Certificate, Error> {
        #[cfg(feature = "rayon")]
        if let Some(pool) = self.pool.clone() {
            return pool.install(|| self.certify_here(x));
        }
        self.certify_here(x)
    }

    /// [`Model::certify`] on the current thread's pool.
    fn certify_here(&mut self, x: &[f64]) -> Result<Certificate, Error> {
        let container = self.load(x)?;
        crate::certificate::certify(&self.bodies, &container)
    }

    /// Reference: the overlap sum of eq. 19 over **all** `m(m−1)/2` pairs, `O(m²)` (in a
    /// periodic cell, over every item and every image within reach).
    pub fn overlap_all_pairs(&mut self, x: &[f64]) -> Result<f64, Error> {
        if let Container::Periodic { cell } = self.load(x)? {
            return Ok(self.overlap_all_images(&cell));
        }
        let b = &self.bodies;
        let mut sum = 0.0;
        for i in 0..b.len() {
            for j in i + 1..b.len() {
                sum += overlap_measure(&b[i], &b[j]);
            }
        }
        Ok(sum)
    }

    /// How many times the pair list has been built (see [`PAIR_LIST_SKIN`]): once per
    /// evaluation would mean that the skin is outrun at every step.
    pub fn pair_list_builds(&self) -> usize {
        self.pairs.builds() + self.lattice.as_ref().map_or(0, Lattice::builds)
    }

    /// The bodies of the last evaluation.
    pub fn bodies(&self) -> &[Body<N>] {
        &self.bodies
    }

    /// The container that the variables `x` stand for (centred at the origin).
    ///
    /// # Errors
    /// As [`Model::evaluate`].
    pub fn container_at(&mut self, x: &[f64]) -> Result<Container<N>, Error> {
        self.load(x)
    }

    /// The bodies (centres and rotations) that the variables `x` stand for.
    ///
    /// # Errors
    /// As [`Model::evaluate`].
    pub fn bodies_at(&mut self, x: &[f64]) -> Result<&[Body<N>], Error> {
        self.load(x)?;
        Ok(&self.bodies)
    }

    /// The variable vector of a configuration: each body's centre and angles (eq. 1's `θ`, or
    /// eq. 2's `[φ, θ, ψ]` recovered from the rotation, e.g. of a quaternion; none for a round
    /// item, whose rotation is dropped, and a spheroid's `[θ, ψ]` of the direction of its
    /// distinct axis, its turn about that axis dropped: see [`Layout`]), then the container
    /// dimensions.
    ///
    /// # Errors
    /// [`Error::LengthMismatch`] if the number of bodies or dimensions is wrong,
    /// [`Error::InvalidSemiAxis`] naming the body whose semi-axes differ from the problem's.
    pub fn pack_variables(&self, bodies: &[Body<N>], container: &[f64]) -> Result<Vec<f64>, Error> {
        Error::check_length("bodies", self.len(), bodies.len())?;
        let nc = self.kind.dimension_count(N);
        Error::check_length("container dimensions", nc, container.len())?;
        let cell = match Container::<N>::from_dimensions(self.kind, container)? {
            Container::Periodic { cell } => Some(cell),
            _ => None,
        };
        let mut x = Vec::with_capacity(self.var_count());
        for (i, b) in bodies.iter().enumerate() {
            let l = b.semi_axes();
            if let Some(axis) = (0..N).find(|&k| l[k] != self.semi_axes[i][k]) {
                return Err(Error::InvalidSemiAxis {
                    item: Some(i),
                    axis,
                    value: l[axis],
                });
            }
            match &cell {
                Some(cell) => {
                    x.extend_from_slice(&crate::periodic::to_fractional(cell, &b.centre()))
                }
                None => x.extend_from_slice(&b.centre()),
            }
            let q = b.rotation();
            if self.layout.angles(i) == 0 {
                continue;
            }
            if N == 2 {
                x.push(q[1][0].atan2(q[0][0]));
            } else {
                let mut m = [[0.0; 3]; 3];
                for r in 0..3 {
                    for c in 0..3 {
                        m[r][c] = q[r][c];
                    }
                }
                match spheroid_axis(&self.semi_axes[i]) {
                    // Only the direction of the distinct axis counts: `R e_1 = P_d Q e_d`,
                    // whatever `R`'s φ.
                    Some(d) => {
                        let angles = angles_from_rotation(&spheroid_frame_rotation(d, &m));
                        x.extend_from_slice(&angles[1..]);
                    }
                    None => x.extend_from_slice(&angles_from_rotation(&m)),
                }
            }
        }
        x.extend_from_slice(container);
        Ok(x)
    }
}

/// The running sums of the periodic gradient: `Σf`, the force on every point (item or
/// image) and the torque on every item.
struct PeriodicSums<'a, const N: usize> {
    sum: f64,
    forces: &'a mut Vec<[f64; N]>,
    torques: &'a mut Vec<[f64; 3]>,
}

impl<const N: usize> PeriodicSums<'_, N> {
    #[cfg(not(feature = "rayon"))]
    fn add(&mut self, owner: &[u32], a: usize, b: usize, &(f, ref g): &Term<N>) {
        if f > 0.0 {
            self.sum += f;
            self.add_gradient(owner, a, b, g);
        }
    }

    /// The forces of a pair term on its two points, its torques on their owners.
    #[cfg(not(feature = "rayon"))]
    fn add_gradient(&mut self, owner: &[u32], a: usize, b: usize, g: &PairGradient<N>) {
        for k in 0..N {
            self.forces[a][k] += g.centre_i[k];
            self.forces[b][k] += g.centre_j[k];
        }
        let (oa, ob) = (owner[a] as usize, owner[b] as usize);
        for k in 0..3 {
            self.torques[oa][k] += g.angular_i[k];
            self.torques[ob][k] += g.angular_j[k];
        }
    }
}

use crate::certificate::MAX_CELLS;

/// The periodic cell ([`crate::periodic`]): pair terms over the lattice images, no containment,
/// the objective `det H`.
impl<const N: usize> Model<N> {
    fn evaluate_periodic(
        &mut self,
        cell: &[[f64; N]; N],
        n: usize,
        gradient: Option<&mut ModelGradient>,
    ) -> Result<Evaluation, Error> {
        let (objective, dobj) = Container::Periodic { cell: *cell }.measure();
        let mut ev = Evaluation {
            objective,
            ..Evaluation::default()
        };
        let lattice = self.lattice.as_mut().ok_or(Error::Empty)?;
        match gradient {
            None => {
                (ev.overlap, ev.pairs) = periodic_pair_value(lattice, &mut self.ranges)?;
            }
            Some(g) => {
                g.reset(n);
                ev.overlap = self.periodic_gradient(cell, &mut g.overlap, &mut ev.pairs)?;
                let nb = self.layout.item_variables();
                g.objective[nb..nb + N].copy_from_slice(&dobj);
            }
        }
        Ok(ev)
    }

    /// Σf over the lattice pairs, its gradient added to `out` (fractional centres, angles,
    /// cell entries), the pair count added to `pairs`.
    fn periodic_gradient(
        &mut self,
        cell: &[[f64; N]; N],
        out: &mut [f64],
        pairs: &mut usize,
    ) -> Result<f64, Error> {
        let m = self.len();
        let lattice = self.lattice.as_mut().ok_or(Error::Empty)?;
        // Forces per point (item or image), torques per item.
        let forces = &mut self.forces;
        forces.resize(lattice.images.owner.len(), [0.0; N]);
        fill(forces, [0.0; N]);
        self.torques.resize(m, [0.0; 3]);
        fill(&mut self.torques, [0.0; 3]);
        let mut acc = PeriodicSums {
            sum: 0.0,
            forces,
            torques: &mut self.torques,
        };
        #[cfg(not(feature = "rayon"))]
        {
            let mut queue = KernelQueue::<N, WithGradient>::default();
            lattice.for_each_pair(|(bodies, owner), a, b| {
                *pairs += 1;
                queue.push(bodies, a, b, &mut |a, b, t| acc.add(owner, a, b, t));
            })?;
            let (bodies, owner) = lattice.points();
            queue.flush(bodies, &mut |a, b, t| acc.add(owner, a, b, t));
        }
        #[cfg(feature = "rayon")]
        {
            let ranges = &mut self.ranges.gradients;
            lattice.par_fold_pairs_into(ranges, restart_terms, |s, (bodies, _), a, b| {
                add_term(s, bodies, a, b)
            })?;
            let bodies = lattice.points().0;
            for RangeShare { kept, queue } in ranges.iter_mut() {
                queue.flush(bodies, &mut keep(kept));
                acc.sum += kept.0;
                *pairs += kept.1;
            }
            let lists: Vec<&[Entry<N>]> = ranges.iter().map(|s| s.kept.2.as_slice()).collect();
            crate::scatter::add_to_points(&lists, &lattice.images, acc.forces, acc.torques);
        }
        let sum = acc.sum;
        let nb = self.layout.item_variables();
        let dcell = cell_gradient(
            (cell, &lattice.images, &lattice.fractional),
            (&self.forces, &self.torques),
            (&self.bodies, &self.spins),
            (&self.layout, &mut out[..nb]),
        );
        for k in 0..N * (N + 1) / 2 {
            let (r, c) = entry::<N>(k);
            out[nb + k] += dcell[r][c];
        }
        Ok(sum)
    }

    /// Hessian–vector products in a periodic cell: the overlap's by a central difference of
    /// its exact gradient, `(∇(x + h v) − ∇(x − h v)) / 2h` with `h` as in
    /// [`Model::hessian_vector_product`]; the objective's exactly; no containment.
    fn hessian_product_periodic(
        &mut self,
        x: &[f64],
        v: &[f64],
        container: &Container<N>,
        out: &mut ModelGradient,
    ) -> Result<(), Error> {
        let n = x.len();
        out.reset(n);
        let vmax = v.iter().fold(0.0f64, |m, a| m.max(a.abs()));
        if vmax == 0.0 {
            return Ok(());
        }
        let h = 6e-6 * x.iter().fold(1.0f64, |m, a| m.max(a.abs())) / vmax;
        let mut gp = ModelGradient::default();
        let mut gm = ModelGradient::default();
        let xp: Vec<f64> = x.iter().zip(v).map(|(a, b)| a + h * b).collect();
        let xm: Vec<f64> = x.iter().zip(v).map(|(a, b)| a - h * b).collect();
        self.evaluate(&xp, Some(&mut gp))?;
        self.evaluate(&xm, Some(&mut gm))?;
        for k in 0..n {
            out.overlap[k] = (gp.overlap[k] - gm.overlap[k]) / (2.0 * h);
        }
        let hess = container.measure_hessian();
        let nb = self.layout.item_variables();
        for r in 0..N {
            out.objective[nb + r] = (0..N).map(|c| hess[r][c] * v[nb + c]).sum();
        }
        // Leave the workspace at x, as the other paths do.
        self.load(x)?;
        Ok(())
    }

    /// The variables `x` of a configuration dilated by `s > 0` about the origin: every length
    /// (centres and container dimensions) times `s`, angles unchanged. Every pair's contact
    /// function is multiplied by `s²` (PW85 theory). In a periodic cell the centres are
    /// fractional and only the cell is scaled.
    pub fn dilated(&self, x: &[f64], s: f64) -> Vec<f64> {
        let mut y = x.to_vec();
        let bodies_end = self.layout.item_variables().min(y.len());
        for v in &mut y[bodies_end..] {
            *v *= s;
        }
        if self.kind != ContainerShape::Periodic {
            for i in 0..self.len() {
                let start = self.layout.start(i);
                for v in y.iter_mut().skip(start).take(N) {
                    *v *= s;
                }
            }
        }
        y
    }

    /// Reference for the periodic cell: the overlap sum over every pair of the lattice by brute
    /// force, each item against every image of every item within reach, `O(m²)`.
    fn overlap_all_images(&mut self, cell: &[[f64; N]; N]) -> f64 {
        let w = crate::periodic::widths(cell);
        let b = &self.bodies;
        let s: Vec<[f64; N]> = b
            .iter()
            .map(|x| crate::periodic::to_fractional(cell, &x.centre()))
            .collect();
        let mut sum = 0.0;
        for i in 0..b.len() {
            for j in i..b.len() {
                let reach = b[i].bounding_radius() + b[j].bounding_radius();
                let d: [f64; N] = std::array::from_fn(|k| s[j][k] - s[i][k]);
                let lo: [i32; N] = std::array::from_fn(|k| (-d[k] - reach / w[k]).floor() as i32);
                let hi: [i32; N] = std::array::from_fn(|k| (-d[k] + reach / w[k]).ceil() as i32);
                let mut n = lo;
                loop {
                    let positive = n.iter().find(|&&v| v != 0).is_some_and(|&v| v > 0);
                    if i < j || positive {
                        let t: [f64; N] = std::array::from_fn(|k| s[j][k] + f64::from(n[k]));
                        let c = crate::periodic::to_cartesian(cell, &t);
                        let image =
                            Body::from_parts_unchecked(c, b[j].semi_axes(), b[j].rotation());
                        sum += overlap_measure(&b[i], &image);
                    }
                    let mut k = 0;
                    while k < N {
                        if n[k] < hi[k] {
                            n[k] += 1;
                            break;
                        }
                        n[k] = lo[k];
                        k += 1;
                    }
                    if k == N {
                        break;
                    }
                }
            }
        }
        sum
    }
}

/// Σf over the representative pairs of a periodic cell's points, and their number: on rayon's
/// pool range by range with the `rayon` feature (the same sum on any number of threads).
fn periodic_pair_value<const N: usize>(
    lattice: &mut crate::periodic::Lattice<N>,
    #[cfg_attr(not(feature = "rayon"), allow(unused_variables))] ranges: &mut RangeWork<N>,
) -> Result<(f64, usize), Error> {
    #[cfg(not(feature = "rayon"))]
    {
        let (mut sum, mut count) = (0.0, 0);
        let mut queue = KernelQueue::<N, ValueOnly>::default();
        let mut emit = |_: usize, _: usize, &f: &f64| sum += f;
        lattice.for_each_pair(|(bodies, _), a, b| {
            count += 1;
            queue.push(bodies, a, b, &mut emit);
        })?;
        queue.flush(lattice.points().0, &mut emit);
        Ok((sum, count))
    }
    #[cfg(feature = "rayon")]
    {
        lattice.par_fold_pairs_into(
            &mut ranges.values,
            |s| s.kept = (0.0, 0, ()),
            |s, (bodies, _), a, b| add_value(s, bodies, a, b),
        )?;
        Ok(summed_values(&mut ranges.values, lattice.points().0))
    }
}

/// A range's share of a value-only pair sum after one more pair.
#[cfg(feature = "rayon")]
fn add_value<const N: usize>(
    share: &mut RangeShare<(f64, usize, ()), N, ValueOnly>,
    bodies: &[Body<N>],
    i: usize,
    j: usize,
) {
    let RangeShare { kept, queue } = share;
    kept.1 += 1;
    queue.push(bodies, i, j, &mut |_, _, &f| kept.0 += f);
}

/// Σf and the pair count of the ranges' shares, each queue flushed, in the order of the
/// ranges (each queue's last pairs after its others: the order of the serial scan).
#[cfg(feature = "rayon")]
fn summed_values<const N: usize>(
    shares: &mut [RangeShare<(f64, usize, ()), N, ValueOnly>],
    bodies: &[Body<N>],
) -> (f64, usize) {
    let (mut sum, mut count) = (0.0, 0);
    for RangeShare { kept, queue } in shares {
        queue.flush(bodies, &mut |_, _, &f| kept.0 += f);
        sum += kept.0;
        count += kept.1;
    }
    (sum, count)
}

/// The model's error for a failure of the neighbour search.
fn grid_error(e: cell_grid::Error) -> Error {
    Error::Grid(e)
}

/// The pair list and the centres it is queried at.
type Candidates<'a, const N: usize> = (&'a mut cell_grid::PairList<N>, &'a [[f64; N]]);

/// The rayon pair sums' workspace; nothing on one thread.
#[cfg(not(feature = "rayon"))]
#[derive(Debug, Default)]
struct RangeWork<const N: usize> {}

#[cfg(not(feature = "rayon"))]
fn pair_sum_value<const N: usize>(
    (list, centres): Candidates<'_, N>,
    bodies: &[Body<N>],
    _: &mut RangeWork<N>,
) -> Result<(f64, usize), Error> {
    let mut sum = 0.0;
    let count = through_kernel::<N, ValueOnly>((list, centres), bodies, &mut |_, _, &f| sum += f)?;
    Ok((sum, count))
}

/// Every close pair through the kernel, four at a time; `emit` receives the results in the
/// order of the pairs, so sums over them are those of a plain loop of scalar calls. Returns
/// the number of close pairs.
#[cfg(not(feature = "rayon"))]
fn through_kernel<const N: usize, K: crate::batch::Kernel<N>>(
    (list, centres): Candidates<'_, N>,
    bodies: &[Body<N>],
    emit: &mut impl FnMut(usize, usize, &K::Out),
) -> Result<usize, Error> {
    let mut count = 0;
    let mut queue = KernelQueue::<N, K>::default();
    list.for_each_close_pair(centres, |i, j, _, _| {
        count += 1;
        queue.push(bodies, i, j, emit);
    })
    .map_err(grid_error)?;
    queue.flush(bodies, emit);
    Ok(count)
}

#[cfg(feature = "rayon")]
fn pair_sum_value<const N: usize>(
    (list, centres): Candidates<'_, N>,
    bodies: &[Body<N>],
    ranges: &mut RangeWork<N>,
) -> Result<(f64, usize), Error> {
    list.par_fold_close_pairs_into(
        centres,
        0..centres.len(),
        &mut ranges.values,
        |s| s.kept = (0.0, 0, ()),
        |s, i, j, _, _| add_value(s, bodies, i, j),
    )
    .map_err(grid_error)?;
    Ok(summed_values(&mut ranges.values, bodies))
}

/// Bodies per task of [`body_terms`]: fixed, so that its sums are grouped the same way on
/// any number of threads.
const BODIES_PER_TASK: usize = 2048;

/// `Σ_b r_b`, the containment residuals summed as in [`body_terms`].
fn containment_sum<const N: usize>(bodies: &[Body<N>], container: &Container<N>) -> f64 {
    let group = |g: &[Body<N>]| -> f64 {
        g.iter()
            .map(|b| containment_residual(b, container))
            .sum::<f64>()
    };
    #[cfg(feature = "rayon")]
    let groups: Vec<f64> = {
        use rayon::prelude::*;
        bodies.par_chunks(BODIES_PER_TASK).map(group).collect()
    };
    #[cfg(not(feature = "rayon"))]
    let groups = bodies.chunks(BODIES_PER_TASK).map(group);
    groups.into_iter().sum()
}

/// The per-body part of a gradient: each body's summed pair torques (`torques`) become angle
/// derivatives of the overlap, `∂/∂α_b = ω_α · Σ_pairs τ_b`, and its containment residual `r_b`
/// adds its gradient; `overlap` and `containment` are the bodies' variables. Returns `Σ r_b`
/// and `Σ ∂r_b/∂(container)`, summed over consecutive groups of [`BODIES_PER_TASK`] bodies in
/// order (on rayon's pool with the `rayon` feature, one task per group).
fn body_terms<const N: usize>(
    (bodies, spins, torques): (&[Body<N>], &[[f64; 2]], &[[f64; 3]]),
    layout: &Layout,
    container: &Container<N>,
    overlap: &mut [f64],
    containment: &mut [f64],
) -> (f64, [f64; N]) {
    let group = |first: usize, overlap: &mut [f64], containment: &mut [f64]| {
        let (mut r_sum, mut dc) = (0.0, [0.0; N]);
        let base = layout.start(first);
        let end = (first + BODIES_PER_TASK).min(bodies.len());
        for i in first..end {
            let own = layout.range(i);
            let own = own.start - base..own.end - base;
            let b = &bodies[i];
            let spin = spin_rows(b, spins[i]);
            scatter_force_torque(&mut overlap[own.clone()], &[0.0; N], &torques[i], &spin);
            let (r, cg) = containment_gradient(b, container);
            if r == 0.0 {
                continue;
            }
            r_sum += r;
            scatter_force_torque(&mut containment[own], &cg.centre, &cg.torque, &spin);
            for (d, c) in dc.iter_mut().zip(cg.container) {
                *d += c;
            }
        }
        (r_sum, dc)
    };
    let bounds = layout.groups(BODIES_PER_TASK);
    let pieces = layout
        .split_mut(overlap, &bounds)
        .into_iter()
        .zip(layout.split_mut(containment, &bounds))
        .enumerate();
    #[cfg(feature = "rayon")]
    let groups: Vec<(f64, [f64; N])> = {
        use rayon::prelude::*;
        let pieces: Vec<_> = pieces.collect();
        pieces
            .into_par_iter()
            .map(|(t, (ov, co))| group(t * BODIES_PER_TASK, ov, co))
            .collect()
    };
    #[cfg(not(feature = "rayon"))]
    let groups = pieces.map(|(t, (ov, co))| group(t * BODIES_PER_TASK, ov, co));
    let (mut r_sum, mut dc) = (0.0, [0.0; N]);
    for (r, d) in groups {
        r_sum += r;
        for k in 0..N {
            dc[k] += d[k];
        }
    }
    (r_sum, dc)
}

/// The cell's part of the periodic gradient, the items' part added to `out` (their
/// variables): with `F_e` the summed pair forces on point `e` (an item or a ghost, at
/// fractional position `u_e`) and `τ_i` the torques on item `i`,
///
/// ```text
/// ∂/∂s_i  = Hᵀ Σ_{e of i} F_e        ∂/∂α_i = ω_α · τ_i        ∂/∂H_ab = Σ_e F_e,a u_e,b
/// ```
///
/// (module `periodic`; `s_i` the fractional centre, `H` the upper-triangular cell). Items are
/// taken in fixed groups of [`BODIES_PER_TASK`] (on rayon's pool with the `rayon` feature, one
/// task per group), each item with its ghosts; the groups' `∂/∂H` are summed in order, so the
/// result does not depend on the number of threads.
fn cell_gradient<const N: usize>(
    (cell, images, fractional): (&[[f64; N]; N], &ImageSet<N>, &[[f64; N]]),
    (forces, torques): (&[[f64; N]], &[[f64; 3]]),
    (bodies, spins): (&[Body<N>], &[[f64; 2]]),
    (layout, out): (&Layout, &mut [f64]),
) -> [[f64; N]; N] {
    let group = |first: usize, out: &mut [f64]| {
        let mut dcell = [[0.0; N]; N];
        let mut ghost = images.first_ghost(first);
        let base = layout.start(first);
        for i in first..(first + BODIES_PER_TASK).min(bodies.len()) {
            let own = layout.range(i);
            let vars = &mut out[own.start - base..own.end - base];
            let mut force = [0.0; N];
            let mut add_point = |e: usize| {
                let (f, u) = (forces[e], images.fractional(e, fractional));
                for a in 0..N {
                    force[a] += f[a];
                    for b in a..N {
                        dcell[a][b] += f[a] * u[b];
                    }
                }
            };
            add_point(i);
            while images.owner.get(ghost).is_some_and(|&o| o as usize == i) {
                add_point(ghost);
                ghost += 1;
            }
            let spin = spin_rows(&bodies[i], spins[i]);
            let ds: [f64; N] =
                std::array::from_fn(|c| (0..=c).map(|r| cell[r][c] * force[r]).sum());
            scatter_force_torque(vars, &ds, &torques[i], &spin);
        }
        dcell
    };
    let bounds = layout.groups(BODIES_PER_TASK);
    let pieces = layout.split_mut(out, &bounds).into_iter().enumerate();
    #[cfg(feature = "rayon")]
    let groups: Vec<[[f64; N]; N]> = if bounds.len() > 2 {
        use rayon::prelude::*;
        let pieces: Vec<_> = pieces.collect();
        pieces
            .into_par_iter()
            .map(|(t, vars)| group(t * BODIES_PER_TASK, vars))
            .collect()
    } else {
        pieces
            .map(|(t, vars)| group(t * BODIES_PER_TASK, vars))
            .collect()
    };
    #[cfg(not(feature = "rayon"))]
    let groups = pieces.map(|(t, vars)| group(t * BODIES_PER_TASK, vars));
    let mut dcell = [[0.0; N]; N];
    for d in groups {
        for a in 0..N {
            for b in a..N {
                dcell[a][b] += d[a][b];
            }
        }
    }
    dcell
}

/// Adds a force and a torque on a body to `out`, its variables: the force on its centre, and
/// on its angle `α` the derivative `ω_α · τ` (`spin` holds the rows `ω_α` of all of eq. 1's
/// or eq. 2's angles, precomputed by `load`; an item with fewer angles has the last ones).
#[inline(always)]
fn scatter_force_torque<const N: usize>(
    out: &mut [f64],
    force: &[f64; N],
    torque: &[f64; 3],
    spin: &[[f64; 3]; 3],
) {
    let (centre, angles) = out.split_at_mut(N);
    for k in 0..N {
        centre[k] += force[k];
    }
    let first = angle_count(N) - angles.len();
    for (a, d) in angles.iter_mut().enumerate() {
        let w = &spin[first + a];
        *d += w[0] * torque[0] + w[1] * torque[1] + w[2] * torque[2];
    }
}

/// Adds a pair gradient to `out` (centres) and `torques` (per body, turned into angle
/// derivatives once all pairs are summed, see [`Model::evaluate`]).
#[cfg(not(feature = "rayon"))]
#[inline(always)]
fn add_pair<const N: usize>(
    (out, starts): (&mut [f64], &[usize]),
    torques: &mut [[f64; 3]],
    i: usize,
    j: usize,
    g: &PairGradient<N>,
) {
    for k in 0..N {
        out[starts[i] + k] += g.centre_i[k];
        out[starts[j] + k] += g.centre_j[k];
    }
    for k in 0..3 {
        torques[i][k] += g.angular_i[k];
        torques[j][k] += g.angular_j[k];
    }
}

/// The angular velocities `ω_α` of a body's angles, row `α` (world frame), from its rotation
/// and `(sin ψ, cos ψ)`: for eq. 2, `ω_φ` is the first column of `Q`, `ω_θ = (−sin ψ, cos ψ,
/// 0)` and `ω_ψ = e_z` (the same expressions as `rotation_and_velocities_3d`, so the same
/// bits); in 2D `ω_θ = e_z`.
#[inline]
fn spin_rows<const N: usize>(body: &Body<N>, [sp, cp]: [f64; 2]) -> [[f64; 3]; 3] {
    let mut spin = [[0.0; 3]; 3];
    if N == 2 {
        spin[0][2] = 1.0;
    } else {
        let q = body.rotation();
        spin[0] = [q[0][0], q[1][0], q[2][0]];
        spin[1] = [-sp, cp, 0.0];
        spin[2][2] = 1.0;
        if let Some(d) = turned_spheroid(&body.semi_axes()) {
            // A spheroid has no φ: only the rows of θ and ψ are read.
            spin = spheroid_rows(d, &spin);
        }
    }
    spin
}

/// Σf over the close pairs and their number; the gradient of Σf is added to `out`, with each
/// body's torque left in `torques`.
fn pair_sum_gradient<const N: usize>(
    (list, centres): Candidates<'_, N>,
    (bodies, layout): (&[Body<N>], &Layout),
    #[cfg_attr(not(feature = "rayon"), allow(unused_variables))] ranges: &mut RangeWork<N>,
    torques: &mut Vec<[f64; 3]>,
    out: &mut [f64],
) -> Result<(f64, usize), Error> {
    torques.resize(bodies.len(), [0.0; 3]);
    fill(torques, [0.0; 3]);
    #[cfg(not(feature = "rayon"))]
    {
        let mut sum = 0.0;
        let mut emit = |i: usize, j: usize, &(f, ref g): &Term<N>| {
            if f > 0.0 {
                sum += f;
                add_pair((out, layout.starts()), torques, i, j, g);
            }
        };
        let count = through_kernel::<N, WithGradient>((list, centres), bodies, &mut emit)?;
        Ok((sum, count))
    }
    #[cfg(feature = "rayon")]
    {
        list.par_fold_close_pairs_into(
            centres,
            0..centres.len(),
            &mut ranges.gradients,
            restart_terms,
            |s, i, j, _, _| add_term(s, bodies, i, j),
        )
        .map_err(grid_error)?;
        // Σf range by range; the gradient terms item by item in the order of the serial scan
        // (module `scatter`): the same bits as the serial path's whatever the scheduling.
        let (mut sum, mut count) = (0.0, 0);
        for RangeShare { kept, queue } in &mut ranges.gradients {
            queue.flush(bodies, &mut keep(kept));
            sum += kept.0;
            count += kept.1;
        }
        let lists: Vec<&[Entry<N>]> = ranges
            .gradients
            .iter()
            .map(|s| s.kept.2.as_slice())
            .collect();
        crate::scatter::add_to_items(&lists, layout.starts(), out, torques);
        Ok((sum, count))
    }
}

/// A range's share of the rayon pair sums: what it kept and its kernel queue.
#[cfg(feature = "rayon")]
#[derive(Debug)]
struct RangeShare<T, const N: usize, K> {
    kept: T,
    queue: KernelQueue<N, K>,
}

#[cfg(feature = "rayon")]
impl<T: Default, const N: usize, K> Default for RangeShare<T, N, K> {
    fn default() -> Self {
        Self {
            kept: T::default(),
            queue: KernelQueue::default(),
        }
    }
}

/// The rayon pair sums' workspace, one share per range of rows of the pair list, kept from
/// evaluation to evaluation so that the terms' vectors are allocated once.
#[cfg(feature = "rayon")]
#[derive(Debug, Default)]
struct RangeWork<const N: usize> {
    /// `Σf` and the pair count of a value-only call.
    values: Vec<RangeShare<(f64, usize, ()), N, ValueOnly>>,
    /// `Σf`, the pair count and the non-zero terms of a call with gradients.
    gradients: Vec<RangeShare<Kept<N>, N, WithGradient>>,
}

/// A range's `Σf`, pair count and non-zero terms, in the order of its pairs.
#[cfg(feature = "rayon")]
type Kept<const N: usize> = (f64, usize, Vec<(usize, usize, PairGradient<N>)>);

/// A range's share of a pair sum with gradients, emptied for the next evaluation (its
/// vector keeps its memory).
#[cfg(feature = "rayon")]
fn restart_terms<const N: usize>(share: &mut RangeShare<Kept<N>, N, WithGradient>) {
    share.kept.0 = 0.0;
    share.kept.1 = 0;
    share.kept.2.clear();
}

/// A range's share of a pair sum with gradients after one more pair.
#[cfg(feature = "rayon")]
fn add_term<const N: usize>(
    share: &mut RangeShare<Kept<N>, N, WithGradient>,
    bodies: &[Body<N>],
    i: usize,
    j: usize,
) {
    let RangeShare { kept, queue } = share;
    kept.1 += 1;
    queue.push(bodies, i, j, &mut keep(kept));
}

/// Adds the terms a queue emits to a range's share.
#[cfg(feature = "rayon")]
fn keep<const N: usize>(acc: &mut Kept<N>) -> impl FnMut(usize, usize, &Term<N>) + '_ {
    move |i, j, &(f, ref g)| {
        if f > 0.0 {
            acc.0 += f;
            acc.2.push((i, j, *g));
        }
    }
}

/// A rayon pool of `threads` threads, for work that is to share them with the model's
/// evaluations.
///
/// # Errors
/// [`Error::ThreadPool`] when the threads cannot be started.
#[cfg(feature = "rayon")]
pub fn thread_pool(threads: usize) -> Result<rayon::ThreadPool, Error> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| Error::ThreadPool {
            threads,
            reason: e.to_string(),
        })
}

/// `f` run inside a rayon pool of `threads` threads, so that every parallel step of the
/// model (and of whatever else `f` does on rayon) is a task of that pool rather than a job
/// handed to it from outside, which costs a wake-up each time. `threads = 0`: in place when the
/// caller already runs in a pool, else in a new pool of as many threads as rayon's global
/// one (every core by default). The model's values are the same bits on any number of
/// threads.
///
/// # Errors
/// [`Error::ThreadPool`] when the threads cannot be started.
#[cfg(feature = "rayon")]
pub fn on_threads<R: Send>(threads: usize, f: impl FnOnce() -> R + Send) -> Result<R, Error> {
    if threads == 0 && rayon::current_thread_index().is_some() {
        return Ok(f());
    }
    let n = if threads == 0 {
        rayon::current_num_threads()
    } else {
        threads
    };
    Ok(thread_pool(n)?.install(f))
}

/// The first variable of `x` (`m` items, then the container) that is NaN or infinite, or a
/// centre coordinate beyond [`MAX_MAGNITUDE`]; in tasks of [`BODIES_PER_TASK`] items on
/// rayon's pool with the feature.
fn first_bad_variable<const N: usize>(x: &[f64], layout: &Layout) -> Option<usize> {
    let nb = layout.item_variables();
    let (items, container) = x.split_at(nb);
    let bounds = layout.groups(BODIES_PER_TASK);
    let in_group = |g: usize| {
        let (first, end) = (bounds[g], bounds[g + 1]);
        (first..end).find_map(|i| {
            layout.range(i).find(|&k| {
                let limit = if k - layout.start(i) < N {
                    MAX_MAGNITUDE
                } else {
                    f64::INFINITY
                };
                !(items[k].is_finite() && items[k].abs() <= limit)
            })
        })
    };
    let groups = bounds.len() - 1;
    #[cfg(feature = "rayon")]
    let bad = if groups > 1 {
        use rayon::prelude::*;
        (0..groups).into_par_iter().find_map_first(in_group)
    } else {
        (0..groups).find_map(in_group)
    };
    #[cfg(not(feature = "rayon"))]
    let bad = (0..groups).find_map(in_group);
    bad.or_else(|| {
        let k = container.iter().position(|v| !v.is_finite())?;
        Some(nb + k)
    })
}

/// The fractional centres `s_i` of the items of a periodic cell's variables `x`, written to
/// `out`.
///
/// # Errors
/// [`Error::FractionalOutOfRange`] for the first coordinate beyond [`MAX_CELLS`] cells.
fn fractional_centres<const N: usize>(
    x: &[f64],
    layout: &Layout,
    out: &mut Vec<[f64; N]>,
) -> Result<(), Error> {
    let m = layout.items();
    let centre = |i: usize| -> [f64; N] { std::array::from_fn(|k| x[layout.start(i) + k]) };
    let far = |s: &[f64; N]| s.iter().any(|v| v.abs() > MAX_CELLS);
    #[cfg(feature = "rayon")]
    let first = if m > BODIES_PER_TASK {
        use rayon::prelude::*;
        (0..m)
            .into_par_iter()
            .with_min_len(BODIES_PER_TASK)
            .map(centre)
            .collect_into_vec(out);
        out.par_iter()
            .with_min_len(BODIES_PER_TASK)
            .position_first(far)
    } else {
        serial_centres(m, centre, out, far)
    };
    #[cfg(not(feature = "rayon"))]
    let first = serial_centres(m, centre, out, far);
    match first {
        Some(i) => {
            let k = (0..N).find(|&k| out[i][k].abs() > MAX_CELLS).unwrap_or(0);
            Err(Error::FractionalOutOfRange {
                index: layout.start(i) + k,
                value: out[i][k],
            })
        }
        None => Ok(()),
    }
}

/// [`fractional_centres`] on the current thread: the `m` centres written to `out`, the first
/// that is `far`.
fn serial_centres<const N: usize>(
    m: usize,
    centre: impl Fn(usize) -> [f64; N],
    out: &mut Vec<[f64; N]>,
    far: impl Fn(&[f64; N]) -> bool,
) -> Option<usize> {
    out.clear();
    out.extend((0..m).map(centre));
    out.iter().position(far)
}

/// Sets every entry of `v` to `value` (by blocks on rayon's pool with the feature).
fn fill<T: Copy + Send + Sync>(v: &mut [T], value: T) {
    #[cfg(feature = "rayon")]
    const CHUNK: usize = 1 << 14;
    #[cfg(feature = "rayon")]
    if v.len() > CHUNK {
        use rayon::prelude::*;
        v.par_chunks_mut(CHUNK).for_each(|c| c.fill(value));
        return;
    }
    v.fill(value);
}

/// The bodies and spins of the items, `body_of((i, l_i))` each, appended in order: on
/// rayon's pool with the feature, in tasks of at least [`BODIES_PER_TASK`] items (a small
/// model never waits for the pool).
fn make_bodies<const N: usize>(
    semi_axes: &[[f64; N]],
    body_of: impl Fn((usize, &[f64; N])) -> (Body<N>, [f64; 2]) + Sync + Send,
    bodies: &mut Vec<Body<N>>,
    spins: &mut Vec<[f64; 2]>,
) {
    #[cfg(feature = "rayon")]
    {
        use rayon::prelude::*;
        semi_axes
            .par_iter()
            .with_min_len(BODIES_PER_TASK)
            .enumerate()
            .map(body_of)
            .unzip_into_vecs(bodies, spins);
    }
    #[cfg(not(feature = "rayon"))]
    for (body, spin) in semi_axes.iter().enumerate().map(body_of) {
        bodies.push(body);
        spins.push(spin);
    }
}

/// A body from its variables `[c, Ω]` (crate-built rotation, orthogonal by construction).
fn make_body<const N: usize>(l: &[f64; N], vars: &[f64]) -> Body<N> {
    make_body_and_spins(l, vars).0
}

/// A body from its variables `[c, Ω]` and the angular velocities `ω_α` of its angles (rows;
/// 2D: `ω_θ = e_z`), from one set of sines and cosines. A round item has no angles: its
/// rotation is the identity.
fn make_body_and_spins<const N: usize>(l: &[f64; N], vars: &[f64]) -> (Body<N>, [f64; 2]) {
    let mut c = [0.0; N];
    c.copy_from_slice(&vars[..N]);
    let mut q = [[0.0; N]; N];
    let mut spin = [0.0, 1.0];
    if vars.len() == N {
        for (a, row) in q.iter_mut().enumerate() {
            row[a] = 1.0;
        }
    } else if N == 2 {
        let r = rotation_2d(vars[2]);
        for a in 0..2 {
            for b in 0..2 {
                q[a][b] = r[a][b];
            }
        }
    } else {
        let (mut r, w) = rotation_and_velocities_3d(full_angles(&vars[N..]));
        if let Some(d) = turned_spheroid(l) {
            r = spheroid_rotation(d, &r);
        }
        for a in 0..N {
            for b in 0..N {
                q[a][b] = r[a][b];
            }
        }
        // ω_θ = (−sin ψ, cos ψ, 0).
        spin = [-w[1][0], w[1][1]];
    }
    (Body::from_parts_unchecked(c, *l, q), spin)
}

/// The distinct axis `d` of a spheroid whose frame `P_d` is not the identity (module
/// `layout`): its rotation and its angles' angular velocities are conjugated by `P_d`.
fn turned_spheroid<const N: usize>(l: &[f64; N]) -> Option<usize> {
    spheroid_axis(l).filter(|&d| d != 0)
}

/// The world angular velocities of eq. 2's angles (rows) at the angles `full`, for an item
/// with semi-axes `l` (a spheroid's taken through its frame).
fn angle_rows<const N: usize>(l: &[f64; N], full: [f64; 3]) -> [[f64; 3]; 3] {
    let w = angular_velocities_3d(full);
    match turned_spheroid(l) {
        Some(d) => spheroid_rows(d, &w),
        None => w,
    }
}

/// Eq. 2's `[φ, θ, ψ]` of an item's angles in 3D: an item with fewer than three has the last
/// ones, the first being 0.
fn full_angles(angles: &[f64]) -> [f64; 3] {
    let mut full = [0.0; 3];
    full[3 - angles.len()..].copy_from_slice(angles);
    full
}

/// The pair direction of `v` for the bodies `i`, `j`: centre velocities and world angular
/// velocities `w = Σ_α ω_α v_α` (2D: `w = v_θ e_z`; none for a round item).
fn direction<const N: usize>(
    (x, v): (&[f64], &[f64]),
    (layout, semi_axes): (&Layout, &[[f64; N]]),
    i: usize,
    j: usize,
) -> PairDirection<N> {
    let spin = |b: usize| -> [f64; 3] {
        let own = layout.range(b);
        let (xa, va) = (&x[own.start + N..own.end], &v[own.start + N..own.end]);
        if va.is_empty() {
            [0.0; 3]
        } else if N == 2 {
            [0.0, 0.0, va[0]]
        } else {
            let w = angle_rows(&semi_axes[b], full_angles(xa));
            let first = 3 - va.len();
            let mut s = [0.0; 3];
            for (a, &rate) in va.iter().enumerate() {
                for k in 0..3 {
                    s[k] += w[first + a][k] * rate;
                }
            }
            s
        }
    };
    let (si, sj) = (layout.start(i), layout.start(j));
    let mut ci = [0.0; N];
    let mut cj = [0.0; N];
    ci.copy_from_slice(&v[si..si + N]);
    cj.copy_from_slice(&v[sj..sj + N]);
    PairDirection {
        centre_i: ci,
        centre_j: cj,
        angular_i: spin(i),
        angular_j: spin(j),
    }
}

/// Adds the second-order terms of a body to `out`, with `x` and `v` its variables and
/// direction: `δ(force)` on the centre, and on angle `α` `ω_α · δτ + Σ_β (∂ω_α/∂β v_β) · τ`
/// (the parametrisation's own curvature; zero in 2D).
fn scatter_second<const N: usize>(
    (x, v, out): (&[f64], &[f64], &mut [f64]),
    l: &[f64; N],
    dforce: &[f64; N],
    dtorque: &[f64; 3],
    torque: &[f64; 3],
) {
    for k in 0..N {
        out[k] += dforce[k];
    }
    let angles = out.len() - N;
    if angles == 0 {
        return;
    }
    if N == 2 {
        out[2] += dtorque[2];
    } else {
        let ang = full_angles(&x[N..]);
        let w = angle_rows(l, ang);
        let mut dw = angular_velocity_derivatives_3d(ang);
        if let Some(d) = turned_spheroid(l) {
            for rows in &mut dw {
                *rows = spheroid_rows(d, rows);
            }
        }
        let first = 3 - angles;
        for a in first..3 {
            let mut e = (0..3).map(|k| w[a][k] * dtorque[k]).sum::<f64>();
            for bb in first..3 {
                e += (0..3).map(|k| dw[a][bb][k] * torque[k]).sum::<f64>() * v[N + bb - first];
            }
            out[N + a - first] += e;
        }
    }
}

/// `x + h v`, read lazily (no allocation).
struct ShiftedVars<'a> {
    x: &'a [f64],
    v: &'a [f64],
    h: f64,
}

impl ShiftedVars<'_> {
    fn get(&self, k: usize) -> f64 {
        self.x[k] + self.h * self.v[k]
    }
}

fn shifted_vars<'a>(x: &'a [f64], v: &'a [f64], h: f64) -> ShiftedVars<'a> {
    ShiftedVars { x, v, h }
}

/// The variable-space gradient of the body whose variables start at `base` (centre, then
/// angles at the shifted point) from a force and a torque; `out` is as long as its variables.
fn body_gradient_into<const N: usize>(
    (xs, base): (&ShiftedVars<'_>, usize),
    l: &[f64; N],
    force: &[f64; N],
    torque: &[f64; 3],
    out: &mut [f64],
) {
    out[..N].copy_from_slice(force);
    let angles = out.len() - N;
    if angles == 0 {
        return;
    }
    if N == 2 {
        out[2] = torque[2];
    } else {
        let mut shifted = [0.0; 3];
        for (a, v) in shifted.iter_mut().take(angles).enumerate() {
            *v = xs.get(base + N + a);
        }
        // (P_dᵀ ω)·τ = ω·(P_d τ) for a spheroid's rows.
        let torque = match turned_spheroid(l) {
            Some(d) => frame_times(d, torque),
            None => *torque,
        };
        let g = angle_gradient_3d(full_angles(&shifted[..angles]), &torque);
        out[N..].copy_from_slice(&g[3 - angles..]);
    }
}
