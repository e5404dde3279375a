//! The radial distribution function of the centres,
//! `g(r) = n(r, r + Δr) / (m ρ V_shell(r, r + Δr))`, `ρ = m / V`: the number of centres at
//! distance r from a centre over that of an ideal gas of the same number density. In a
//! container (not a periodic cell) the centres near the wall have fewer neighbours, and g(r)
//! falls below 1 at large r by about the fraction of the container within r of its wall:
//! the measure is not corrected for that.

use crate::Error;
use crate::neighbours::for_each_bond;

/// g(r) on bins of equal width.
#[derive(Clone, Debug, PartialEq)]
pub struct Rdf {
    /// The centre of each bin.
    pub r: Vec<f64>,
    /// g at each bin.
    pub g: Vec<f64>,
}

/// g(r) of the centres (in a periodic cell, of every image) up to `range` in `bins` bins, for
/// a container of area or volume `measure`.
///
/// # Errors
/// Those of [`for_each_bond`].
pub fn rdf<const N: usize>(
    centres: &[[f64; N]],
    cell: Option<&[[f64; N]; N]>,
    measure: f64,
    range: f64,
    bins: usize,
) -> Result<Rdf, Error> {
    let m = centres.len() as f64;
    let width = range / bins as f64;
    let mut counts = vec![0u64; bins];
    for_each_bond(centres, cell, range, |_, _, d| {
        let r = d.iter().map(|v| v * v).sum::<f64>().sqrt();
        let k = (r / width) as usize;
        if k < bins {
            counts[k] += 1;
        }
    })?;
    let density = m / measure;
    let ball = |r: f64| {
        if N == 2 {
            std::f64::consts::PI * r * r
        } else {
            4.0 / 3.0 * std::f64::consts::PI * r * r * r
        }
    };
    let r: Vec<f64> = (0..bins).map(|k| (k as f64 + 0.5) * width).collect();
    let g = (0..bins)
        .map(|k| {
            let shell = ball((k + 1) as f64 * width) - ball(k as f64 * width);
            counts[k] as f64 / (m * density * shell)
        })
        .collect();
    Ok(Rdf { r, g })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An ideal gas has g = 1: the normalisation by m ρ V_shell is right in 2D and 3D.
    #[test]
    fn uniform_points_have_g_one() {
        let mut rng = testkit::Rng::new(7);
        let mut next = || rng.uniform();
        let points: Vec<[f64; 2]> = (0..4000).map(|_| [40.0 * next(), 40.0 * next()]).collect();
        let cell = [[40.0, 0.0], [0.0, 40.0]];
        let g = rdf(&points, Some(&cell), 1600.0, 8.0, 8).unwrap();
        for (r, g) in g.r.iter().zip(&g.g).skip(2) {
            assert!((g - 1.0).abs() < 0.05, "g({r}) = {g}");
        }
        let points: Vec<[f64; 3]> = (0..4000)
            .map(|_| [16.0 * next(), 16.0 * next(), 16.0 * next()])
            .collect();
        let cell = [[16.0, 0.0, 0.0], [0.0, 16.0, 0.0], [0.0, 0.0, 16.0]];
        let g = rdf(&points, Some(&cell), 4096.0, 6.0, 6).unwrap();
        for (r, g) in g.r.iter().zip(&g.g).skip(2) {
            assert!((g - 1.0).abs() < 0.05, "g({r}) = {g}");
        }
    }
}
