//! A user's hard-ellipsoid Monte Carlo loop: `pw85::overlap` is the only thing it needs from
//! the crate. Identical prolate ellipsoids in a periodic box are displaced and turned one at a
//! time; a move is accepted when the moved ellipsoid overlaps none of the others.
//!
//! Run with `cargo run --release -p pw85 --example monte_carlo`.

use pw85::overlap;
use pw85::shape::from_axes_angles;

/// The semi-axes of every ellipsoid.
const AXES: [f64; 3] = [1.5, 0.5, 0.5];
/// The periodic box: the start is a 4 × 4 × 4 lattice of aligned ellipsoids, 3.2 apart along
/// their long axes and 1.2 apart across them, at volume fraction 0.34.
const BOX: [f64; 3] = [12.8, 4.8, 4.8];
const SITES_PER_EDGE: usize = 4;
const SWEEPS: usize = 20;
/// Largest displacement per coordinate and largest change of each Euler angle of one trial.
const STEP: f64 = 0.15;
const TURN: f64 = 0.15;

struct Particle {
    centre: [f64; 3],
    angles: [f64; 3],
    /// The shape matrix in PW85 storage, kept in step with `angles`.
    q: [f64; 6],
}

/// xorshift64*: the simulation brings its own generator, as a user's code would.
struct Rng(u64);

impl Rng {
    /// Uniform in [-1, 1).
    fn symmetric(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        let bits = self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11;
        2.0 * (bits as f64 / (1u64 << 53) as f64) - 1.0
    }
}

/// The separation c_j − c_i under periodic boundaries (nearest image).
fn separation(ci: &[f64; 3], cj: &[f64; 3]) -> [f64; 3] {
    std::array::from_fn(|k| {
        let d = cj[k] - ci[k];
        d - BOX[k] * (d / BOX[k]).round()
    })
}

/// Whether `candidate`, standing in for particle `moved`, overlaps any other particle.
fn collides(
    particles: &[Particle],
    moved: usize,
    candidate: &Particle,
) -> Result<bool, pw85::Error> {
    // Two ellipsoids whose circumscribed spheres are apart cannot overlap.
    let reach2 = (2.0 * AXES[0]) * (2.0 * AXES[0]);
    for (j, other) in particles.iter().enumerate() {
        if j == moved {
            continue;
        }
        let r12 = separation(&candidate.centre, &other.centre);
        let d2 = r12.iter().map(|x| x * x).sum::<f64>();
        if d2 < reach2 && overlap(&r12, &candidate.q, &other.q)? {
            return Ok(true);
        }
    }
    Ok(false)
}

fn main() -> Result<(), pw85::Error> {
    let mut particles = Vec::new();
    for a in 0..SITES_PER_EDGE {
        for b in 0..SITES_PER_EDGE {
            for c in 0..SITES_PER_EDGE {
                let centre: [f64; 3] = std::array::from_fn(|k| {
                    ([a, b, c][k] as f64 + 0.5) * BOX[k] / SITES_PER_EDGE as f64
                });
                let angles = [0.0; 3];
                let q = from_axes_angles(&AXES, &angles)?;
                particles.push(Particle { centre, angles, q });
            }
        }
    }
    let volume_fraction =
        particles.len() as f64 * 4.0 / 3.0 * std::f64::consts::PI * AXES.iter().product::<f64>()
            / BOX.iter().product::<f64>();
    println!(
        "{} ellipsoids {AXES:?}, volume fraction {volume_fraction:.3}",
        particles.len()
    );

    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    for sweep in 1..=SWEEPS {
        let mut accepted = 0;
        for i in 0..particles.len() {
            let old = particles[i].centre;
            let centre: [f64; 3] =
                std::array::from_fn(|k| (old[k] + STEP * rng.symmetric()).rem_euclid(BOX[k]));
            let angles = particles[i].angles.map(|a| a + TURN * rng.symmetric());
            let q = from_axes_angles(&AXES, &angles)?;
            let candidate = Particle { centre, angles, q };
            if !collides(&particles, i, &candidate)? {
                particles[i] = candidate;
                accepted += 1;
            }
        }
        if sweep % 5 == 0 {
            println!(
                "sweep {sweep:3}: acceptance rate {:.2}",
                accepted as f64 / particles.len() as f64
            );
        }
    }

    // The final configuration holds no overlapping pair: every accepted move was checked.
    for i in 0..particles.len() {
        assert!(!collides(&particles, i, &particles[i])?);
    }
    println!("no overlapping pair after {SWEEPS} sweeps");
    Ok(())
}
