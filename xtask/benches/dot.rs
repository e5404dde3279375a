//! The dot product the inner solvers take over vectors of all the model's variables (6 per
//! ellipsoid: m = 1e2 … 1e5): one running sum (what `auglag` used before), `simd::dot` (eight
//! partial sums, what it uses now) and faer's dot product of two columns, the dense kernel
//! the user named. Built only with the `faer` feature, so that the workspace build does not
//! compile faer: `cargo bench -p xtask --features faer --bench dot`.

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use std::hint::black_box;

/// Σ aᵢ bᵢ with one running sum, in index order.
fn one_sum(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

fn faer_dot(a: &[f64], b: &[f64]) -> f64 {
    let (a, b) = (faer::ColRef::from_slice(a), faer::ColRef::from_slice(b));
    a.transpose() * b
}

fn dot(c: &mut Criterion) {
    let mut group = c.benchmark_group("dot");
    for m in [100usize, 1_000, 10_000, 100_000] {
        let n = 6 * m;
        let a: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).sin()).collect();
        let b: Vec<f64> = (0..n).map(|i| (i as f64 * 0.11).cos()).collect();
        // The three agree to rounding: the bench compares equals.
        let (s, v, f) = (one_sum(&a, &b), simd::dot(&a, &b), faer_dot(&a, &b));
        assert!((s - v).abs() <= 1e-12 * n as f64 && (s - f).abs() <= 1e-12 * n as f64);
        group.throughput(Throughput::Elements(n as u64));
        group.bench_with_input(BenchmarkId::new("one running sum", n), &n, |bench, _| {
            bench.iter(|| one_sum(black_box(&a), black_box(&b)));
        });
        group.bench_with_input(BenchmarkId::new("simd::dot", n), &n, |bench, _| {
            bench.iter(|| simd::dot(black_box(&a), black_box(&b)));
        });
        group.bench_with_input(BenchmarkId::new("faer", n), &n, |bench, _| {
            bench.iter(|| faer_dot(black_box(&a), black_box(&b)));
        });
    }
    group.finish();
}

criterion_group!(benches, dot);
criterion_main!(benches);
