//! Speed of the contact function, the verdict and the batch path against a straightforward
//! baseline (Brent's method on f(λ) with an LDLᵀ solve per evaluation, as the PW85 library
//! does), all on the same pairs in the same run.
//!
//! Data: 100 000 pairs from a fixed seed. Each ellipsoid has semi-axes s·(1, 10^−U, 10^−U)
//! with U uniform in [0, 1] (aspect ratio 1 to 10) and s = 2^V, V uniform in [−1, 1], and a
//! uniformly random orientation; the centre distance along a uniformly random direction is
//! chosen so that μ² = 2^W, W uniform in [−2, 2]: μ² spread over [0.25, 4], half the pairs
//! overlapping.
//!
//! After criterion's own report, the bench prints ns per pair and the ratios the issue asks
//! for, measured again in this run (best of several passes over all pairs), and the same for
//! 100 000 pairs of ellipses (semi-axes s·(1, 10^−U), a uniformly random angle, the centre
//! distance chosen as in 3D).

use criterion::measurement::WallTime;
use criterion::{BenchmarkGroup, Criterion, Throughput, criterion_group};
use pw85::QuadraticForm;
use pw85::batch::{BatchPair, Pair, Pair2d, Parallelism, contact_functions, overlaps};
use std::hint::black_box;
use std::time::Instant;
use testkit::Rng;

const PAIRS: usize = 100_000;

fn pairs() -> Vec<Pair> {
    let mut rng = Rng::new(0x5EED_0085);
    let ellipsoid = |rng: &mut Rng| {
        let u = rng.uniform();
        let s = 2f64.powf(2.0 * rng.uniform() - 1.0);
        let thin = s * 10f64.powf(-u);
        rng.ellipsoid([s, thin, thin])
    };
    (0..PAIRS)
        .map(|_| {
            let q1 = ellipsoid(&mut rng);
            let q2 = ellipsoid(&mut rng);
            let dir = rng.direction();
            Pair {
                r12: at_random_mu2(dir, &q1, &q2, &mut rng),
                q1,
                q2,
            }
        })
        .collect()
}

/// `dir` scaled so that μ² of the pair (`q1`, `q2`) is log-uniform in [1/4, 4].
fn at_random_mu2<const D: usize, Q: QuadraticForm<Vector = [f64; D]>>(
    dir: [f64; D],
    q1: &Q,
    q2: &Q,
    rng: &mut Rng,
) -> [f64; D] {
    let unit = pw85::contact_function(&dir, q1, q2)
        .expect("valid pair")
        .mu2;
    let target = 2f64.powf(4.0 * rng.uniform() - 2.0);
    let scale = (target / unit).sqrt();
    dir.map(|x| x * scale)
}

fn pairs_2d() -> Vec<Pair2d> {
    let mut rng = Rng::new(0x5EED_2D85);
    let ellipse = |rng: &mut Rng| {
        let u = rng.uniform();
        let s = 2f64.powf(2.0 * rng.uniform() - 1.0);
        rng.ellipse([s, s * 10f64.powf(-u)])
    };
    (0..PAIRS)
        .map(|_| {
            let q1 = ellipse(&mut rng);
            let q2 = ellipse(&mut rng);
            let angle = std::f64::consts::TAU * rng.uniform();
            let dir = [angle.cos(), angle.sin()];
            Pair2d {
                r12: at_random_mu2(dir, &q1, &q2, &mut rng),
                q1,
                q2,
            }
        })
        .collect()
}

/// A pair of ellipsoids or of ellipses, for the scalar contact function.
trait Scalar {
    /// The contact function of the pair.
    fn contact(&self) -> Result<pw85::Contact, pw85::Error>;
}

impl Scalar for Pair {
    fn contact(&self) -> Result<pw85::Contact, pw85::Error> {
        pw85::contact_function(&self.r12, &self.q1, &self.q2)
    }
}

impl Scalar for Pair2d {
    fn contact(&self) -> Result<pw85::Contact, pw85::Error> {
        pw85::contact_function(&self.r12, &self.q1, &self.q2)
    }
}

/// The sum of μ² over `pairs` (of ellipsoids or of ellipses), one pair at a time; a failed pair
/// counts 0.
fn scalar_contact<P: Scalar>(pairs: &[P]) -> f64 {
    pairs
        .iter()
        .map(|p| p.contact().map_or(0.0, |c| c.mu2))
        .sum()
}

fn baseline_brent(pairs: &[Pair]) -> f64 {
    pairs
        .iter()
        .map(|p| pw85::baseline::brent(&p.r12, &p.q1, &p.q2, 1e-10).mu2)
        .sum()
}

fn scalar_overlap(pairs: &[Pair]) -> usize {
    pairs
        .iter()
        .filter(|p| pw85::overlap(&p.r12, &p.q1, &p.q2).unwrap_or(false))
        .count()
}

/// The batch path over `pairs` (of ellipsoids or of ellipses), serial.
fn batch_contact<P: BatchPair>(pairs: &[P], out: &mut [Result<pw85::Contact, pw85::Error>]) -> f64 {
    contact_functions(pairs, out, Parallelism::Serial);
    out.iter().map(|c| c.map_or(0.0, |c| c.mu2)).sum()
}

fn batch_overlap(pairs: &[Pair], out: &mut [Result<bool, pw85::Error>]) -> usize {
    overlaps(pairs, out, Parallelism::Serial);
    out.iter().filter(|v| matches!(v, Ok(true))).count()
}

/// The benchmark group `name`, in pairs per second over all pairs, ten samples.
fn pair_group<'a>(c: &'a mut Criterion, name: &str) -> BenchmarkGroup<'a, WallTime> {
    let mut group = c.benchmark_group(name);
    group.throughput(Throughput::Elements(PAIRS as u64));
    group.sample_size(10);
    group
}

fn bench(c: &mut Criterion) {
    let data = pairs();
    let mut contacts = vec![Ok(pw85::batch::EMPTY_CONTACT); PAIRS];
    let mut verdicts = vec![Ok(false); PAIRS];
    let mut group = pair_group(c, "contact_1e5_pairs");
    group.bench_function("baseline_brent_ldlt", |b| {
        b.iter(|| baseline_brent(black_box(&data)))
    });
    group.bench_function("contact_function", |b| {
        b.iter(|| scalar_contact(black_box(&data)))
    });
    group.bench_function("overlap", |b| b.iter(|| scalar_overlap(black_box(&data))));
    group.bench_function("batch_contact_functions", |b| {
        b.iter(|| batch_contact(black_box(&data), &mut contacts))
    });
    group.bench_function("batch_overlaps", |b| {
        b.iter(|| batch_overlap(black_box(&data), &mut verdicts))
    });
    group.finish();
    let data_2d = pairs_2d();
    let mut group = pair_group(c, "contact_2d_1e5_pairs");
    group.bench_function("contact_function_2d", |b| {
        b.iter(|| scalar_contact(black_box(&data_2d)))
    });
    group.bench_function("batch_contact_functions_2d", |b| {
        b.iter(|| batch_contact(black_box(&data_2d), &mut contacts))
    });
    group.finish();
}

/// Best of `passes` timings of `f` over all pairs, in ns per pair.
fn ns_per_pair<R>(passes: usize, mut f: impl FnMut() -> R) -> f64 {
    (0..passes)
        .map(|_| {
            let start = Instant::now();
            black_box(f());
            start.elapsed().as_secs_f64() * 1e9 / PAIRS as f64
        })
        .fold(f64::INFINITY, f64::min)
}

fn ratios() {
    let data = pairs();
    let mut contacts = vec![Ok(pw85::batch::EMPTY_CONTACT); PAIRS];
    let mut verdicts = vec![Ok(false); PAIRS];
    let brent = ns_per_pair(5, || baseline_brent(&data));
    let contact = ns_per_pair(10, || scalar_contact(&data));
    let verdict = ns_per_pair(10, || scalar_overlap(&data));
    let batch = ns_per_pair(10, || batch_contact(&data, &mut contacts));
    let batch_verdict = ns_per_pair(10, || batch_overlap(&data, &mut verdicts));
    let refined = data
        .iter()
        .filter(|p| pw85::contact_function(&p.r12, &p.q1, &p.q2).is_ok_and(|c| c.refined))
        .count();
    let overlapping = scalar_overlap(&data);
    println!(
        "\n== pw85 contact bench: {PAIRS} pairs, {overlapping} overlapping, {refined} refined in double-double =="
    );
    println!("baseline (Brent + LDLt)      {brent:8.1} ns/pair");
    println!(
        "contact_function             {contact:8.1} ns/pair   {:5.2}x faster than baseline (target >= 6)",
        brent / contact
    );
    println!(
        "overlap                      {verdict:8.1} ns/pair   {:5.2}x faster than contact_function (target >= 2)",
        contact / verdict
    );
    println!(
        "batch contact_functions    {batch:8.1} ns/pair   {:5.2}x faster than scalar (target >= 1.5)",
        contact / batch
    );
    println!(
        "batch overlaps               {batch_verdict:8.1} ns/pair   {:5.2}x faster than scalar overlap",
        verdict / batch_verdict
    );
    let data_2d = pairs_2d();
    let contact_2d = ns_per_pair(10, || scalar_contact(&data_2d));
    let batch_2d = ns_per_pair(10, || batch_contact(&data_2d, &mut contacts));
    println!("contact_function_2d          {contact_2d:8.1} ns/pair");
    println!(
        "batch contact_functions_2d   {batch_2d:8.1} ns/pair   {:5.2}x faster than scalar 2D",
        contact_2d / batch_2d
    );
}

criterion_group!(benches, bench);

fn main() {
    benches();
    Criterion::default().configure_from_args().final_summary();
    ratios();
}
