"""`import ellipack as pypw85`: pypw85's public API (spheroid, contact_function, f_neg,
lambda_atol, metadata) with pypw85's meaning, checked as pypw85's own tests check it."""

import numpy as np
import pytest

import ellipack as pypw85


def test_module_attributes():
    assert isinstance(pypw85.lambda_atol, float) and pypw85.lambda_atol == 1e-6
    # The keys of pypw85's metadata, with ellipack's values.
    assert set(pypw85.metadata) == {
        "author", "author_email", "description", "license", "name", "url", "version", "year"
    }
    assert pypw85.metadata["name"] == "ellipack"
    assert pypw85.metadata["version"] == pypw85.__version__
    assert all(isinstance(v, str) for v in pypw85.metadata.values())


def test_spheroid_uses_n_as_given():
    """pypw85 computes Q = a² I + (c² − a²) n nᵀ without normalising n."""
    q = np.empty(6)
    pypw85.spheroid(1.0, 3.0, np.array([0.0, 0.0, 2.0]), q)
    assert q.tolist() == [1.0, 0.0, 0.0, 1.0, 0.0, 33.0]
    # Bit for bit pypw85's formula, in its order of operations, on nearly-unit directions.
    rng = np.random.default_rng(11)
    n = rng.normal(size=(200, 3))
    n /= np.linalg.norm(n, axis=1)[:, None]
    a, c = rng.uniform(0.01, 10.0, size=(2, 200))
    k = c * c - a * a
    a2 = a * a
    i, j = np.array([0, 0, 0, 1, 1, 2]), np.array([0, 1, 2, 1, 2, 2])
    expected = n[:, i] * n[:, j] * k[:, None] + np.where(i == j, a2[:, None], 0.0)
    assert np.array_equal(pypw85.spheroid(a, c, n), expected)
    # A direction that makes the form indefinite is refused, naming n.
    with pytest.raises(ValueError, match=r"^n = \[0.0, 0.0, 2.0\]: .* not positive definite"):
        pypw85.spheroid(2.0, 1.0, [0.0, 0.0, 2.0])
    with pytest.raises(ValueError, match="n, the axis of revolution, is zero"):
        pypw85.spheroid(2.0, 1.0, [0.0, 0.0, 0.0])


def spheroids_and_directions():
    """Spheroids of pypw85's tests: radii from needles and pancakes to spheres, a few
    directions of the unit sphere."""
    radii = [0.0199, 1.0, 9.999]
    rng = np.random.default_rng(5)
    directions = rng.normal(size=(4, 3))
    directions /= np.linalg.norm(directions, axis=1)[:, None]
    directions = np.vstack([directions, np.eye(3)[[2]]])
    forms = []
    for a in radii:
        for c in radii:
            for n in directions[:2]:
                q = np.empty(6)
                pypw85.spheroid(a, c, n, q)
                forms.append(q)
    return forms, directions


def full(q):
    return np.array([[q[0], q[1], q[2]], [q[1], q[3], q[4]], [q[2], q[4], q[5]]])


def test_contact_function_passes_pypw85s_stationarity_check():
    """The check of pypw85's test_contact_function: out = [μ², λ] with μ² on both scaled
    ellipsoids and |f′(λ)| <= lambda_atol |f″(λ)|."""
    forms, directions = spheroids_and_directions()
    out = np.empty(2)
    for distance in (0.15, 1.1, 11.0):
        for n in directions:
            r12 = distance * n
            for q1 in forms:
                for q2 in forms:
                    pypw85.contact_function(r12, q1, q2, out)
                    mu2, lam = out
                    Q1, Q2 = full(q1), full(q2)
                    Q = (1 - lam) * Q1 + lam * Q2
                    s = np.linalg.solve(Q, r12)
                    u = (Q2 - Q1) @ s
                    v = np.linalg.solve(Q, u)
                    rs, su, uv = r12 @ s, s @ u, u @ v
                    mu2_1 = (1 - lam) ** 2 * (rs - lam * su)
                    mu2_2 = lam**2 * (rs + (1 - lam) * su)
                    assert abs(mu2 - mu2_1) <= 1e-10 * mu2_1 + 1e-15
                    assert abs(mu2 - mu2_2) <= 1e-10 * mu2_2 + 1e-15
                    f1 = (1 - 2 * lam) * rs - lam * (1 - lam) * su
                    f2 = -2 * rs - 2 * (1 - 2 * lam) * su + 2 * lam * (1 - lam) * uv
                    assert abs(f1) <= pypw85.lambda_atol * abs(f2)
