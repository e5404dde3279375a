//! Items merged into one another during a placement, found and pulled apart.
//!
//! The overlap measure of a pair is bounded (the paper's eqs. (21)–(26)): two items whose
//! centres almost coincide cost little more than two that barely overlap, and by merging
//! they leave room to their neighbours. A placement that minimises the overlap energy can
//! therefore drive a few pairs into one another, ever deeper, while every other overlap
//! vanishes, and no dilation small enough certifies its point: on 1e5 ellipsoids
//! (1, 0.75, 0.5) aimed at φ = 0.64 in a periodic cell, the energy fell from 7.0 to 0.001
//! over 5 068 inner iterations while three pairs went from 1/μ = 99 to 1 552 (PW85 theory
//! eq. (7): 1/μ is the dilation their centres need).
//!
//! A placement's tries ([`crate::compression`]) therefore look for such pairs: few pairs
//! asking for more than the placement accepts, some of them merged ([`merged_pairs`]), the
//! same at two tries in a row. Pulled apart along the line of their centres to the distance
//! of their enclosing balls ([`pulled_apart`]), each pair becomes an ordinary overlap with
//! its neighbours, which the placement then removes; a placement whose pairs merge again
//! after a few pulls is given up (its container is too small along this path). On 3·10⁵
//! ellipsoids compressed to φ = 0.6, the last step pulled pairs apart after 1 588 and 10
//! inner iterations and certified 30 inner iterations later; aimed at φ = 0.64, 1e5
//! ellipsoids re-merged after each pull, and the step was given up after 2 100 inner
//! iterations instead of running to its cap of 6 000.
//!
//! A local minimisation that stops with pairs merged is pulled apart and solved again
//! likewise, when the merged pairs are few ([`few_merged`]).

use implicit_packing::model::{Certificate, Model};
use implicit_packing::periodic::{to_cartesian, to_fractional};

/// A pair is merged when its centres need a dilation of at least this factor, 1/μ: their
/// distance is less than half the distance at which they would touch. A compression step of
/// δ leaves pairs that ask for 1/(1 − δ) at most.
pub(crate) const MERGED_DILATION: f64 = 2.0;

/// Pairs are pulled apart only when those that ask more than the placement accepts are at most
/// this fraction of the items (and at least one): a placement still settling its overlaps has
/// many deep pairs at once, which it resolves by itself (at 1e5 items, 100 such pairs were
/// still pushed through one another and apart).
pub(crate) const FEW_PAIRS_PER_ITEM: f64 = 1e-4;

/// The merged pairs of `certificate` when they are among the few that ask for a dilation
/// beyond `limit`, which stop the placement (see the module documentation); empty otherwise.
pub(crate) fn merged_pairs(
    certificate: &Certificate,
    items: usize,
    limit: f64,
) -> Vec<(usize, usize)> {
    let asks = |mu2: f64| {
        if mu2 > 0.0 {
            1.0 / mu2.sqrt()
        } else {
            f64::INFINITY
        }
    };
    let too_much = certificate
        .overlapping
        .iter()
        .filter(|o| asks(o.mu2) > limit)
        .count();
    let few = (FEW_PAIRS_PER_ITEM * items as f64).max(1.0);
    if too_much == 0 || too_much as f64 > few {
        return Vec::new();
    }
    merged(certificate)
}

/// A local minimisation's merged pairs are pulled apart only when they are at most this
/// fraction of the items, or [`FEW_MERGED`]. From perturbations of a packing of 100
/// ellipsoids (1, 0.75, 0.5) in a ball at 0.1, the solver stopped with 2 to 5 merged pairs,
/// and pulled apart once or twice, most starts converged. From perturbations that moved
/// further than the packing absorbs, it stopped with 39 merged pairs among 300 such
/// ellipsoids (at 0.1) and 115 among 1 000 ellipses (2, 1) in a rectangle (at 0.025): three
/// pulls left 16 and 45 of them, and the starts failed after 306 s and 245 s, three times
/// the work of failing at once.
pub(crate) const FEW_MERGED_PER_ITEM: f64 = 0.05;

/// Merged pairs pulled apart after a local minimisation in any case: on a few dozen items
/// a solve costs little.
pub(crate) const FEW_MERGED: f64 = 3.0;

/// The merged pairs of `certificate` ([`merged`]) when they are few among `items`
/// ([`FEW_MERGED_PER_ITEM`], [`FEW_MERGED`]); empty otherwise.
pub(crate) fn few_merged(certificate: &Certificate, items: usize) -> Vec<(usize, usize)> {
    let pairs = merged(certificate);
    let few = (FEW_MERGED_PER_ITEM * items as f64).max(FEW_MERGED);
    if pairs.len() as f64 > few {
        return Vec::new();
    }
    pairs
}

/// The pairs of `certificate` merged into one another: their centres need a dilation of at
/// least [`MERGED_DILATION`], 1/μ ≥ 2 (μ² ≤ 1/4).
pub(crate) fn merged(certificate: &Certificate) -> Vec<(usize, usize)> {
    certificate
        .overlapping
        .iter()
        .filter(|o| o.mu2 * MERGED_DILATION * MERGED_DILATION <= 1.0)
        .map(|o| o.items)
        .collect()
}

/// The variables `x` with the items of each pair moved apart along the line of their centres
/// (the nearest image's, in a periodic cell) until the centres are as far apart as the sum of
/// the pair's largest semi-axes, each item moving half; centres that coincide part along the
/// first coordinate axis. `None` when the model refuses `x`.
pub(crate) fn pulled_apart<const N: usize>(
    problem: &mut Model<N>,
    x: &[f64],
    pairs: &[(usize, usize)],
) -> Option<Vec<f64>> {
    let cell = match problem.container_at(x).ok()? {
        implicit_packing::containment::Container::Periodic { cell } => Some(cell),
        _ => None,
    };
    let mut centres: Vec<[f64; N]> = problem
        .bodies_at(x)
        .ok()?
        .iter()
        .map(|b| b.centre())
        .collect();
    let reach = |i: usize| {
        problem.semi_axes()[i]
            .iter()
            .fold(0.0_f64, |r, &l| r.max(l))
    };
    for &(i, j) in pairs {
        let mut d: [f64; N] = std::array::from_fn(|k| centres[j][k] - centres[i][k]);
        if let Some(cell) = &cell {
            let s = to_fractional(cell, &d).map(|s| s - s.round());
            d = to_cartesian(cell, &s);
        }
        let length = d.iter().map(|v| v * v).sum::<f64>().sqrt();
        let apart = reach(i) + reach(j);
        if length >= apart {
            continue;
        }
        let unit: [f64; N] = if length > 1e-12 * apart {
            d.map(|v| v / length)
        } else {
            std::array::from_fn(|k| if k == 0 { 1.0 } else { 0.0 })
        };
        let half = 0.5 * (apart - length);
        for k in 0..N {
            centres[i][k] -= half * unit[k];
            centres[j][k] += half * unit[k];
        }
    }
    let layout = problem.layout();
    let mut y = x.to_vec();
    for &item in pairs.iter().flat_map(|(i, j)| [i, j]) {
        let centre = match &cell {
            Some(cell) => to_fractional(cell, &centres[item]),
            None => centres[item],
        };
        let at = layout.start(item);
        y[at..at + N].copy_from_slice(&centre);
    }
    Some(y)
}

#[cfg(test)]
mod tests {
    use super::*;
    use implicit_packing::certificate::Overlap;
    use implicit_packing::containment::ContainerShape;

    fn certificate(mu2: &[f64]) -> Certificate {
        Certificate {
            overlapping: mu2
                .iter()
                .enumerate()
                .map(|(k, &mu2)| Overlap {
                    items: (k, k + 1),
                    mu2,
                })
                .collect(),
            ..Certificate::default()
        }
    }

    #[test]
    fn only_deep_pairs_among_few_are_merged() {
        // 1/μ = 10 and 1.05 beyond a limit of 1.01, among 20 000 items (few: 2 at most).
        let c = certificate(&[0.01, 0.9, 0.999]);
        assert_eq!(merged_pairs(&c, 20_000, 1.01), vec![(0, 1)]);
        // Three pairs ask too much: too many for 20 000 items, the placement goes on.
        let c = certificate(&[0.01, 0.9, 0.95]);
        assert!(merged_pairs(&c, 20_000, 1.01).is_empty());
        // A merged pair counts even with μ² = 0 (centres at the same point).
        let c = certificate(&[0.0]);
        assert_eq!(merged_pairs(&c, 10, 1.01), vec![(0, 1)]);
        // Nothing beyond the limit: nothing to pull apart.
        let c = certificate(&[0.999]);
        assert!(merged_pairs(&c, 10, 1.01).is_empty());
    }

    #[test]
    fn only_a_few_merged_pairs_are_pulled_after_a_local_minimisation() {
        let c = certificate(&[0.2; 4]);
        assert_eq!(few_merged(&c, 80).len(), 4);
        assert!(few_merged(&c, 79).is_empty());
        // Three merged pairs are always few.
        assert_eq!(few_merged(&certificate(&[0.2; 3]), 4).len(), 3);
        assert!(few_merged(&c, 5).is_empty());
    }

    /// Two spheres of radius 1 in a periodic cube of edge 10, one near each face (nearest
    /// images 0.2 apart across the face), and a pair at the same point in a box: each pulled
    /// to distance 2, the periodic pair through the face, and then certified apart.
    #[test]
    fn merged_pairs_part_to_their_enclosing_balls() {
        let mut p = Model::<3>::new(vec![[1.0; 3]; 2], ContainerShape::Periodic).unwrap();
        // Fractional centres (a ball has no angles), then the cell (diagonal, then tilts).
        let mut x = vec![0.01, 0.5, 0.5, 0.99, 0.5, 0.5];
        x.extend_from_slice(&[10.0, 10.0, 10.0, 0.0, 0.0, 0.0]);
        assert_eq!(x.len(), p.var_count());
        let y = pulled_apart(&mut p, &x, &[(0, 1)]).unwrap();
        let gap = (y[0] + 1.0 - y[3]) * 10.0;
        assert!((gap - 2.0).abs() < 1e-12, "{gap}");
        assert!(p.certify(&y).unwrap().overlapping.is_empty());

        let mut p = Model::<3>::new(vec![[1.0, 0.5, 0.5]; 2], ContainerShape::Box).unwrap();
        let mut x = vec![0.0; p.var_count()];
        x[p.layout().item_variables()..].copy_from_slice(&[5.0, 5.0, 5.0]);
        let y = pulled_apart(&mut p, &x, &[(0, 1)]).unwrap();
        let second = p.layout().start(1);
        assert_eq!(&y[..3], &[-1.0, 0.0, 0.0]);
        assert_eq!(&y[second..second + 3], &[1.0, 0.0, 0.0]);
        assert!(p.certify(&y).unwrap().overlapping.is_empty());
    }
}
