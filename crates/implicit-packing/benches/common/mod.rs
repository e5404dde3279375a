//! The configuration the model benches time.

use testkit::Rng;

/// `m` ellipsoids (1, 0.75, 0.5) scaled by a factor in [0.9, 1.1], their centres on a jittered
/// cubic lattice filling the cube centred at the origin whose volume they fill to `density`,
/// their angles drawn by `angles`: the semi-axes, the items' variables (centre, then angles)
/// and the cube's side. The same `m` gives the same configuration.
pub fn configuration(
    m: usize,
    density: f64,
    mut angles: impl FnMut(&mut Rng) -> [f64; 3],
) -> (Vec<[f64; 3]>, Vec<f64>, f64) {
    let mut rng = Rng::new(m as u64);
    let axes: Vec<[f64; 3]> = (0..m)
        .map(|_| {
            let s = 0.9 + 0.2 * rng.uniform();
            [s, 0.75 * s, 0.5 * s]
        })
        .collect();
    let volume: f64 = axes
        .iter()
        .map(|l| 4.0 / 3.0 * std::f64::consts::PI * l[0] * l[1] * l[2])
        .sum();
    let side = (volume / density).cbrt();
    let per = (m as f64).cbrt().ceil() as usize;
    let h = side / per as f64;
    // Room for the container variables the benches append.
    let mut x = Vec::with_capacity(6 * m + 6);
    for i in 0..m {
        for idx in [i % per, (i / per) % per, i / (per * per)] {
            x.push((idx as f64 + 0.5) * h - side / 2.0 + (rng.uniform() - 0.5) * 0.2 * h);
        }
        x.extend_from_slice(&angles(&mut rng));
    }
    (axes, x, side)
}
