"""The repository's reference files through the Python API, with the tolerances of the Rust
tests (validation/reference/README.md, "Who reads what, with which tolerance")."""

import numpy as np

import ellipack
from conftest import read_reference


def columns(rows, names):
    return np.array([[float(r[n]) for n in names] for r in rows])


def scaled_error(value, reference):
    """Relative where |reference| >= 1e-2, 100 x absolute below (1e-12 means 1e-12 relative or
    1e-14 absolute), as the Rust test kit's scaled_error."""
    e = np.abs(value - reference)
    return np.where(np.abs(reference) < 1e-2, e * 1e2, e / np.abs(reference))


def test_pw85_contact_reference():
    rows = read_reference("pw85_contact.csv")
    assert len(rows) == 305
    r12 = columns(rows, ["r12_x", "r12_y", "r12_z"])
    q1 = columns(rows, [f"q1_{k}" for k in range(6)])
    q2 = columns(rows, [f"q2_{k}" for k in range(6)])
    mu2_ref = np.array([float(r["mu2_ref"]) for r in rows])
    lam_ref = np.array([float(r["lambda_ref"]) for r in rows])
    mu2, lam = ellipack.contact_function(r12, q1, q2)
    # Relative error; absolute where the reference is 0 (coincident centres).
    rel = np.abs(mu2 - mu2_ref) / np.where(mu2_ref == 0.0, 1.0, mu2_ref)
    worst = int(np.argmax(rel))
    assert rel.max() <= 1e-13, f"case {rows[worst]['case_id']}: relative error {rel.max():e}"
    assert np.all((0.0 <= lam) & (lam <= 1.0))
    defined = np.isfinite(lam_ref) & (mu2_ref > 0.0)
    assert np.abs(lam - lam_ref)[defined].max() <= 1e-12
    # The verdict, outside 2e-13 of tangency.
    verdict = ellipack.overlap(r12, q1, q2)
    away = np.abs(mu2_ref - 1.0) > 2e-13
    wrong = np.nonzero(away & (verdict != (mu2_ref < 1.0)))[0]
    assert wrong.size == 0, [rows[i]["case_id"] for i in wrong]
    # The same through every core and one row at a time.
    mu2_all, lam_all = ellipack.contact_function(r12, q1, q2, threads=0)
    assert np.array_equal(mu2_all, mu2) and np.array_equal(lam_all, lam)
    for i in range(0, 305, 37):
        assert ellipack.contact_function(r12[i], q1[i], q2[i]) == (mu2[i], lam[i])


def check_measure(rows, dim):
    m = ellipack.overlap_measure(*blm_arguments(rows, dim))
    u_ref = np.array([float(r["U"]) for r in rows])
    d2_ref = np.array([float(r["d2"]) for r in rows])
    eps_ref = np.array([float(r["eps"]) for r in rows])
    f_ref = np.array([float(r["f"]) for r in rows])
    mu2_ref = np.array([float(r["mu2_pw85"]) for r in rows])
    assert scaled_error(m.u, u_ref).max() <= 1e-12
    assert scaled_error(m.d2, d2_ref).max() <= 1e-12
    assert (np.abs(m.eps - eps_ref) / eps_ref).max() <= 1e-15
    overlap_ref = (f_ref > 0.0) | (mu2_ref < 1.0)
    assert np.array_equal(m.f > 0.0, overlap_ref)
    checked = 0
    for i, r in enumerate(rows):
        if r["category"] == "near_hard" or r["X_1"] == "":
            continue
        x_ref = np.array([float(r[f"X_{k + 1}"]) for k in range(dim)])
        assert np.all(np.isfinite(m.x[i])), f"case {r['case_id']}: X not unique"
        err = np.linalg.norm(m.x[i] - x_ref) / np.linalg.norm(x_ref)
        assert err <= 1e-12, f"case {r['case_id']}: relative error of X {err:e}"
        checked += 1
    assert checked > len(rows) // 2


def blm_arguments(rows, dim):
    if dim == 3:
        return (
            columns(rows, ["cix", "ciy", "ciz"]),
            columns(rows, ["ai", "bi", "ci_ax"]),
            columns(rows, ["qwi", "qxi", "qyi", "qzi"]),
            columns(rows, ["cjx", "cjy", "cjz"]),
            columns(rows, ["aj", "bj", "cj_ax"]),
            columns(rows, ["qwj", "qxj", "qyj", "qzj"]),
        )
    return (
        columns(rows, ["cix", "ciy"]),
        columns(rows, ["ai", "bi"]),
        columns(rows, ["theta_i"])[:, 0],
        columns(rows, ["cjx", "cjy"]),
        columns(rows, ["aj", "bj"]),
        columns(rows, ["theta_j"])[:, 0],
    )


def test_blm_3d_reference():
    rows = read_reference("blm_3d.csv")
    assert len(rows) == 257
    check_measure(rows, 3)


def test_blm_2d_reference():
    rows = read_reference("blm_2d.csv")
    assert len(rows) == 104
    check_measure(rows, 2)
