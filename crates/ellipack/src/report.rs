//! What `ellipack pack` says of a finished run on standard output.

use ellipack::pack::RunOutcome;
use ellipack::scene::Scene;
use implicit_packing::certificate::shown_mu2;

/// The run's report: the density and the container's size, the certificate and the repair,
/// and why a run kept its start or gave up starts.
pub(crate) fn pack(scene: &Scene, outcome: &RunOutcome, resumed: bool) {
    let s = &outcome.summary;
    crate::say!("{}", scene.title());
    crate::say!(
        "density {:.5} ({} {}), found after {:.1} s of {:.1} s, {} local minimisations{}",
        s.density,
        s.container.size_name(),
        {
            let size = s.container.size();
            let text = |v: &[f64]| {
                v.iter()
                    .map(|v| format!("{v:.6}"))
                    .collect::<Vec<_>>()
                    .join(" × ")
            };
            match s.container.cell_matrix() {
                Some(h) => {
                    let n = h.len();
                    format!("{}, tilts {}", text(&size[..n]), text(&size[n..]))
                }
                None => text(&size),
            }
        },
        outcome.seconds_to_best,
        s.wall_seconds,
        s.local_minimisations,
        if outcome.interrupted {
            " (interrupted)"
        } else {
            ""
        }
    );
    let min_mu2 = s
        .certificate
        .min_mu2
        .map_or("—".into(), |m| shown_mu2(m, 9));
    if scene.fixed_container().is_some() {
        // A fixed container is filled, never dilated: there is no repair to report.
        crate::say!(
            "certificate: {} overlapping pairs, {} containment violations, min μ² = {min_mu2}; \
             the container is the scene's",
            s.certificate.overlapping_pairs,
            s.certificate.containment_violations,
        );
    } else {
        crate::say!(
            "certificate: {} overlapping pairs, {} containment violations, min μ² = {min_mu2}; \
             repair dilation {:.2e} (density {:.5} before)",
            s.certificate.overlapping_pairs,
            s.certificate.containment_violations,
            outcome.repair_factor - 1.0,
            outcome.density_before_repair
        );
    }
    if outcome.restarts > 0 {
        crate::say!(
            "{} new chains from fresh lattice starts (after {} starts without improvement)",
            outcome.restarts,
            scene.solver.restart_after
        );
    }
    let limit = scene.solver.time_limit.as_secs_f64();
    if outcome.start_kept && outcome.seconds_to_best >= limit {
        crate::say!(
            "the time limit ({limit:.3e} s) is shorter than building and certifying the start \
             took ({:.3} s): give at least that for any local minimisation",
            outcome.seconds_to_best
        );
    }
    if outcome.start_kept && scene.fixed_container().is_some() {
        crate::say!("the start is already a packing in the fixed container: wrote the start");
    } else if outcome.start_kept {
        crate::say!(
            "no local minimisation found a denser certified packing than the start{}: wrote \
             the start",
            if resumed {
                " (the resumed packing)"
            } else {
                ""
            }
        );
    }
    if outcome.failed_starts > 0 {
        crate::say!(
            "{} starts were abandoned: their local minimisation ended at a point that could \
             not be certified",
            outcome.failed_starts
        );
    }
}
