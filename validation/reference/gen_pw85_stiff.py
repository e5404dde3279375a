#!/usr/bin/env python3
"""Generates `pw85_objective.csv` and `pw85_details.csv` (see README.md in this folder).

Every value is computed from the definitions alone, in mpmath, from the inputs as IEEE doubles:

    Q(λ) = (1 − λ) Q1 + λ Q2,   y = Q(λ)⁻¹ r12,   f(λ) = λ (1 − λ) r12ᵀ y,
    λ₀ = argmax f on [0, 1],    μ² = f(λ₀),
    point = x₀ − c1 = (1 − λ₀) Q1 y(λ₀),   normal = y(λ₀) / |y(λ₀)|,   grad_r12 = 2 λ₀ (1 − λ₀) y(λ₀).

Each case is evaluated twice, with 70 and with 110 significant digits, and the script stops
unless the two agree to 50 digits or more on every output; it also checks the tangency
conditions of eq. 13 (the point on both ellipsoids scaled by μ) at 110 digits. The outputs are
written with 36 significant digits, the inputs with 17 (they read back as the same doubles).

Usage: python gen_pw85_stiff.py [OUTPUT_FOLDER]   (default: this script's folder; takes about a
15 s; needs mpmath only).
"""

import math
import os
import random
import sys

import mpmath
from mpmath import mp, mpf

LOW, HIGH, AGREE, WRITTEN = 70, 110, 50, 36
LAMBDAS = [k / 10 for k in range(1, 10)]  # 0.1 … 0.9, as doubles
# The radii of upstream PW85's test grid.
RADII = [0.01999, 1.999, 9.999]


def icosahedron():
    """The 12 vertices of the icosahedron, as unit vectors (doubles)."""
    phi = (1 + math.sqrt(5)) / 2
    out = []
    for s1 in (-1, 1):
        for s2 in (-1, 1):
            for v in ((0, s1, s2 * phi), (s1, s2 * phi, 0), (s2 * phi, 0, s1)):
                n = math.sqrt(sum(x * x for x in v))
                out.append(tuple(x / n for x in v))
    return out


def spheroid(a, c, n):
    """Q = a² I + (c² − a²) n nᵀ as pypw85's `spheroid` builds it (n unit), in doubles."""
    q = []
    for i, j in ((0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2)):
        q.append((a * a if i == j else 0.0) + (c * c - a * a) * n[i] * n[j])
    return q


def quaternion(rng):
    w = [rng.gauss(0, 1) for _ in range(4)]
    n = math.sqrt(sum(x * x for x in w))
    return [x / n for x in w]


def triaxial(axes, q):
    """Q = R diag(axes²) Rᵀ, R the rotation of the unit quaternion q = (w, x, y, z), in doubles."""
    w, x, y, z = q
    r = [
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ]
    out = []
    for i, j in ((0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2)):
        out.append(sum(r[i][k] * r[j][k] * axes[k] ** 2 for k in range(3)))
    return out


def direction(rng):
    v = [rng.gauss(0, 1) for _ in range(3)]
    n = math.sqrt(sum(x * x for x in v))
    return [x / n for x in v]


def full(q):
    return [[q[0], q[1], q[2]], [q[1], q[3], q[4]], [q[2], q[4], q[5]]]


def solve(m, r):
    """m⁻¹ r for a symmetric 3×3 mp matrix, by the adjugate (exact up to the working precision)."""
    a, b, c = m[0]
    _, d, e = m[1]
    f = m[2][2]
    adj = [
        [d * f - e * e, c * e - b * f, b * e - c * d],
        [c * e - b * f, a * f - c * c, b * c - a * e],
        [b * e - c * d, b * c - a * e, a * d - b * b],
    ]
    det = a * adj[0][0] + b * adj[1][0] + c * adj[2][0]
    return [sum(adj[i][k] * r[k] for k in range(3)) / det for i in range(3)]


def pencil(lam, q1, q2):
    return [[(1 - lam) * q1[i][j] + lam * q2[i][j] for j in range(3)] for i in range(3)]


def dot(x, y):
    return sum(a * b for a, b in zip(x, y))


def mat_vec(m, v):
    return [dot(row, v) for row in m]


def f_value(lam, r, q1, q2):
    lam = mpf(lam)
    y = solve(pencil(lam, q1, q2), r)
    return lam * (1 - lam) * dot(r, y)


def maximiser(r, q1, q2):
    """λ₀ ∈ (0, 1) where f′ = 0: bisection on the log-odds, then Newton in λ (or in 1 − λ)."""
    d = [[q2[i][j] - q1[i][j] for j in range(3)] for i in range(3)]

    def derivatives(lam):
        # y′ = −Q⁻¹ D y (D = Q2 − Q1): f′ = (1 − 2λ) rᵀy − λ(1 − λ) yᵀDy and
        # f″ = −2 rᵀy − 2 (1 − 2λ) yᵀDy + 2 λ (1 − λ) (Dy)ᵀ Q⁻¹ (Dy).
        m = pencil(lam, q1, q2)
        y = solve(m, r)
        dy = mat_vec(d, y)
        ry, ydy = dot(r, y), dot(y, dy)
        w = solve(m, dy)
        f1 = (1 - 2 * lam) * ry - lam * (1 - lam) * ydy
        f2 = -2 * ry - 2 * (1 - 2 * lam) * ydy + 2 * lam * (1 - lam) * dot(dy, w)
        return f1, f2

    lo, hi = mpf(-200), mpf(200)  # ln u, u = λ / (1 − λ)
    for _ in range(70):
        mid = (lo + hi) / 2
        u = mp.exp(mid)
        f1, _ = derivatives(u / (1 + u))
        if f1 > 0:
            lo = mid
        else:
            hi = mid
    u = mp.exp((lo + hi) / 2)
    lam = u / (1 + u)
    # Quadratic convergence: once a step is below 10^-(dps/2 + 5) relative, one more step
    # reaches the working precision.
    small = mpf(10) ** (-(mp.dps // 2 + 5))
    for _ in range(30):
        f1, f2 = derivatives(lam)
        step = f1 / f2
        lam -= step
        if abs(step) <= small * min(lam, 1 - lam):
            f1, f2 = derivatives(lam)
            return lam - f1 / f2
    raise RuntimeError("Newton did not converge")


def lift(case):
    r = [mpf(x) for x in case["r12"]]
    return r, full([mpf(x) for x in case["q1"]]), full([mpf(x) for x in case["q2"]])


def details(case):
    r, q1, q2 = lift(case)
    lam = maximiser(r, q1, q2)
    y = solve(pencil(lam, q1, q2), r)
    mu2 = lam * (1 - lam) * dot(r, y)
    point = [(1 - lam) * x for x in mat_vec(q1, y)]
    norm = mp.sqrt(dot(y, y))
    normal = [x / norm for x in y]
    grad = [2 * lam * (1 - lam) * x for x in y]
    return [lam, mu2] + point + normal + grad, (r, q1, q2, lam, mu2, point)


def check_tangency(r, q1, q2, mu2, point):
    """Eq. 13: (x₀ − c1)ᵀ Q1⁻¹ (x₀ − c1) = (x₀ − c2)ᵀ Q2⁻¹ (x₀ − c2) = μ²."""
    other = [p - x for p, x in zip(point, r)]
    for value in (dot(point, solve(q1, point)), dot(other, solve(q2, other))):
        if abs(value - mu2) > mpf(10) ** (-AGREE) * mu2:
            raise RuntimeError(f"eq. 13 fails: {value} against {mu2}")


def agree(a, b):
    """Significant digits on which two mp vectors agree (Euclidean norm of the difference over
    the larger norm: a component that is 0 in exact arithmetic is compared on the vector's
    scale)."""
    diff = mp.sqrt(sum((x - y) ** 2 for x, y in zip(a, b)))
    scale = max(mp.sqrt(dot(a, a)), mp.sqrt(dot(b, b)))
    if diff == 0:
        return 1000.0
    return float(-mp.log10(diff / scale))


# How the outputs of `details` group into quantities: λ₀ (and 1 − λ₀, so that a λ₀ near 1
# is compared on its distance to 1), μ², the point, the normal, the gradient.
DETAIL_GROUPS = [(0, 1), (1, 2), (2, 5), (5, 8), (8, 11)]


def twice(compute, groups):
    """The outputs at 70 and at 110 digits, checked to agree to 50 digits on every group of
    outputs; the 110-digit ones returned, with the digits of agreement."""
    mp.dps = LOW
    low = compute()
    mp.dps = HIGH
    high = compute()
    lv = low[0] if isinstance(low, tuple) else low
    hv = high[0] if isinstance(high, tuple) else high
    digits = min(agree(lv[i:j], hv[i:j]) for i, j in groups)
    if groups is DETAIL_GROUPS:
        digits = min(digits, agree([1 - lv[0]], [1 - hv[0]]))
    if digits < AGREE:
        raise RuntimeError(f"70 and 110 digits agree to {digits:.1f} digits only")
    return high, digits


def pairs(rng):
    """(category, r12, q1, q2) of the stiff pairs, in a fixed order from a fixed seed."""
    ico = icosahedron()
    out = []
    # Upstream PW85's grid: spheroids of radii (a, c) from 0.01999, 1.999, 9.999 along the 12
    # icosahedron directions; here always with the needle a = 0.01999, c = 9.999 first.
    shapes = [(a, c) for a in RADII for c in RADII]
    for _ in range(200):
        n1, n2, d = rng.choice(ico), rng.choice(ico), rng.choice(ico)
        a2, c2 = rng.choice(shapes)
        length = rng.choice([0.5, 2.0, 10.0, 20.0])
        q1 = spheroid(0.01999, 9.999, n1)
        q2 = spheroid(a2, c2, n2)
        if rng.random() < 0.5:
            q1, q2 = q2, q1
        out.append(("needle_grid", [length * x for x in d], q1, q2))

    def body(kind):
        size = 2 ** rng.uniform(-1, 1)
        if kind == "needle":
            thin = size * 10 ** -rng.uniform(2, 4)
            axes = [size, thin * rng.uniform(0.5, 1), thin]
        elif kind == "pancake":
            thin = size * 10 ** -rng.uniform(2, 4)
            axes = [size, size * rng.uniform(0.5, 1), thin]
        else:
            axes = [size, size * 10 ** -rng.uniform(0, 1), size * 10 ** -rng.uniform(0, 1)]
        rng.shuffle(axes)
        return axes

    def random_pair(category, k1, k2, ratio=1.0):
        a1, a2 = body(k1), [x * ratio for x in body(k2)]
        q1, q2 = triaxial(a1, quaternion(rng)), triaxial(a2, quaternion(rng))
        if rng.random() < 0.5:
            q1, q2, a1, a2 = q2, q1, a2, a1
        # Centre distance from 1/10 to 10 times the sum of the largest semi-axes.
        length = (max(a1) + max(a2)) * 10 ** rng.uniform(-1, 1)
        return (category, [length * x for x in direction(rng)], q1, q2)

    for _ in range(60):
        out.append(random_pair("needles", "needle", "needle"))
    for _ in range(60):
        out.append(random_pair("pancakes", "pancake", "pancake"))
    for _ in range(50):
        out.append(random_pair("needle_pancake", "needle", "pancake"))
    for e in (2, 4, 6, 8):
        for _ in range(20):
            kinds = rng.choice([("moderate", "moderate"), ("needle", "moderate"),
                                ("moderate", "needle"), ("pancake", "moderate")])
            out.append(random_pair(f"size_ratio_1e{e}", kinds[0], kinds[1], 10.0 ** e))
    for _ in range(40):
        out.append(random_pair("moderate", "moderate", "moderate"))
    return out


def fmt_in(x):
    return f"{x:.16e}"


def fmt_out(x):
    return mpmath.nstr(x, WRITTEN, min_fixed=1, max_fixed=0, strip_zeros=False)


def main():
    folder = sys.argv[1] if len(sys.argv) > 1 else os.path.dirname(os.path.abspath(__file__))
    rng = random.Random(20261128)
    cases = [
        {"category": c, "r12": r, "q1": q1, "q2": q2} for c, r, q1, q2 in pairs(rng)
    ]
    inputs = ["r12_x", "r12_y", "r12_z"] + [f"q1_{k}" for k in range(6)] + [
        f"q2_{k}" for k in range(6)
    ]

    def row_inputs(case):
        return [fmt_in(x) for x in case["r12"] + case["q1"] + case["q2"]]

    worst = 1000.0
    with open(os.path.join(folder, "pw85_details.csv"), "w") as out:
        out.write(",".join(["case_id", "category"] + inputs + [
            "lambda_ref", "mu2_ref", "point_x", "point_y", "point_z",
            "normal_x", "normal_y", "normal_z", "grad_r12_x", "grad_r12_y", "grad_r12_z",
        ]) + "\n")
        for i, case in enumerate(cases):
            (values, parts), digits = twice(lambda: details(case), DETAIL_GROUPS)
            check_tangency(*parts[:3], parts[4], parts[5])
            worst = min(worst, digits)
            out.write(",".join([str(i), case["category"]] + row_inputs(case)
                               + [fmt_out(v) for v in values]) + "\n")
    print(f"pw85_details.csv: {len(cases)} cases, 70 and 110 digits agree to {worst:.1f}")

    # The objective on every fourth pair of each category (all categories represented).
    chosen = [c for k, c in enumerate(cases) if k % 4 == 0]
    worst = 1000.0
    rows = 0
    with open(os.path.join(folder, "pw85_objective.csv"), "w") as out:
        out.write(",".join(["case_id", "category"] + inputs + ["lambda", "f_ref"]) + "\n")
        for case in chosen:
            for lam in LAMBDAS:
                value, digits = twice(lambda: [f_value(lam, *lift(case))], [(0, 1)])
                worst = min(worst, digits)
                out.write(",".join([str(rows), case["category"]] + row_inputs(case)
                                   + [repr(lam), fmt_out(value[0])]) + "\n")
                rows += 1
    print(f"pw85_objective.csv: {rows} rows, 70 and 110 digits agree to {worst:.1f}")


if __name__ == "__main__":
    main()
