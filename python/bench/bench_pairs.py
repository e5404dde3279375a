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


def timed(run):
    start = time.perf_counter()
    run()
    return time.perf_counter() - start


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--pairs", type=int, default=1_000_000)
    parser.add_argument("--repeat", type=int, default=9)
    args = parser.parse_args()
    n = args.pairs
    r12, q1, q2 = random_pairs(n)
    mu2, _ = ellipack.contact_function(r12, q1, q2)
    out = np.empty((n, 2))
    print(f"{n} pairs, {np.mean(mu2 < 1):.0%} overlapping, {os.cpu_count()} cores; best of "
          f"{args.repeat} runs, the three calls taking turns (other load on the machine hits "
          f"all three alike)")
    print(f"{'':>12} {'Python ns/pair':>15} {'with out=':>10} {'Rust batch':>11} "
          f"{'ratio':>6} {'with out=':>10}")
    for label, threads, all_threads in (("one thread", 1, False), ("all threads", 0, True)):
        best = [float("inf")] * 3
        for _ in range(args.repeat):
            runs = (
                lambda: ellipack.contact_function(r12, q1, q2, threads=threads),
                lambda: ellipack.contact_function(r12, q1, q2, out, threads=threads),
                None,
            )
            for k in range(3):
                seconds = (
                    _ellipack._bench_rust_batch(r12, q1, q2, all_threads)
                    if runs[k] is None
                    else timed(runs[k])
                )
                best[k] = min(best[k], seconds)
        py, py_out, rust = (b / n * 1e9 for b in best)
        print(f"{label:>12} {py:15.1f} {py_out:10.1f} {rust:11.1f} {py / rust:6.2f} "
              f"{py_out / rust:10.2f}")


if __name__ == "__main__":
    main()
