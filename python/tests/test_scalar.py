"""The fast path of scalar calls (one pair, one shape: pypw85's calls): taken for the inputs
pypw85's users pass, left for anything it does not read as it is, and indistinguishable from
the vectorised path (``threads=1`` forces that path) in results, errors and ``out``. No
timings: the path taken is observed, not its speed."""

import numpy as np
import pytest

import ellipack
from ellipack import _ellipack

Q1 = ellipack.spheroid(1.0, 2.0, np.array([0.0, 0.6, 0.8]))
Q2 = ellipack.from_axes_quaternion(np.array([0.3, 1.0, 2.0]), np.array([1.0, 2.0, 3.0, 4.0]))
R12 = np.array([1.0, 0.5, 0.2])
UNIT = np.array([1.0, 0.2, 0.3, 0.4]) / np.sqrt(1.29)


def scalar_calls():
    """(name, call(threads)) for every vectorised function called on one row, with the kinds
    of argument pypw85's users write: float64 arrays, lists, tuples, Python and NumPy numbers,
    0-d arrays, strided views, ``out``."""
    strided = np.arange(12.0)[::4] / 10.0
    e = ellipack
    return [
        ("spheroid", lambda t: e.spheroid(1.0, 3.0, np.array([0.0, 0.0, 2.0]), threads=t)),
        ("spheroid out", lambda t: e.spheroid(1, np.float64(2.5), [0, 0.6, 0.8], np.empty(6),
                                              threads=t)),
        ("spheroid 0-d", lambda t: e.spheroid(np.array(0.5), 2, (1, 0, 0), threads=t)),
        ("contact_function", lambda t: e.contact_function(R12, Q1, Q2, threads=t)),
        ("contact_function out", lambda t: e.contact_function(R12, Q1, Q2, np.empty(2),
                                                              threads=t)),
        ("contact_function lists", lambda t: e.contact_function([3, 0, 0], list(Q1), tuple(Q2),
                                                                threads=t)),
        ("contact_function strided", lambda t: e.contact_function(strided, Q1, Q2, threads=t)),
        ("contact_function_2d", lambda t: e.contact_function_2d([1.0, 0.5], [1, 0, 1],
                                                                np.array([2.0, 0.1, 1.0]),
                                                                np.empty(2), threads=t)),
        ("overlap", lambda t: e.overlap(R12, Q1, Q2, threads=t)),
        ("overlap_2d", lambda t: e.overlap_2d([1.0, 0.5], [1, 0, 1], [2, 0.1, 1], threads=t)),
        ("contact_details", lambda t: e.contact_details(R12, Q1, Q2, threads=t)),
        ("contact_details_2d", lambda t: e.contact_details_2d([1.0, 0.5], [1, 0, 1],
                                                              [2, 0.1, 1], threads=t)),
        ("f_neg", lambda t: e.f_neg(0.3, R12, Q1, Q2, threads=t)),
        ("f_neg ends", lambda t: (e.f_neg(0, R12, Q1, Q2, threads=t),
                                  e.f_neg(np.float64(1.0), R12, Q1, Q2, threads=t))),
        ("from_axes_quaternion", lambda t: e.from_axes_quaternion([1, 2, 3], UNIT, threads=t)),
        ("from_axes_rotation", lambda t: e.from_axes_rotation([1.0, 2.0, 3.0],
                                                              np.eye(3)[[1, 0, 2]] * [1, 1, -1],
                                                              np.empty(6), threads=t)),
        ("from_axes_rotation lists", lambda t: e.from_axes_rotation(
            (1, 2, 3), [[0, 1, 0], [1, 0, 0], [0, 0, -1.0]], threads=t)),
        ("from_axes_angle_2d", lambda t: e.from_axes_angle_2d([1.0, 2.0], 0.3, threads=t)),
        ("overlap_measure", lambda t: e.overlap_measure(R12, [1, 2, 3], UNIT, -R12,
                                                        [1.0, 1, 1], [1, 0, 0, 0], threads=t)),
        ("overlap_measure 2d", lambda t: e.overlap_measure([0.5, 0.2], [1, 2], 0.3, [0, 0],
                                                           [1, 1], 0.1, threads=t)),
    ]


def same(a, b):
    """Equal values and types, arrays bit for bit (NaN equal to NaN), recursively."""
    if isinstance(a, np.ndarray):
        return (isinstance(b, np.ndarray) and a.dtype == b.dtype and a.shape == b.shape
                and np.array_equal(a, b, equal_nan=True))
    if isinstance(a, tuple):
        return (type(a) is type(b) and len(a) == len(b)
                and all(same(x, y) for x, y in zip(a, b)))
    return type(a) is type(b) and (a == b or (a != a and b != b))


@pytest.fixture
def vectorised_path_refused(monkeypatch):
    """Makes the vectorised path fail: a call that still works took the fast path."""

    def refuse(*args, **kwargs):
        raise AssertionError("the vectorised path was taken")

    for name in ("_evaluate", "_rows", "_f64"):
        monkeypatch.setattr(ellipack, name, refuse)


def test_scalar_calls_take_the_fast_path(vectorised_path_refused):
    for name, call in scalar_calls():
        call(None)  # raises AssertionError if the vectorised path is taken


@pytest.mark.parametrize("name, call", scalar_calls(), ids=[n for n, _ in scalar_calls()])
def test_fast_path_equals_vectorised_path(name, call):
    fast, vectorised = call(None), call(1)
    assert same(fast, vectorised), (name, fast, vectorised)


def test_out_is_filled_and_returned():
    out = np.full(6, np.nan)
    assert ellipack.spheroid(1.0, 3.0, [0.0, 0.0, 2.0], out) is out
    assert out.tolist() == [1.0, 0.0, 0.0, 1.0, 0.0, 33.0]
    out = np.full(2, np.nan)
    sphere = np.array([1.0, 0, 0, 1, 0, 1])
    assert ellipack.contact_function([3.0, 0, 0], [1, 0, 0, 1, 0, 1], sphere, out) == (2.25, 0.5)
    assert out.tolist() == [2.25, 0.5]
    # A fresh array per call without out.
    a, b = ellipack.spheroid(1.0, 2.0, [0, 0, 1.0]), ellipack.spheroid(1.0, 2.0, [0, 0, 1.0])
    assert a is not b and not np.shares_memory(a, b) and a.flags.writeable


def test_what_the_fast_path_leaves_to_the_vectorised_path():
    """None from `_one`: the Python wrapper then converts or refuses the value as before."""
    q = [1.0, 0, 0, 1, 0, 1]
    left = [
        np.ones(3, dtype=np.float32),        # another dtype: converted by the vectorised path
        np.ones(3, dtype=np.int64),
        np.ones(3).astype(">f8"),            # non-native byte order
        np.ones((1, 3)),                     # a batch of one row
        [True, False, True],                 # bools: refused (TypeError)
        [1.0, True, 0.0],                    # converted by NumPy, not read here
        [2**70, 0, 0],                       # beyond int64: NumPy's object dtype, refused
        [1 + 0j, 0, 0],
        [np.float32(1), 0, 0],
        "abc",
        [1.0, 2.0],                          # a wrong shape: refused naming r12
        np.ma.masked_array(np.ones(3)),      # an ndarray subclass
    ]
    for r12 in left:
        assert _ellipack._one("contact3", None, r12, q, q) is None, r12
    assert _ellipack._one("contact3", None, [3, 0, 0], q, q) == (2.25, 0.5)
    assert _ellipack._one("spheroid", None, np.array([1.0]), 2.0, [0, 0, 1.0]) is None  # batch
    # An out the fast path does not fill: not writeable, strided, wrong shape or dtype, shared
    # with an input.
    read_only = np.empty(2)
    read_only.flags.writeable = False
    buffer = np.zeros(12)
    buffer[:6] = q
    for out in (read_only, np.empty(4)[::2], np.empty(3), np.empty(2, np.float32), [0.0, 0.0],
                buffer[5:7]):
        assert _ellipack._one("contact3", out, [3.0, 0, 0], buffer[:6], q) is None
    assert _ellipack._one("contact3", buffer[6:8], [3.0, 0, 0], buffer[:6], q) == (2.25, 0.5)
    assert _ellipack._one("overlap3", np.empty((), bool), [3.0, 0, 0], q, q) is None


def test_refusals_are_those_of_the_vectorised_path():
    """Every bad input raises the same error, with the same message, on both paths."""
    q = [1.0, 0, 0, 1, 0, 1]
    buffer = np.zeros(9)
    buffer[2] = 1.0
    e = ellipack
    bad = [
        lambda t: e.contact_function([np.nan, 0, 0], q, q, threads=t),
        lambda t: e.contact_function([1.0, 0, 0], [1.0, 2, 0, 1, 0, 1], q, threads=t),
        lambda t: e.contact_function([1.0, 0], q, q, threads=t),
        lambda t: e.contact_function([True, False, True], q, q, threads=t),
        lambda t: e.contact_function([2**70, 0, 0], q, q, threads=t),
        lambda t: e.contact_function([1.0, 0, 0], q, q, np.empty(3), threads=t),
        lambda t: e.contact_function([1.0, 0, 0], q, q, np.empty(2, np.float32), threads=t),
        lambda t: e.overlap_2d([1.0, 0], [1.0, 0, -1], [1, 0, 1], threads=t),
        lambda t: e.contact_details([0.0, 0, 0], [0.0] * 6, q, threads=t),
        lambda t: e.f_neg(1.5, [1.0, 0, 0], q, q, threads=t),
        lambda t: e.f_neg(np.nan, [1.0, 0, 0], q, q, threads=t),
        lambda t: e.spheroid(1e200, 1.0, [0, 0, 1.0], threads=t),
        lambda t: e.spheroid(-1, 1.0, [0, 0, 1.0], threads=t),
        lambda t: e.spheroid(2.0, 1.0, [0, 0, 2.0], threads=t),
        lambda t: e.spheroid(1.0, 2.0, [0, 0, 0], threads=t),
        lambda t: e.spheroid(1.0, 2.0, [0, 0, 1e300], threads=t),
        lambda t: e.spheroid(1.0, 2.0, buffer[:3], buffer[2:8], threads=t),
        lambda t: e.spheroid("1", 2.0, [0, 0, 1.0], threads=t),
        lambda t: e.from_axes_quaternion([1.0, 2, 3], [0, 0, 0, 0], threads=t),
        lambda t: e.from_axes_quaternion([1e-200, 2, 3], UNIT, threads=t),
        lambda t: e.from_axes_rotation([1.0, 2, 3], 2 * np.eye(3), threads=t),
        lambda t: e.from_axes_rotation([1.0, 2, 3], np.eye(3)[:2], threads=t),
        lambda t: e.from_axes_angle_2d([1.0, -2], 0.3, threads=t),
        lambda t: e.from_axes_angle_2d([1.0, 2], np.inf, threads=t),
        lambda t: e.overlap_measure(R12, [1, 2, 3], [1, 2, 3, 4], -R12, [1, 1, 1], UNIT,
                                    threads=t),
        lambda t: e.overlap_measure([0.5, 0.2], [1, 2], np.nan, [0, 0], [1, 1], 0.1, threads=t),
    ]
    for k, call in enumerate(bad):
        errors = []
        for threads in (None, 1):
            with pytest.raises((ValueError, TypeError)) as info:
                call(threads)
            errors.append((type(info.value), str(info.value)))
        assert errors[0] == errors[1], (k, errors)
