//! The certificate and the least repair of a solver's point: scaling every centre and the
//! container by s leaves the shapes as they are and multiplies every pair's contact function by
//! s² (PW85 theory), so the overlapping pairs need s = max 1/μ_ij exactly; an item still outside
//! is then held by scaling the container alone by its containment scale t. The repair costs a
//! factor (s·t)^N in density.

use crate::Error;
use crate::settings::{LocalResult, check_start, empty_report, item_measure};
use auglag::Report;
use implicit_packing::model::{Certificate, Model};

/// The start `x` as a result of its own, without minimising, when it is certified as it is
/// (no overlap, every item inside): a lattice start is, and so is a packing read back from a
/// finished run. `Ok(Err(certificate))` says what is wrong with a start that is not.
///
/// A run keeps this as its first best packing, so that it ends with a certified packing even
/// when its first local minimisation is cut off before it converges, and a resumed run never
/// writes a packing worse than the one it started from.
///
/// # Errors
/// [`Error::Model`] (`LengthMismatch`) when `x` does not fit the problem; errors of the model on
/// non-finite variables.
pub fn certified_start<const N: usize>(
    problem: &mut Model<N>,
    x: &[f64],
) -> Result<Result<LocalResult, Certificate>, Error> {
    check_start(problem, x)?;
    let certificate = problem.certify(x)?;
    if !certificate.is_feasible() {
        return Ok(Err(certificate));
    }
    let objective = problem.evaluate(x, None)?.objective;
    let density = item_measure(problem) / objective;
    Ok(Ok(LocalResult {
        x: x.to_vec(),
        density,
        density_before_repair: density,
        repair_factor: 1.0,
        objective,
        certificate,
        // No solver ran: no iterations, no evaluations beyond the certificate's.
        report: Report {
            objective,
            best_feasible_objective: Some(objective),
            ..empty_report()
        },
    }))
}

/// A certified result with the solver's own point kept for a warm start.
pub(crate) struct Certified {
    pub(crate) result: LocalResult,
    pub(crate) x_unrepaired: Vec<f64>,
    pub(crate) repair_factor: f64,
    pub(crate) report: Report,
}

pub(crate) fn certified<const N: usize>(
    problem: &mut Model<N>,
    solution: auglag::Solution,
) -> Result<Certified, Error> {
    let repaired = repair(problem, &solution.x)?;
    certified_as(problem, solution, repaired)
}

/// [`certified`] with the repair of the solver's point already done (`repaired` as returned
/// by [`repair`] for `solution.x`).
pub(crate) fn certified_as<const N: usize>(
    problem: &mut Model<N>,
    solution: auglag::Solution,
    repaired: (Vec<f64>, f64, Certificate),
) -> Result<Certified, Error> {
    let (x, repair_factor, certificate) = repaired;
    let items = item_measure(problem);
    let before = problem.evaluate(&solution.x, None)?.objective;
    let objective = problem.evaluate(&x, None)?.objective;
    Ok(Certified {
        result: LocalResult {
            x,
            density: items / objective,
            density_before_repair: items / before,
            repair_factor,
            objective,
            certificate,
            report: solution.report.clone(),
        },
        x_unrepaired: solution.x,
        repair_factor,
        report: solution.report,
    })
}

/// A packing made of `x` by the least enlargement of its container found in two exact steps:
/// the centres and the container dilated by s = max 1/μ_ij over the overlapping pairs
/// (dilating the centres multiplies every pair's contact function μ² by s²), then the
/// container alone scaled about its centre by t, the largest containment scale of an item
/// still outside (the least factor that holds it, [`containment_scale`]; the centres stay, so
/// no pair changes). Returns the packing, the container's linear factor s·t ≥ 1 and the
/// certificate. Scaling the container alone costs far less than dilating everything: an item
/// a depth d outside needs t − 1 ≈ d/R of a container of size R, but a dilation only gains
/// (s − 1)·(R − |c|) on it, s − 1 ≈ d/r for an item of size r at the wall. When rounding leaves
/// anything uncertified, the least uniform dilation that certifies (by doubling and bisection)
/// is returned instead.
///
/// [`containment_scale`]: implicit_packing::certificate::containment_scale
///
/// # Errors
/// Errors of the model (non-finite variables); [`Error::NotCertifiable`] when no factor up to
/// 4 makes a packing (an item far outside the container).
pub fn repair<const N: usize>(
    problem: &mut Model<N>,
    x: &[f64],
) -> Result<(Vec<f64>, f64, Certificate), Error> {
    let certificate = problem.certify(x)?;
    if certificate.is_feasible() {
        return Ok((x.to_vec(), 1.0, certificate));
    }
    match separated_then_held(problem, x, &certificate)? {
        Some(repaired) if repaired.1 <= MAX_DILATION => Ok(repaired),
        _ => least_uniform_dilation(problem, x, &certificate),
    }
}

/// The two exact steps of [`repair`] for a point `x` whose certificate is `certificate`: the
/// packing, its factor s·t and its certificate, or `None` when rounding leaves anything
/// uncertified.
pub(crate) fn separated_then_held<const N: usize>(
    problem: &mut Model<N>,
    x: &[f64],
    certificate: &Certificate,
) -> Result<Option<(Vec<f64>, f64, Certificate)>, Error> {
    let (s, y, dilated) = if certificate.overlapping.is_empty() {
        (1.0, x.to_vec(), certificate.clone())
    } else {
        let s = pair_dilation(certificate);
        let y = dilate::<N>(problem, x, s);
        let dilated = problem.certify(&y)?;
        (s, y, dilated)
    };
    if !dilated.overlapping.is_empty() {
        return Ok(None);
    }
    if dilated.outside.is_empty() {
        return Ok(Some((y, s, dilated)));
    }
    let t = dilated.outside.iter().fold(1.0_f64, |t, o| t.max(o.scale)) * (1.0 + MARGIN);
    let z = container_scaled::<N>(problem, &y, t);
    let held = problem.certify(&z)?;
    Ok(held.is_feasible().then_some((z, s * t, held)))
}

/// Past this factor of the container's linear size a point is given up: an item far outside
/// (its centre outside the container, for a dilation) is no packing worth keeping.
const MAX_DILATION: f64 = 4.0;

/// A relative margin on every factor keeps the verdicts clear of rounding at tangency.
const MARGIN: f64 = 1e-12;

/// The dilation of centres and container that settles every overlapping pair of `certificate`
/// exactly, s = max 1/μ_ij (μ² grows as s²), with the margin.
fn pair_dilation(certificate: &Certificate) -> f64 {
    let s = certificate
        .overlapping
        .iter()
        .filter(|o| o.mu2 > 0.0)
        .fold(1.0_f64, |s, o| s.max(1.0 / o.mu2.sqrt()));
    s * (1.0 + MARGIN)
}

/// The least uniform dilation s ≥ 1 of the centres and the container after which `x` passes
/// [`Model::certify`] (`certificate` is that of `x`): the pairs' s = max 1/μ_ij, then
/// containment, which improves monotonically with s, by doubling and bisection.
fn least_uniform_dilation<const N: usize>(
    problem: &mut Model<N>,
    x: &[f64],
    certificate: &Certificate,
) -> Result<(Vec<f64>, f64, Certificate), Error> {
    let given_up = |c: &Certificate| Error::NotCertifiable {
        max_dilation: MAX_DILATION,
        overlapping: c.overlapping.len(),
        outside: c.outside.len(),
    };
    let mut s = pair_dilation(certificate);
    // Two items collapsed into each other (μ near 0, as when the solver ends with a pair's
    // centres almost together) would need a dilation of thousands: a container that size
    // holds nothing worth keeping, so the point is given up as for an item far outside.
    if s > MAX_DILATION {
        return Err(given_up(certificate));
    }
    // Containment and any pair the formula could not settle: grow until certified, then
    // bisect back to the least factor that passes.
    let mut lo = 1.0;
    let mut y = dilate::<N>(problem, x, s);
    let mut cert = problem.certify(&y)?;
    // Dilation scales a centre and the container together, so an item whose centre is
    // outside the container is never repaired: past MAX_DILATION the point is given up.
    while !cert.is_feasible() {
        lo = s;
        s = 1.0 + 2.0 * (s - 1.0).max(1e-9);
        if s > MAX_DILATION {
            return Err(given_up(&cert));
        }
        y = dilate::<N>(problem, x, s);
        cert = problem.certify(&y)?;
    }
    let mut hi = s;
    for _ in 0..60 {
        if hi - lo <= MARGIN * hi {
            break;
        }
        let mid = 0.5 * (lo + hi);
        let trial = dilate::<N>(problem, x, mid);
        let c = problem.certify(&trial)?;
        if c.is_feasible() {
            hi = mid;
            y = trial;
            cert = c;
        } else {
            lo = mid;
        }
    }
    Ok((y, hi, cert))
}

/// The container's dimensions of `x` multiplied by `t` (scaled about its centre); the items
/// stay.
fn container_scaled<const N: usize>(problem: &Model<N>, x: &[f64], t: f64) -> Vec<f64> {
    let bodies_end = problem.layout().item_variables();
    let mut y = x.to_vec();
    y[bodies_end..].iter_mut().for_each(|v| *v *= t);
    y
}

/// Centres and container dimensions multiplied by `s`; angles unchanged ([`Model::dilated`]).
fn dilate<const N: usize>(problem: &Model<N>, x: &[f64], s: f64) -> Vec<f64> {
    problem.dilated(x, s)
}
