//! One local minimisation from the paper's lattice start (or, with a fourth argument `dense`,
//! the face-centred cubic / hexagonal start of `ellipsoid_packer::starts`), certified and
//! repaired: `cargo run --release -p ellipsoid-packer --example local_minimisation -- 3 ball 100`.
//! A fifth argument chooses the inner solver: `lbfgs` (default), `spg` or `newton`; a sixth the
//! cap on inner iterations per outer iteration (default 2000); a seventh the semi-axes of every
//! item, separated by commas (default `2,1` in 2D, `1,0.75,0.5` in 3D; `1,1,1` for balls).
//! Prints the time of the minimisation alone and per evaluation of the model.

use ellipsoid_packer::local::{LocalSettings, local_minimisation};
use ellipsoid_packer::starts::lattice_start;
use ellipsoid_packer::starts::{LatticeStart, lattice_start_of};
use implicit_packing::containment::ContainerShape;
use implicit_packing::model::Model;
use std::time::Instant;

mod common;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let dim: usize = args.get(1).map_or(Ok(3), |s| s.parse())?;
    let kind = common::container_kind(args.get(2).map_or("ball", String::as_str))?;
    let m: usize = args.get(3).map_or(Ok(100), |s| s.parse())?;
    let dense = match args.get(4).map_or("paper", String::as_str) {
        "paper" => false,
        "dense" => true,
        other => return Err(format!("unknown start `{other}` (paper or dense)").into()),
    };
    let solver = match args.get(5).map_or("lbfgs", String::as_str) {
        "lbfgs" => auglag::InnerSolver::ProjectedLbfgs,
        "spg" => auglag::InnerSolver::Spg,
        "newton" => auglag::InnerSolver::TruncatedNewton,
        other => return Err(format!("unknown inner solver `{other}` (lbfgs, spg, newton)").into()),
    };
    let mut settings = LocalSettings::default().with_inner_solver(solver);
    if let Some(cap) = args.get(6).filter(|c| *c != "-") {
        settings = settings.with_max_inner_iterations(cap.parse()?);
    }
    let axes: Vec<f64> = match args.get(7) {
        Some(list) => list
            .split(',')
            .map(|v| v.trim().parse::<f64>())
            .collect::<Result<_, _>>()?,
        None if dim == 2 => vec![2.0, 1.0],
        None => vec![1.0, 0.75, 0.5],
    };
    if axes.len() != dim {
        return Err(format!("{} semi-axes for dimension {dim}", axes.len()).into());
    }
    let start = Instant::now();
    // Outer iterations on stderr: a large m takes minutes.
    let mut observe = |p: &auglag::Progress<'_>| {
        if let auglag::Event::Outer {
            objective,
            infeasibility,
            ..
        } = p.event
        {
            eprintln!(
                "{:8.1} s  outer {:3}  inner {:6}  evaluations {:7}  objective {objective:.6e}  \
                 infeasibility {infeasibility:.2e}",
                start.elapsed().as_secs_f64(),
                p.outer_iteration,
                p.total_inner_iterations,
                p.evaluations
            );
        }
        false
    };
    let (density, before, factor, report, check, builds, seconds) = if dim == 2 {
        minimise(
            vec![[axes[0], axes[1]]; m],
            kind,
            dense,
            &settings,
            &mut observe,
        )?
    } else {
        let l = [axes[0], axes[1], axes[2]];
        minimise(vec![l; m], kind, dense, &settings, &mut observe)?
    };
    let elapsed = start.elapsed();
    println!("{check}");
    println!(
        "{dim}D m = {m} {axes:?} {kind:?}: density {density:.5} (before repair {before:.5}, factor \
         {factor:.6}), {:.2} s ({seconds:.2} s the minimisation, {:.1} µs per evaluation), {:?}, \
         {} outer / {} inner iterations, {} evaluations, {} Hessian products, {builds} builds of \
         the pair list",
        elapsed.as_secs_f64(),
        1e6 * seconds / report.function_evaluations.max(1) as f64,
        report.stop_reason,
        report.outer_iterations,
        report.inner_iterations,
        report.function_evaluations,
        report.hessian_products
    );
    Ok(())
}

/// What one run reports: density, density before the repair, repair factor, the solver's
/// report, the independent check, how many times the pair list was built and the seconds of
/// the minimisation alone.
type Outcome = (f64, f64, f64, auglag::Report, String, usize, f64);

/// One local minimisation of items with semi-axes `axes` in a container of `kind`, from the
/// paper's lattice start or (`dense`) the centred lattice start.
fn minimise<const N: usize>(
    axes: Vec<[f64; N]>,
    kind: ContainerShape,
    dense: bool,
    settings: &LocalSettings,
    observe: &mut dyn FnMut(&auglag::Progress<'_>) -> bool,
) -> Result<Outcome, Box<dyn std::error::Error>> {
    let mut p = Model::<N>::new(axes, kind)?;
    let x0 = if dense {
        lattice_start_of(&p, &LatticeStart::centred())
    } else {
        lattice_start(&p)
    };
    let start = Instant::now();
    let r = local_minimisation(&mut p, &x0, settings, observe)?;
    let seconds = start.elapsed().as_secs_f64();
    let check = independent_check(&mut p, &r.x)?;
    Ok((
        r.density,
        r.density_before_repair,
        r.repair_factor,
        r.report,
        check,
        p.pair_list_builds(),
        seconds,
    ))
}

/// Checks a packing without the model's own certificate: PW85 verdicts on all m(m−1)/2 pairs,
/// and containment by sampling points of every item's surface against the container's
/// implicit equation.
fn independent_check<const N: usize>(
    p: &mut Model<N>,
    x: &[f64],
) -> Result<String, Box<dyn std::error::Error>> {
    let kind = p.container_kind();
    let dims = x[x.len() - kind.dimension_count(N)..].to_vec();
    let bodies = p.bodies_at(x)?.to_vec();
    let mut overlapping = 0;
    let mut min_mu2 = f64::INFINITY;
    for i in 0..bodies.len() {
        for j in i + 1..bodies.len() {
            let (a, b) = (bodies[i].shape_matrix(), bodies[j].shape_matrix());
            let (ci, cj) = (bodies[i].centre(), bodies[j].centre());
            let mu2 = if N == 2 {
                pw85::contact_function(
                    &[cj[0] - ci[0], cj[1] - ci[1]],
                    &[a[0][0], a[0][1], a[1][1]],
                    &[b[0][0], b[0][1], b[1][1]],
                )?
                .mu2
            } else {
                pw85::contact_function(
                    &[cj[0] - ci[0], cj[1] - ci[1], cj[2] - ci[2]],
                    &[a[0][0], a[0][1], a[0][2], a[1][1], a[1][2], a[2][2]],
                    &[b[0][0], b[0][1], b[0][2], b[1][1], b[1][2], b[2][2]],
                )?
                .mu2
            };
            min_mu2 = min_mu2.min(mu2);
            if mu2 < 1.0 {
                overlapping += 1;
            }
        }
    }
    // Surface samples: the unit circle / sphere mapped by R diag(l).
    let samples: Vec<[f64; 3]> = if N == 2 {
        (0..720)
            .map(|k| {
                let t = k as f64 * std::f64::consts::TAU / 720.0;
                [t.cos(), t.sin(), 0.0]
            })
            .collect()
    } else {
        let mut v = Vec::new();
        for a in 0..60 {
            for b in 0..120 {
                let th = (a as f64 + 0.5) * std::f64::consts::PI / 60.0;
                let ph = b as f64 * std::f64::consts::TAU / 120.0;
                v.push([th.sin() * ph.cos(), th.sin() * ph.sin(), th.cos()]);
            }
        }
        v
    };
    let mut worst = f64::NEG_INFINITY;
    for body in &bodies {
        let (c, l, r) = (body.centre(), body.semi_axes(), body.rotation());
        for s in &samples {
            let mut point = [0.0; N];
            for i in 0..N {
                point[i] = c[i] + (0..N).map(|k| r[i][k] * l[k] * s[k]).sum::<f64>();
            }
            let g = match kind {
                ContainerShape::Ball => point.iter().map(|v| v * v).sum::<f64>().sqrt() / dims[0],
                ContainerShape::Ellipsoid => (0..N)
                    .map(|k| (point[k] / dims[k]).powi(2))
                    .sum::<f64>()
                    .sqrt(),
                ContainerShape::Box => (0..N).map(|k| point[k].abs() / dims[k]).fold(0.0, f64::max),
                // Nothing sticks out of a periodic cell.
                ContainerShape::Periodic => 0.0,
            };
            worst = worst.max(g);
        }
    }
    Ok(format!(
        "independent check: {overlapping} overlapping pairs of {} (min μ² = {min_mu2:.12}), \
         largest sampled surface point at {worst:.12} of the container (≤ 1 is inside)",
        bodies.len() * (bodies.len() - 1) / 2
    ))
}
