//! The peer: hoomd-rs hard-particle Monte Carlo of ellipsoids in a periodic cube, compressed
//! by its `QuickCompress` with the protocol of its hard-shape tutorial (random insertion at a
//! low packing fraction, compression under the `OverlapPenalty` Hamiltonian, translation and
//! rotation sweeps at temperature 1).

use super::{Cell, PeerMoves, Point, RandomPair, RunRow, SEMI_AXES, certify_periodic, item_volume};
use crate::error::Error;
use crate::provenance::{commit, machine};
use hoomd_geometry::{
    Convex, IntersectsAtGlobal, Volume,
    shape::{Cuboid, Ellipsoid},
};
use hoomd_interaction::{
    MaximumInteractionRange, PairwiseCutoff, TotalEnergy,
    pairwise::{Anisotropic, ApproximateShapeOverlap, HardShape},
    univariate::OverlapPenalty,
};
use hoomd_mc::{QuickCompress, QuickInsert, Rotate, Sweep, Translate, Trial, UniformIn};
use hoomd_microstate::{Microstate, SiteKey, boundary::Periodic, property::OrientedPoint};
use hoomd_simulation::macrostate::Isothermal;
use hoomd_spatial::VecCell;
use hoomd_utility::valid::PositiveReal;
use hoomd_vector::{Cartesian, Quaternion, Versor};
use std::time::{Duration, Instant};

type Site = OrientedPoint<Cartesian<3>, Versor>;
type State = Microstate<Site, Site, VecCell<SiteKey, 3>, Periodic<Cuboid>>;

/// Packing fraction of the random insertion (the tutorial's for three-dimensional shapes).
const INITIAL_FRACTION: f64 = 0.3;
/// The compression's target.
const TARGET_FRACTION: f64 = 0.74;
/// Resolution of the approximate overlap depth of the penalty Hamiltonian (the tutorial's).
const OVERLAP_RESOLUTION: f64 = 0.01;

fn study_error(context: &str, e: impl std::fmt::Display) -> Error {
    Error::Study {
        context: format!("hoomd-rs: {context}"),
        message: e.to_string(),
    }
}

fn positive(x: f64, what: &str) -> Result<PositiveReal, Error> {
    x.try_into().map_err(|e| study_error(what, e))
}

fn shape() -> Result<Convex<Ellipsoid>, Error> {
    let [a, b, c] = SEMI_AXES;
    Ok(Convex(Ellipsoid::with_semi_axes([
        positive(a, "semi-axis")?,
        positive(b, "semi-axis")?,
        positive(c, "semi-axis")?,
    ])))
}

fn versor(q: [f64; 4]) -> Result<Versor, Error> {
    Quaternion {
        scalar: q[0],
        vector: Cartesian::from([q[1], q[2], q[3]]),
    }
    .to_versor()
    .map_err(|e| study_error("orientation", e))
}

/// A configuration in the certificate's terms.
struct Snapshot {
    cell: Cell,
    centres: Vec<[f64; 3]>,
    quaternions: Vec<[f64; 4]>,
}

fn snapshot(state: &State) -> Snapshot {
    let cell = Cell::orthorhombic(state.boundary().shape().edge_lengths.map(|l| l.get()));
    let (centres, quaternions) = state
        .sites()
        .iter()
        .map(|site| {
            let q = site.properties.orientation.get();
            let v = q.vector.coordinates;
            (
                site.properties.position.coordinates,
                [q.scalar, v[0], v[1], v[2]],
            )
        })
        .unzip();
    Snapshot {
        cell,
        centres,
        quaternions,
    }
}

/// Runs hoomd-rs on `n` ellipsoids for `seconds` of its own wall time and returns the
/// certified packing fractions it reached (each time its box had shrunk and its hard-shape
/// Hamiltonian reported no overlap, checked with [`certify_periodic`]; the checks are not
/// counted in its time) and the run's summary.
///
/// # Errors
/// [`Error::Study`] when hoomd-rs refuses the set-up, [`Error::Pw85`] for a form pw85 refuses.
pub fn run_peer(
    n: usize,
    seconds: f64,
    seed: u64,
    moves: PeerMoves,
) -> Result<(Vec<Point>, RunRow), Error> {
    let ellipsoid = shape()?;
    let hamiltonian = PairwiseCutoff(HardShape(ellipsoid.clone()));
    let range = hamiltonian.maximum_interaction_range();
    let items_volume = n as f64 * item_volume();
    let edge = (items_volume / INITIAL_FRACTION).cbrt();
    let cube = Cuboid::with_equal_edges(positive(edge, "box edge")?);
    let periodic = Periodic::new(range, cube).map_err(|e| study_error("periodic box", e))?;
    let cells = VecCell::builder()
        .nominal_search_radius(positive(range, "search radius")?)
        .build();
    // hoomd-rs seeds are 32 bits; the study's seed is folded into them.
    let seed32 = (seed ^ (seed >> 32)) as u32;
    let mut state: State = Microstate::builder()
        .boundary(periodic)
        .spatial_data(cells)
        .seed(seed32)
        .try_build()
        .map_err(|e| study_error("microstate", e))?;
    let mut translate = Sweep(Translate::with_maximum_distance(positive(
        moves.translate,
        "translation",
    )?));
    let mut rotate = Sweep(Rotate::with_maximum_rotation(positive(
        moves.rotate,
        "rotation",
    )?));
    let distribution = UniformIn {
        boundary: state.boundary().clone(),
        template_sites: vec![Site::default()],
    };
    let mut insert = QuickInsert::new(distribution, n);
    let mut compress =
        QuickCompress::with_target_volume(positive(items_volume / TARGET_FRACTION, "target")?);
    let penalty = PairwiseCutoff(Anisotropic {
        interaction: ApproximateShapeOverlap::new(
            ellipsoid,
            OverlapPenalty::default(),
            positive(OVERLAP_RESOLUTION, "resolution")?,
        ),
        r_cut: range,
    });
    let temperature = Isothermal { temperature: 1.0 };

    let budget = Duration::from_secs_f64(seconds);
    let start = Instant::now();
    let mut excluded = Duration::ZERO;
    let mut certified_volume = f64::INFINITY;
    let mut rejected_volume = f64::NAN;
    let mut points = Vec::new();
    let (mut checks, mut rejected) = (0u64, 0u64);
    let mut best: Option<Snapshot> = None;
    let mut next_report = 10.0;
    loop {
        let clock = start.elapsed().saturating_sub(excluded);
        if clock >= budget {
            break;
        }
        if insert.is_complete() {
            compress.apply(&mut state, &penalty, |_| true);
        } else {
            insert.apply(&mut state, &penalty);
        }
        translate.apply(&mut state, &penalty, &temperature);
        rotate.apply(&mut state, &penalty, &temperature);
        state.increment_step();

        let volume = state.boundary().volume();
        if !(insert.is_complete() && state.bodies().len() == n && volume < certified_volume) {
            continue;
        }
        let at = start.elapsed().saturating_sub(excluded).as_secs_f64();
        let pause = Instant::now();
        if hamiltonian.total_energy(&state) == 0.0 {
            checks += 1;
            let snap = snapshot(&state);
            let certificate = certify_periodic(&snap.cell, &snap.centres, &snap.quaternions)?;
            if certificate.is_certified() {
                certified_volume = volume;
                let fraction = items_volume / volume;
                points.push(Point {
                    who: "peer".into(),
                    n,
                    seconds: at,
                    packing_fraction: fraction,
                });
                best = Some(snap);
                if at >= next_report {
                    eprintln!("  peer N = {n}: {at:8.1} s: {fraction:.5}");
                    next_report = at + 10.0;
                }
            } else if volume != rejected_volume {
                rejected += 1;
                rejected_volume = volume;
                eprintln!(
                    "  peer N = {n}: {at:8.1} s: hoomd-rs reports no overlap at {:.5}, PW85 finds {} overlapping pairs",
                    items_volume / volume,
                    certificate.overlapping_pairs
                );
            }
        }
        excluded += pause.elapsed();
    }
    let best = best.ok_or_else(|| {
        study_error(
            "run",
            format!("no overlap-free configuration of {n} ellipsoids within {seconds} s"),
        )
    })?;
    let final_check = certify_periodic(&best.cell, &best.centres, &best.quaternions)?;
    if !final_check.is_certified() {
        return Err(study_error(
            "final configuration",
            format!("{} overlapping pairs", final_check.overlapping_pairs),
        ));
    }
    let last = points
        .last()
        .cloned()
        .ok_or_else(|| study_error("run", "no point"))?;
    eprintln!(
        "  peer N = {n}: final {:.5} at {:.1} s ({} steps, min μ² {:?})",
        last.packing_fraction,
        last.seconds,
        state.step(),
        final_check.min_mu2
    );
    let row = RunRow {
        who: "peer".into(),
        n,
        budget_seconds: seconds,
        final_fraction: last.packing_fraction,
        final_seconds: last.seconds,
        checks,
        rejected,
        min_mu2: final_check.min_mu2,
        machine: machine(),
        commit: commit(),
        protocol: format!(
            "QuickInsert at {INITIAL_FRACTION}, QuickCompress to {TARGET_FRACTION}, moves ≤ {} \
             and {} rad, seed {seed}",
            moves.translate, moves.rotate
        ),
    };
    Ok((points, row))
}

/// Times hoomd-rs's ellipsoid overlap test — `Convex<Ellipsoid>::intersects_at_global`, the
/// call its `HardShape` makes — on the pairs (the fastest of `repeats` passes) and returns
/// its nanoseconds per pair and verdicts.
///
/// # Errors
/// [`Error::Study`] for an orientation hoomd-rs refuses.
pub fn time_overlaps(pairs: &[RandomPair], repeats: usize) -> Result<(f64, Vec<bool>), Error> {
    let ellipsoid = shape()?;
    let origin = Cartesian::from([0.0; 3]);
    let prepared = pairs
        .iter()
        .map(|p| Ok((versor(p.q1)?, versor(p.q2)?, Cartesian::from(p.r12))))
        .collect::<Result<Vec<_>, Error>>()?;
    let mut verdicts = vec![false; pairs.len()];
    let mut best = f64::INFINITY;
    for _ in 0..repeats.max(1) {
        let start = Instant::now();
        for (v, (q1, q2, r)) in verdicts.iter_mut().zip(&prepared) {
            *v = std::hint::black_box(&ellipsoid).intersects_at_global(
                &ellipsoid,
                &origin,
                std::hint::black_box(q1),
                r,
                q2,
            );
        }
        best = best.min(start.elapsed().as_secs_f64());
        std::hint::black_box(&verdicts);
    }
    Ok((best * 1e9 / pairs.len().max(1) as f64, verdicts))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hoomd_and_pw85_agree_away_from_tangency() {
        let pairs = super::super::random_pairs(200, 3).unwrap();
        let (_, verdicts) = time_overlaps(&pairs, 1).unwrap();
        for (p, v) in pairs.iter().zip(&verdicts) {
            if p.mu2_minus_one.abs() > 1e-6 {
                assert_eq!(*v, p.mu2_minus_one < 0.0, "{p:?}");
            }
        }
    }
}
