//! Figure 6: packings. A multi-start run of the packer (`ellipsoid_packer::multistart`: lattice
//! start, augmented-Lagrangian local minimisations from perturbations, PW85 certificate and
//! repair of every result) on a small 2D instance with a wall-time limit: the best density
//! against wall time, and a picture of the best certified packing.

use crate::Run;
use crate::error::Error;
use crate::output::{self, Stability};
use crate::plot::{Corner, Figure, Kind, Panel, Series, render};
use crate::report::Section;
use crate::scene::LoadedScene;
use ellipsoid_packer::multistart::{Callbacks, MultiStartProgress, MultiStartSettings, multistart};
use ellipsoid_packer::starts::lattice_start;
use implicit_packing::containment::ContainerShape;
use implicit_packing::model::Model;
use std::time::Duration;

fn refused(e: impl std::fmt::Display) -> Error {
    Error::Implicit {
        context: "the packing study".into(),
        message: e.to_string(),
    }
}

/// Points on the outline of an ellipse (centre, semi-axes along the columns of the rotation).
fn outline(c: [f64; 2], l: [f64; 2], q: [[f64; 2]; 2]) -> Vec<(f64, f64)> {
    (0..=96)
        .map(|k| {
            let t = f64::from(k) * std::f64::consts::TAU / 96.0;
            let (u, v) = (l[0] * t.cos(), l[1] * t.sin());
            (
                c[0] + q[0][0] * u + q[0][1] * v,
                c[1] + q[1][0] * u + q[1][1] * v,
            )
        })
        .collect()
}

/// Figure 6.
pub fn run(run: &mut Run, s: &LoadedScene) -> Result<Section, Error> {
    s.require_dimension(2, "the packing study draws ellipses (2)")?;
    let axes = s.item_axes(2)?;
    let m = match s.scene.item_counts.as_slice() {
        [m] if *m > 0 => *m,
        _ => {
            return Err(s.value_error("item_counts", 0..0, "needs exactly one positive count"));
        }
    };
    let seconds = s.workload(run.quick).seconds;
    if !(seconds.is_finite() && seconds > 0.0) {
        return Err(s.value_error(
            &format!("{}.seconds", if run.quick { "quick" } else { "full" }),
            0..0,
            "needs a positive wall-time limit",
        ));
    }
    let l = [axes[0], axes[1]];
    let semi_axes = vec![l; m];
    let problem = Model::<2>::new(semi_axes.clone(), ContainerShape::Ball).map_err(refused)?;
    let x0 = lattice_start(&problem);
    let mut settings = MultiStartSettings::paper(2, s.scene.seed);
    settings.max_local_minimisations = usize::MAX;
    settings.time_limit = Some(Duration::from_secs_f64(seconds));
    let mut best = Vec::new();
    let mut last = Vec::new();
    let say = crate::progress(run.start);
    let result = multistart::<2>(
        &semi_axes,
        ContainerShape::Ball,
        &x0,
        &settings,
        &mut Callbacks::on_finished(|p: &MultiStartProgress| {
            let t = p.elapsed.as_secs_f64();
            best.push((t, p.best_density));
            last.push((t, p.last_density));
            if p.local_minimisations.is_power_of_two() {
                say(&format!(
                    "  {} local minimisations, best density {:.4}",
                    p.local_minimisations, p.best_density
                ));
            }
        }),
    )
    .map_err(refused)?;
    let mut problem = Model::<2>::new(semi_axes, ContainerShape::Ball).map_err(refused)?;
    let x = result.best.x.clone();
    let radius = x.last().copied().unwrap_or(f64::NAN);
    let bodies = problem.bodies_at(&x).map_err(refused)?.to_vec();
    let cert = problem.certify(&x).map_err(refused)?;
    if !cert.is_feasible() {
        run.failures.push(format!(
            "FAIL  packing ({}): the best packing is not certified: overlapping {:?}, outside {:?}",
            s.name(),
            cert.overlapping_pairs(),
            cert.outside_items()
        ));
    }

    let spread = last.iter().map(|p| p.1).fold(f64::NEG_INFINITY, f64::max)
        - last.iter().map(|p| p.1).fold(f64::INFINITY, f64::min);
    let rows: Vec<Vec<String>> = best
        .iter()
        .zip(&last)
        .map(|(b, l)| vec![output::short(b.0), output::full(b.1), output::full(l.1)])
        .collect();
    run.write_csv(
        s,
        &["seconds", "best_density", "last_density"],
        &rows,
        Stability::Volatile,
    )?;
    if let Some(fig) = &s.scene.outputs.figure {
        let mut series: Vec<Series> = bodies
            .iter()
            .map(|b| Series {
                name: String::new(),
                points: outline(b.centre(), b.semi_axes(), b.rotation()),
                kind: Kind::Line,
                color: 0,
            })
            .collect();
        series.push(Series {
            name: format!("container, radius {radius:.4}"),
            points: outline([0.0, 0.0], [radius, radius], [[1.0, 0.0], [0.0, 1.0]]),
            kind: Kind::Line,
            color: 7,
        });
        // The plot area of a 984-pixel panel is about 866 × 866 pixels: equal ranges keep the
        // ellipses' proportions.
        let r = 1.08 * radius;
        render(
            &Figure {
                panels: vec![Panel {
                    title: format!(
                        "Best certified packing: {m} ellipses ({}, {}) in a ball, density {:.4}",
                        l[0], l[1], result.best.density
                    ),
                    x_label: "x".into(),
                    y_label: "y".into(),
                    x_range: Some((-r, r)),
                    y_range: Some((-r, r)),
                    series,
                    legend: Corner::UpperLeft,
                    ..Panel::default()
                }],
                panel_height: 984,
            },
            &run.figures_dir(),
            &format!("{fig}_picture"),
            &mut run.outputs,
        )?;
        render(
            &Figure {
                panels: vec![Panel {
                    title: format!(
                        "Multi-start: density against wall time ({m} ellipses, one thread)"
                    ),
                    x_label: "wall time (s)".into(),
                    y_label: "density".into(),
                    series: vec![
                        Series {
                            name: "each local minimisation (certified, repaired)".into(),
                            points: last.clone(),
                            kind: Kind::Points,
                            color: 1,
                        },
                        Series {
                            name: "best so far".into(),
                            points: best.clone(),
                            kind: Kind::LinePoints,
                            color: 0,
                        },
                    ],
                    legend: Corner::LowerRight,
                    ..Panel::default()
                }],
                panel_height: 640,
            },
            &run.figures_dir(),
            &format!("{fig}_density"),
            &mut run.outputs,
        )?;
    }
    let text = format!(
        "{m} ellipses with semi-axes ({}, {}) in the smallest ball, by `ellipsoid_packer::\
         multistart` (the paper's lattice start, perturbations of the latest feasible packing, \
         one thread, seed {}) for {seconds} s of wall time: {} local minimisations, each \
         certified with PW85 and repaired. The best density, {:.4} (container radius {:.4}), \
         was reached after {:.1} s. The certificate of the drawn packing, recomputed here: {} \
         candidate pairs checked, {} overlapping, {} outside. {} The pictures are \
         `docs/figures/{}_picture.png` and the density curve `docs/figures/{}_density.png`; \
         timings and the number of minimisations depend on the machine, so the figure changes \
         from run to run.",
        l[0],
        l[1],
        s.scene.seed,
        result.local_minimisations,
        result.best.density,
        radius,
        result.time_to_best.as_secs_f64(),
        cert.pairs_checked,
        cert.overlapping.len(),
        cert.outside.len(),
        if spread < 1e-4 {
            format!(
                "The densities of all local minimisations lie within {spread:.1e} of each \
                 other: the perturbations (2.5 %) lead back to the same packing, so the curve \
                 mostly measures the cost per start."
            )
        } else {
            format!(
                "The best density rose from {:.4} (first start) to {:.4}.",
                best.first().map_or(f64::NAN, |p| p.1),
                result.best.density
            )
        },
        s.scene.outputs.figure.as_deref().unwrap_or("packing"),
        s.scene.outputs.figure.as_deref().unwrap_or("packing"),
    );
    let mut section = Section::new(s, text);
    section.figure = None;
    let mut table = s.scene.outputs.figure.as_ref().map_or_else(String::new, |f| {
        format!("![packing](figures/{f}_picture.png)\n\n![density against wall time](figures/{f}_density.png)\n")
    });
    for (name, line) in solved_scenes(run, s, seconds)? {
        table.push_str(&format!("\n{line}\n\n![{name}](figures/{name}.png)\n"));
    }
    section.table = (!table.is_empty()).then_some(table);
    Ok(section)
}

/// Solves the scene's `pack_scenes` exactly as `ellipack pack` does (same scene format, same
/// run, same certificate) for `seconds` each on one thread, and draws each packing with the
/// command line's pictures into `docs/figures/packing_<stem>.{svg,png}`. Returns (figure name,
/// one-line description) per scene.
fn solved_scenes(
    run: &mut Run,
    s: &LoadedScene,
    seconds: f64,
) -> Result<Vec<(String, String)>, Error> {
    let mut out = Vec::new();
    for file in &s.scene.pack_scenes {
        let path = run.root.join("validation/scenes").join(file);
        let pack_error = |message: String| Error::Pack {
            context: file.clone(),
            message,
        };
        let scene = ellipack::scene::Scene::from_file(&path)
            .map_err(|e| pack_error(e.to_string()))?
            .overridden(&ellipack::scene::Overrides {
                time_limit: Some(Duration::from_secs_f64(seconds)),
                threads: Some(1),
                ..Default::default()
            });
        let options = ellipack::pack::RunOptions::default();
        crate::progress(run.start)(&format!("  {} ({seconds} s)", scene.title()));
        let outcome = ellipack::pack::run(&scene, &options, &mut ())
            .map_err(|e| pack_error(e.to_string()))?;
        let c = outcome.summary.certificate;
        if !c.is_certified() {
            run.failures.push(format!(
                "FAIL  packing ({file}): {} overlapping pairs, {} containment violations",
                c.overlapping_pairs, c.containment_violations
            ));
        }
        let stem = std::path::Path::new(file)
            .file_stem()
            .map_or_else(|| "scene".to_string(), |s| s.to_string_lossy().into_owned());
        let name = format!("packing_{stem}");
        let options = ellipack::render::RenderOptions {
            width: 1200,
            label: scene.name.clone(),
        };
        let svg = ellipack::render::svg_string(&outcome.packing, &options)
            .map_err(|e| pack_error(e.to_string()))?;
        let png = ellipack::render::png_bytes(&outcome.packing, &options)
            .map_err(|e| pack_error(e.to_string()))?;
        let dir = run.figures_dir();
        run.outputs.write(
            &dir.join(format!("{name}.svg")),
            svg.as_bytes(),
            Stability::Volatile,
        )?;
        run.outputs
            .write(&dir.join(format!("{name}.png")), &png, Stability::Volatile)?;
        out.push((
            name,
            format!(
                "{} (`validation/scenes/{file}`, {seconds} s, one thread): density {:.4} after {} \
                 local minimisations; certificate {} overlapping pairs, {} containment \
                 violations, min μ² {}.",
                scene.title(),
                outcome.summary.density,
                outcome.summary.local_minimisations,
                c.overlapping_pairs,
                c.containment_violations,
                c.min_mu2.map_or("—".into(), |m| format!("{m:.6}")),
            ),
        ));
    }
    Ok(out)
}
