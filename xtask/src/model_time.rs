//! Figure 5: the time of one evaluation of the whole packing model (eq. 19 with containment
//! and objective) against the number of ellipsoids m, with the cell grid (Section 5.2) and
//! with the sum over all m(m − 1)/2 pairs, log–log. The grid sum must equal the all-pairs sum
//! (a pair the grid leaves out has f = 0 exactly, eq. 37): that is checked on every m where
//! both are computed.

use crate::Run;
use crate::error::Error;
use crate::output::{self, Stability};
use crate::plot::{Corner, Figure, Kind, Panel, Series, render};
use crate::report::Section;
use crate::scene::LoadedScene;
use ellipsoid_packer::starts::lattice_start;
use implicit_packing::containment::ContainerShape;
use implicit_packing::model::{Model, ModelGradient};
use std::hint::black_box;
use std::time::Instant;

fn refused(e: implicit_packing::Error) -> Error {
    Error::Implicit {
        context: "a model-time problem".into(),
        message: e.to_string(),
    }
}

/// Best of three timings of `f`, each repeated until it has run for at least 20 ms.
fn ns_per_eval(mut f: impl FnMut() -> Result<f64, Error>) -> Result<f64, Error> {
    let mut best = f64::INFINITY;
    for _ in 0..3 {
        let start = Instant::now();
        let mut runs = 0u32;
        let mut acc = 0.0;
        while runs == 0 || start.elapsed().as_secs_f64() < 0.02 {
            acc += f()?;
            runs += 1;
        }
        black_box(acc);
        best = best.min(start.elapsed().as_nanos() as f64 / f64::from(runs));
    }
    Ok(best)
}

/// Relative tolerance of grid sum against all-pairs sum: the same terms added in another
/// order.
const SUM_ORDER: f64 = 1e-12;

/// Figure 5.
pub fn run(run: &mut Run, s: &LoadedScene) -> Result<Section, Error> {
    s.require_dimension(3, "the model-time study is written for ellipsoids (3)")?;
    let axes = s.item_axes(3)?;
    let l = [axes[0], axes[1], axes[2]];
    let w = s.workload(run.quick);
    let counts: Vec<usize> = (s.scene.item_counts.iter().copied())
        .filter(|&m| w.max_items == 0 || m <= w.max_items)
        .collect();
    if counts.is_empty() {
        return Err(s.value_error("item_counts", 0..0, "needs a non-empty list"));
    }
    let (mut value, mut grad, mut all) = (Vec::new(), Vec::new(), Vec::new());
    let mut rows = Vec::new();
    let mut worst_sum = 0.0f64;
    for &m in &counts {
        run.say(&format!("  m = {m}"));
        let mut problem = Model::<3>::new(vec![l; m], ContainerShape::Ball).map_err(refused)?;
        let mut x = lattice_start(&problem);
        // The lattice start touches nowhere; pulling the centres in by 15 % makes neighbours
        // overlap, as during a solve, so that the pair terms are really evaluated.
        for i in 0..m {
            for k in 0..3 {
                x[6 * i + k] *= 0.85;
            }
        }
        let ev = problem.evaluate(&x, None).map_err(refused)?;
        let t_value = ns_per_eval(|| Ok(problem.evaluate(&x, None).map_err(refused)?.overlap))?;
        let mut g = ModelGradient::default();
        let t_grad =
            ns_per_eval(|| Ok(problem.evaluate(&x, Some(&mut g)).map_err(refused)?.overlap))?;
        value.push((m as f64, t_value));
        grad.push((m as f64, t_grad));
        let mut row = vec![
            m.to_string(),
            ev.pairs.to_string(),
            output::full(ev.overlap),
            output::short(t_value),
            output::short(t_grad),
        ];
        if m <= w.all_pairs_up_to {
            let total = problem.overlap_all_pairs(&x).map_err(refused)?;
            let t_all = ns_per_eval(|| problem.overlap_all_pairs(&x).map_err(refused))?;
            all.push((m as f64, t_all));
            let diff = (total - ev.overlap).abs() / total.abs().max(f64::MIN_POSITIVE);
            worst_sum = worst_sum.max(diff);
            row.push(output::full(total));
            row.push(output::short(t_all));
        } else {
            row.push(String::new());
            row.push(String::new());
        }
        rows.push(row);
    }
    let check = format!(
        "{}  model     grid sum of eq. 19 = all-pairs sum (relative)   residual {:>9.2e}  tol {:>7.0e}",
        if worst_sum <= SUM_ORDER {
            "PASS"
        } else {
            "FAIL"
        },
        worst_sum,
        SUM_ORDER
    );
    println!("{check}");
    if worst_sum.is_nan() || worst_sum > SUM_ORDER {
        run.failures.push(check);
    }
    run.write_csv(
        s,
        &[
            "m",
            "candidate_pairs",
            "overlap_grid",
            "ns_value",
            "ns_value_gradient",
            "overlap_all_pairs",
            "ns_all_pairs",
        ],
        &rows,
        Stability::Volatile,
    )?;
    let slope = |v: &[(f64, f64)]| -> f64 {
        match (v.first(), v.last()) {
            (Some(a), Some(b)) if b.0 > a.0 => (b.1 / a.1).ln() / (b.0 / a.0).ln(),
            _ => f64::NAN,
        }
    };
    let (s_value, s_all) = (slope(&value), slope(&all));
    if let Some(fig) = &s.scene.outputs.figure {
        render(
            &Figure {
                panels: vec![Panel {
                    title: "One evaluation of the packing model (3D, one thread)".into(),
                    x_label: "number of ellipsoids m".into(),
                    y_label: "ns per evaluation".into(),
                    x_log: true,
                    y_log: true,
                    series: vec![
                        Series {
                            name: "cell grid: value".into(),
                            points: value,
                            kind: Kind::LinePoints,
                            color: 0,
                        },
                        Series {
                            name: "cell grid: value and gradient".into(),
                            points: grad,
                            kind: Kind::LinePoints,
                            color: 2,
                        },
                        Series {
                            name: "all m(m − 1)/2 pairs: value".into(),
                            points: all,
                            kind: Kind::LinePoints,
                            color: 1,
                        },
                    ],
                    legend: Corner::UpperLeft,
                    ..Panel::default()
                }],
                panel_height: 640,
            },
            &run.figures_dir(),
            fig,
            &mut run.outputs,
        )?;
    }
    let text = format!(
        "m copies of the ellipsoid with semi-axes ({}, {}, {}) in a ball, at the paper's \
         lattice start with the centres pulled in by 15 % so that neighbours overlap as they do \
         during a solve. Time of one evaluation of the model (overlap sum of eq. 19, \
         containment, objective) by `implicit_packing::model::Model::evaluate`, with and \
         without gradients, against the same sum over all pairs \
         (`Model::overlap_all_pairs`, up to m = {}). Log–log slopes between the smallest and \
         the largest m: {:.2} with the grid, {:.2} over all pairs (1 is linear, 2 quadratic). \
         The two sums agree to {:.1e} relative (tolerance {SUM_ORDER:.0e}: the same terms in \
         another order), so the grid misses no overlapping pair.",
        l[0], l[1], l[2], w.all_pairs_up_to, s_value, s_all, worst_sum
    );
    Ok(Section::new(s, text))
}
