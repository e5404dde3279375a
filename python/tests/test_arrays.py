"""Shapes, broadcasting, dtypes, out=, threads and bad input of the vectorised functions."""

import numpy as np
import pytest

import ellipack


def random_forms(rng, n):
    axes = rng.uniform(0.2, 3.0, size=(n, 3))
    q = rng.normal(size=(n, 4))
    return ellipack.from_axes_quaternion(axes, q)


@pytest.fixture
def pairs():
    rng = np.random.default_rng(7)
    n = 1000
    return rng.normal(scale=3.0, size=(n, 3)), random_forms(rng, n), random_forms(rng, n)


def test_batch_equals_one_pair_at_a_time(pairs):
    r12, q1, q2 = pairs
    mu2, lam = ellipack.contact_function(r12, q1, q2)
    assert mu2.shape == lam.shape == (1000,)
    for i in range(0, 1000, 97):
        assert ellipack.contact_function(r12[i], q1[i], q2[i]) == (mu2[i], lam[i])


def test_one_ellipsoid_broadcast_against_many(pairs):
    r12, q1, q2 = pairs
    mu2, lam = ellipack.contact_function(r12, q1[0], q2)
    full = ellipack.contact_function(r12, np.tile(q1[0], (1000, 1)), q2)
    assert np.array_equal(mu2, full[0]) and np.array_equal(lam, full[1])
    mu2_r, _ = ellipack.contact_function(r12[3], q1, q2)
    assert np.array_equal(mu2_r, ellipack.contact_function(np.tile(r12[3], (1000, 1)), q1, q2)[0])


def test_one_row_batches_broadcast_and_empty_batches(pairs):
    r12, q1, q2 = pairs
    mu2, _ = ellipack.contact_function(r12, q1[:1], q2)
    assert np.array_equal(mu2, ellipack.contact_function(r12, q1[0], q2)[0])
    mu2, lam = ellipack.contact_function(r12[:1], q1[:1], q2[:1])
    assert mu2.shape == (1,) and mu2[0] == ellipack.contact_function(r12[0], q1[0], q2[0])[0]
    mu2, lam = ellipack.contact_function(np.empty((0, 3)), q1[0], q2[0])
    assert mu2.shape == lam.shape == (0,)
    assert ellipack.overlap(np.empty((0, 3)), q1[0], q2[0]).shape == (0,)


def test_non_contiguous_and_integer_inputs(pairs):
    r12, q1, q2 = pairs
    expected = ellipack.contact_function(r12, q1, q2)
    # Every other column of a wider array, and a Fortran-ordered copy.
    wide = np.zeros((1000, 6))
    wide[:, ::2] = r12
    strided = wide[:, ::2]
    assert not strided.flags.c_contiguous
    got = ellipack.contact_function(strided, np.asfortranarray(q1), q2)
    assert np.array_equal(got[0], expected[0]) and np.array_equal(got[1], expected[1])
    # Integers and lists are converted to float64.
    q = [1, 0, 0, 1, 0, 1]
    assert ellipack.contact_function([3, 0, 0], q, q) == (2.25, 0.5)
    assert ellipack.contact_function(np.array([3, 0, 0], dtype=np.int32), q, q) == (2.25, 0.5)


def test_out_is_filled_as_pypw85_does():
    q = ellipack.spheroid(1.0, 1.0, [0.0, 0.0, 1.0])
    out = np.empty(2)
    ellipack.contact_function(np.array([3.0, 0.0, 0.0]), q, q, out)
    assert out.tolist() == [2.25, 0.5]
    outs = np.empty((4, 2))
    r = np.array([[3.0, 0, 0], [0, 4.0, 0], [0, 0, 1.0], [0.5, 0, 0]])
    mu2, lam = ellipack.contact_function(r, q, q, out=outs)
    assert np.shares_memory(mu2, outs)
    assert outs[:, 0].tolist() == [2.25, 4.0, 0.25, 0.0625]
    with pytest.raises(ValueError, match="shape"):
        ellipack.contact_function(r, q, q, out=np.empty((4, 3)))
    with pytest.raises(TypeError, match="dtype"):
        ellipack.contact_function(r, q, q, out=np.empty((4, 2), dtype=np.float32))
    with pytest.raises(ValueError, match="C-contiguous"):
        ellipack.contact_function(r, q, q, out=np.empty((2, 4)).T)
    verdicts = np.empty(4, dtype=bool)
    ellipack.overlap(r, q, q, out=verdicts)
    assert verdicts.tolist() == [False, False, True, True]


def test_threads_give_the_same_bits(pairs):
    r12, q1, q2 = pairs
    one = ellipack.contact_function(r12, q1, q2)
    for threads in (0, 2, 3):
        many = ellipack.contact_function(r12, q1, q2, threads=threads)
        assert np.array_equal(one[0], many[0]) and np.array_equal(one[1], many[1])
    assert np.array_equal(ellipack.overlap(r12, q1, q2), ellipack.overlap(r12, q1, q2, threads=0))
    with pytest.raises(ValueError, match="threads"):
        ellipack.contact_function(r12, q1, q2, threads=-1)
    with pytest.raises(ValueError, match="threads"):
        ellipack.contact_function(r12, q1, q2, threads=100_000)
    with pytest.raises(TypeError, match="threads"):
        ellipack.contact_function(r12, q1, q2, threads=1.5)


def test_verdict_agrees_with_mu2(pairs):
    r12, q1, q2 = pairs
    mu2, _ = ellipack.contact_function(r12, q1, q2)
    verdict = ellipack.overlap(r12, q1, q2)
    assert verdict.dtype == np.bool_
    clear = np.abs(mu2 - 1.0) > 1e-12
    assert np.array_equal(verdict[clear], (mu2 < 1.0)[clear])
    assert 100 < verdict.sum() < 900
    assert ellipack.overlap(r12[0], q1[0], q2[0]) in (True, False)


def test_wrong_shapes_and_dtypes():
    q = [1.0, 0, 0, 1, 0, 1]
    with pytest.raises(ValueError, match=r"r12: expected shape \(3,\) or \(n, 3\), got shape \(2,\)"):
        ellipack.contact_function([1.0, 0], q, q)
    with pytest.raises(ValueError, match=r"q1: expected shape \(6,\)"):
        ellipack.contact_function([1.0, 0, 0], np.eye(3), q)
    with pytest.raises(ValueError, match="q2 has 4 rows but r12 has 5"):
        ellipack.contact_function(np.ones((5, 3)), q, np.tile(q, (4, 1)))
    with pytest.raises(ValueError, match="cj has 3 rows but ci has 2"):
        ellipack.overlap_measure(np.zeros((2, 2)), [1.0, 1], 0.0, np.ones((3, 2)), [1.0, 1], 0.0)
    with pytest.raises(TypeError, match="complex"):
        ellipack.contact_function(np.ones(3, dtype=complex), q, q)
    with pytest.raises(TypeError, match="dtype"):
        ellipack.contact_function(["a", "b", "c"], q, q)
    with pytest.raises(TypeError, match="dtype"):
        ellipack.contact_function(np.ones(3, dtype=bool), q, q)


def test_bad_values_name_the_row():
    q = np.tile([1.0, 0, 0, 1, 0, 1], (5, 1))
    r = np.ones((5, 3))
    bad = q.copy()
    bad[3, 0] = np.nan
    with pytest.raises(ValueError, match=r"row 3: Q1\[0\] is not finite"):
        ellipack.contact_function(r, bad, q)
    not_pd = q.copy()
    not_pd[2] = [1.0, 2.0, 0, 1.0, 0, 1.0]
    with pytest.raises(ValueError, match="row 2: Q2 is not positive definite"):
        ellipack.contact_function(r, q, not_pd)
    with pytest.raises(ValueError, match="row 2: Q2 is not positive definite"):
        ellipack.overlap(r, q, not_pd, threads=2)
    r_bad = r.copy()
    r_bad[4, 1] = np.inf
    with pytest.raises(ValueError, match=r"row 4: r12\[1\] is not finite"):
        ellipack.contact_function(r_bad, q, q)
    # One pair: no row to name.
    with pytest.raises(ValueError, match=r"^Q1 is not positive definite"):
        ellipack.contact_function([1.0, 0, 0], [1.0, 0, 0, -1.0, 0, 1.0], q[0])
    # The lowest failing row is named, also on several threads.
    many = np.tile([1.0, 0, 0, 1, 0, 1], (5000, 1))
    many[[1234, 4321]] = np.nan
    with pytest.raises(ValueError, match="row 1234:"):
        ellipack.contact_function(np.ones((5000, 3)), many, many[0], threads=0)


def random_ellipse_pairs(seed, n):
    """r12, q1, q2 of n random pairs of ellipses (semi-axes 0.3 to 2, any angle)."""
    rng = np.random.default_rng(seed)
    axes_1, axes_2 = rng.uniform(0.3, 2.0, size=(2, n, 2))
    th_1, th_2 = rng.uniform(-np.pi, np.pi, size=(2, n))
    q1 = ellipack.from_axes_angle_2d(axes_1, th_1)
    q2 = ellipack.from_axes_angle_2d(axes_2, th_2)
    return rng.normal(scale=2.0, size=(n, 2)), q1, q2


def test_two_dimensions_match_ellipsoids_in_the_plane():
    n = 200
    r, q1, q2 = random_ellipse_pairs(3, n)
    mu2, lam = ellipack.contact_function_2d(r, q1, q2)

    # The same ellipses as ellipsoids with a third axis along z: f(λ) is the same.
    def lift(q, c):
        return np.column_stack([q[:, 0], q[:, 1], np.zeros(n), q[:, 2], np.zeros(n), np.full(n, c)])

    r3 = np.column_stack([r, np.zeros(n)])
    mu2_3, _ = ellipack.contact_function(r3, lift(q1, 1.0), lift(q2, 2.0))
    assert np.allclose(mu2, mu2_3, rtol=1e-12, atol=0)
    assert np.array_equal(ellipack.overlap_2d(r, q1, q2)[np.abs(mu2 - 1) > 1e-12],
                          (mu2 < 1)[np.abs(mu2 - 1) > 1e-12])
    # θ rotates the first semi-axis from x towards y.
    assert np.allclose(ellipack.from_axes_angle_2d([2.0, 1.0], np.pi / 2), [1.0, 0.0, 4.0])


def test_ellipse_details_are_checked_independently():
    n = 100
    r, q1, q2 = random_ellipse_pairs(5, n)
    d = ellipack.contact_details_2d(r, q1, q2)
    assert d.point.shape == (n, 2) and d.grad_q1.shape == (n, 3)
    assert np.array_equal(d.mu2, ellipack.contact_function_2d(r, q1, q2)[0])
    assert np.allclose(np.linalg.norm(d.normal, axis=1), 1.0)

    def inverse(q):
        a, b, c = q[:, 0], q[:, 1], q[:, 2]
        det = a * c - b * b
        return np.stack([np.stack([c, -b], -1), np.stack([-b, a], -1)], -2) / det[:, None, None]

    # The point is on both ellipses scaled by mu: (x - ci)^T Qi^-1 (x - ci) = mu^2.
    x1, x2 = d.point, d.point - r
    on_1 = np.einsum("ni,nij,nj->n", x1, inverse(q1), x1)
    on_2 = np.einsum("ni,nij,nj->n", x2, inverse(q2), x2)
    assert np.allclose(on_1, d.mu2, rtol=1e-10) and np.allclose(on_2, d.mu2, rtol=1e-10)
    # The normal is the gradient direction of the first scaled ellipse at the point.
    g = np.einsum("nij,nj->ni", inverse(q1), x1)
    assert np.allclose(g / np.linalg.norm(g, axis=1)[:, None], d.normal, atol=1e-10)
    # The gradients against central differences of the ellipses' own contact function.
    h = 1e-6
    i = 7
    for k in range(2):
        e = np.zeros(2)
        e[k] = h
        plus = ellipack.contact_function_2d(r[i] + e, q1[i], q2[i])[0]
        minus = ellipack.contact_function_2d(r[i] - e, q1[i], q2[i])[0]
        assert (plus - minus) / (2 * h) == pytest.approx(d.grad_r12[i, k], rel=1e-6)
    for k in range(3):
        e = np.zeros(3)
        e[k] = h
        plus = ellipack.contact_function_2d(r[i], q1[i] + e, q2[i])[0]
        minus = ellipack.contact_function_2d(r[i], q1[i] - e, q2[i])[0]
        # An off-diagonal stored entry stands for Q12 and Q21: the difference moves both.
        assert (plus - minus) / (2 * h) == pytest.approx(d.grad_q1[i, k], rel=1e-5, abs=1e-9)
    with pytest.raises(ValueError, match="Q1 is not positive definite"):
        ellipack.contact_details_2d([1.0, 0.0], [1.0, 0.0, -1.0], [1.0, 0.0, 1.0])


def test_shape_constructors_agree():
    axes = np.array([1.0, 2.0, 3.0])
    # The quaternion of a rotation by 90° about z: x → y.
    qz = np.array([np.cos(np.pi / 4), 0, 0, np.sin(np.pi / 4)])
    rot = np.array([[0.0, -1, 0], [1, 0, 0], [0, 0, 1]])
    a = ellipack.from_axes_quaternion(axes, qz)
    b = ellipack.from_axes_rotation(axes, rot)
    assert np.allclose(a, b, atol=1e-15)
    assert np.allclose(a, [4.0, 0, 0, 1.0, 0, 9.0], atol=1e-14)
    # A spheroid of revolution about x against the same from semi-axes (n is used as given,
    # as pypw85 does: test_pypw85.py).
    s = ellipack.spheroid(1.0, 3.0, [1.0, 0, 0])
    assert np.allclose(s, ellipack.from_axes_quaternion([3.0, 1.0, 1.0], [1, 0, 0, 0]))
    # Vectorised: rows of rotations.
    many = ellipack.from_axes_rotation(np.tile(axes, (3, 1)), np.stack([rot] * 3))
    assert many.shape == (3, 6) and np.allclose(many, b)
    with pytest.raises(ValueError, match="row 1: semi-axis 1 must be a positive"):
        ellipack.spheroid([1.0, 1.0], [2.0, -1.0], [0, 0, 1])
    with pytest.raises(ValueError, match="invalid rotation"):
        ellipack.from_axes_rotation(axes, 2 * np.eye(3))
    with pytest.raises(ValueError, match="invalid rotation"):
        ellipack.from_axes_quaternion(axes, [0, 0, 0, 0])
    with pytest.raises(ValueError, match=r"rotation: expected shape \(3, 3\)"):
        ellipack.from_axes_rotation(axes, np.eye(4))


def numpy_f(lam, r, q1, q2):
    """f(λ) = λ(1 − λ) rᵀ Q(λ)⁻¹ r with NumPy's solver, from the full matrices."""
    def full(q):
        return np.array([[q[0], q[1], q[2]], [q[1], q[3], q[4]], [q[2], q[4], q[5]]])
    Q = (1 - lam) * full(q1) + lam * full(q2)
    return lam * (1 - lam) * r @ np.linalg.solve(Q, r)


def test_f_neg_and_the_details(pairs):
    r12, q1, q2 = pairs
    i = 11
    mu2, lam = ellipack.contact_function(r12[i], q1[i], q2[i])
    assert ellipack.f_neg(lam, r12[i], q1[i], q2[i]) == pytest.approx(-mu2, rel=1e-14)
    grid = np.linspace(0, 1, 101)
    values = ellipack.f_neg(grid, r12[i], q1[i], q2[i])
    assert values.shape == (101,) and values.min() >= -mu2 * (1 + 1e-14)
    for g, v in zip(grid[1:-1:10], values[1:-1:10]):
        assert v == pytest.approx(-numpy_f(g, r12[i], q1[i], q2[i]), rel=1e-12)
    with pytest.raises(ValueError, match=r"lambda must lie in \[0, 1\]"):
        ellipack.f_neg(1.5, r12[i], q1[i], q2[i])

    d = ellipack.contact_details(r12, q1, q2)
    assert d.point.shape == (1000, 3) and d.grad_q2.shape == (1000, 6)
    assert np.allclose(np.linalg.norm(d.normal, axis=1), 1.0)
    assert np.array_equal(d.mu2, ellipack.contact_function(r12, q1, q2)[0])
    # ∂μ²/∂r12 against a central difference.
    h = 1e-6
    e = np.array([h, 0.0, 0.0])
    plus = ellipack.contact_function(r12[i] + e, q1[i], q2[i])[0]
    minus = ellipack.contact_function(r12[i] - e, q1[i], q2[i])[0]
    assert (plus - minus) / (2 * h) == pytest.approx(d.grad_r12[i, 0], rel=1e-6)
    one = ellipack.contact_details(r12[i], q1[i], q2[i])
    assert one.mu2 == d.mu2[i] and np.array_equal(one.point, d.point[i])


def test_measure_broadcasting_and_errors():
    ci, ai, qi = [0.0, 0, 0], [1.0, 1, 1], [1.0, 0, 0, 0]
    cj = np.array([[3.0, 0, 0], [1.5, 0, 0], [0, 0, 0.5]])
    m = ellipack.overlap_measure(ci, ai, qi, cj, ai, qi)
    assert m.f.shape == (3,) and m.x.shape == (3, 3)
    assert m.f[0] == 0.0 and m.f[1] > 0.0 and m.f[2] > 0.0
    assert m.d2[0] == pytest.approx(4.0, rel=1e-14)
    one = ellipack.overlap_measure(ci, ai, qi, cj[1], ai, qi)
    assert one.f == m.f[1] and one.u == m.u[1]
    # Coincident centres: X is not unique (NaN).
    assert np.all(np.isnan(ellipack.overlap_measure(ci, ai, qi, ci, ai, qi).x))
    two = ellipack.overlap_measure([0.0, 0], [2.0, 1], 0.0, [[5.0, 0], [0, 1.5]], [1.0, 1], [0.0, 1.0])
    assert two.f[0] == 0.0 and two.f[1] > 0.0
    with pytest.raises(ValueError, match="row 1: ellipsoid j:"):
        ellipack.overlap_measure(ci, ai, qi, cj, [[1.0, 1, 1], [1, -1, 1], [1, 1, 1]], qi)
    with pytest.raises(ValueError, match="aj has 2 rows but cj has 3"):
        ellipack.overlap_measure(ci, ai, qi, cj, np.ones((2, 3)), qi)


def test_shape_constructors_refuse_what_float64_cannot_hold():
    """A semi-axis whose square overflows (or underflows) float64 raises, naming the argument,
    instead of returning inf or NaN."""
    q = [1.0, 0, 0, 0]
    with pytest.raises(ValueError, match=r"^a = 1e200 is too large: its square overflows"):
        ellipack.spheroid(1e200, 1.0, [0.0, 0, 1])
    with pytest.raises(ValueError, match=r"^c = 1e-200 is too small: its square underflows"):
        ellipack.spheroid(1.0, 1e-200, [0.0, 0, 1])
    with pytest.raises(ValueError, match=r"^n = \[1e200, 0.0, 0.0\] is too long"):
        ellipack.spheroid(1.0, 2.0, [1e200, 0, 0])
    with pytest.raises(ValueError, match=r"^axes\[0\] = 1e200 is too large"):
        ellipack.from_axes_quaternion([1e200, 2, 3], q)
    with pytest.raises(ValueError, match=r"^axes\[2\] = 1e-160 is too small"):
        ellipack.from_axes_rotation([1.0, 2, 1e-160], np.eye(3))
    with pytest.raises(ValueError, match=r"^axes\[1\] = 1e200 is too large"):
        ellipack.from_axes_angle_2d([2.0, 1e200], 0.3)
    # In a batch, the row is named; the rows before are unaffected.
    axes = np.tile([1.0, 2.0, 3.0], (4, 1))
    axes[2, 1] = 1e155
    with pytest.raises(ValueError, match=r"^row 2: axes\[1\] = 1e155 is too large"):
        ellipack.from_axes_quaternion(axes, q)
    with pytest.raises(ValueError, match=r"^row 1: a = 1e300"):
        ellipack.spheroid([1.0, 1e300], 2.0, [0.0, 0, 1])
    # The largest and smallest semi-axes that fit still give finite, positive forms.
    for l in (1.3e154, 1.5e-154):
        form = ellipack.from_axes_quaternion([l, l, l], [1.0, 1, 1, 1])
        assert np.all(np.isfinite(form)) and form[0] > 0 and form[3] > 0 and form[5] > 0
        assert np.all(np.isfinite(ellipack.from_axes_angle_2d([l, l], 0.7)))
        assert np.all(np.isfinite(ellipack.spheroid(l, l, [0.6, 0, 0.8])))


def test_unaligned_arrays_are_read_and_an_unaligned_out_is_named():
    def unaligned(values):
        """A C-contiguous float64 view that starts one byte into its buffer."""
        values = np.asarray(values, dtype=np.float64)
        raw = np.zeros(values.size * 8 + 1, dtype=np.uint8)[1:]
        a = raw.view(np.float64).reshape(values.shape)
        a[...] = values
        assert a.flags.c_contiguous and not a.flags.aligned
        return a

    rng = np.random.default_rng(3)
    r12 = rng.normal(size=(50, 3))
    q1 = random_forms(rng, 50)
    q2 = random_forms(rng, 50)
    expected = ellipack.contact_function(r12, q1, q2)
    got = ellipack.contact_function(unaligned(r12), unaligned(q1), q2)
    assert np.array_equal(got[0], expected[0]) and np.array_equal(got[1], expected[1])
    assert ellipack.contact_function(unaligned([3.0, 0, 0]), q1[0], q1[0])[0] == pytest.approx(
        ellipack.contact_function([3.0, 0, 0], q1[0], q1[0])[0], rel=0
    )
    with pytest.raises(ValueError, match=r"^out is not aligned.*np\.empty"):
        ellipack.contact_function(r12, q1, q2, out=unaligned(np.zeros((50, 2))))


def test_out_must_not_be_an_input():
    r = np.array([[3.0, 0.0], [0.0, 5.0]])
    q = [1.0, 0.0, 1.0]
    with pytest.raises(ValueError, match="out must not be one of the inputs: it shares memory "
                                         "with r12"):
        ellipack.contact_function_2d(r, q, q, out=r)
    # A view of an input counts too, and the input is left as it was.
    rows = np.tile([1.0, 0.0, 1.0], (2, 1))
    with pytest.raises(ValueError, match="shares memory with q2"):
        ellipack.contact_function_2d(r, q, rows, out=rows.reshape(-1)[:4].reshape(2, 2))
    assert rows.tolist() == [[1.0, 0.0, 1.0]] * 2
    axes = np.array([[2.0, 1.0, 0.0]])
    with pytest.raises(ValueError, match="shares memory with axes"):
        ellipack.from_axes_angle_2d(axes[:, :2], 0.0, out=axes)
    # A separate out is filled.
    out = np.empty((2, 2))
    ellipack.contact_function_2d(r, q, q, out=out)
    assert out[:, 0].tolist() == [2.25, 6.25]
