//! Minimum-container packing: one local minimisation of the model by the augmented Lagrangian,
//! from the paper's initial solutions, then an exact certificate and the least repair.
//!
//! The problem (paper Section 6, eqs. 19 and 33):
//!
//! ```text
//! minimise   area or volume of the container
//! subject to overlap(x) = Σ_{i<j} f_ij = 0,   containment(x) = 0,   container dims ≥ l_min
//! ```
//!
//! solved by [`auglag`] (PHR augmented Lagrangian, as Algencan) through a fused evaluation of
//! the model: the objective, both constraints and their gradients in one pass over the grid.
//!
//! The model satisfies its constraints only to a tolerance, so every result is certified with
//! PW85 verdicts and exact containment ([`Model::certify`]) and, if anything still overlaps
//! or sticks out, repaired ([`repair`]): scaling every centre and the container by s leaves
//! the shapes as they are and multiplies every pair's contact function by s², so the
//! overlapping pairs need s = max 1/μ_ij exactly; an item still outside is then held by
//! scaling the container alone by its containment scale t. The repair costs a factor (s·t)^N
//! in density, which is reported.
//!
//! # References
//! - E. G. Birgin, R. D. Lobato, J. M. Martínez, *A nonlinear programming model with implicit
//!   variables for packing ellipsoids*, J. Global Optim. 68 (2017), Section 6 (initial
//!   solutions, Algencan).

use crate::Error;
use crate::compression::compression_to;
use crate::problem::Adapter;
use crate::repair::certified;
pub use crate::repair::{certified_start, repair};
pub use crate::settings::{
    FIXED_MARGIN, InnerSolver, LocalMethod, LocalResult, LocalSettings, infeasibility, item_measure,
};
use crate::settings::{add_counts, centre_bound, check_start, solver};
use auglag::Progress;
use implicit_packing::model::Model;

/// One local minimisation from `x0`, certified and repaired. `observe` sees the solver's
/// progress at every iteration (objective and infeasibility at the end of each outer
/// iteration); returning `true` stops the solver, and the point reached is still certified and
/// repaired.
///
/// # Errors
/// [`Error::Model`] (`LengthMismatch`) when `x0` does not fit the problem; errors of the model on
/// non-finite variables at the start; [`Error::Solver`] when the solver refuses the start;
/// [`Error::NotCertifiable`] when no repair by a factor up to 4 certifies the point reached
/// (an item far outside the container).
pub fn local_minimisation<const N: usize>(
    problem: &mut Model<N>,
    x0: &[f64],
    settings: &LocalSettings,
    observe: &mut dyn FnMut(&Progress<'_>) -> bool,
) -> Result<LocalResult, Error> {
    check_start(problem, x0)?;
    problem.evaluate(x0, None)?;
    if settings.fixed_container {
        return placement(problem, x0, settings, observe);
    }
    match settings.method {
        LocalMethod::AugmentedLagrangian => lagrangian(problem, x0, settings, observe),
        LocalMethod::Compression => {
            compression_to(problem, x0, settings, None, observe, &mut |_| {})
        }
        LocalMethod::CompressionThenLagrangian => {
            let compressed = compression_to(problem, x0, settings, None, observe, &mut |_| {})?;
            if compressed.report.stop_reason == auglag::StopReason::Interrupted {
                return Ok(compressed);
            }
            // The compressed packing is certified: whatever the augmented Lagrangian does
            // after it, it is never lost.
            let Ok(refined) = lagrangian(problem, &compressed.x, settings, observe) else {
                return Ok(compressed);
            };
            let stop_reason = refined.report.stop_reason;
            let (mut kept, other) = if refined.density > compressed.density {
                (refined, compressed)
            } else {
                (compressed, refined)
            };
            add_counts(&mut kept.report, &other.report);
            kept.report.stop_reason = stop_reason;
            Ok(kept)
        }
    }
}

/// The augmented Lagrangian on the paper's model from `x0`, certified and repaired, with
/// the polish when the repair had something to do.
fn lagrangian<const N: usize>(
    problem: &mut Model<N>,
    x0: &[f64],
    settings: &LocalSettings,
    observe: &mut dyn FnMut(&Progress<'_>) -> bool,
) -> Result<LocalResult, Error> {
    let mut run = solver(settings, observe);
    let mut solve = |problem: &mut Model<N>, x: &[f64], feasibility: f64| {
        let adapter = Adapter::new(problem, centre_bound::<N>(x0), None);
        run(&adapter, x, feasibility)
    };
    let mut first = solve(problem, x0, settings.feasibility_tolerance)?;
    for _ in 0..PULLS_PER_MINIMISATION {
        if first.report.stop_reason == auglag::StopReason::Interrupted {
            break;
        }
        let pairs = crate::merged::few_merged(&problem.certify(&first.x)?, problem.len());
        if pairs.is_empty() {
            break;
        }
        let Some(apart) = crate::merged::pulled_apart(problem, &first.x, &pairs) else {
            break;
        };
        let mut again = solve(problem, &apart, settings.feasibility_tolerance)?;
        add_counts(&mut again.report, &first.report);
        first = again;
    }
    let mut best = certified(problem, first)?;
    if let Some(tolerance) = settings.polish_tolerance
        && best.repair_factor > 1.0
        && best.report.stop_reason != auglag::StopReason::Interrupted
    {
        let start = best.x_unrepaired.clone();
        let solution = solve(problem, &start, tolerance)?;
        let polished = certified(problem, solution)?;
        if polished.result.density > best.result.density {
            best = polished;
        }
    }
    Ok(best.result)
}

/// Solves from pairs pulled apart in one local minimisation at most: the pairs that merge
/// again after as many pulls are given up with the point.
///
/// The overlap measure is bounded, so where the solver shrinks the container against a few
/// deep overlaps it can push those pairs through one another and stop with them merged
/// (`PenaltyTooLarge`, [`crate::merged::merged`]): a point no dilation of 4 repairs. From a
/// perturbation of the best packing of 100 ellipsoids (1, 0.75, 0.5) in a ball at the paper's
/// amplitude 0.1 this was every start tried, with 2 to 5 such pairs among points of density
/// 0.61–0.68 before repair. Pulled apart ([`crate::merged::pulled_apart`]), they are ordinary
/// overlaps for the next solve. Only a few merged pairs are pulled
/// ([`crate::merged::few_merged`]).
const PULLS_PER_MINIMISATION: usize = 3;

/// [`local_minimisation`] in feasibility mode: the container stays as the start gives it, the
/// solver drives overlap and containment to zero for items grown by [`FIXED_MARGIN`], and the
/// true items are certified. A point the first solve leaves uncertified is solved again from
/// where it stopped at the polish tolerance; the less infeasible of the two is returned.
fn placement<const N: usize>(
    problem: &mut Model<N>,
    x0: &[f64],
    settings: &LocalSettings,
    observe: &mut dyn FnMut(&Progress<'_>) -> bool,
) -> Result<LocalResult, Error> {
    let grown: Vec<[f64; N]> = problem
        .semi_axes()
        .iter()
        .map(|l| l.map(|v| v * (1.0 + FIXED_MARGIN)))
        .collect();
    let mut solver_model = Model::<N>::new(grown, problem.container_kind())?;
    let container = x0[problem.layout().item_variables()..].to_vec();
    let mut run = solver(settings, observe);
    let mut solve = |x: &[f64], feasibility: f64| {
        let adapter = Adapter::new(
            &mut solver_model,
            centre_bound::<N>(x0),
            Some(container.clone()),
        );
        run(&adapter, x, feasibility)
    };
    let items = item_measure(problem);
    let judge = |problem: &mut Model<N>, solution: auglag::Solution| {
        let certificate = problem.certify(&solution.x)?;
        let objective = problem.evaluate(&solution.x, None)?.objective;
        Ok::<_, Error>(LocalResult {
            density: items / objective,
            density_before_repair: items / objective,
            repair_factor: 1.0,
            objective,
            certificate,
            report: solution.report,
            x: solution.x,
        })
    };
    let first = solve(x0, settings.feasibility_tolerance)?;
    let first = judge(problem, first)?;
    if first.certificate.is_feasible()
        || first.report.stop_reason == auglag::StopReason::Interrupted
    {
        return Ok(first);
    }
    let Some(tolerance) = settings.polish_tolerance else {
        return Ok(first);
    };
    let second = solve(&first.x, tolerance)?;
    let second = judge(problem, second)?;
    if second.certificate.is_feasible()
        || infeasibility(problem, &second.x)? <= infeasibility(problem, &first.x)?
    {
        Ok(second)
    } else {
        Ok(first)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::starts::lattice_start;
    use auglag::Phr;
    use implicit_packing::containment::ContainerShape;

    /// In energy mode the objective is overlap + containment with its gradient (against
    /// central differences), the Lagrangian the same scaled, and there are no constraints.
    #[test]
    fn energy_mode_is_the_overlap_energy_without_constraints() {
        use auglag::Problem;
        let mut model = Model::<2>::new(vec![[2.0, 1.0]; 6], ContainerShape::Ellipsoid).unwrap();
        let mut x = lattice_start(&model);
        let n = x.len();
        // Centres (and angles) drawn together, the container shrunk more: overlaps and items
        // sticking out.
        for (k, v) in x.iter_mut().enumerate() {
            *v *= if k >= n - 2 { 0.7 } else { 0.8 };
        }
        let e = model.evaluate(&x, None).unwrap();
        assert!(e.overlap > 0.0 && e.containment > 0.0, "{e:?}");
        let container = x[n - 2..].to_vec();
        let adapter = Adapter::new(&mut model, 1e3, Some(container)).in_energy_mode(true);
        assert_eq!(adapter.n_eq(), 0);
        let mut g = vec![0.0; n];
        assert_eq!(
            adapter.objective(&x, Some(&mut g)),
            e.overlap + e.containment
        );
        let phr = Phr::new(10.0, 0, 0.5, &[], &[]);
        let mut gl = vec![0.0; n];
        assert_eq!(
            adapter.lagrangian(&x, &phr, Some(&mut gl)),
            Some(0.5 * (e.overlap + e.containment))
        );
        let h = 1e-6;
        for k in 0..n - 2 {
            let at = |t: f64| {
                let mut y = x.clone();
                y[k] += t;
                adapter.objective(&y, None)
            };
            let fd = (at(h) - at(-h)) / (2.0 * h);
            assert!(
                (fd - g[k]).abs() <= 1e-5 * (1.0 + g[k].abs()),
                "{k}: {fd} {}",
                g[k]
            );
            assert_eq!(gl[k], 0.5 * g[k]);
        }
    }

    /// The adapter's exact Hessian products against central differences of its own fused
    /// gradient, on an overlapping point, for ellipses and ellipsoids.
    #[test]
    fn hessian_products_match_differences_of_the_gradient() {
        fn check<const N: usize>(axes: [f64; N], kind: ContainerShape) {
            use auglag::Problem;
            let mut model = Model::<N>::new(vec![axes; 12], kind).unwrap();
            let mut x = lattice_start(&model);
            let n = x.len();
            // Shrink the container and shift the items: overlaps and items sticking out.
            for (k, v) in x.iter_mut().enumerate() {
                *v *= if k >= n - N { 0.85 } else { 1.0 };
                *v += 0.01 * ((k * 7919 % 13) as f64 - 6.0);
            }
            let adapter = Adapter::new(&mut model, 1e3, None);
            let (scales, multipliers) = ([0.5, 2.0], [0.3, -0.2]);
            let phr = Phr::new(10.0, 2, 0.7, &scales, &multipliers);
            let v: Vec<f64> = (0..n).map(|k| ((k * 31 % 17) as f64 - 8.0) / 8.0).collect();
            let mut hv = vec![0.0; n];
            assert!(adapter.hessian_times(&x, &phr, &v, &mut hv));
            let h = 1e-6;
            let gradient_at = |t: f64| {
                let y: Vec<f64> = x.iter().zip(&v).map(|(a, b)| a + t * b).collect();
                let mut g = vec![0.0; n];
                adapter.lagrangian(&y, &phr, Some(&mut g)).unwrap();
                g
            };
            let (plus, minus) = (gradient_at(h), gradient_at(-h));
            let scale = hv.iter().fold(1.0_f64, |m, a| m.max(a.abs()));
            for k in 0..n {
                let fd = (plus[k] - minus[k]) / (2.0 * h);
                assert!(
                    (hv[k] - fd).abs() <= 1e-5 * scale,
                    "{N}D, variable {k}: {} against {fd}",
                    hv[k]
                );
            }
            assert!(hv.iter().any(|&a| a != 0.0));
        }
        check([2.0, 1.0], ContainerShape::Ellipsoid);
        check([1.0, 0.75, 0.5], ContainerShape::Ball);
    }

    #[test]
    fn lattice_start_is_certified_feasible() {
        let mut p2 = Model::<2>::new(vec![[2.0, 1.0]; 30], ContainerShape::Ellipsoid).unwrap();
        let x = lattice_start(&p2);
        assert!(p2.certify(&x).unwrap().is_feasible());
        let mut p3 = Model::<3>::new(vec![[1.0, 0.75, 0.5]; 27], ContainerShape::Box).unwrap();
        let x = lattice_start(&p3);
        assert!(p3.certify(&x).unwrap().is_feasible());
    }

    #[test]
    fn two_and_three_unit_circles_in_the_smallest_circle() {
        // Known optima: R = 2 for two unit circles, 1 + 2/√3 for three.
        for (m, optimum) in [(2, 2.0), (3, 1.0 + 2.0 / 3f64.sqrt())] {
            let mut p = Model::<2>::new(vec![[1.0, 1.0]; m], ContainerShape::Ball).unwrap();
            let mut x = lattice_start(&p);
            // Break the symmetry of the lattice start a little.
            x[2] += 0.1;
            let settings = LocalSettings {
                feasibility_tolerance: 1e-8,
                optimality_tolerance: 1e-8,
                ..LocalSettings::default()
            };
            let r = local_minimisation(&mut p, &x, &settings, &mut |_| false).unwrap();
            assert!(r.certificate.is_feasible());
            let radius = *r.x.last().unwrap();
            assert!(
                (radius - optimum).abs() < 1e-3 * optimum,
                "m = {m}: R = {radius} vs {optimum} ({:?})",
                r.report.stop_reason
            );
            assert!(r.density <= m as f64 / (optimum * optimum) * (1.0 + 1e-9));
        }
    }

    #[test]
    fn ellipses_in_an_ellipse_end_certified_and_denser_than_the_start() {
        let mut p = Model::<2>::new(vec![[2.0, 1.0]; 12], ContainerShape::Ellipsoid).unwrap();
        let x0 = lattice_start(&p);
        let start_density = item_measure(&p) / p.evaluate(&x0, None).unwrap().objective;
        let r = local_minimisation(&mut p, &x0, &LocalSettings::default(), &mut |_| false).unwrap();
        assert!(r.certificate.is_feasible());
        assert!(
            r.density > start_density,
            "{} vs start {start_density}",
            r.density
        );
        assert!(r.repair_factor >= 1.0 && r.density <= r.density_before_repair);
    }

    /// Two unit spheres at `x₁` and `x₂` on the x axis in a ball of `radius`, repaired: the
    /// variables before and after (a sphere's centre, no angles; the radius last), and the
    /// dilation; the repair is certified.
    fn two_unit_spheres_repaired(x1: f64, x2: f64, radius: f64) -> (Vec<f64>, Vec<f64>, f64) {
        let mut p = Model::<3>::new(vec![[1.0, 1.0, 1.0]; 2], ContainerShape::Ball).unwrap();
        let mut x = vec![0.0; 7];
        (x[0], x[3], x[6]) = (x1, x2, radius);
        let (y, s, cert) = repair(&mut p, &x).unwrap();
        assert!(cert.is_feasible());
        (x, y, s)
    }

    #[test]
    fn repair_holds_an_item_outside_by_scaling_the_container_alone() {
        // A unit sphere at 2.5 from the centre of a ball of radius 3 sticks out by 0.5: the
        // container needs t = 3.5/3, a uniform dilation s = 2 (2.5 s + 1 ≤ 3 s).
        let (x, y, s) = two_unit_spheres_repaired(2.5, -1.5, 3.0);
        assert!((s - 3.5 / 3.0).abs() < 1e-9, "{s}");
        assert_eq!(y[..6], x[..6]);
        assert!((y[6] - 3.5).abs() < 1e-9);
    }

    #[test]
    fn repair_holds_an_item_outside_a_box_by_scaling_its_half_sides() {
        let mut p = Model::<2>::new(vec![[2.0, 1.0]; 2], ContainerShape::Box).unwrap();
        // The first ellipse reaches x = 4.5 in a box of half-sides (4, 2): t = 4.5/4, and the
        // box keeps its aspect.
        let x = vec![2.5, 0.0, 0.0, -1.6, 0.0, 0.0, 4.0, 2.0];
        let (y, s, cert) = repair(&mut p, &x).unwrap();
        assert!(cert.is_feasible());
        assert!((s - 1.125).abs() < 1e-9, "{s}");
        assert_eq!(y[..6], x[..6]);
        assert!((y[6] - 4.5).abs() < 1e-9 && (y[7] - 2.25).abs() < 1e-9);
    }

    #[test]
    fn repair_separates_then_holds_by_the_product_of_the_two_factors() {
        // Unit spheres 1.5 apart in a ball of radius 1.2: s = 4/3 moves them to ±1 in a ball
        // of radius 1.6, which t = 2/1.6 then makes 2. A uniform dilation needs 1/0.45.
        let (_, y, s) = two_unit_spheres_repaired(0.75, -0.75, 1.2);
        assert!((s - 4.0 / 3.0 * 1.25).abs() < 1e-9, "{s}");
        assert!((y[0] - 1.0).abs() < 1e-9 && (y[3] + 1.0).abs() < 1e-9);
        assert!((y[6] - 2.0).abs() < 1e-9, "{}", y[6]);
    }

    #[test]
    fn repair_separates_overlapping_items_by_the_least_dilation() {
        // Two unit spheres 1.5 apart in a ball of radius 3: μ = 0.75, s = 4/3.
        let (_, y, s) = two_unit_spheres_repaired(-0.75, 0.75, 3.0);
        assert!((s - 4.0 / 3.0).abs() < 1e-9, "{s}");
        assert!((y[3] - y[0] - 2.0).abs() < 1e-9);
    }

    /// A perturbation of a packing at the paper's 3D amplitude drives a few pairs through one
    /// another; pulled apart and solved again, the point is a packing, denser than the one
    /// perturbed (without the pulls no repair within a factor of 4 makes it one).
    #[test]
    fn merged_pairs_are_pulled_apart_and_solved_again() {
        let mut p = Model::<3>::new(vec![[1.0, 0.75, 0.5]; 100], ContainerShape::Ball).unwrap();
        let settings = LocalSettings::default();
        let x0 = lattice_start(&p);
        let packed = local_minimisation(&mut p, &x0, &settings, &mut |_| false).unwrap();
        let start = crate::starts::perturb::<3>(&packed.x, p.layout(), 0.1, 0, 1);
        let mut never = |_: &Progress<'_>| false;
        let mut solve = solver::<3>(&settings, &mut never);
        let adapter = Adapter::new(&mut p, centre_bound::<3>(&start), None);
        let first = solve(&adapter, &start, settings.feasibility_tolerance).unwrap();
        drop(adapter);
        let certificate = p.certify(&first.x).unwrap();
        assert!(
            !crate::merged::merged(&certificate).is_empty(),
            "the first solve merged no pair"
        );
        assert!(
            !crate::merged::few_merged(&certificate, p.len()).is_empty(),
            "too many merged pairs to pull"
        );
        let r = local_minimisation(&mut p, &start, &settings, &mut |_| false).unwrap();
        assert!(r.certificate.is_feasible());
        assert!(r.repair_factor < 1.001, "{}", r.repair_factor);
        assert!(
            r.density > packed.density,
            "{} vs {}",
            r.density,
            packed.density
        );
    }

    /// Two spheres almost on top of each other (μ ≈ 0.005) would need a dilation of 200: no
    /// repair past a factor of 4 is a packing, whichever step would find it.
    #[test]
    fn repair_gives_up_on_items_collapsed_into_each_other() {
        let mut p = Model::<3>::new(vec![[1.0, 1.0, 1.0]; 2], ContainerShape::Ball).unwrap();
        let x = vec![0.005, 0.0, 0.0, -0.005, 0.0, 0.0, 3.0];
        let e = repair(&mut p, &x).unwrap_err();
        assert!(
            matches!(e, Error::NotCertifiable { max_dilation, overlapping: 1, outside: 0 }
                if max_dilation == 4.0),
            "{e:?}"
        );
        // At μ = 0.3 (centres 0.6 apart) the dilation of 1/0.3 is within the limit.
        let (_, y, s) = two_unit_spheres_repaired(0.3, -0.3, 3.0);
        assert!((s - 1.0 / 0.3).abs() < 1e-9, "{s}");
        assert!((y[0] - y[3] - 2.0).abs() < 1e-9);
    }

    #[test]
    fn interrupt_still_returns_a_certified_packing() {
        let mut p = Model::<3>::new(vec![[1.0, 0.75, 0.5]; 20], ContainerShape::Ball).unwrap();
        let x0 = lattice_start(&p);
        let mut calls = 0;
        let r = local_minimisation(&mut p, &x0, &LocalSettings::default(), &mut |_| {
            calls += 1;
            calls > 5
        })
        .unwrap();
        assert!(r.certificate.is_feasible());
        assert_eq!(r.report.stop_reason, auglag::StopReason::Interrupted);
    }
}
