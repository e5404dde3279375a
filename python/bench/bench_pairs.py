"""Time per pair of the contact function for 1e6 pairs: the Python call
(ellipack.contact_function on NumPy arrays) against pw85's Rust batch on the same pairs in the
same process (ellipack._ellipack._bench_rust_batch, which times only the batch call on pairs
already laid out as it wants them), on one thread and on every core.

    python python/bench/bench_pairs.py [--pairs N] [--repeat R]
"""

import argparse
import os
import time

import numpy as np

import ellipack
from ellipack import _ellipack


def random_pairs(n, seed=1):
    rng = np.random.default_rng(seed)
    # Triaxial ellipsoids with axis ratios up to 10, centres a few diameters apart: the
    # moderate pairs of the reference file, half of them overlapping.
    axes = rng.uniform(0.1, 1.0, size=(2, n, 3))
    quaternions = rng.normal(size=(2, n, 4))
    q1 = ellipack.from_axes_quaternion(axes[0], quaternions[0], threads=0)
    q2 = ellipack.from_axes_quaternion(axes[1], quaternions[1], threads=0)
    r12 = rng.normal(scale=0.8, size=(n, 3))
    return r12, q1, q2


def best_of(repeat, run):
    best = float("inf")
    for _ in range(repeat):
        best = min(best, run())
    return best


def python_call(r12, q1, q2, threads):
    def run():
        start = time.perf_counter()
        ellipack.contact_function(r12, q1, q2, threads=threads)
        return time.perf_counter() - start
    return run


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--pairs", type=int, default=1_000_000)
    parser.add_argument("--repeat", type=int, default=5)
    args = parser.parse_args()
    n = args.pairs
    r12, q1, q2 = random_pairs(n)
    mu2, _ = ellipack.contact_function(r12, q1, q2)
    print(f"{n} pairs, {np.mean(mu2 < 1):.0%} overlapping, {os.cpu_count()} cores, "
          f"best of {args.repeat}")
    print(f"{'':>12} {'Python ns/pair':>15} {'Rust batch ns/pair':>19} {'ratio':>6}")
    for label, threads, all_threads in (("one thread", 1, False), ("all threads", 0, True)):
        py = best_of(args.repeat, python_call(r12, q1, q2, threads))
        rust = best_of(args.repeat, lambda: _ellipack._bench_rust_batch(r12, q1, q2, all_threads))
        print(f"{label:>12} {py / n * 1e9:15.1f} {rust / n * 1e9:19.1f} {py / rust:6.2f}")


if __name__ == "__main__":
    main()
