//! Figure 3, error against run time: every PW85 solver at several tolerances on λ, ours, and
//! the projection solver of the implicit-variable model, each one point (ns per call, worst
//! relative error) against the independent reference values. Figure 5 (model time against m)
//! is a declared study that needs the model-evaluation API.

use crate::Run;
use crate::error::Error;
use crate::figures::ns_per_call;
use crate::implicit;
use crate::output::{self, Stability};
use crate::plot::{Figure, Kind, Panel, Series, render};
use crate::reference::{self, relative_error, scaled_error};
use crate::report::Section;
use crate::scene::{LoadedScene, Method};
use pw85::baseline;

/// A PW85 solver applied to one pair: μ².
pub fn solve(method: Method, tol: f64, p: &crate::sample::Pw85Pair) -> f64 {
    match method {
        Method::Bisection => baseline::bisection(&p.r12, &p.q1, &p.q2, tol).mu2,
        Method::Brent => baseline::brent(&p.r12, &p.q1, &p.q2, tol).mu2,
        Method::Newton => baseline::newton(&p.r12, &p.q1, &p.q2, tol).mu2,
        Method::Ours => pw85::contact_function(&p.r12, &p.q1, &p.q2).map_or(f64::NAN, |c| c.mu2),
        Method::Projection => f64::NAN,
    }
}

/// The reference categories whose inputs an "error against run time" study uses: ordinary
/// pairs, where every solver is meant to work.
const ORDINARY_CATEGORIES: [&str; 3] = ["random_moderate", "identical_orientation", "spheres"];

/// Figure 3.
pub fn error_time(run: &mut Run, s: &LoadedScene) -> Result<Section, Error> {
    let tols = s.tolerances()?.to_vec();
    let repeats = s.require_workload(run.quick, "repeats", s.workload(run.quick).repeats)?;
    let cases: Vec<_> = reference::contact_cases()?
        .into_iter()
        .filter(|c| ORDINARY_CATEGORIES.contains(&c.category.as_str()))
        .collect();
    if cases.is_empty() {
        return Err(Error::Reference {
            path: reference::path("pw85_contact.csv"),
            line: 0,
            message: format!(
                "no case in the categories {}",
                ORDINARY_CATEGORIES.join(", ")
            ),
        });
    }
    let pairs: Vec<_> = cases.iter().map(|c| c.pair).collect();
    let mut rows = Vec::new();
    let mut series = Vec::new();
    let mut ours_point = (f64::NAN, f64::NAN);
    let mut best_baseline: Vec<String> = Vec::new();
    for (color, &method) in s.scene.methods.iter().enumerate() {
        let points_for: Vec<f64> = if method.has_tolerance() {
            tols.clone()
        } else {
            vec![f64::NAN]
        };
        let mut pts = Vec::new();
        for tol in points_for {
            let (err, median, ns) = if method == Method::Projection {
                let blm = reference::blm_3d()?;
                let picked: Vec<_> = blm
                    .iter()
                    .filter(|c| c.category == "random_moderate" || c.category == "paper_shape")
                    .collect();
                if picked.is_empty() {
                    return Err(Error::Reference {
                        path: reference::path("blm_3d.csv"),
                        line: 0,
                        message: "no case in the categories random_moderate, paper_shape".into(),
                    });
                }
                let bodies = picked
                    .iter()
                    .map(|c| implicit::bodies(&c.pair))
                    .collect::<Result<Vec<_>, _>>()?;
                let mut errs: Vec<f64> = picked
                    .iter()
                    .zip(&bodies)
                    .map(|(c, (i, j))| {
                        let t = implicit::term_of(i, j);
                        scaled_error(t.u, c.u).max(scaled_error(t.d2, c.d2))
                    })
                    .collect();
                errs.sort_by(f64::total_cmp);
                let ns = ns_per_call(&bodies, repeats, |(i, j)| implicit::term_of(i, j).d2);
                (errs[errs.len() - 1], errs[errs.len() / 2], ns)
            } else {
                let mut errs: Vec<f64> = cases
                    .iter()
                    .map(|c| relative_error(solve(method, tol, &c.pair), c.mu2))
                    .collect();
                errs.sort_by(|a, b| a.total_cmp(b));
                let ns = ns_per_call(&pairs, repeats, |p| solve(method, tol, p));
                (errs[errs.len() - 1], errs[errs.len() / 2], ns)
            };
            if method == Method::Ours {
                ours_point = (ns, err);
            }
            if method.has_tolerance()
                && err <= 1e-15
                && pts.iter().all(|&(_, e): &(f64, f64)| e > 1e-15)
            {
                best_baseline.push(format!(
                    "{} reaches {err:.1e} at tolerance {tol:e} for {ns:.0} ns",
                    method.name()
                ));
            }
            pts.push((ns, err));
            rows.push(vec![
                method.name().to_string(),
                if tol.is_nan() {
                    String::new()
                } else {
                    format!("{tol:e}")
                },
                output::short(ns),
                output::short(err),
                output::short(median),
            ]);
        }
        series.push(Series {
            name: match method {
                Method::Ours => "ours (pw85::contact_function)".into(),
                Method::Projection => "implicit: projection (U, d² error)".into(),
                m => format!(
                    "{} (tolerances {:e} … {:e})",
                    m.name(),
                    tols[0],
                    tols[tols.len() - 1]
                ),
            },
            points: pts,
            kind: if method.has_tolerance() {
                Kind::LinePoints
            } else {
                Kind::Points
            },
            color,
        });
    }
    run.write_csv(
        s,
        &[
            "method",
            "tolerance",
            "ns_per_call",
            "max_rel_error",
            "median_rel_error",
        ],
        &rows,
        Stability::Volatile,
    )?;
    if let Some(fig) = &s.scene.outputs.figure {
        render(
            &Figure {
                panels: vec![Panel {
                    title: "Error against run time (one thread, reference values of 36 digits)"
                        .into(),
                    x_label: "ns per call".into(),
                    y_label: "worst relative error".into(),
                    x_log: true,
                    y_log: true,
                    series,
                    hlines: vec![(f64::EPSILON, "machine epsilon".into())],
                    ..Panel::default()
                }],
                panel_height: 720,
            },
            &run.figures_dir(),
            fig,
            &mut run.outputs,
        )?;
    }
    let text = format!(
        "{} ordinary pairs of `pw85_contact.csv` (categories {}), whose μ² is known to 36 \
         digits; each solver is timed over the whole set, {repeats} times, best of three \
         trials, on one thread. One point per (method, tolerance on λ): the baselines of \
         `pw85::baseline` — bisection on c(λ) as the PW85 library, Brent on f(λ), Newton on \
         c(λ) — at tolerances {}, and ours, which has no tolerance parameter. A tolerance \
         on λ is not one on μ²: f is stationary at λ₀, so the error in μ² falls like the \
         square of the λ error until the rounding of the sampled coefficients (eq. 17) takes \
         over. The implicit-variable projection solver is the one point whose error is the \
         worst of U and d² against `blm_3d.csv` (categories random_moderate and paper_shape; \
         relative error, absolute × 100 below 1e-2). Ours: {:.0} ns per call, worst error \
         {:.1e}. {} Errors of exactly 0 are drawn at 1e-18.",
        cases.len(),
        ORDINARY_CATEGORIES.join(", "),
        tols.iter()
            .map(|t| format!("{t:e}"))
            .collect::<Vec<_>>()
            .join(", "),
        ours_point.0,
        ours_point.1,
        if best_baseline.is_empty() {
            "No baseline reaches 1e-15 at any tolerance.".to_string()
        } else {
            format!("For comparison: {}.", best_baseline.join("; "))
        }
    );
    Ok(Section::new(s, text))
}
