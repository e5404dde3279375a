"""Microseconds per call of the scalar functions (one pair, one shape): the call as written, the
same call forced through the vectorised path (``threads=1``, which skips the fast path of
single rows), and pypw85's figure for its three functions, measured here when pypw85 is
importable, else the figures of issue 37 (pypw85 on the development machine).

    python python/bench/scalar_calls.py [--repeat R] [--number N]

timeit, best of R repeats of N calls each.
"""

import argparse
import timeit

import numpy as np

import ellipack

try:
    import pypw85
except ImportError:
    pypw85 = None

# pypw85's timings on the development machine, as issue 37 (item 20) quotes them, in µs.
ISSUE_PYPW85 = {"spheroid": 0.7, "contact_function": 3.3, "f_neg": 1.3}


def calls():
    """(label, ellipack call, the same call through the vectorised path, pypw85's call or
    None, key of ISSUE_PYPW85 or None), in pypw85's style: float64 arrays, ``out`` given."""
    n = np.array([0.0, 0.6, 0.8])
    q1 = ellipack.spheroid(1.0, 2.0, n)
    q2 = ellipack.from_axes_quaternion(np.array([0.3, 1.0, 2.0]), np.array([1.0, 2.0, 3.0, 4.0]))
    r12 = np.array([1.0, 0.5, 0.2])
    q, out = np.empty(6), np.empty(2)
    r2, e1, e2 = np.array([1.0, 0.5]), np.array([1.0, 0.0, 1.0]), np.array([2.0, 0.1, 1.0])
    axes, rotation = np.array([1.0, 2.0, 3.0]), np.eye(3)
    quaternion = np.array([1.0, 0.2, 0.3, 0.4]) / np.sqrt(1.29)
    l1, l2 = q1.tolist(), q2.tolist()
    e = ellipack
    table = [
        ("spheroid(a, c, n, q)", lambda t=None: e.spheroid(1.0, 2.0, n, q, threads=t),
         lambda: pypw85.spheroid(1.0, 2.0, n, q), "spheroid"),
        ("spheroid(a, c, n)", lambda t=None: e.spheroid(1.0, 2.0, n, threads=t), None, None),
        ("contact_function(r12, q1, q2, out)",
         lambda t=None: e.contact_function(r12, q1, q2, out, threads=t),
         lambda: pypw85.contact_function(r12, q1, q2, out), "contact_function"),
        ("contact_function(r12, q1, q2)",
         lambda t=None: e.contact_function(r12, q1, q2, threads=t), None, None),
        ("f_neg(lambda_, r12, q1, q2)", lambda t=None: e.f_neg(0.3, r12, q1, q2, threads=t),
         lambda: pypw85.f_neg(0.3, r12, q1, q2), "f_neg"),
        ("contact_function(lists)",
         lambda t=None: e.contact_function([1.0, 0.5, 0.2], l1, l2, threads=t), None, None),
        ("contact_function_2d", lambda t=None: e.contact_function_2d(r2, e1, e2, threads=t),
         None, None),
        ("overlap", lambda t=None: e.overlap(r12, q1, q2, threads=t), None, None),
        ("overlap_2d", lambda t=None: e.overlap_2d(r2, e1, e2, threads=t), None, None),
        ("contact_details", lambda t=None: e.contact_details(r12, q1, q2, threads=t), None, None),
        ("contact_details_2d", lambda t=None: e.contact_details_2d(r2, e1, e2, threads=t),
         None, None),
        ("from_axes_quaternion",
         lambda t=None: e.from_axes_quaternion(axes, quaternion, threads=t), None, None),
        ("from_axes_rotation", lambda t=None: e.from_axes_rotation(axes, rotation, threads=t),
         None, None),
        ("from_axes_angle_2d", lambda t=None: e.from_axes_angle_2d(r2, 0.3, threads=t),
         None, None),
        ("overlap_measure",
         lambda t=None: e.overlap_measure(r12, axes, quaternion, -r12, axes, quaternion,
                                          threads=t), None, None),
        ("overlap_measure (2D)",
         lambda t=None: e.overlap_measure(r2, r2, 0.3, -r2, r2, 0.1, threads=t), None, None),
    ]
    return table


def best(run, repeat, number):
    return min(timeit.repeat(run, repeat=repeat, number=number)) / number * 1e6


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeat", type=int, default=7)
    parser.add_argument("--number", type=int, default=20_000)
    args = parser.parse_args()
    source = "measured" if pypw85 is not None else "issue 37"
    print(f"µs per call, best of {args.repeat} x {args.number} calls; pypw85: {source}")
    print(f"{'call':36} {'ellipack':>9} {'vectorised':>11} {'pypw85':>7}")
    for label, call, pypw85_call, key in calls():
        fast = best(call, args.repeat, args.number)
        vectorised = best(lambda: call(1), args.repeat, args.number)
        if key is None:
            reference = ""
        elif pypw85 is not None:
            reference = f"{best(pypw85_call, args.repeat, args.number):7.2f}"
        else:
            reference = f"{ISSUE_PYPW85[key]:7.2f}"
        print(f"{label:36} {fast:9.2f} {vectorised:11.2f} {reference:>7}")


if __name__ == "__main__":
    main()
