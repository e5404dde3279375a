//! Random packings: random sequential addition at a low packing fraction, then compression to
//! a chosen packing fraction or until jammed.
//!
//! **The start** ([`sequential_addition`]) puts the items, largest first, one at a time at a
//! uniformly random position of the container (a uniformly random point of the periodic cell)
//! with a uniformly random orientation — an angle uniform in [0, π) in 2D, a rotation uniform
//! on SO(3) in 3D (a uniform unit quaternion, Shoemake's construction) — and keeps it when it
//! lies inside the container and PW85 says it overlaps no item placed before (μ² ≥ 1 against
//! every item, and in a periodic cell against every image, itself included). A grid of
//! buckets whose edge is the largest enclosing diameter finds the items within reach, so an
//! attempt costs O(1) and the start O(m) at a fraction well below saturation (about 0.38 for
//! spheres, 0.55 for discs). The start is certified by construction.
//!
//! **The compression** ([`compression_to`]) shrinks the container (its shape kept) through
//! placements in fixed containers, each driving the model's overlap measure (the paper's eqs.
//! (21)–(26)) to zero, and keeps each step whose packing certifies. With a target fraction it
//! stops at the first packing at least that dense, dilated back to the target container
//! exactly; without one it ends where no step can be certified any more: a jammed packing of
//! this protocol, which keeps the disorder of its start (no lattice is ever imposed).
//!
//! **Memory order.** The start leaves the items where chance put them, so an item's neighbours
//! in space are anywhere in memory, and every evaluation of a large packing would wait on the
//! cache for each pair. The compression therefore works on the items sorted along a Z-order
//! (Morton) curve through their start positions ([`spatial_order`]), which keeps most
//! neighbours close in memory (about 12 % less time per inner iteration at 1e5 ellipsoids);
//! the packing is returned in the problem's order. The progress reports of the compression
//! (`observe`) carry the variables in the sorted order.
//!
//! # References
//! - B. Widom, *Random sequential addition of hard spheres to a volume*, J. Chem. Phys. 44
//!   (1966): the start.
//! - K. Shoemake, *Uniform random rotations*, Graphics Gems III (1992): the quaternion.
//! - C. S. O'Hern, L. E. Silbert, A. J. Liu, S. R. Nagel, *Jamming at zero temperature and
//!   zero applied stress*, Phys. Rev. E 68, 011306 (2003): jamming by compression and
//!   minimisation of an overlap energy from random states.
//! - A. Donev et al., *Improving the density of jammed disordered packings using ellipsoids*,
//!   Science 303, 990 (2004).

use crate::Error;
use crate::compression::compression_to;
use crate::fixed::Unfinished;
use crate::local::{LocalMethod, LocalResult, LocalSettings, certified_start, infeasibility};
use crate::starts::SplitMix64;
use auglag::Progress;
use implicit_packing::Layout;
use implicit_packing::containment::{Container, containment_residual};
use implicit_packing::model::Model;
use implicit_packing::periodic::{to_cartesian, to_fractional, widths};
use implicit_packing::shape::Body;
use std::time::Instant;

/// The packing fraction of the random start in 2D unless the settings say otherwise: well
/// below the saturation of random sequential addition of discs (0.547), so that most attempts
/// succeed.
pub const START_FRACTION_2D: f64 = 0.35;
/// The same in 3D (saturation of spheres 0.384, higher for moderately elongated ellipsoids).
pub const START_FRACTION_3D: f64 = 0.2;
/// The largest relative shrink δ of the container's linear size in one compression step
/// toward a packing fraction (jammed runs keep the settings' own, 0.02 by default). From a
/// random start most of the way costs a few iterations a step: 10⁴ ellipsoids (1, 0.75, 0.5)
/// went from φ = 0.2 to 0.53 in six steps and 142 inner iterations with δ up to 0.08, to
/// 0.52 in sixteen steps and 360 inner iterations with δ up to 0.02 (placements by the
/// augmented Lagrangian); δ up to 0.12 lost a step given up after 1 712 iterations.
pub const LARGEST_STEP_TO_A_FRACTION: f64 = 0.08;
/// Attempts per item before the start is tried again in a container twice as large.
pub const ATTEMPTS_PER_ITEM: usize = 10_000;
/// Times the start is tried in a larger container (twice the area or volume each time)
/// before the run gives up.
pub const START_RETRIES: usize = 4;

/// How dense the random packing is to be.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Target {
    /// Exactly this packing fraction, in the given container (the run's container).
    Fraction,
    /// As dense as compression gets while no step can be certified any more.
    Jammed,
}

/// Settings of a random packing.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct RandomSettings {
    /// The fraction to reach, or jammed.
    pub target: Target,
    /// Packing fraction of the random start (`None`: [`START_FRACTION_2D`] or
    /// [`START_FRACTION_3D`]; a target below it is the start itself).
    pub start_fraction: Option<f64>,
    /// The seed: the same seed gives the same start and the same packing.
    pub seed: u64,
    /// Attempts per item of the random start: random sequential addition draws a place and an
    /// orientation until the item overlaps nothing placed, and after this many tries the whole
    /// start again in a container twice as large ([`ATTEMPTS_PER_ITEM`] by default).
    pub attempts_per_item: usize,
    /// Settings of the compression's placements.
    pub local: LocalSettings,
    /// How each item is oriented in the random start, by item (empty: every item
    /// [`Orientation::Isotropic`]). The compression turns the items as it needs.
    pub orientations: Vec<Orientation>,
    /// Threads of the run with the `rayon` feature, shared by the model's evaluations and the
    /// solver's reductions over long vectors (0: rayon's current pool, by default every
    /// core); the packing is the same bits on any number. Without the feature the run is
    /// serial.
    pub threads: usize,
}

auglag::with_setters!(RandomSettings:
    with_target => target: Target,
    with_start_fraction => start_fraction: Option<f64>,
    with_seed => seed: u64,
    with_attempts_per_item => attempts_per_item: usize,
    with_local => local: LocalSettings,
    with_orientations => orientations: Vec<Orientation>,
    with_threads => threads: usize,
);

impl RandomSettings {
    /// A random packing to `target` from seed `seed`, with the compression's default settings.
    pub fn new(target: Target, seed: u64) -> Self {
        Self {
            target,
            start_fraction: None,
            seed,
            attempts_per_item: ATTEMPTS_PER_ITEM,
            local: LocalSettings::default().with_method(LocalMethod::Compression),
            orientations: Vec::new(),
            threads: 0,
        }
    }
}

/// A random packing and how it was made.
#[derive(Clone, Debug)]
pub struct RandomPacking {
    /// The certified packing (its variables, density, certificate, the compression's report).
    pub packing: LocalResult,
    /// Packing fraction of the random start.
    pub start_density: f64,
}

/// A random packing of the problem's items (see the module documentation). `container` gives
/// the container's variables: with [`Target::Fraction`] the container to fill, whose
/// fraction is the target; with [`Target::Jammed`] only its shape matters (its aspect ratios,
/// a periodic cell's angles). `observe` sees the compression's progress; returning `true`
/// stops the run with the densest packing so far.
///
/// # Errors
/// [`Error::RandomStart`] when no random start could be made; [`Error::NotReached`] when a
/// target fraction was not reached (compression jammed first, or the observer stopped it),
/// with the densest packing reached, compressed into the target container, as its least
/// overlapping point; errors of the model for an invalid container.
pub fn random_packing<const N: usize>(
    problem: &mut Model<N>,
    container: &[f64],
    settings: &RandomSettings,
    observe: &mut (dyn FnMut(&Progress<'_>) -> bool + Send),
) -> Result<RandomPacking, Error> {
    random_packing_seen(problem, container, settings, observe, &mut |_| {})
}

/// [`random_packing`] that also shows `kept` the density of every packing the compression
/// keeps, the random start's first.
///
/// # Errors
/// As [`random_packing`].
pub fn random_packing_seen<const N: usize>(
    problem: &mut Model<N>,
    container: &[f64],
    settings: &RandomSettings,
    observe: &mut (dyn FnMut(&Progress<'_>) -> bool + Send),
    kept: &mut (dyn FnMut(f64) + Send),
) -> Result<RandomPacking, Error> {
    // The whole run inside a pool of the settings' threads: the model's evaluations and the
    // solver's passes over long vectors share it.
    let heard = Heard { observe, kept };
    #[cfg(feature = "rayon")]
    return implicit_packing::model::on_threads(settings.threads, || {
        random_packing_here(problem, container, settings, heard)
    })?;
    #[cfg(not(feature = "rayon"))]
    random_packing_here(problem, container, settings, heard)
}

/// Who hears of a random packing as it goes: the solver's progress (which may stop it) and the
/// density of every packing the compression keeps.
struct Heard<'a> {
    observe: &'a mut (dyn FnMut(&Progress<'_>) -> bool + Send),
    kept: &'a mut (dyn FnMut(f64) + Send),
}

/// [`random_packing_seen`] on the current thread's pool.
fn random_packing_here<const N: usize>(
    problem: &mut Model<N>,
    container: &[f64],
    settings: &RandomSettings,
    heard: Heard<'_>,
) -> Result<RandomPacking, Error> {
    let Heard { observe, kept } = heard;
    let began = Instant::now();
    let items = crate::local::item_measure(problem);
    let target_measure = Container::<N>::from_dimensions(problem.container_kind(), container)?
        .measure()
        .0;
    let start_fraction = settings.start_fraction.unwrap_or(if N == 2 {
        START_FRACTION_2D
    } else {
        START_FRACTION_3D
    });
    let wanted = items / target_measure;
    let mut start_scale = match settings.target {
        Target::Fraction if wanted <= start_fraction => 1.0,
        _ => (wanted / start_fraction).powf(1.0 / N as f64),
    };
    let mut retries = 0;
    let x0 = loop {
        let dims: Vec<f64> = container.iter().map(|d| d * start_scale).collect();
        match sequential_addition_oriented(
            problem,
            &dims,
            settings.seed,
            settings.attempts_per_item,
            &settings.orientations,
        ) {
            Ok(x) => break x,
            Err(e @ Error::RandomStart { .. }) if retries == START_RETRIES => return Err(e),
            Err(Error::RandomStart { .. }) => {
                retries += 1;
                start_scale *= 2f64.powf(1.0 / N as f64);
            }
            Err(e) => return Err(e),
        }
    };
    let start = certified_start(problem, &x0)?.map_err(|c| Error::NotCertifiable {
        max_dilation: 1.0,
        overlapping: c.overlapping.len(),
        outside: c.outside.len(),
    })?;
    let start_density = start.density;
    let aim = match settings.target {
        Target::Fraction => Some(target_measure),
        Target::Jammed => None,
    };
    let mut interrupted = false;
    let mut watch = |p: &Progress<'_>| {
        interrupted |= observe(p);
        interrupted
    };
    let mut local = match settings.target {
        Target::Fraction => settings.local.clone().with_largest_compression_step(
            LARGEST_STEP_TO_A_FRACTION.max(settings.local.largest_compression_step),
        ),
        Target::Jammed => settings.local.clone(),
    };
    let order = spatial_order::<N>(&x0, problem.layout());
    let axes = problem.semi_axes();
    let mut sorted = Model::<N>::new(
        order.iter().map(|&i| axes[i]).collect(),
        problem.container_kind(),
    )?;
    if !local.fixed_orientations.is_empty() {
        let fixed = &local.fixed_orientations;
        local.fixed_orientations = order
            .iter()
            .map(|&i| fixed.get(i).copied().unwrap_or(false))
            .collect();
    }
    let compressed = compression_to(
        &mut sorted,
        &in_order(&x0, &order, problem.layout()),
        &local,
        aim,
        &mut watch,
        &mut |p| kept(p.density),
    )?;
    let compressed = LocalResult {
        x: back_in_order(&compressed.x, &order, (sorted.layout(), problem.layout())),
        ..compressed
    };
    drop(sorted);
    let Some(target) = aim else {
        return Ok(RandomPacking {
            packing: compressed,
            start_density,
        });
    };
    // Dilated back to the target container exactly: every length times s ≥ 1.
    let s = (target / compressed.objective)
        .powf(1.0 / N as f64)
        .max(1.0);
    let body_variables = problem.layout().item_variables();
    let mut x = problem.dilated(&compressed.x, s);
    x[body_variables..].copy_from_slice(container);
    match certified_start(problem, &x)? {
        Ok(mut packing) if compressed.objective <= target => {
            packing.report = compressed.report;
            Ok(RandomPacking {
                packing,
                start_density,
            })
        }
        reached => {
            let certificate = match reached {
                Ok(p) => p.certificate,
                Err(c) => c,
            };
            Err(Error::NotReached(Box::new(Unfinished {
                infeasibility: infeasibility(problem, &x)?,
                x,
                certificate,
                density: wanted,
                local_minimisations: 1,
                wall_time: began.elapsed(),
                interrupted,
            })))
        }
    }
}

/// The items `0..m` of the variables `x` in the order of a Z-order (Morton) curve through their
/// centres: each centre's coordinates, scaled to the items' bounding box, quantised to
/// `64 / N` bits, their bits interleaved; ties by index. Items close in space are mostly
/// close in this order.
///
/// # References
/// G. M. Morton, *A computer oriented geodetic data base and a new technique in file
/// sequencing*, IBM (1966).
pub fn spatial_order<const N: usize>(x: &[f64], layout: &Layout) -> Vec<usize> {
    let m = layout.items();
    let centre = |i: usize| -> [f64; N] { std::array::from_fn(|k| x[layout.start(i) + k]) };
    let (mut lo, mut hi) = ([f64::INFINITY; N], [f64::NEG_INFINITY; N]);
    for i in 0..m {
        let c = centre(i);
        for k in 0..N {
            lo[k] = lo[k].min(c[k]);
            hi[k] = hi[k].max(c[k]);
        }
    }
    let bits = 64 / N as u32;
    let top = ((1u64 << bits) - 1) as f64;
    let code = |i: usize| {
        let c = centre(i);
        let q: [u64; N] = std::array::from_fn(|k| {
            let span = hi[k] - lo[k];
            if span > 0.0 {
                ((c[k] - lo[k]) / span * top) as u64
            } else {
                0
            }
        });
        (0..bits).rev().fold(0u64, |code, b| {
            q.iter().fold(code, |code, v| code << 1 | (v >> b & 1))
        })
    };
    let mut keyed: Vec<(u64, usize)> = (0..m).map(|i| (code(i), i)).collect();
    keyed.sort_unstable();
    keyed.into_iter().map(|(_, i)| i).collect()
}

/// The variables `x` with the items (at their places in `layout`) taken in `order`, the container's
/// variables last.
fn in_order(x: &[f64], order: &[usize], layout: &Layout) -> Vec<f64> {
    let mut out = Vec::with_capacity(x.len());
    for &i in order {
        out.extend_from_slice(&x[layout.range(i)]);
    }
    out.extend_from_slice(&x[layout.item_variables()..]);
    out
}

/// The inverse of [`in_order`]: item `k` of `sorted` is item `order[k]` of the result.
fn back_in_order(sorted: &[f64], order: &[usize], (from, to): (&Layout, &Layout)) -> Vec<f64> {
    let mut out = sorted.to_vec();
    for (k, &i) in order.iter().enumerate() {
        out[to.range(i)].copy_from_slice(&sorted[from.range(k)]);
    }
    out
}

/// A random start: the problem's items by random sequential addition into the container of
/// variables `container` (see the module documentation), as the model's variables.
///
/// # Errors
/// [`Error::RandomStart`] when an item found no place in `attempts_per_item` attempts;
/// errors of the model for an invalid container.
pub fn sequential_addition<const N: usize>(
    problem: &Model<N>,
    container: &[f64],
    seed: u64,
    attempts_per_item: usize,
) -> Result<Vec<f64>, Error> {
    sequential_addition_oriented(problem, container, seed, attempts_per_item, &[])
}

/// [`sequential_addition`] with the orientation of each item drawn from `orientations[i]`
/// (items beyond its end: [`Orientation::Isotropic`]).
///
/// # Errors
/// As [`sequential_addition`]; an [`Orientation::Given`] the body refuses (a quaternion that
/// is not a unit one, a wrong number of values) is an error of the model.
pub fn sequential_addition_oriented<const N: usize>(
    problem: &Model<N>,
    container: &[f64],
    seed: u64,
    attempts_per_item: usize,
    orientations: &[Orientation],
) -> Result<Vec<f64>, Error> {
    let shape = Container::<N>::from_dimensions(problem.container_kind(), container)?;
    let axes = problem.semi_axes();
    let reach = axes
        .iter()
        .map(|l| l.iter().fold(0.0_f64, |a, &b| a.max(b)))
        .fold(0.0_f64, f64::max);
    let mut order: Vec<usize> = (0..axes.len()).collect();
    let radius = |i: usize| axes[i].iter().fold(0.0_f64, |a, &b| a.max(b));
    order.sort_by(|&a, &b| radius(b).total_cmp(&radius(a)).then(a.cmp(&b)));
    let mut grid = Buckets::new(&shape, 2.0 * reach, axes.len());
    let mut placed: Vec<Option<Body<N>>> = vec![None; axes.len()];
    let mut rng = SplitMix64::stream(seed, u64::MAX);
    for (count, &i) in order.iter().enumerate() {
        let mut attempt = 0;
        let body = loop {
            if attempt == attempts_per_item {
                return Err(Error::RandomStart {
                    item: i,
                    placed: count,
                    attempts: attempts_per_item,
                });
            }
            attempt += 1;
            let centre = random_point(&shape, &mut rng);
            let orientation = orientations.get(i).unwrap_or(&Orientation::Isotropic);
            let body = Body::oriented(centre, axes[i], &orientation.draw::<N>(&mut rng))?;
            let inside = matches!(shape, Container::Periodic { .. })
                || containment_residual(&body, &shape) <= 0.0;
            if inside && !grid.overlaps(&body, &placed)? {
                break body;
            }
        };
        grid.insert(i, &body);
        placed[i] = Some(body);
    }
    let bodies: Vec<Body<N>> = placed.into_iter().flatten().collect();
    Ok(problem.pack_variables(&bodies, container)?)
}

/// A point uniform in the container: by rejection from the bounding box of a ball or an
/// ellipsoid (which accepts π/4 of the draws in 2D and π/6 in 3D), directly in a box or a
/// periodic cell.
fn random_point<const N: usize>(container: &Container<N>, rng: &mut SplitMix64) -> [f64; N] {
    let mut symmetric =
        |h: &[f64; N]| -> [f64; N] { std::array::from_fn(|k| h[k] * (2.0 * rng.uniform() - 1.0)) };
    match *container {
        Container::Box { half_sides } => symmetric(&half_sides),
        Container::Periodic { cell } => {
            let s: [f64; N] = std::array::from_fn(|_| rng.uniform());
            to_cartesian(&cell, &s)
        }
        Container::Ball { radius } => loop {
            let p = symmetric(&[radius; N]);
            if p.iter().map(|v| v * v).sum::<f64>() < radius * radius {
                return p;
            }
        },
        Container::Ellipsoid { semi_axes } => loop {
            let p = symmetric(&semi_axes);
            if (0..N).map(|k| (p[k] / semi_axes[k]).powi(2)).sum::<f64>() < 1.0 {
                return p;
            }
        },
    }
}

/// How an item is oriented in a random start.
#[derive(Clone, Debug, PartialEq)]
pub enum Orientation {
    /// Uniformly at random: an angle uniform in [0, π) in 2D (an ellipse is symmetric under a
    /// half turn), a rotation uniform on SO(3) in 3D (a uniform unit quaternion, Shoemake).
    Isotropic,
    /// The first body axis about `axis` (2D: its first two components), apolar, with
    /// concentration κ ≥ 0: in 3D the axis is drawn from the von Mises–Fisher density
    /// ∝ exp(κ u·n) and its sign at random, the item turned about it uniformly; in 2D the
    /// doubled angle 2θ is von Mises about the axis's. κ = 0 is isotropic; the nematic order
    /// of the start is S = 1 − 3 L(κ)/κ in 3D (L(κ) = coth κ − 1/κ, so S ≈ 1 − 3/κ for large
    /// κ) and S₂ = I₁(κ)/I₀(κ) ≈ 1 − 1/(2κ) in 2D.
    Aligned {
        /// The direction (need not be unit; not zero).
        axis: [f64; 3],
        /// κ ≥ 0.
        concentration: f64,
    },
    /// As given, in [`Body::oriented`]'s form: `[θ]` in 2D, a unit quaternion `[w, x, y, z]`
    /// in 3D.
    Given(Vec<f64>),
}

impl Orientation {
    /// An orientation in [`Body::oriented`]'s form.
    fn draw<const N: usize>(&self, rng: &mut SplitMix64) -> Vec<f64> {
        match self {
            Orientation::Given(v) => v.clone(),
            Orientation::Aligned {
                axis,
                concentration,
            } if *concentration > 0.0 => aligned::<N>(axis, *concentration, rng),
            _ => isotropic::<N>(rng),
        }
    }
}

/// See [`Orientation::Isotropic`].
fn isotropic<const N: usize>(rng: &mut SplitMix64) -> Vec<f64> {
    if N == 2 {
        return vec![std::f64::consts::PI * rng.uniform()];
    }
    let (u1, u2, u3) = (rng.uniform(), rng.uniform(), rng.uniform());
    let tau = std::f64::consts::TAU;
    let (a, b) = ((1.0 - u1).sqrt(), u1.sqrt());
    vec![
        b * (tau * u3).cos(),
        a * (tau * u2).sin(),
        a * (tau * u2).cos(),
        b * (tau * u3).sin(),
    ]
}

/// See [`Orientation::Aligned`]. 3D: the cosine w to the axis by inversion of the von
/// Mises–Fisher marginal, `w = 1 + ln(ξ + (1 − ξ) e^{−2κ}) / κ` (Wood 1994); 2D: Best and
/// Fisher's (1979) rejection for the von Mises angle.
fn aligned<const N: usize>(axis: &[f64; 3], kappa: f64, rng: &mut SplitMix64) -> Vec<f64> {
    if N == 2 {
        let base = axis[1].atan2(axis[0]);
        let doubled = von_mises(kappa, rng);
        return vec![base + 0.5 * doubled];
    }
    let norm = axis.iter().map(|v| v * v).sum::<f64>().sqrt();
    let n = if norm > 0.0 && norm.is_finite() {
        axis.map(|v| v / norm)
    } else {
        [1.0, 0.0, 0.0]
    };
    let xi = rng.uniform();
    let w = (1.0 + (xi + (1.0 - xi) * (-2.0 * kappa).exp()).ln() / kappa).clamp(-1.0, 1.0);
    let phi = std::f64::consts::TAU * rng.uniform();
    let (e1, e2) = perpendicular(&n);
    let r = (1.0 - w * w).max(0.0).sqrt();
    let sign = if rng.uniform() < 0.5 { -1.0 } else { 1.0 };
    let u: [f64; 3] =
        std::array::from_fn(|k| sign * (w * n[k] + r * (phi.cos() * e1[k] + phi.sin() * e2[k])));
    // The other two axes: a frame about u, turned by a uniform angle.
    let (f1, f2) = perpendicular(&u);
    let psi = std::f64::consts::TAU * rng.uniform();
    let v: [f64; 3] = std::array::from_fn(|k| psi.cos() * f1[k] + psi.sin() * f2[k]);
    let t = [
        u[1] * v[2] - u[2] * v[1],
        u[2] * v[0] - u[0] * v[2],
        u[0] * v[1] - u[1] * v[0],
    ];
    // Columns u, v, t: the body's axes.
    let rotation = [[u[0], v[0], t[0]], [u[1], v[1], t[1]], [u[2], v[2], t[2]]];
    implicit_packing::shape::quaternion_from_rotation(&rotation).to_vec()
}

/// Two unit vectors completing the unit vector `n` to a right-handed orthonormal frame.
fn perpendicular(n: &[f64; 3]) -> ([f64; 3], [f64; 3]) {
    let helper = if n[0].abs() < 0.9 {
        [1.0, 0.0, 0.0]
    } else {
        [0.0, 1.0, 0.0]
    };
    let dot: f64 = (0..3).map(|k| helper[k] * n[k]).sum();
    let a: [f64; 3] = std::array::from_fn(|k| helper[k] - dot * n[k]);
    let norm = a.iter().map(|v| v * v).sum::<f64>().sqrt();
    let a = a.map(|v| v / norm);
    let b = [
        n[1] * a[2] - n[2] * a[1],
        n[2] * a[0] - n[0] * a[2],
        n[0] * a[1] - n[1] * a[0],
    ];
    (a, b)
}

/// An angle from the von Mises density ∝ exp(κ cos φ) on (−π, π] (Best and Fisher 1979).
fn von_mises(kappa: f64, rng: &mut SplitMix64) -> f64 {
    let tau = 1.0 + (1.0 + 4.0 * kappa * kappa).sqrt();
    let rho = (tau - (2.0 * tau).sqrt()) / (2.0 * kappa);
    let r = (1.0 + rho * rho) / (2.0 * rho);
    loop {
        let z = (std::f64::consts::PI * rng.uniform()).cos();
        let f = (1.0 + r * z) / (r + z);
        let c = kappa * (r - f);
        let u2 = rng.uniform();
        if c * (2.0 - c) > u2 || (c / u2).ln() + 1.0 >= c {
            let sign = if rng.uniform() < 0.5 { -1.0 } else { 1.0 };
            return sign * f.clamp(-1.0, 1.0).acos();
        }
    }
}

/// A distribution of a positive factor: the scale of an item's semi-axes (its size), or the
/// stretch of its first semi-axis against the others at constant area or volume (its
/// aspect, [`stretched`]). Samples outside [min, max] are drawn again.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Distribution {
    /// ln s normal with mean 0 (median 1) and standard deviation σ.
    LogNormal {
        /// σ of ln s (≥ 0).
        sigma: f64,
        /// Least factor kept (> 0).
        min: f64,
        /// Largest factor kept.
        max: f64,
    },
    /// s normal with mean 1 and standard deviation σ.
    Normal {
        /// σ of s (≥ 0).
        sigma: f64,
        /// Least factor kept (> 0).
        min: f64,
        /// Largest factor kept.
        max: f64,
    },
    /// s uniform in [min, max].
    Uniform {
        /// Least factor (> 0).
        min: f64,
        /// Largest factor.
        max: f64,
    },
}

/// Draws of a [`Distribution`] outside its cut-offs before it gives up.
pub const MAX_REJECTIONS: usize = 1_000_000;

impl Distribution {
    /// What is wrong with the distribution's parameters, if anything: a σ that is negative or
    /// not finite, bounds that are not positive and finite or not ordered, a normal
    /// distribution whose cut-offs keep less than one draw in [`MAX_REJECTIONS`] / 100.
    pub fn defect(&self) -> Option<String> {
        let (sigma, min, max) = match *self {
            Distribution::LogNormal { sigma, min, max }
            | Distribution::Normal { sigma, min, max } => (sigma, min, max),
            Distribution::Uniform { min, max } => (0.0, min, max),
        };
        if !(sigma >= 0.0 && sigma.is_finite()) {
            return Some(format!(
                "sigma must be zero or positive and finite, not {sigma}"
            ));
        }
        if !(min > 0.0 && min.is_finite() && max.is_finite() && min <= max) {
            return Some(format!(
                "the bounds must be positive and finite with min ≤ max, not min = {min}, max = \
                 {max}"
            ));
        }
        let kept = match *self {
            Distribution::LogNormal { sigma, min, max } => {
                normal_mass((min.ln()) / sigma, (max.ln()) / sigma, sigma)
            }
            Distribution::Normal { sigma, min, max } => {
                normal_mass((min - 1.0) / sigma, (max - 1.0) / sigma, sigma)
            }
            Distribution::Uniform { .. } => 1.0,
        };
        (kept < 100.0 / MAX_REJECTIONS as f64).then(|| {
            format!(
                "its cut-offs [{min}, {max}] keep a fraction {kept:.2e} of the draws: widen them"
            )
        })
    }

    /// One factor, or `None` when [`MAX_REJECTIONS`] draws in a row fell outside the bounds.
    fn sample(&self, rng: &mut SplitMix64) -> Option<f64> {
        for _ in 0..MAX_REJECTIONS {
            let (s, min, max) = match *self {
                Distribution::LogNormal { sigma, min, max } => {
                    ((sigma * standard_normal(rng)).exp(), min, max)
                }
                Distribution::Normal { sigma, min, max } => {
                    (1.0 + sigma * standard_normal(rng), min, max)
                }
                Distribution::Uniform { min, max } => (min + (max - min) * rng.uniform(), min, max),
            };
            if (min..=max).contains(&s) {
                return Some(s);
            }
        }
        None
    }
}

/// The probability mass of a standard normal variable in [a, b]; with σ = 0 the point mass
/// at 0 (1 when a ≤ 0 ≤ b).
fn normal_mass(a: f64, b: f64, sigma: f64) -> f64 {
    if sigma == 0.0 {
        return if a <= 0.0 && b >= 0.0 { 1.0 } else { 0.0 };
    }
    let cdf = |x: f64| 0.5 * erfc(-x / std::f64::consts::SQRT_2);
    cdf(b) - cdf(a)
}

/// The complementary error function to about 1e-7 relative (Numerical Recipes' Chebyshev
/// fit), enough to judge whether cut-offs keep a usable fraction of draws.
fn erfc(x: f64) -> f64 {
    let z = x.abs();
    let t = 1.0 / (1.0 + 0.5 * z);
    let poly = -z * z - 1.265_512_23
        + t * (1.000_023_68
            + t * (0.374_091_96
                + t * (0.096_784_18
                    + t * (-0.186_288_06
                        + t * (0.278_868_07
                            + t * (-1.135_203_98
                                + t * (1.488_515_87 + t * (-0.822_152_23 + t * 0.170_872_77))))))));
    let r = t * poly.exp();
    if x >= 0.0 { r } else { 2.0 - r }
}

/// A standard normal variate (Box–Muller).
fn standard_normal(rng: &mut SplitMix64) -> f64 {
    let u1 = 1.0 - rng.uniform();
    let u2 = rng.uniform();
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}

/// `l` with its first semi-axis stretched by `t^((N−1)/N)` and the others by `t^(−1/N)`: the
/// ratio of the first to each other grows by t, the area or volume stays.
pub fn stretched<const N: usize>(l: &[f64; N], t: f64) -> [f64; N] {
    let n = N as f64;
    std::array::from_fn(|k| {
        if k == 0 {
            l[k] * t.powf((n - 1.0) / n)
        } else {
            l[k] * t.powf(-1.0 / n)
        }
    })
}

/// The semi-axes of `count` items of one group, drawn once: `base` scaled by a factor of
/// `size` and stretched ([`stretched`]) by a factor of `aspect` (each `None`: 1), from stream
/// `group` of `seed`.
///
/// # Errors
/// [`Error::Distribution`] when a distribution gave no draw within its bounds.
pub fn draw_semi_axes<const N: usize>(
    base: &[f64; N],
    count: usize,
    size: Option<&Distribution>,
    aspect: Option<&Distribution>,
    seed: u64,
    group: u64,
) -> Result<Vec<[f64; N]>, Error> {
    let mut rng = SplitMix64::stream(seed, group.wrapping_add(0x5EED));
    let mut draw = |d: Option<&Distribution>| match d {
        None => Ok(1.0),
        Some(d) => d.sample(&mut rng).ok_or(Error::Distribution { group }),
    };
    (0..count)
        .map(|_| {
            let s = draw(size)?;
            let t = draw(aspect)?;
            Ok(stretched(&base.map(|l| l * s), t))
        })
        .collect()
}

/// Placed items by bucket: cells of edge at least the largest enclosing diameter, so that
/// items within reach of each other lie in the same or adjacent buckets. In a container the
/// buckets divide its bounding box; in a periodic cell they divide the fractional coordinates,
/// `n_k = ⌊w_k / edge⌋` of them along axis k (`w_k` the cell's width across its lattice
/// planes): a Cartesian distance d has |Δs_k|·w_k ≤ d, so the same argument holds with
/// indices taken modulo `n_k`. The buckets are a dense array of linked lists (first item per
/// bucket, next item per item); the edge grows when the container would need more than
/// [`BUCKETS_PER_ITEM`] buckets per item.
struct Buckets<const N: usize> {
    edge: f64,
    /// The grid's lower corner (a container's bounding box; unused in a periodic cell).
    lower: [f64; N],
    periodic: Option<Cell<N>>,
    /// Buckets along each axis.
    counts: [i64; N],
    /// The last item put in each bucket ([`NO_ITEM`]: none).
    first: Vec<u32>,
    /// The item put in the same bucket before each item.
    next: Vec<u32>,
}

/// The end of a bucket's list.
const NO_ITEM: u32 = u32::MAX;

/// Largest number of buckets per item: a container much larger than its items gets coarser
/// buckets rather than an array mostly empty.
const BUCKETS_PER_ITEM: f64 = 8.0;

/// A periodic cell as the buckets see it.
struct Cell<const N: usize> {
    /// The cell matrix (columns: lattice vectors).
    matrix: [[f64; N]; N],
    /// Its widths across lattice planes.
    widths: [f64; N],
}

impl<const N: usize> Buckets<N> {
    /// Buckets for `items` items in `container`, of edge at least `edge`.
    fn new(container: &Container<N>, edge: f64, items: usize) -> Self {
        let (extent, periodic) = match *container {
            Container::Periodic { cell } => {
                let w = widths(&cell);
                let periodic = Cell {
                    matrix: cell,
                    widths: w,
                };
                (w, Some(periodic))
            }
            Container::Ball { radius } => ([2.0 * radius; N], None),
            Container::Ellipsoid { semi_axes } => (semi_axes.map(|a| 2.0 * a), None),
            Container::Box { half_sides } => (half_sides.map(|h| 2.0 * h), None),
        };
        let volume: f64 = extent.iter().product();
        let fine = (volume / (BUCKETS_PER_ITEM * items.max(1) as f64)).powf(1.0 / N as f64);
        let edge = edge.max(fine);
        let counts: [i64; N] = std::array::from_fn(|k| {
            let n = extent[k] / edge;
            // Fractional buckets must not be narrower than the edge; a container's must cover it.
            (if periodic.is_some() {
                n.floor()
            } else {
                n.ceil()
            } as i64)
                .max(1)
        });
        let total = counts.iter().product::<i64>() as usize;
        Self {
            edge,
            lower: extent.map(|e| -0.5 * e),
            periodic,
            counts,
            first: vec![NO_ITEM; total],
            next: vec![NO_ITEM; items],
        }
    }

    fn key(&self, centre: &[f64; N]) -> [i64; N] {
        let counts = &self.counts;
        match &self.periodic {
            None => std::array::from_fn(|k| {
                (((centre[k] - self.lower[k]) / self.edge).floor() as i64).clamp(0, counts[k] - 1)
            }),
            Some(Cell { matrix: cell, .. }) => {
                let s = to_fractional(cell, centre);
                std::array::from_fn(|k| {
                    let f = s[k] - s[k].floor();
                    ((f * counts[k] as f64) as i64).clamp(0, counts[k] - 1)
                })
            }
        }
    }

    fn slot(&self, key: &[i64; N]) -> usize {
        key.iter()
            .zip(&self.counts)
            .rev()
            .fold(0, |slot, (&k, &n)| slot * n as usize + k as usize)
    }

    fn insert(&mut self, item: usize, body: &Body<N>) {
        let slot = self.slot(&self.key(&body.centre()));
        self.next[item] = self.first[slot];
        self.first[slot] = item as u32;
    }

    /// Calls `f` on the keys of the bucket of `key` and its neighbours, each once, until it
    /// returns true; returns whether it did.
    fn any_around(
        &self,
        key: [i64; N],
        mut f: impl FnMut([i64; N]) -> Result<bool, Error>,
    ) -> Result<bool, Error> {
        let mut seen = [[0i64; N]; 27];
        let mut len = 0;
        // Only a periodic axis of fewer than three buckets wraps a neighbour onto another.
        let wraps = self.periodic.is_some() && self.counts.iter().any(|&n| n < 3);
        'keys: for code in 0..3usize.pow(N as u32) {
            let mut k = key;
            let mut c = code;
            for (axis, v) in k.iter_mut().enumerate() {
                *v += (c % 3) as i64 - 1;
                c /= 3;
                if self.periodic.is_some() {
                    *v = v.rem_euclid(self.counts[axis]);
                } else if !(0..self.counts[axis]).contains(v) {
                    continue 'keys;
                }
            }
            if wraps {
                if seen[..len].contains(&k) {
                    continue;
                }
                seen[len] = k;
                len += 1;
            }
            if f(k)? {
                return Ok(true);
            }
        }
        Ok(false)
    }

    /// Whether `body` overlaps a placed item (in a periodic cell: any image of one, or an
    /// image of itself), by PW85: μ² < 1.
    fn overlaps(&self, body: &Body<N>, placed: &[Option<Body<N>>]) -> Result<bool, Error> {
        if self.overlaps_own_images(body)? {
            return Ok(true);
        }
        self.any_around(self.key(&body.centre()), |key| {
            let mut j = self.first[self.slot(&key)];
            while j != NO_ITEM {
                if let Some(other) = &placed[j as usize]
                    && self.pair_overlaps(body, other)?
                {
                    return Ok(true);
                }
                j = self.next[j as usize];
            }
            Ok(false)
        })
    }

    /// PW85 on `a` and every image of `b` within reach (the body itself in a container).
    fn pair_overlaps(&self, a: &Body<N>, b: &Body<N>) -> Result<bool, Error> {
        let reach = a.bounding_radius() + b.bounding_radius();
        let Some(Cell {
            matrix: cell,
            widths: w,
            ..
        }) = &self.periodic
        else {
            return overlap_at(a, b, b.centre(), reach);
        };
        let (sa, sb) = (
            to_fractional(cell, &a.centre()),
            to_fractional(cell, &b.centre()),
        );
        let ds: [f64; N] = std::array::from_fn(|k| {
            let d = sb[k] - sa[k];
            d - d.round()
        });
        // |Δs_k + n_k|·w_k ≤ reach with |Δs_k| ≤ 1/2 bounds |n_k| by 1/2 + reach / w_k.
        let bound: [i64; N] = std::array::from_fn(|k| (0.5 + reach / w[k]).floor() as i64);
        let mut hit = false;
        for_each_shift(&bound, |n| {
            if hit {
                return Ok(());
            }
            let s: [f64; N] = std::array::from_fn(|k| ds[k] + n[k] as f64);
            let d = to_cartesian(cell, &s);
            let at = std::array::from_fn(|k| a.centre()[k] + d[k]);
            hit = overlap_at(a, b, at, reach)?;
            Ok(())
        })?;
        Ok(hit)
    }

    /// In a periodic cell, PW85 on the body and its own images within reach.
    fn overlaps_own_images(&self, body: &Body<N>) -> Result<bool, Error> {
        let Some(Cell {
            matrix: cell,
            widths: w,
            ..
        }) = &self.periodic
        else {
            return Ok(false);
        };
        let reach = 2.0 * body.bounding_radius();
        let bound: [i64; N] = std::array::from_fn(|k| (reach / w[k]).floor() as i64);
        let mut hit = false;
        for_each_shift(&bound, |n| {
            if hit || n.iter().all(|&v| v == 0) {
                return Ok(());
            }
            let d = to_cartesian(cell, &n.map(|v| v as f64));
            let at = std::array::from_fn(|k| body.centre()[k] + d[k]);
            hit = overlap_at(body, body, at, reach)?;
            Ok(())
        })?;
        Ok(hit)
    }
}

/// Whether `a` overlaps `b` moved to `at`: enclosing balls first, then PW85 (μ² < 1).
fn overlap_at<const N: usize>(
    a: &Body<N>,
    b: &Body<N>,
    at: [f64; N],
    reach: f64,
) -> Result<bool, Error> {
    let c = a.centre();
    let d2: f64 = (0..N).map(|k| (at[k] - c[k]).powi(2)).sum();
    if d2 >= reach * reach {
        return Ok(false);
    }
    let moved = b.with_centre(at)?;
    let contact = implicit_packing::certificate::contact(a, &moved).map_err(|source| {
        implicit_packing::Error::Certification {
            pair: (0, 0),
            source,
        }
    })?;
    Ok(contact.mu2 < 1.0)
}

/// Calls `f` for every integer vector n with |n_k| ≤ bound_k.
fn for_each_shift<const N: usize>(
    bound: &[i64; N],
    mut f: impl FnMut([i64; N]) -> Result<(), Error>,
) -> Result<(), Error> {
    let mut n = bound.map(|b| -b);
    loop {
        f(n)?;
        let mut k = 0;
        loop {
            if k == N {
                return Ok(());
            }
            n[k] += 1;
            if n[k] <= bound[k] {
                break;
            }
            n[k] = -bound[k];
            k += 1;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use implicit_packing::containment::ContainerShape;

    fn fraction<const N: usize>(p: &mut Model<N>, x: &[f64]) -> f64 {
        crate::local::item_measure(p) / p.evaluate(x, None).unwrap().objective
    }

    /// The Z-order of the 4 × 4 points of a square visits each 2 × 2 quadrant in turn, and
    /// the sorted variables go back to the same bits, with round items (no angle) among the
    /// others.
    #[test]
    fn the_spatial_order_visits_quadrants_in_turn_and_is_undone() {
        // Items 0..16 at (a, b) with item index 4a + b, the odd ones ellipses with angle 0.5 i;
        // container last.
        let axes: Vec<[f64; 2]> = (0..16)
            .map(|i| if i % 2 == 0 { [1.0, 1.0] } else { [2.0, 1.0] })
            .collect();
        let layout = Layout::of(&axes);
        let mut x = Vec::new();
        for i in 0..16 {
            x.extend_from_slice(&[(i / 4) as f64, (i % 4) as f64]);
            if i % 2 == 1 {
                x.push(0.5 * i as f64);
            }
        }
        x.extend_from_slice(&[9.0, 8.0]);
        let order = spatial_order::<2>(&x, &layout);
        let mut seen = order.clone();
        seen.sort_unstable();
        assert_eq!(seen, (0..16).collect::<Vec<_>>());
        for quadrant in order.chunks(4) {
            let corner = |i: usize| (i / 4 / 2, i % 4 / 2);
            assert!(
                quadrant.iter().all(|&i| corner(i) == corner(quadrant[0])),
                "{order:?}"
            );
        }
        let sorted_layout = Layout::of(&order.iter().map(|&i| axes[i]).collect::<Vec<_>>());
        let sorted = in_order(&x, &order, &layout);
        assert_eq!(sorted[sorted_layout.range(0)], x[layout.range(order[0])]);
        assert_eq!(sorted[sorted.len() - 2..], [9.0, 8.0]);
        assert_eq!(back_in_order(&sorted, &order, (&sorted_layout, &layout)), x);
    }

    #[test]
    fn random_starts_are_certified_in_every_container_kind() {
        for kind in [
            ContainerShape::Ball,
            ContainerShape::Ellipsoid,
            ContainerShape::Box,
            ContainerShape::Periodic,
        ] {
            let mut p = Model::<3>::new(vec![[1.0, 0.75, 0.5]; 60], kind).unwrap();
            let dims: Vec<f64> = match kind {
                ContainerShape::Ball => vec![6.0],
                ContainerShape::Periodic => vec![9.0, 9.0, 9.0, 0.0, 0.0, 0.0],
                _ => vec![7.0, 5.5, 5.0],
            };
            let x = sequential_addition(&p, &dims, 7, ATTEMPTS_PER_ITEM).unwrap();
            assert!(p.certify(&x).unwrap().is_feasible(), "{kind:?}");
            assert_eq!(&x[60 * 6..], &dims[..]);
            let mut q = Model::<2>::new(vec![[2.0, 1.0]; 40], kind).unwrap();
            let dims2: Vec<f64> = match kind {
                ContainerShape::Ball => vec![18.0],
                ContainerShape::Periodic => vec![30.0, 28.0, 3.0],
                _ => vec![17.0, 14.0],
            };
            let y = sequential_addition(&q, &dims2, 7, ATTEMPTS_PER_ITEM).unwrap();
            assert!(q.certify(&y).unwrap().is_feasible(), "{kind:?} 2D");
            assert!(fraction(&mut q, &y) > 0.0);
        }
    }

    #[test]
    fn the_same_seed_gives_the_same_start_and_another_seed_another() {
        let p = Model::<2>::new(vec![[1.0, 1.0]; 16], ContainerShape::Periodic).unwrap();
        let dims = [12.0, 12.0, 0.0];
        let a = sequential_addition(&p, &dims, 3, ATTEMPTS_PER_ITEM).unwrap();
        let b = sequential_addition(&p, &dims, 3, ATTEMPTS_PER_ITEM).unwrap();
        let c = sequential_addition(&p, &dims, 4, ATTEMPTS_PER_ITEM).unwrap();
        assert_eq!(a, b);
        assert_ne!(a, c);
    }

    /// The first axis's nematic order over many draws against the closed forms of
    /// [`Orientation::Aligned`].
    #[test]
    fn aligned_orientations_have_the_order_of_their_concentration() {
        let mut rng = SplitMix64::new(5);
        let kappa = 20.0;
        let n = 20_000;
        let (mut c2, mut cos, mut sin) = (0.0, 0.0, 0.0);
        for _ in 0..n {
            let q = aligned::<3>(&[0.0, 0.0, 2.0], kappa, &mut rng);
            let m = implicit_packing::shape::rotation_from_quaternion([q[0], q[1], q[2], q[3]])
                .unwrap();
            c2 += m[2][0] * m[2][0];
            let t = aligned::<2>(&[1.0, 1.0, 0.0], kappa, &mut rng)[0];
            let d = 2.0 * (t - std::f64::consts::FRAC_PI_4);
            cos += d.cos();
            sin += d.sin();
        }
        let s3 = (3.0 * c2 / n as f64 - 1.0) / 2.0;
        let langevin = 1.0 / kappa.tanh() - 1.0 / kappa;
        assert!((s3 - (1.0 - 3.0 * langevin / kappa)).abs() < 0.005, "{s3}");
        // I1/I0 by their series.
        let bessel = |order: i32| {
            (0..80)
                .map(|k: i32| {
                    let lg = |v: i32| (1..=v).map(|i| (i as f64).ln()).sum::<f64>();
                    ((2 * k + order) as f64 * (kappa / 2.0).ln() - lg(k) - lg(k + order)).exp()
                })
                .sum::<f64>()
        };
        let s2 = (cos * cos + sin * sin).sqrt() / n as f64;
        assert!((s2 - bessel(1) / bessel(0)).abs() < 0.005, "{s2}");
    }

    #[test]
    fn distributions_keep_their_bounds_and_centre() {
        let mut rng = SplitMix64::new(3);
        let lognormal = Distribution::LogNormal {
            sigma: 0.3,
            min: 0.5,
            max: 2.0,
        };
        let mut draws: Vec<f64> = (0..10_001)
            .map(|_| lognormal.sample(&mut rng).unwrap())
            .collect();
        draws.sort_by(f64::total_cmp);
        assert!(draws[0] >= 0.5 && draws[10_000] <= 2.0);
        assert!((draws[5000] - 1.0).abs() < 0.02, "median {}", draws[5000]);
        let uniform = Distribution::Uniform { min: 1.0, max: 3.0 };
        let mean = (0..10_000)
            .map(|_| uniform.sample(&mut rng).unwrap())
            .sum::<f64>()
            / 1e4;
        assert!((mean - 2.0).abs() < 0.03);
        assert_eq!(lognormal.defect(), None);
        let far = Distribution::Normal {
            sigma: 0.01,
            min: 2.0,
            max: 3.0,
        };
        assert!(far.defect().unwrap().contains("keep a fraction"));
        let bad = Distribution::Uniform { min: 2.0, max: 1.0 };
        assert!(bad.defect().unwrap().contains("min ≤ max"));
        let axes = draw_semi_axes(&[2.0, 1.0, 1.0], 50, None, Some(&uniform), 1, 0).unwrap();
        for l in axes {
            let ratio = l[0] / l[1];
            assert!((2.0..=6.0 + 1e-12).contains(&ratio), "{ratio}");
            assert!((l.iter().product::<f64>() - 2.0).abs() < 1e-12);
        }
    }

    #[test]
    fn polydisperse_aligned_items_jam_certified_in_a_periodic_cell() {
        let sizes = Distribution::LogNormal {
            sigma: 0.25,
            min: 0.6,
            max: 1.6,
        };
        let axes = draw_semi_axes(&[1.0, 0.6, 0.4], 60, Some(&sizes), None, 4, 0).unwrap();
        let mut p = Model::<3>::new(axes, ContainerShape::Periodic).unwrap();
        let along_z = Orientation::Aligned {
            axis: [0.0, 0.0, 1.0],
            concentration: 50.0,
        };
        let local = LocalSettings::default()
            .with_method(LocalMethod::Compression)
            .with_fixed_orientations(vec![true; 60]);
        let settings = RandomSettings::new(Target::Jammed, 4)
            .with_orientations(vec![along_z; 60])
            .with_local(local);
        let r = random_packing(
            &mut p,
            &[1.0, 1.0, 1.0, 0.0, 0.0, 0.0],
            &settings,
            &mut |_| false,
        )
        .unwrap();
        assert!(p.certify(&r.packing.x).unwrap().is_feasible());
        assert!(r.packing.density > 0.5, "{}", r.packing.density);
        // The first axes kept their alignment along z: S = 1 − 3 L(50)/50 ≈ 0.94 at the start.
        let bodies = p.bodies_at(&r.packing.x).unwrap();
        let c2 = bodies
            .iter()
            .map(|b| b.rotation()[2][0].powi(2))
            .sum::<f64>()
            / 60.0;
        let order = (3.0 * c2 - 1.0) / 2.0;
        assert!(order > 0.85, "{order}");
    }

    #[test]
    fn a_container_too_small_for_the_items_is_a_typed_error() {
        let p = Model::<2>::new(vec![[1.0, 1.0]; 10], ContainerShape::Ball).unwrap();
        // Ten unit discs do not fit in a disc of radius 2.
        let r = sequential_addition(&p, &[2.0], 1, 200);
        assert!(
            matches!(r, Err(Error::RandomStart { attempts: 200, .. })),
            "{r:?}"
        );
    }

    /// An item longer than a thin periodic cell is wide overlaps its own image; the start
    /// never keeps such a placement.
    #[test]
    fn items_never_overlap_their_own_images() {
        let mut p = Model::<2>::new(vec![[3.0, 0.5]; 4], ContainerShape::Periodic).unwrap();
        let dims = [4.0, 40.0, 0.0];
        let x = sequential_addition(&p, &dims, 11, ATTEMPTS_PER_ITEM).unwrap();
        assert!(p.certify(&x).unwrap().is_feasible());
    }

    #[test]
    fn a_target_fraction_is_reached_exactly_in_a_periodic_cell() {
        let m = 40;
        let mut p = Model::<3>::new(vec![[1.0, 1.0, 1.0]; m], ContainerShape::Periodic).unwrap();
        let volume = crate::local::item_measure(&p);
        let side = (volume / 0.5).cbrt();
        let dims = [side, side, side, 0.0, 0.0, 0.0];
        let settings = RandomSettings::new(Target::Fraction, 5);
        let r = random_packing(&mut p, &dims, &settings, &mut |_| false).unwrap();
        assert!(r.packing.certificate.is_feasible());
        assert_eq!(&r.packing.x[p.layout().item_variables()..], &dims[..]);
        assert!(
            (r.packing.density - 0.5).abs() < 1e-12,
            "{}",
            r.packing.density
        );
        assert!(r.start_density < 0.21);
        assert!(p.certify(&r.packing.x).unwrap().is_feasible());
    }

    #[test]
    fn a_fixed_ball_is_filled_at_its_fraction_from_a_random_start() {
        let m = 30;
        let mut p = Model::<2>::new(vec![[1.5, 1.0]; m], ContainerShape::Ball).unwrap();
        let area = crate::local::item_measure(&p);
        let radius = (area / 0.6 / std::f64::consts::PI).sqrt();
        let settings = RandomSettings::new(Target::Fraction, 2);
        let r = random_packing(&mut p, &[radius], &settings, &mut |_| false).unwrap();
        assert!(p.certify(&r.packing.x).unwrap().is_feasible());
        assert_eq!(*r.packing.x.last().unwrap(), radius);
        assert!((r.packing.density - 0.6).abs() < 1e-12);
    }

    /// Jammed discs of two sizes (ratio 1.4, half and half) in a periodic square: denser than
    /// the start and than random close packing's lower reaches, and less dense than the
    /// hexagonal crystal (0.9069).
    #[test]
    fn bidisperse_discs_jam_between_random_and_crystal() {
        let mut axes = vec![[0.5, 0.5]; 24];
        axes.extend(vec![[0.7, 0.7]; 24]);
        let mut p = Model::<2>::new(axes, ContainerShape::Periodic).unwrap();
        let settings = RandomSettings::new(Target::Jammed, 9);
        let r = random_packing(&mut p, &[1.0, 1.0, 0.0], &settings, &mut |_| false).unwrap();
        assert!(p.certify(&r.packing.x).unwrap().is_feasible());
        let d = r.packing.density;
        eprintln!("jammed bidisperse discs: {d} from {}", r.start_density);
        assert!(d > 0.78 && d < 0.9069, "jammed at {d}");
        let cell = &r.packing.x[p.layout().item_variables()..];
        assert_eq!(cell[2], 0.0, "the square stays a square");
        assert!((cell[0] - cell[1]).abs() < 1e-12 * cell[0]);
    }

    #[test]
    fn the_observer_stops_a_target_run_short_of_its_fraction() {
        let mut p = Model::<2>::new(vec![[1.0, 1.0]; 20], ContainerShape::Box).unwrap();
        let half = (crate::local::item_measure(&p) / 0.8).sqrt() / 2.0;
        let settings = RandomSettings::new(Target::Fraction, 1);
        let r = random_packing(&mut p, &[half, half], &settings, &mut |_| true);
        let Err(Error::NotReached(u)) = r else {
            panic!("an interrupted run reached its fraction: {r:?}");
        };
        assert!(u.interrupted);
        assert_eq!(&u.x[p.layout().item_variables()..], &[half, half]);
        assert!((u.density - 0.8).abs() < 1e-12);
    }
}
