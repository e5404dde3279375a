//! SplitMix64 (Steele, Lea, Flood 2014).

/// A small seeded generator: the same stream on every run and machine, so that a failing
/// random case reproduces from its seed.
///
/// Derived values use +, −, ×, / and √ only (all correctly rounded in IEEE arithmetic), so the
/// samples do not depend on the platform's `libm` either.
#[derive(Debug, Clone)]
pub struct Rng {
    state: u64,
}

impl Rng {
    /// A generator from a seed; equal seeds give equal streams.
    pub fn new(seed: u64) -> Self {
        Rng { state: seed }
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.state = self.state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1): the top 53 bits, so every value is an exact double.
    pub fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Uniform in [lo, hi).
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.uniform()
    }

    /// A point uniform in the cube [lo, hi)^D.
    pub fn point<const D: usize>(&mut self, lo: f64, hi: f64) -> [f64; D] {
        std::array::from_fn(|_| self.range(lo, hi))
    }

    /// A point uniform in the unit ball, drawn again while within 1e-2 of the centre (so that
    /// its direction is not mostly rounding).
    pub fn in_ball(&mut self) -> [f64; 3] {
        loop {
            let v: [f64; 3] = self.point(-1.0, 1.0);
            let n2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
            if n2 > 1e-4 && n2 <= 1.0 {
                return v;
            }
        }
    }

    /// A uniformly distributed unit vector: [`Rng::in_ball`], normalised.
    pub fn direction(&mut self) -> [f64; 3] {
        let v = self.in_ball();
        let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        v.map(|x| x / n)
    }

    /// A uniformly distributed rotation as a unit quaternion (w, x, y, z): a point uniform in
    /// the 4-ball, normalised (points within 0.1 of the centre are drawn again).
    pub fn unit_quaternion(&mut self) -> [f64; 4] {
        loop {
            let q: [f64; 4] = self.point(-1.0, 1.0);
            let n2: f64 = q.iter().map(|x| x * x).sum();
            if (1e-2..=1.0).contains(&n2) {
                let n = n2.sqrt();
                return q.map(|x| x / n);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::Rng;

    #[test]
    fn splitmix64_reference_stream() {
        // The first outputs for seed 1234567 published with the algorithm (Vigna's
        // splitmix64.c test vector).
        let mut rng = Rng::new(1_234_567);
        assert_eq!(rng.next_u64(), 6_457_827_717_110_365_317);
        assert_eq!(rng.next_u64(), 3_203_168_211_198_807_973);
        assert_eq!(rng.next_u64(), 9_817_491_932_198_370_423);
    }

    #[test]
    fn derived_values_are_in_range_and_normalised() {
        let mut rng = Rng::new(7);
        for _ in 0..10_000 {
            let u = rng.uniform();
            assert!((0.0..1.0).contains(&u));
            let r = rng.range(-2.0, 3.0);
            assert!((-2.0..3.0).contains(&r));
            let d = rng.direction();
            let n: f64 = d.iter().map(|x| x * x).sum();
            assert!((n - 1.0).abs() < 1e-15, "{n}");
            let q = rng.unit_quaternion();
            let n: f64 = q.iter().map(|x| x * x).sum();
            assert!((n - 1.0).abs() < 1e-15, "{n}");
        }
    }
}
