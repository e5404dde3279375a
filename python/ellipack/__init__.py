"""ellipack from Python: the PW85 contact function, the implicit-variable overlap measure and
the certified ellipse/ellipsoid packer, over NumPy arrays.

Conventions
-----------
An ellipsoid with centre c is {x : (x - c)^T Q^-1 (x - c) <= 1}. Its quadratic form Q is stored
as its upper triangle row by row: ``[Q11, Q12, Q13, Q22, Q23, Q33]`` (shape ``(6,)``), an
ellipse's as ``[Q11, Q12, Q22]`` (shape ``(3,)``). Semi-axis k lies along column k of the
rotation, Q = R diag(a^2, b^2, c^2) R^T. Quaternions are (w, x, y, z), Hamilton active rotations.

Vectorised functions take one row (``(3,)``, ``(6,)``) or n rows (``(n, 3)``, ``(n, 6)``) per
argument; a single row (``(3,)`` or ``(1, 3)``) is broadcast against the n rows of the others. Inputs are converted to
float64 (integers too) and copied when not C-contiguous or not aligned. ``threads=1`` (the
default) computes on the calling thread, ``threads=0`` on every core, ``threads=k`` on k
threads; the GIL is released during the computation. Bad input raises ValueError naming the
row; wrong shapes raise ValueError, non-numeric dtypes TypeError. ``out`` must not share memory
with an input.

For code written for pypw85 (``import ellipack as pypw85``): ``spheroid``, ``contact_function``
and ``f_neg`` take pypw85's arguments, and :data:`lambda_atol` and :data:`metadata` are there.
"""

from __future__ import annotations

import errno
import json
import os
from typing import Any, Callable, NamedTuple, Optional, Tuple, Union

import numpy as np
import numpy.typing as npt

from . import _ellipack
from ._ellipack import NotReached, Packing, read_packing, verify

__version__ = _ellipack.__version__

lambda_atol: float = 1e-6
"""pypw85's ``lambda_atol``: the absolute tolerance on lambda of :func:`contact_function`, so
that code written for pypw85 (its tests check |f'(lambda)| <= lambda_atol |f''(lambda)|) runs
unchanged. pypw85 stops its Brent iterations at this tolerance; ellipack has no tolerance
parameter: its lambda is the maximiser to about rounding error, well within ``lambda_atol``."""

metadata: dict = {
    "author": "The ellipack developers",
    "author_email": "",
    "description": (
        "The Perram-Wertheim contact function of ellipsoids and ellipses, the implicit-variable "
        "overlap measure of Birgin, Lobato and Martinez, and a certified ellipse/ellipsoid "
        "packer, over NumPy arrays"
    ),
    "license": "MIT OR Apache-2.0",
    "name": "ellipack",
    "url": "https://github.com/ellipack/ellipack",
    "version": __version__,
    "year": "2026",
}
"""Metadata about the library, with the keys of pypw85's ``metadata`` (author, author_email,
description, license, name, url, version, year); the values are ellipack's."""

__all__ = [
    "contact_function",
    "contact_function_2d",
    "overlap",
    "overlap_2d",
    "contact_details",
    "ContactDetails",
    "contact_details_2d",
    "f_neg",
    "spheroid",
    "from_axes_quaternion",
    "from_axes_rotation",
    "from_axes_angle_2d",
    "overlap_measure",
    "OverlapMeasure",
    "pack",
    "Packing",
    "NotReached",
    "packing_from_arrays",
    "read_packing",
    "verify",
    "analyse",
    "lambda_atol",
    "metadata",
]


def _real(name: str, x: Any) -> np.ndarray:
    """`x` as an array (no copy of an array), refused unless its dtype is a real number type."""
    a = np.asarray(x)
    if a.dtype.kind not in "fiu":
        raise TypeError(
            f"{name}: expected real numbers (converted to float64), got an array of dtype "
            f"{a.dtype}"
        )
    return a


def _f64(name: str, x: Any) -> np.ndarray:
    """`x` as an aligned C-contiguous float64 array; integers are converted, other dtypes
    refused."""
    a = _real(name, x)
    if a.dtype != np.float64:
        a = a.astype(np.float64)
    # Not np.ascontiguousarray: it turns a 0-d array into shape (1,). An unaligned array (a view
    # at an odd byte offset, a packed record field) is copied too: the kernels read aligned rows.
    return a if a.flags.c_contiguous and a.flags.aligned else a.copy(order="C")


def _rows(name: str, x: Any, width: int) -> Tuple[np.ndarray, Optional[int]]:
    """`x` as a (rows, width) matrix, and its row count when it is a batch (None: one row)."""
    a = _f64(name, x)
    if width == 1:
        if a.ndim == 0:
            return a.reshape(1, 1), None
        if a.ndim == 1:
            return a.reshape(-1, 1), a.shape[0]
        raise ValueError(f"{name}: expected a number or shape (n,), got shape {a.shape}")
    if a.ndim == 1 and a.shape[0] == width:
        return a.reshape(1, width), None
    if a.ndim == 2 and a.shape[1] == width:
        return a, a.shape[0]
    raise ValueError(f"{name}: expected shape ({width},) or (n, {width}), got shape {a.shape}")


# The fast path of one pair or one shape (pypw85's scalar calls): `_one(kind, out, *args)` reads
# numbers, float64 arrays of the row's shape and lists of numbers as they are, evaluates the row
# as `_evaluate` would, and returns None for anything else (other dtypes, batches, a wrong
# shape, an `out` it does not fill), which then takes the vectorised path: its conversions,
# checks and errors.
_one = _ellipack._one

# More threads than this is a mistake, not a wish: each count keeps its own pool alive.
_MAX_THREADS = 1024


def _count(name: str, value: Any, largest: int) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise TypeError(f"{name} must be an integer, not {type(value).__name__}")
    if not 0 <= value <= largest:
        raise ValueError(f"{name} must lie in [0, {largest}], not {value}")
    return int(value)


def _threads(threads: Optional[int]) -> int:
    return 1 if threads is None else _count("threads", threads, _MAX_THREADS)


def _evaluate(
    kind: str,
    args: list,
    out_width: int,
    out: Optional[np.ndarray],
    threads: Optional[int],
) -> np.ndarray:
    """Runs the row kernel `kind` on `args` ((name, value, width) triples) and returns the
    output, shape (n, out_width) for a batch and (out_width,) for one row."""
    matrices = []
    counted = []
    for name, value, width in args:
        m, rows = _rows(name, value, width)
        matrices.append(m)
        if rows is not None:
            counted.append((name, rows))
    n = _common_rows(counted)
    shape = (out_width,) if n is None else (n, out_width)
    if out is None:
        result = np.empty(shape)
    else:
        result = _check_out(out, shape)
        for name, value, _ in args:
            if isinstance(value, np.ndarray) and np.may_share_memory(value, result):
                raise ValueError(
                    f"out must not be one of the inputs: it shares memory with {name} (pass "
                    "a new array, e.g. np.empty_like(out), or none)"
                )
    _ellipack._rows(
        kind,
        matrices,
        result.reshape(1 if n is None else n, out_width),
        _threads(threads),
        n is not None,
    )
    return result


def _common_rows(counted: list) -> Optional[int]:
    """The row count of a call from the (name, rows) of its batch arguments: as in NumPy, an
    argument of one row is broadcast against the others; None when no argument is a batch."""
    if not counted:
        return None
    many = [(name, rows) for name, rows in counted if rows != 1]
    for name, rows in many[1:]:
        if rows != many[0][1]:
            raise ValueError(f"{name} has {rows} rows but {many[0][0]} has {many[0][1]}")
    return many[0][1] if many else 1


def _check_out(out: Any, shape: tuple, dtype: Any = np.float64) -> np.ndarray:
    if not isinstance(out, np.ndarray):
        raise TypeError(f"out must be a NumPy array, not {type(out).__name__}")
    if out.dtype != dtype:
        raise TypeError(f"out must have dtype {np.dtype(dtype)}, not {out.dtype}")
    if out.shape != shape:
        raise ValueError(f"out must have shape {shape}, not {out.shape}")
    if not out.flags.c_contiguous or not out.flags.writeable:
        raise ValueError("out must be C-contiguous and writeable")
    if not out.flags.aligned:
        raise ValueError(
            "out is not aligned (its values do not start at a multiple of their size in bytes): "
            "the results are written into out itself, so allocate it with np.empty"
        )
    return out


def _pair_args(r12: Any, q1: Any, q2: Any, dim: int) -> list:
    """The (name, value, width) triples of a pair of ellipsoids (dim 3) or ellipses (dim 2)."""
    forms = 6 if dim == 3 else 3
    return [("r12", r12, dim), ("q1", q1, forms), ("q2", q2, forms)]


def _pair(
    kind: str, r12: Any, q1: Any, q2: Any, dim: int, out: Any, threads: Optional[int]
) -> tuple:
    if threads is None:
        one = _one(kind, out, r12, q1, q2)
        if one is not None:
            return one
    result = _evaluate(kind, _pair_args(r12, q1, q2, dim), 2, out, threads)
    if result.ndim == 1:
        return float(result[0]), float(result[1])
    return result[:, 0], result[:, 1]


def _fast_or_evaluate(
    kind: str, args: list, out_width: int, out: Any, threads: Optional[int]
) -> Any:
    """`_evaluate` for kernels whose fast-path result (`_one`) is already the final one: a
    single row of `args` without a thread count is read as it is, anything else vectorised."""
    if threads is None:
        one = _one(kind, out, *(value for _, value, _ in args))
        if one is not None:
            return one
    return _evaluate(kind, args, out_width, out, threads)


def _output_shape(args: list, width: int) -> tuple:
    counted = []
    for name, value, w in args:
        _, rows = _rows(name, value, w)
        if rows is not None:
            counted.append((name, rows))
    n = _common_rows(counted)
    return (width,) if n is None else (n, width)


def contact_function(
    r12: npt.ArrayLike, q1: npt.ArrayLike, q2: npt.ArrayLike, out: Optional[np.ndarray] = None,
    *, threads: Optional[int] = None,
) -> Tuple[Any, Any]:
    """The PW85 contact function mu^2 of two ellipsoids and its maximiser lambda.

    ``r12 = c2 - c1``; ``q1``, ``q2`` are the quadratic forms ``[Q11, Q12, Q13, Q22, Q23, Q33]``.
    mu^2 = max over 0 <= lambda <= 1 of f(lambda) = lambda (1 - lambda) r12^T Q(lambda)^-1 r12,
    Q(lambda) = (1 - lambda) Q1 + lambda Q2. The ellipsoids overlap iff mu^2 < 1 (at 1 they
    touch); mu is the factor by which both must be scaled about their centres to touch.
    Coincident centres give mu^2 = 0 and lambda = 1/2.

    Shapes: r12 (3,) or (n, 3), q1, q2 (6,) or (n, 6). ``out``, when given, is float64 of shape
    (2,) (one pair) or (n, 2) and receives ``[mu2, lam]`` per pair (as pypw85 fills it).
    Returns ``(mu2, lam)``: floats for one pair, arrays of shape (n,) (views into ``out``)
    otherwise.
    """
    return _pair("contact3", r12, q1, q2, 3, out, threads)


def contact_function_2d(
    r12: npt.ArrayLike, q1: npt.ArrayLike, q2: npt.ArrayLike, out: Optional[np.ndarray] = None,
    *, threads: Optional[int] = None,
) -> Tuple[Any, Any]:
    """The contact function of two ellipses: as :func:`contact_function` with r12 (2,) or
    (n, 2) and q1, q2 ``[Q11, Q12, Q22]`` (3,) or (n, 3)."""
    return _pair("contact2", r12, q1, q2, 2, out, threads)


def _verdict(kind, r12, q1, q2, dim, out, threads):
    if threads is None and out is None:
        one = _one(kind, None, r12, q1, q2)
        if one is not None:
            return one
    args = _pair_args(r12, q1, q2, dim)
    shape = _output_shape(args, 1)
    if out is not None:
        out = _check_out(out, shape[:-1], np.bool_)
    values = _evaluate(kind, args, 1, None, threads)[..., 0]
    if out is None:
        return values != 0.0 if values.ndim else bool(values != 0.0)
    np.not_equal(values, 0.0, out=out)
    return out


def overlap(
    r12: npt.ArrayLike, q1: npt.ArrayLike, q2: npt.ArrayLike, out: Optional[np.ndarray] = None,
    *, threads: Optional[int] = None,
) -> Any:
    """Whether two ellipsoids overlap (mu^2 < 1), decided without computing mu^2 to full
    precision (early exit): the same verdict as ``contact_function(...)[0] < 1``.

    Shapes as :func:`contact_function`; returns a bool for one pair, a bool array of shape (n,)
    otherwise (``out``: a bool array of that shape).
    """
    return _verdict("overlap3", r12, q1, q2, 3, out, threads)


def overlap_2d(
    r12: npt.ArrayLike, q1: npt.ArrayLike, q2: npt.ArrayLike, out: Optional[np.ndarray] = None,
    *, threads: Optional[int] = None,
) -> Any:
    """Whether two ellipses overlap: :func:`overlap` in 2D."""
    return _verdict("overlap2", r12, q1, q2, 2, out, threads)


class ContactDetails(NamedTuple):
    """What :func:`contact_details` returns; every field has a leading (n,) for n pairs."""

    mu2: Any
    """mu^2."""
    lam: Any
    """The maximiser lambda."""
    point: Any
    """x0 - c1 = (1 - lambda) Q1 Q(lambda)^-1 r12: where the ellipsoids scaled by mu touch,
    relative to the first centre, shape (3,)."""
    normal: Any
    """The unit normal there, pointing out of the first ellipsoid, shape (3,)."""
    grad_r12: Any
    """d mu^2 / d r12 = 2 lambda (1 - lambda) Q(lambda)^-1 r12, shape (3,)."""
    grad_q1: Any
    """d mu^2 / d q1 for the six stored entries (off-diagonal entries count twice), (6,)."""
    grad_q2: Any
    """d mu^2 / d q2, as grad_q1."""


# A row of the details kernels' output is mu2, lam, then the vector fields of ContactDetails
# (point, normal, grad_r12, grad_q1, grad_q2): per dimension, their columns and the row's width.
_DETAIL_COLUMNS = {
    3: ((slice(2, 5), slice(5, 8), slice(8, 11), slice(11, 17), slice(17, 23)), 23),
    2: ((slice(2, 4), slice(4, 6), slice(6, 8), slice(8, 11), slice(11, 14)), 14),
}


def _details(
    kind: str, dim: int, r12: Any, q1: Any, q2: Any, threads: Optional[int]
) -> ContactDetails:
    """The ContactDetails of ellipsoids (dim 3) or ellipses (dim 2) from the kernel `kind`."""
    columns, width = _DETAIL_COLUMNS[dim]
    d = None if threads is not None else _one(kind, None, r12, q1, q2)
    if d is None:
        d = _evaluate(kind, _pair_args(r12, q1, q2, dim), width, None, threads)
    vectors = [d[..., c] for c in columns]
    if d.ndim == 1:
        return ContactDetails(float(d[0]), float(d[1]), *vectors)
    return ContactDetails(d[..., 0], d[..., 1], *vectors)


def contact_details(
    r12: npt.ArrayLike, q1: npt.ArrayLike, q2: npt.ArrayLike, *, threads: Optional[int] = None
) -> ContactDetails:
    """mu^2, lambda, the contact point, the common normal and the gradients of mu^2 with
    respect to r12, q1 and q2 (see :class:`ContactDetails`). Shapes as
    :func:`contact_function`."""
    return _details("details3", 3, r12, q1, q2, threads)


def contact_details_2d(
    r12: npt.ArrayLike, q1: npt.ArrayLike, q2: npt.ArrayLike, *, threads: Optional[int] = None
) -> ContactDetails:
    """:func:`contact_details` of two ellipses: r12 (2,) or (n, 2), q1, q2 ``[Q11, Q12, Q22]``
    (3,) or (n, 3); the point, normal and ``grad_r12`` have 2 entries, ``grad_q1`` and
    ``grad_q2`` 3 (off-diagonal entries counted twice). mu^2 and lambda are those of
    :func:`contact_function_2d`."""
    return _details("details2", 2, r12, q1, q2, threads)


def f_neg(
    lambda_: npt.ArrayLike,
    r12: npt.ArrayLike,
    q1: npt.ArrayLike,
    q2: npt.ArrayLike,
    *,
    threads: Optional[int] = None,
) -> Any:
    """-f(lambda) = -lambda (1 - lambda) r12^T Q(lambda)^-1 r12, Q(lambda) = (1 - lambda) Q1 +
    lambda Q2: the function whose minimum over [0, 1] is -mu^2 (pypw85's ``f_neg``, for use
    with a scalar minimiser). ``lambda_`` in [0, 1], a number or shape (n,)."""
    if threads is None:
        one = _one("f_neg3", None, lambda_, r12, q1, q2)
        if one is not None:
            return one
    r = _evaluate(
        "f_neg3", [("lambda_", lambda_, 1), ("r12", r12, 3), ("q1", q1, 6), ("q2", q2, 6)],
        1, None, threads,
    )
    return r[..., 0] if r.ndim > 1 else float(r[0])


def spheroid(
    a: npt.ArrayLike, c: npt.ArrayLike, n: npt.ArrayLike, out: Optional[np.ndarray] = None,
    *, threads: Optional[int] = None,
) -> np.ndarray:
    """The quadratic form of the spheroid with equatorial semi-axis ``a``, polar semi-axis
    ``c`` and axis of revolution ``n``: Q = a^2 I + (c^2 - a^2) n n^T, with ``n`` as given, as
    pypw85 computes it. ``n`` should be a unit vector; it is not normalised, so any other n
    gives the polar semi-axis sqrt(a^2 + (c^2 - a^2) |n|^2) instead of c (pypw85's result).

    a, c: numbers or shape (n,); n: (3,) or (n, 3). Returns shape (6,) or (n, 6), into ``out``
    when given. ValueError, naming the argument, for a or c not positive and finite or whose
    square overflows or underflows float64 (beyond about 1.3e154 or below 1.5e-154), n not
    finite or zero, and a Q that overflows or is not positive definite (c < a with |n| > 1).
    """
    args = [("a", a, 1), ("c", c, 1), ("n", n, 3)]
    return _fast_or_evaluate("spheroid", args, 6, out, threads)


def from_axes_quaternion(
    axes: npt.ArrayLike, quaternion: npt.ArrayLike, out: Optional[np.ndarray] = None,
    *, threads: Optional[int] = None,
) -> np.ndarray:
    """Q = R diag(axes^2) R^T for semi-axes (3,) or (n, 3) and quaternions (w, x, y, z) (4,) or
    (n, 4), normalised here. Returns shape (6,) or (n, 6). A semi-axis whose square overflows
    or underflows float64 (beyond about 1.3e154 or below 1.5e-154) raises ValueError naming
    it."""
    args = [("axes", axes, 3), ("quaternion", quaternion, 4)]
    return _fast_or_evaluate("axes_quaternion", args, 6, out, threads)


def from_axes_rotation(
    axes: npt.ArrayLike, rotation: npt.ArrayLike, out: Optional[np.ndarray] = None,
    *, threads: Optional[int] = None,
) -> np.ndarray:
    """Q = R diag(axes^2) R^T for semi-axes (3,) or (n, 3) and rotation matrices (3, 3) or
    (n, 3, 3) whose column k is the direction of semi-axis k (orthogonal within 1e-6,
    determinant +1). Returns shape (6,) or (n, 6). Semi-axes as :func:`from_axes_quaternion`."""
    if threads is None:
        one = _one("axes_rotation", out, axes, rotation)
        if one is not None:
            return one
    r = _f64("rotation", rotation)
    if r.shape[-2:] != (3, 3) or r.ndim not in (2, 3):
        raise ValueError(f"rotation: expected shape (3, 3) or (n, 3, 3), got shape {r.shape}")
    args = [("axes", axes, 3), ("rotation", r.reshape(r.shape[:-2] + (9,)), 9)]
    return _evaluate("axes_rotation", args, 6, out, threads)


def from_axes_angle_2d(
    axes: npt.ArrayLike, theta: npt.ArrayLike, out: Optional[np.ndarray] = None,
    *, threads: Optional[int] = None,
) -> np.ndarray:
    """The ellipse's Q = R(theta) diag(a^2, b^2) R(theta)^T, R(theta) = [[cos, -sin], [sin,
    cos]], for semi-axes (2,) or (n, 2) and angles (radians), a number or shape (n,). Returns
    ``[Q11, Q12, Q22]``, shape (3,) or (n, 3). Semi-axes as :func:`from_axes_quaternion`."""
    args = [("axes", axes, 2), ("theta", theta, 1)]
    return _fast_or_evaluate("axes_angle_2d", args, 3, out, threads)


class OverlapMeasure(NamedTuple):
    """The implicit-variable overlap measure of Birgin, Lobato and Martinez (2016), eqs. 21-35,
    of body i against body j. Body i is mapped to the unit ball: c = P_i^-1/2 Q_i^T (c_i - c_j)
    and E_j becomes {x : x^T S x <= 1}."""

    f: Any
    """f = max(0, 1 - d2)^2 + max(0, eps - U)^2 (eq. 34): 0 iff the bodies do not overlap."""
    u: Any
    """The multiplier U of eq. 22: X + U S X = c."""
    d2: Any
    """d2 = |c - X|^2."""
    eps: Any
    """eps = min(l_i) min(l_j)^2 / (max(l_i)^2 max(l_j)) (Prop. 3.3)."""
    x: Any
    """X, the point of the boundary x^T S x = 1 nearest to c (eq. 35), shape (dim,); NaN where
    it is not unique (the hard case)."""


def overlap_measure(
    ci: npt.ArrayLike,
    ai: npt.ArrayLike,
    oi: npt.ArrayLike,
    cj: npt.ArrayLike,
    aj: npt.ArrayLike,
    oj: npt.ArrayLike,
    *,
    threads: Optional[int] = None,
) -> OverlapMeasure:
    """The overlap measure (f, U, d2, eps, X) of body i against body j (not symmetric in i, j).

    3D: centres ``ci``, ``cj`` (3,) or (n, 3), semi-axes ``ai``, ``aj`` (3,) or (n, 3),
    orientations ``oi``, ``oj`` quaternions (w, x, y, z) (4,) or (n, 4). 2D: centres and
    semi-axes (2,) or (n, 2), orientations angles theta (a number or (n,)). The dimension is
    the centres' last axis. Evaluated as ``ellipack measure`` does (in the units of the larger
    body), so the result does not depend on the units.
    """
    if threads is None:
        r = _one("measure3", None, ci, ai, oi, cj, aj, oj)
        if r is None:
            r = _one("measure2", None, ci, ai, oi, cj, aj, oj)
        if r is not None:
            return _overlap_measure(r, r.shape[0] - 5)
    c = _f64("ci", ci)
    dim = c.shape[-1] if c.ndim else 0
    if dim not in (2, 3):
        raise ValueError(f"ci: expected shape (3,), (n, 3), (2,) or (n, 2), got {c.shape}")
    ow = 1 if dim == 2 else 4
    parts = [("ci", ci, dim), ("ai", ai, dim), ("oi", oi, ow), ("cj", cj, dim), ("aj", aj, dim),
             ("oj", oj, ow)]
    blocks = [_rows(name, value, w) for name, value, w in parts]
    n = _common_rows([(p[0], b[1]) for p, b in zip(parts, blocks) if b[1] is not None])
    rows = 1 if n is None else n
    table = np.concatenate([np.broadcast_to(m, (rows, m.shape[1])) for m, _ in blocks], axis=1)
    width = 2 * (2 * dim + ow)
    r = _evaluate(f"measure{dim}", [("pairs", table if n is not None else table[0], width)],
                  3 + dim + 2, None, threads)
    return _overlap_measure(r, dim)


def _overlap_measure(r: np.ndarray, dim: int) -> OverlapMeasure:
    """The measure from its output rows (U, d2, eps, f, X, whether X is unique)."""
    x = np.where(r[..., -1:] != 0.0, r[..., 4:4 + dim], np.nan)
    if r.ndim == 1:
        return OverlapMeasure(float(r[3]), float(r[0]), float(r[1]), float(r[2]), x)
    return OverlapMeasure(r[:, 3], r[:, 0], r[:, 1], r[:, 2], x)


# ---- the packer -------------------------------------------------------------------------------


def _scene_source(scene) -> Tuple[Union[str, dict, None], Optional[str]]:
    if scene is None:
        return None, None
    if isinstance(scene, dict):
        return scene, None
    if isinstance(scene, str) and ("\n" in scene or "=" in scene):
        return scene, None
    if isinstance(scene, (str, os.PathLike)):
        path = os.fspath(scene)
        if not os.path.isfile(path):
            raise FileNotFoundError(errno.ENOENT, "no scene file", path)
        return None, path
    raise TypeError(
        f"scene: a dict, a path or a TOML string, not {type(scene).__name__}"
    )


def _progress(progress) -> Tuple[Optional[Callable[[dict], Any]], Callable[[], None]]:
    if progress is False:
        return None, lambda: None
    if callable(progress):
        return progress, lambda: None
    if progress is None or progress is True:
        try:
            from tqdm.auto import tqdm
        except ImportError:
            return None, lambda: None
        bar = tqdm(desc="ellipack", unit=" local minimisations")

        def show(p: dict) -> None:
            bar.update(1)
            bar.set_postfix(best=f"{p['best_density']:.5f}", last=f"{p['last_density']:.5f}")

        return show, bar.close
    raise TypeError(f"progress: a callable, True, False or None, not {type(progress).__name__}")


def _items_group(scene: Any, items: Any, folder: str) -> dict:
    """The scene dict with one more shape group, read from ``items`` written as CSV."""
    if not isinstance(scene, dict):
        raise TypeError("items: give the scene as a dict (items add a shape group to it)")
    dim = scene.get("dimension")
    if dim not in (2, 3):
        raise ValueError("items: the scene dict needs dimension = 2 or 3")
    rows = _f64("items", items)
    if rows.ndim != 2:
        raise ValueError(f"items must have shape (m, {dim}) or (m, {dim + (1 if dim == 2 else 4)})")
    axes = ["a", "b"] if dim == 2 else ["a", "b", "c"]
    turned = ["theta"] if dim == 2 else ["qw", "qx", "qy", "qz"]
    if rows.shape[1] == dim:
        header = axes
    elif rows.shape[1] == dim + len(turned):
        header = axes + turned
    else:
        raise ValueError(
            f"items must have {dim} columns (semi-axes) or {dim + len(turned)} (semi-axes and "
            f"{', '.join(turned)}), not {rows.shape[1]}"
        )
    if not np.all(np.isfinite(rows)):
        row = int(np.argwhere(~np.isfinite(rows))[0][0])
        raise ValueError(f"items: row {row} has a value that is not finite")
    path = os.path.join(folder, "items.csv")
    np.savetxt(path, rows, delimiter=",", header=",".join(header), comments="", fmt="%.17g")
    out = dict(scene)
    out["shapes"] = list(scene.get("shapes", [])) + [{"file": path}]
    return out


def pack(
    scene: Union[dict, str, "os.PathLike[str]", None] = None,
    *,
    items: Optional[npt.ArrayLike] = None,
    time_limit: Optional[float] = None,
    seed: Optional[int] = None,
    threads: Optional[int] = None,
    progress: Union[Callable[[dict], Any], bool, None] = None,
) -> Packing:
    """Packs the scene's items as densely as it can within the time limit and returns the best
    certified packing (:class:`Packing`): no two items overlap (PW85 mu^2 >= 1 on every pair)
    and every item is inside the container, checked by the certificate.

    ``scene``: a dict with the keys of the scene file (``dimension``, ``container``,
    ``shapes``, ``solver``, ...), a path (``str`` without ``=`` or a newline, or a
    ``pathlib.Path``) to a scene file, a TOML string, or None for the built-in scene. Errors
    in it raise ValueError naming the line and the key. ``time_limit`` (seconds), ``seed`` and
    ``threads`` (0: every core) override the scene's solver settings.

    ``items``: an array of shape (m, dim) of semi-axes, one row per item (a measured particle
    size distribution), or (m, dim + 1) in 2D with the angle, (m, dim + 4) in 3D with the
    quaternion (w, x, y, z) each item starts from in a random packing: one more shape group
    of the scene, which must then be a dict.

    ``progress``: called with a dict (``local_minimisations``, ``best_density``,
    ``last_density``, ``elapsed``) after every local minimisation, on the calling thread;
    None (the default) shows a tqdm bar when tqdm is installed; False shows nothing.

    Ctrl-C (KeyboardInterrupt, also when raised by ``progress``) stops the run within about
    0.1 s plus the end of the current solver iteration, and ``pack`` *returns* the best
    certified packing found so far, with ``packing.interrupted`` True; KeyboardInterrupt is
    not raised. Any other exception from a signal handler or from ``progress`` stops the run
    and is raised.

    A container of fixed size (its size or ``packing_fraction`` given in the scene) is filled
    rather than minimised: ``pack`` returns the first certified packing, or raises
    :class:`NotReached` (a ValueError) when the time limit (or Ctrl-C) ends the run first. The
    exception's ``packing`` is the least overlapping configuration, not a packing (items may
    overlap or stick out; its ``certificate`` counts them and ``summary["not_reached"]`` is
    True), as ``ellipack pack`` writes it to OUT/unfinished/.
    """
    if items is not None:
        import tempfile

        with tempfile.TemporaryDirectory(prefix="ellipack-items-") as folder:
            return pack(
                _items_group(scene, items, folder),
                time_limit=time_limit,
                seed=seed,
                threads=threads,
                progress=progress,
            )
    given, path = _scene_source(scene)
    if time_limit is not None:
        time_limit = float(time_limit)
    if seed is not None:
        seed = _count("seed", seed, 2**64 - 1)
    if threads is not None:
        threads = _count("threads", threads, _MAX_THREADS)
    callback, close = _progress(progress)
    try:
        return _ellipack._pack(given, path, time_limit, seed, threads, callback)
    finally:
        close()


def packing_from_arrays(
    container: dict, centres: npt.ArrayLike, semi_axes: npt.ArrayLike, orientations: npt.ArrayLike
) -> Packing:
    """A :class:`Packing` of your own items, e.g. to :func:`verify` it or ``write`` it.

    ``container``: as summary.json has it, e.g. ``{"kind": "ball", "radius": 5.0}`` or
    ``{"kind": "cuboid", "half_sides": [1, 2, 3], "center": [0, 0, 0]}``; ``centres``,
    ``semi_axes``: shape (m, dim); ``orientations``: quaternions (w, x, y, z), shape (m, 4), in
    3D, angles, shape (m,) or (m, 1), in 2D. At most 10 000 000 items. Shapes, dtypes and the
    item count are checked before anything is converted; float64 C-contiguous arrays are read
    in place. Its certificate is computed.
    """
    text = json.dumps(container, default=lambda v: v.tolist())
    dim = _ellipack._container_dimension(text)
    c = _real("centres", centres)
    a = _real("semi_axes", semi_axes)
    o = _real("orientations", orientations)
    # (name, array, columns, whether shape (m,) is accepted too)
    parts = [("centres", c, dim, False), ("semi_axes", a, dim, False),
             ("orientations", o, 1 if dim == 2 else 4, dim == 2)]
    for name, x, width, flat in parts:
        if not ((x.ndim == 2 and x.shape[1] == width) or (flat and x.ndim == 1)):
            wanted = "(m,) or (m, 1)" if flat else f"(m, {width})"
            raise ValueError(
                f"{name}: expected shape {wanted} for a {dim}D container, got shape {x.shape}"
            )
    if o.ndim == 1:
        o = o.reshape(-1, 1)
    m = c.shape[0]
    if a.shape[0] != m or o.shape[0] != m:
        raise ValueError(
            f"{m} centres, {a.shape[0]} semi-axes and {o.shape[0]} orientations: one of each "
            "per item"
        )
    if m > _ellipack._MAX_ITEMS:
        raise ValueError(f"{m} items, more than {_ellipack._MAX_ITEMS}")
    return _ellipack._packing_from_arrays(
        text, _f64("centres", c), _f64("semi_axes", a), _f64("orientations", o),
    )


def analyse(
    packing: Packing,
    *,
    gap: float = 1e-3,
    bond_cutoff: Optional[float] = None,
    rdf_range: Optional[float] = None,
    rdf_bins: int = 200,
) -> dict:
    """The structure of a packing, as ``ellipack analyse`` writes it to structure.json: a dict
    with ``density``, ``nematic`` (per body axis: ``order`` S and ``director``),
    ``bond_order`` (Steinhardt ``q4``, ``q6`` and their mean local values in 3D; ``psi6`` in
    2D), ``contacts`` (``mean_contacts`` Z, ``distribution``, ``rattlers``, ...), and ``rdf``
    with arrays ``r`` and ``g``.

    ``gap``: two items touch when PW85's mu < (1 + gap)·s, s the dilation by which the run
    repaired its packing (1 for a packing it did not repair); ``bond_cutoff``: the bonds of the
    bond-order parameters (default 1.4 mean equivalent diameters); ``rdf_range``, ``rdf_bins``:
    g(r) up to that distance (default 5 mean equivalent diameters, at most half the smallest
    width of a periodic cell) in that many bins.
    """
    text, r, g = _ellipack._analyse(
        packing, float(gap), None if bond_cutoff is None else float(bond_cutoff),
        None if rdf_range is None else float(rdf_range), _count("rdf_bins", rdf_bins, 10**7),
    )
    out = json.loads(text)
    out["rdf"] = {"r": np.asarray(r), "g": np.asarray(g)}
    return out
