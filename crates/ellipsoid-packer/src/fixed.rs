//! Filling a container of given size: the multi-start in feasibility mode
//! ([`LocalSettings::fixed_container`](crate::local::LocalSettings::fixed_container)).
//!
//! Every packing of the items in a fixed container has the same density, so the first start
//! whose local solve ends certified ends the run. The starts are the given point, then
//! [`fill_start`]s (dense lattice starts dilated to the container's area or volume, the lattice's
//! orientation and shift varying as in [`LatticeStart::sequence`]), then perturbations of the
//! least infeasible point so far, in the order and with the amplitudes of the ordinary
//! multi-start ([`MultiStartSettings`]). The container variables are those of the given start
//! (the model's variables after the items'), for every container kind alike, a periodic cell
//! included.
//!
//! A run that reaches its time limit, its cap on local minimisations or an interrupt without a
//! certified packing ends with [`Error::NotReached`], which carries the least infeasible point
//! ([`Unfinished`]).
//!
//! With several threads, a start that is certified stops the others of its round; the lowest
//! certified start of the round is returned, so which packing that is may depend on timing.

use crate::Error;
use crate::local::{LocalResult, certified_start, infeasibility};
use crate::multistart::{
    MultiStartProgress, MultiStartResult, MultiStartSettings, Observer, Start, in_parallel,
    minimise_start, start_kind,
};
use crate::starts::{LatticeStart, fill_start, perturb};
use implicit_packing::model::{Certificate, Model};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// The point of a fixed-container run that came closest to a packing, when none was certified.
#[derive(Clone, Debug)]
pub struct Unfinished {
    /// Its variables (the container's are the fixed ones).
    pub x: Vec<f64>,
    /// Its overlap plus containment violation in the model ([`infeasibility`]); 0 only at a
    /// packing.
    pub infeasibility: f64,
    /// What the certificate found wrong with it.
    pub certificate: Certificate,
    /// The packing fraction the container asks for: item area or volume over the container's.
    pub density: f64,
    /// Local minimisations completed.
    pub local_minimisations: usize,
    /// Wall time of the run.
    pub wall_time: Duration,
    /// Whether the run was stopped by its observer rather than by a limit.
    pub interrupted: bool,
}

/// The multi-start in feasibility mode (see the module documentation) of the items of
/// `problem`; `x0` fixes the container. Its local minimisations keep the container
/// ([`LocalSettings::fixed_container`](crate::local::LocalSettings::fixed_container) is set for
/// them).
///
/// # Errors
/// [`Error::NotReached`] when no certified packing was found; errors of the model (a start of
/// the wrong length, an invalid container).
pub fn fill<const N: usize>(
    mut problem: Model<N>,
    x0: &[f64],
    settings: &MultiStartSettings,
    observer: &mut dyn Observer,
) -> Result<MultiStartResult, Error> {
    let start = Instant::now();
    let settings = &MultiStartSettings {
        local: settings.local.clone().with_fixed_container(true),
        ..settings.clone()
    };
    let out_of_time = || settings.time_limit.is_some_and(|t| start.elapsed() >= t);
    // The round's threads minimise on models of their own.
    let (semi_axes, kind) = (problem.semi_axes().to_vec(), problem.container_kind());
    let container = x0
        .get(problem.layout().item_variables()..)
        .unwrap_or_default()
        .to_vec();
    let given = certified_start(&mut problem, x0)?;
    let density = match &given {
        Ok(r) => r.density,
        Err(_) => crate::local::item_measure(&problem) / problem.evaluate(x0, None)?.objective,
    };
    let result = |best: LocalResult, done: usize, failed: usize, kept: bool, interrupted: bool| {
        MultiStartResult {
            best,
            local_minimisations: done,
            failed_starts: failed,
            restarts: 0,
            time_to_best: start.elapsed(),
            wall_time: start.elapsed(),
            interrupted,
            start_density: kept.then_some(density),
            start_kept: kept,
        }
    };
    let mut least = match given {
        Ok(packing) => return Ok(result(packing, 0, 0, true, false)),
        Err(certificate) => Least {
            infeasibility: infeasibility(&mut problem, x0)?,
            x: x0.to_vec(),
            certificate,
        },
    };
    let mut latest_round = least.x.clone();
    let threads = settings.threads.max(1);
    let shard = settings.shard;
    let (mut done, mut failed, mut cut_off) = (0usize, 0usize, 0usize);
    while done < settings.max_local_minimisations && !(observer.should_stop() || out_of_time()) {
        let round = threads.min(settings.max_local_minimisations - done);
        let first_index = done + failed + cut_off;
        let mut starts = Vec::with_capacity(round);
        for index in first_index..first_index + round {
            let x = if index == 0 {
                if shard.index() == 0 {
                    x0.to_vec()
                } else {
                    perturb::<N>(
                        x0,
                        problem.layout(),
                        settings.perturbation,
                        settings.seed,
                        shard.index() as u64,
                    )
                }
            } else {
                match start_kind(settings, index) {
                    Start::Lattice(n) => {
                        // Lattice start 0 of the sequence is the centred one, which callers
                        // fill for the given start: begin after it.
                        let global = n * shard.count() + shard.index() + 1;
                        fill_start(&mut problem, &LatticeStart::sequence(global), &container)?
                    }
                    Start::Perturbed(amplitude) => perturb::<N>(
                        if settings.from_best {
                            &least.x
                        } else {
                            &latest_round
                        },
                        problem.layout(),
                        amplitude,
                        settings.seed,
                        (index * shard.count() + shard.index()) as u64,
                    ),
                }
            };
            starts.push(x);
        }
        let found = AtomicBool::new(false);
        let shared: &dyn Observer = &*observer;
        let (found, out_of_time) = (&found, &out_of_time);
        let results = in_parallel(&starts, threads, |x| {
            let r = minimise_start(&semi_axes, kind, x, &settings.local, shared, || {
                found.load(Ordering::Relaxed) || shared.should_stop() || out_of_time()
            });
            if r.as_ref().is_ok_and(|r| r.certificate.is_feasible()) {
                found.store(true, Ordering::Relaxed);
            }
            r
        });
        let mut round_least: Option<Least> = None;
        for r in results {
            let Ok(r) = r else {
                failed += 1;
                continue;
            };
            if r.certificate.is_feasible() {
                done += 1;
                observer.finished(&MultiStartProgress {
                    local_minimisations: done,
                    best_density: r.density,
                    last_density: r.density,
                    elapsed: start.elapsed(),
                });
                return Ok(result(r, done, failed, false, observer.should_stop()));
            }
            if r.report.stop_reason == auglag::StopReason::Interrupted {
                cut_off += 1;
            } else {
                done += 1;
                observer.finished(&MultiStartProgress {
                    local_minimisations: done,
                    // No certified packing yet.
                    best_density: 0.0,
                    last_density: r.density,
                    elapsed: start.elapsed(),
                });
            }
            let candidate = Least {
                infeasibility: infeasibility(&mut problem, &r.x)?,
                x: r.x,
                certificate: r.certificate,
            };
            if round_least
                .as_ref()
                .is_none_or(|b| candidate.infeasibility < b.infeasibility)
            {
                round_least = Some(candidate);
            }
        }
        if let Some(r) = round_least {
            latest_round = r.x.clone();
            if r.infeasibility < least.infeasibility {
                least = r;
            }
        }
    }
    Err(Error::NotReached(Box::new(Unfinished {
        x: least.x,
        infeasibility: least.infeasibility,
        certificate: least.certificate,
        density,
        local_minimisations: done,
        wall_time: start.elapsed(),
        interrupted: observer.should_stop(),
    })))
}

/// The least infeasible point of a run or a round.
struct Least {
    infeasibility: f64,
    x: Vec<f64>,
    certificate: Certificate,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::local::{LocalSettings, item_measure};
    use implicit_packing::containment::ContainerShape;

    /// 20 ellipsoids (1, 0.75, 0.5) in a ball of the radius that makes their packing fraction
    /// `fraction`, filled from the centred fill start.
    fn ball_run(
        fraction: f64,
        settings: MultiStartSettings,
    ) -> (f64, Vec<f64>, Result<MultiStartResult, Error>) {
        let axes = vec![[1.0, 0.75, 0.5]; 20];
        let mut p = Model::<3>::new(axes.clone(), ContainerShape::Ball).unwrap();
        let volume = item_measure(&p);
        let radius = (volume / fraction / (4.0 / 3.0 * std::f64::consts::PI)).cbrt();
        let x0 = fill_start(&mut p, &LatticeStart::centred(), &[radius]).unwrap();
        let local = settings.local.clone().with_fixed_container(true);
        let settings = settings.with_local(local);
        let p = Model::<3>::new(axes, ContainerShape::Ball).unwrap();
        let r = fill(p, &x0, &settings, &mut ());
        (radius, x0, r)
    }

    #[test]
    fn a_ball_at_fraction_045_is_filled_and_keeps_its_radius() {
        let settings = MultiStartSettings::paper(3, 1)
            .with_lattice_starts(4)
            .with_max_local_minimisations(20);
        let (radius, x0, r) = ball_run(0.45, settings);
        let r = r.unwrap();
        assert!(r.best.certificate.is_feasible());
        assert_eq!(*r.best.x.last().unwrap(), radius, "the container moved");
        assert_eq!(r.best.repair_factor, 1.0);
        assert!((r.best.density - 0.45).abs() < 1e-12, "{}", r.best.density);
        // The start itself overlaps at this fraction: the solver placed the items.
        let mut p = Model::<3>::new(vec![[1.0, 0.75, 0.5]; 20], ContainerShape::Ball).unwrap();
        assert!(!p.certify(&x0).unwrap().is_feasible());
        assert!(r.local_minimisations >= 1);
    }

    #[test]
    fn an_impossible_fraction_ends_not_reached_with_the_least_infeasible_point() {
        // Few outer iterations: each start fails anyway, and the test stays short.
        let settings = MultiStartSettings::paper(3, 1)
            .with_lattice_starts(1)
            .with_max_local_minimisations(3)
            .with_local(LocalSettings::default().with_max_outer_iterations(5));
        let (radius, _, r) = ball_run(0.95, settings);
        let Err(Error::NotReached(u)) = r else {
            panic!("a ball at packing fraction 0.95 was filled: {r:?}");
        };
        assert!(!u.certificate.is_feasible());
        assert!(u.infeasibility > 0.0);
        assert_eq!(*u.x.last().unwrap(), radius);
        assert!((u.density - 0.95).abs() < 1e-12);
        assert_eq!(u.local_minimisations, 3);
        let message = Error::NotReached(u).to_string();
        assert!(message.contains("packing fraction 0.950000"), "{message}");
    }

    /// A fixed periodic cube of unit spheres at any fraction a cubic or close-packed lattice
    /// reaches in it starts as a packing: 2 and 16 at 0.45 and 0.68 (body-centred cubic,
    /// density 0.6802), 4 at 0.74 (face-centred cubic, 0.7405), 1 at 0.52 (simple cubic,
    /// 0.5236); and 2D: 2 unit discs at 0.9 (hexagonal, 0.9069, in a cell of its shape).
    #[test]
    fn fixed_periodic_cells_start_on_the_lattice_that_fits() {
        let cube = |m: usize, fraction: f64| {
            let mut p = Model::<3>::new(vec![[1.0; 3]; m], ContainerShape::Periodic).unwrap();
            let side = (item_measure(&p) / fraction).cbrt();
            let x = fill_start(
                &mut p,
                &LatticeStart::centred(),
                &[side, side, side, 0.0, 0.0, 0.0],
            )
            .unwrap();
            p.certify(&x).unwrap().is_feasible()
        };
        for (m, fraction) in [
            (2, 0.45),
            (16, 0.45),
            (2, 0.68),
            (16, 0.68),
            (4, 0.74),
            (1, 0.52),
        ] {
            assert!(cube(m, fraction), "{m} spheres at {fraction}");
        }
        assert!(
            !cube(2, 0.70),
            "2 spheres at 0.70: beyond body-centred cubic"
        );
        let mut p = Model::<2>::new(vec![[1.0; 2]; 2], ContainerShape::Periodic).unwrap();
        let area = item_measure(&p) / 0.9;
        let width = (area / 3f64.sqrt()).sqrt();
        let x = fill_start(
            &mut p,
            &LatticeStart::centred(),
            &[width, width * 3f64.sqrt(), 0.0],
        )
        .unwrap();
        assert!(p.certify(&x).unwrap().is_feasible());
    }

    /// The same code fills a fixed periodic cell: a square cell (no tilt) holding 10 ellipses
    /// (2, 1) at packing fraction 0.7.
    #[test]
    fn a_fixed_periodic_cell_is_filled_like_a_container() {
        let axes = vec![[2.0, 1.0]; 10];
        let mut p = Model::<2>::new(axes.clone(), ContainerShape::Periodic).unwrap();
        let side = (item_measure(&p) / 0.7).sqrt();
        let cell = [side, side, 0.0];
        let x0 = fill_start(&mut p, &LatticeStart::sequence(1), &cell).unwrap();
        let settings = MultiStartSettings::paper(2, 1)
            .with_lattice_starts(4)
            .with_max_local_minimisations(20)
            .with_local(LocalSettings::default().with_fixed_container(true));
        let p = Model::<2>::new(axes, ContainerShape::Periodic).unwrap();
        let r = fill(p, &x0, &settings, &mut ()).unwrap();
        assert!(r.best.certificate.is_feasible());
        assert_eq!(&r.best.x[30..], &cell[..]);
        assert!((r.best.density - 0.7).abs() < 1e-12, "{}", r.best.density);
    }

    #[test]
    fn fill_starts_take_the_fixed_container_and_keep_the_items() {
        for kind in [
            ContainerShape::Ball,
            ContainerShape::Ellipsoid,
            ContainerShape::Box,
            ContainerShape::Periodic,
        ] {
            let mut p = Model::<2>::new(vec![[2.0, 1.0]; 12], kind).unwrap();
            let dims: Vec<f64> = match kind {
                ContainerShape::Ball => vec![9.0],
                ContainerShape::Periodic => vec![14.0, 1.0, 11.0],
                _ => vec![10.0, 6.0],
            };
            let x = fill_start(&mut p, &LatticeStart::sequence(3), &dims).unwrap();
            assert_eq!(&x[12 * 3..], &dims[..], "{kind:?}");
            assert!(p.evaluate(&x, None).is_ok());
            assert!(fill_start(&mut p, &LatticeStart::centred(), &[1.0; 7]).is_err());
        }
    }
}
