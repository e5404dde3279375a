//! Figures comparing both criteria: μ² − 1 and f along approach paths (figure 1), verdict
//! agreement and cost per evaluation against aspect ratio (figure 2). Packings (figure 6) are
//! a declared study that needs `ellipack pack`.

use crate::Run;
use crate::error::{self, Error};
use crate::implicit;
use crate::output::{self, Stability};
use crate::plot::{Corner, Figure, Kind, Panel, Series, render};
use crate::report::Section;
use crate::sample::Pw85Form as _;
use crate::sample::{self, Pair3, Rng};
use crate::scene::{Criterion, LoadedScene, Quantity};
use std::hint::black_box;
use std::time::Instant;

fn normalised(v: &[f64]) -> [f64; 3] {
    let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    [v[0] / n, v[1] / n, v[2] / n]
}

fn mu2_of(p: &Pair3) -> Result<f64, Error> {
    let q = p.pw85()?;
    Ok(pw85::contact_function(&q.r12, &q.q1, &q.q2)
        .map_err(error::pw85("an approach-path pair"))?
        .mu2)
}

/// Figure 1: along the line from the first centre in the scene's direction, μ² − 1 and f
/// change sign at the same distance.
pub fn approach(run: &mut Run, s: &LoadedScene) -> Result<Section, Error> {
    s.require_dimension(3, "the approach study is written for ellipsoids (3)")?;
    if s.scene.shapes.is_empty() {
        return Err(s.value_error("shapes", 0..0, "the approach study needs [[shapes]]"));
    }
    let steps = s.require_workload(run.quick, "steps", s.workload(run.quick).steps)?;
    let with_pw85 = s.uses(Criterion::Pw85) && s.wants(Quantity::Mu2);
    let with_f = s.uses(Criterion::Implicit) && s.wants(Quantity::F);
    let mut panels = Vec::new();
    let mut rows = Vec::new();
    let mut summary = Vec::new();
    for shape in &s.scene.shapes {
        let d = normalised(shape.direction.get_ref());
        let axes = |v: &[f64]| [v[0], v[1], v[2]];
        let unit = Pair3 {
            ci: [0.0; 3],
            li: axes(shape.axes_i.get_ref()),
            oi: shape.quaternion_i,
            cj: d,
            lj: axes(shape.axes_j.get_ref()),
            oj: shape.quaternion_j,
        };
        // μ is proportional to the distance along a fixed direction: contact at 1/μ(1).
        let contact = 1.0 / mu2_of(&unit)?.sqrt();
        // The distance where f becomes 0, by bisection on the verdict f > 0.
        let f_at = |t: f64| -> Result<f64, Error> {
            Ok(implicit::term(&crate::sample::at_distance_factor(&unit, t))?.f)
        };
        let (mut lo, mut hi) = (0.5 * contact, 1.5 * contact);
        if with_f {
            for _ in 0..200 {
                let mid = 0.5 * (lo + hi);
                if mid <= lo || mid >= hi {
                    break;
                }
                if f_at(mid)? > 0.0 {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
        }
        let f_zero = hi;
        let gap = (f_zero - contact).abs() / contact;
        if with_f {
            summary.push(format!(
                "{}: PW85 contact at distance {:.6}, f vanishes from {:.6} on (relative \
                 difference {:.1e})",
                shape.name, contact, f_zero, gap
            ));
        }
        let mut mu_series = Vec::new();
        let mut f_series = Vec::new();
        for k in 0..steps {
            let t = contact * (0.6 + 0.8 * k as f64 / (steps - 1).max(1) as f64);
            let p = crate::sample::at_distance_factor(&unit, t);
            let mut row = vec![format!("\"{}\"", shape.name), output::full(t)];
            if with_pw85 {
                let m = mu2_of(&p)? - 1.0;
                mu_series.push((t, m));
                row.push(output::full(m));
            }
            if with_f {
                let f = implicit::term(&p)?.f;
                f_series.push((t, f));
                row.push(output::full(f));
            }
            rows.push(row);
        }
        let mut series = Vec::new();
        if with_pw85 {
            series.push(Series {
                name: "PW85: μ² − 1".into(),
                points: mu_series,
                kind: Kind::Line,
                color: 0,
            });
        }
        if with_f {
            series.push(Series {
                name: "implicit: f".into(),
                points: f_series,
                kind: Kind::Line,
                color: 1,
            });
        }
        panels.push(Panel {
            title: shape.name.clone(),
            x_label: "centre distance".into(),
            y_label: "μ² − 1, f".into(),
            series,
            vlines: vec![(contact, "contact (μ = 1)".into())],
            hlines: vec![(0.0, String::new())],
            legend: Corner::LowerRight,
            ..Panel::default()
        });
    }
    let mut header = vec!["shape", "distance"];
    if with_pw85 {
        header.push("mu2_minus_1");
    }
    if with_f {
        header.push("f");
    }
    run.write_csv(s, &header, &rows, Stability::Stable)?;
    if let Some(fig) = &s.scene.outputs.figure {
        render(
            &Figure {
                panels,
                panel_height: 420,
            },
            &run.figures_dir(),
            fig,
            &mut run.outputs,
        )?;
    }
    let text = format!(
        "Each panel moves the second body along a fixed direction from the first, from 0.6 to \
         1.4 times the contact distance. The contact function μ² − 1 (PW85) crosses zero at the \
         contact distance, the vertical line; the implicit-variable overlap measure f is \
         positive before it and exactly 0 after it, so both criteria change sign at the same \
         distance. The distance where f vanishes, found by bisection on f > 0, is compared with \
         the PW85 contact distance 1/μ (at unit distance): {}. f is not a distance: it \
         behaves like (1 − d²)² near contact, which is why it leaves zero tangentially while \
         μ² − 1 crosses it with a non-zero slope.",
        summary.join("; ")
    );
    Ok(Section::new(s, text))
}

/// Times `eval` over `items` `repeats` times; nanoseconds per call (best of three trials, so
/// that a descheduled trial on a shared machine does not count).
pub fn ns_per_call<T>(items: &[T], repeats: usize, mut eval: impl FnMut(&T) -> f64) -> f64 {
    let mut best = f64::INFINITY;
    for _ in 0..3 {
        let start = Instant::now();
        let mut acc = 0.0;
        for _ in 0..repeats.max(1) {
            for it in items {
                acc += eval(black_box(it));
            }
        }
        black_box(acc);
        let ns = start.elapsed().as_nanos() as f64 / (items.len() * repeats.max(1)) as f64;
        best = best.min(ns);
    }
    best
}

/// Figure 2: verdict agreement and cost per evaluation against the aspect ratio.
pub fn agreement(run: &mut Run, s: &LoadedScene) -> Result<Section, Error> {
    let ratios = s.aspect_ratios()?.to_vec();
    let w = s.workload(run.quick);
    let n = s.require_workload(run.quick, "pairs", w.pairs)?;
    let repeats = w.repeats.max(1);
    let dim = *s.scene.dimension.get_ref();
    // A verdict-only scene times the verdict functions and never asks for μ²; asking for
    // `mu2` and `f` adds the full evaluations.
    let full = s.wants(Quantity::Mu2) && s.wants(Quantity::F);
    let mut rng = Rng::new(s.scene.seed);
    let mut rows = Vec::new();
    let (mut dis, mut t_pw, mut t_im, mut t_mu, mut t_f) = (vec![], vec![], vec![], vec![], vec![]);
    let mut total_dis = 0usize;
    for &aspect in &ratios {
        run.say(&format!("  aspect ratio {aspect:e}"));
        let (disagree, ns_pw, ns_im, ns_mu, ns_f) = if dim == 3 {
            let mut pairs = Vec::with_capacity(n);
            for _ in 0..n {
                let p = sample::pair_near_contact(&mut rng, aspect, 0.5, 1.5)?;
                pairs.push((p.pw85()?, implicit::bodies(&p)?));
            }
            let mut disagree = 0;
            for (q, (i, j)) in &pairs {
                let v = pw85::overlap(&q.r12, &q.q1, &q.q2)
                    .map_err(error::pw85("an agreement pair"))?;
                if v != (implicit::measure(i, j) > 0.0) {
                    disagree += 1;
                }
            }
            let ns_pw = ns_per_call(&pairs, repeats, |(q, _)| {
                f64::from(u8::from(
                    pw85::overlap(&q.r12, &q.q1, &q.q2).unwrap_or(false),
                ))
            });
            let ns_im = ns_per_call(&pairs, repeats, |(_, (i, j))| implicit::measure(i, j));
            let (ns_mu, ns_f) = if full {
                (
                    ns_per_call(&pairs, repeats, |(q, _)| {
                        pw85::contact_function(&q.r12, &q.q1, &q.q2).map_or(0.0, |c| c.mu2)
                    }),
                    ns_per_call(&pairs, repeats, |(_, (i, j))| implicit::term_of(i, j).f),
                )
            } else {
                (f64::NAN, f64::NAN)
            };
            (disagree, ns_pw, ns_im, ns_mu, ns_f)
        } else {
            let mut pairs = Vec::with_capacity(n);
            for _ in 0..n {
                let p = sample::pair_near_contact_2d(&mut rng, aspect, 0.5, 1.5)?;
                pairs.push((p.pw85()?, implicit::ellipses(&p)?));
            }
            let mut disagree = 0;
            for ((r, q1, q2), (i, j)) in &pairs {
                let v = pw85::overlap(r, q1, q2).map_err(error::pw85("a 2D agreement pair"))?;
                if v != (implicit::measure(i, j) > 0.0) {
                    disagree += 1;
                }
            }
            let ns_pw = ns_per_call(&pairs, repeats, |((r, q1, q2), _)| {
                f64::from(u8::from(pw85::overlap(r, q1, q2).unwrap_or(false)))
            });
            let ns_im = ns_per_call(&pairs, repeats, |(_, (i, j))| implicit::measure(i, j));
            let (ns_mu, ns_f) = if full {
                (
                    ns_per_call(&pairs, repeats, |((r, q1, q2), _)| {
                        pw85::contact_function(r, q1, q2).map_or(0.0, |c| c.mu2)
                    }),
                    ns_per_call(&pairs, repeats, |(_, (i, j))| implicit::term_of(i, j).f),
                )
            } else {
                (f64::NAN, f64::NAN)
            };
            (disagree, ns_pw, ns_im, ns_mu, ns_f)
        };
        total_dis += disagree;
        dis.push((aspect, disagree as f64));
        t_pw.push((aspect, ns_pw));
        t_im.push((aspect, ns_im));
        t_mu.push((aspect, ns_mu));
        t_f.push((aspect, ns_f));
        rows.push(vec![
            format!("{aspect:e}"),
            n.to_string(),
            disagree.to_string(),
            output::short(ns_pw),
            output::short(ns_im),
            output::short(ns_mu),
            output::short(ns_f),
        ]);
    }
    run.write_csv(
        s,
        &[
            "aspect_ratio",
            "pairs",
            "disagreements",
            "ns_pw85_overlap",
            "ns_implicit_measure",
            "ns_pw85_contact_function",
            "ns_implicit_pair_term",
        ],
        &rows,
        Stability::Volatile,
    )?;
    let mut cost = vec![
        Series {
            name: format!(
                "PW85 verdict (overlap{})",
                if dim == 2 { "_2d" } else { "" }
            ),
            points: t_pw.clone(),
            kind: Kind::LinePoints,
            color: 0,
        },
        Series {
            name: "implicit: f (overlap_measure)".into(),
            points: t_im.clone(),
            kind: Kind::LinePoints,
            color: 1,
        },
    ];
    if full {
        cost.push(Series {
            name: format!(
                "PW85 μ² (contact_function{})",
                if dim == 2 { "_2d" } else { "" }
            ),
            points: t_mu,
            kind: Kind::LinePoints,
            color: 2,
        });
        cost.push(Series {
            name: "implicit: full pair term".into(),
            points: t_f,
            kind: Kind::LinePoints,
            color: 3,
        });
    }
    if let Some(fig) = &s.scene.outputs.figure {
        let panels = vec![
            Panel {
                title: format!("Verdict disagreements per {n} pairs ({dim}D)"),
                x_label: "aspect ratio".into(),
                y_label: "disagreements".into(),
                x_log: true,
                y_range: Some((-0.5, (total_dis as f64).max(4.0) + 0.5)),
                series: vec![Series {
                    name: "PW85 verdict ≠ (f > 0)".into(),
                    points: dis,
                    kind: Kind::LinePoints,
                    color: 1,
                }],
                ..Panel::default()
            },
            Panel {
                title: format!("Cost per evaluation ({dim}D, one thread)"),
                x_label: "aspect ratio".into(),
                y_label: "ns per call".into(),
                x_log: true,
                y_log: true,
                series: cost,
                legend: Corner::LowerRight,
                ..Panel::default()
            },
        ];
        render(
            &Figure {
                panels,
                panel_height: 460,
            },
            &run.figures_dir(),
            fig,
            &mut run.outputs,
        )?;
    }
    let (lo, hi) = (ratios[0], ratios[ratios.len() - 1]);
    let at = |v: &[(f64, f64)], k: usize| v.get(k).map_or(f64::NAN, |p| p.1);
    let last = ratios.len() - 1;
    let text = format!(
        "{n} random pairs per aspect ratio ({dim}D, axis ratios up to the stated value, random \
         orientations, centre distance between 0.5 and 1.5 times the contact distance; the \
         placement uses one contact function per pair at unit distance, outside the timed \
         loops). Top: \
         pairs where the PW85 verdict (μ² < 1, by `pw85::overlap{}`) and the implicit-variable \
         verdict (f > 0) differ: {total_dis} in total over aspect ratios {lo:e} to {hi:e}. \
         Bottom: time per verdict on one thread, both with their early exits{}: PW85 {:.0} ns \
         at aspect ratio {lo:e} and {:.0} ns at {hi:e}; the implicit measure {:.0} ns and {:.0} \
         ns. {}",
        if dim == 2 { "_2d" } else { "" },
        if full {
            ", and the full evaluations (μ² and λ; the pair term with X, U, d²)"
        } else {
            " (this scene asks for verdicts only, so neither μ² nor the full pair term is computed)"
        },
        at(&t_pw, 0),
        at(&t_pw, last),
        at(&t_im, 0),
        at(&t_im, last),
        if total_dis == 0 {
            "The two criteria agree on every pair."
        } else {
            "Disagreements are listed in the CSV file."
        }
    );
    if total_dis > 0 {
        run.failures.push(format!(
            "FAIL  agreement ({}): {total_dis} verdict disagreements between PW85 and the implicit criterion",
            s.name()
        ));
    }
    Ok(Section::new(s, text))
}
