//! The radial distribution function of the centres,
//! `g(r) = n(r, r + Δr) / (m ρ V_shell(r, r + Δr))`, `ρ = m / V`: the number of centres at
//! distance r from a centre over that of an ideal gas of the same number density. In a
//! container (not a periodic cell) the centres near the wall have fewer neighbours, and g(r)
//! falls below 1 at large r by about the fraction of the container within r of its wall:
//! the measure is not corrected for that.

use crate::neighbours::Bonds;

/// g(r) on bins of equal width.
#[derive(Clone, Debug, PartialEq)]
pub struct Rdf {
    /// The centre of each bin.
    pub r: Vec<f64>,
    /// g at each bin.
    pub g: Vec<f64>,
}

/// g(r) of the bonds up to `range` in `bins` bins, for a container of area or volume
/// `measure`.
pub fn rdf<const N: usize>(bonds: &Bonds<N>, measure: f64, range: f64, bins: usize) -> Rdf {
    let m = bonds.of_item.len() as f64;
    let width = range / bins as f64;
    let mut counts = vec![0u64; bins];
    for list in &bonds.of_item {
        for (_, d) in list {
            let r = d.iter().map(|v| v * v).sum::<f64>().sqrt();
            let k = (r / width) as usize;
            if k < bins {
                counts[k] += 1;
            }
        }
    }
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
    Rdf { r, g }
}
