"""The structure `ellipack analyse` measures, against freud-analysis on packings of known
structure: a face-centred cubic crystal, uniformly random points, a hexagonal crystal and
random points in 2D, aligned and isotropic axes.

Each case writes a packing folder by hand (packing.csv and a summary.json that gives only the
periodic cell), runs `ellipack analyse` with the bond cutoff given to freud, and compares
structure.json with freud's Steinhardt, Hexatic and Nematic on the same points and axes.
The program is $ELLIPACK, by default target/debug/ellipack of this repository.
"""

import json
import os
import subprocess
from pathlib import Path

import numpy as np
import pytest

freud = pytest.importorskip("freud")

ROOT = Path(__file__).resolve().parents[2]
ELLIPACK = os.environ.get("ELLIPACK", str(ROOT / "target" / "debug" / "ellipack"))
# freud computes in single precision: its figures agree with ours to a few float32 ulps.
FREUD = 2e-6


def write_folder(folder, positions, axes, quaternions, lengths):
    """A periodic packing folder: quaternions (w, x, y, z) in 3D, angles in 2D."""
    folder.mkdir(parents=True, exist_ok=True)
    dim = len(lengths)
    if dim == 3:
        header = "id,x,y,z,a,b,c,qw,qx,qy,qz"
        rows = [[i, *p, *a, *q] for i, (p, a, q) in enumerate(zip(positions, axes, quaternions))]
    else:
        header = "id,x,y,a,b,theta"
        rows = [[i, *p, *a, q] for i, (p, a, q) in enumerate(zip(positions, axes, quaternions))]
    text = header + "\n" + "".join(",".join(repr(float(v)) if k else str(v)
                                           for k, v in enumerate(r)) + "\n" for r in rows)
    (folder / "packing.csv").write_text(text)
    tilts = [0.0] * (3 if dim == 3 else 1)
    summary = {"container": {"kind": "periodic", "origin": [0.0] * dim,
                             "lengths": list(lengths), "tilts": tilts}}
    (folder / "summary.json").write_text(json.dumps(summary))


def analyse(folder, *args):
    done = subprocess.run([ELLIPACK, "analyse", str(folder), *args],
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stdout + done.stderr
    return json.loads((folder / "structure.json").read_text())


def fcc(cells, a):
    basis = np.array([[0, 0, 0], [0.5, 0.5, 0], [0.5, 0, 0.5], [0, 0.5, 0.5]])
    grid = np.array([[i, j, k] for i in range(cells) for j in range(cells) for k in range(cells)])
    return ((grid[:, None, :] + basis[None, :, :]).reshape(-1, 3) + 0.25) * a


def freud_steinhardt(points, side, r_max, l):
    box = freud.box.Box.cube(side)
    q = freud.order.Steinhardt(l)
    q.compute((box, points - side / 2), neighbors={"r_max": r_max})
    return q.order, float(np.nanmean(q.particle_order))


def random_quaternions(rng, n):
    q = rng.normal(size=(n, 4))
    return q / np.linalg.norm(q, axis=1)[:, None]


def rotate(q, v):
    """Rotates v by the unit quaternion q = (w, x, y, z)."""
    w, u = q[:, :1], q[:, 1:]
    return v + 2 * np.cross(u, np.cross(u, v) + w * v)


def test_fcc_crystal_matches_freud_and_has_twelve_contacts(tmp_path):
    side = 4 * np.sqrt(2) * 2.0  # unit spheres touching: nearest neighbours at 2
    points = fcc(4, np.sqrt(2) * 2.0)
    n = len(points)
    write_folder(tmp_path, points, [[1.0, 1.0, 1.0]] * n, [[1.0, 0, 0, 0]] * n, [side] * 3)
    s = analyse(tmp_path, "--bond-cutoff", "2.4")
    q6, q6_local = freud_steinhardt(points, side, 2.4, 6)
    q4, _ = freud_steinhardt(points, side, 2.4, 4)
    assert abs(q6 - 0.57452) < 1e-4
    assert s["bond_order"]["q6"] == pytest.approx(q6, abs=FREUD)
    assert s["bond_order"]["q6_local_mean"] == pytest.approx(q6_local, abs=FREUD)
    assert s["bond_order"]["q4"] == pytest.approx(q4, abs=FREUD)
    assert s["contacts"]["mean_contacts"] == 12.0
    assert s["density"] == pytest.approx(np.pi / (3 * np.sqrt(2)), rel=1e-12)


def test_random_points_match_freud(tmp_path):
    rng = np.random.default_rng(1)
    side, n = 12.0, 600
    points = rng.uniform(0, side, size=(n, 3))
    write_folder(tmp_path, points, [[0.01, 0.01, 0.01]] * n, [[1.0, 0, 0, 0]] * n, [side] * 3)
    s = analyse(tmp_path, "--bond-cutoff", "2.2")
    q6, q6_local = freud_steinhardt(points, side, 2.2, 6)
    assert s["bond_order"]["q6"] == pytest.approx(q6, abs=FREUD)
    assert s["bond_order"]["q6_local_mean"] == pytest.approx(q6_local, abs=FREUD)
    # Uniform random points: Q6 of the order of 1/sqrt(bonds), far from any crystal's.
    assert s["bond_order"]["q6"] < 0.1


def test_nematic_order_matches_freud_for_aligned_and_isotropic_axes(tmp_path):
    rng = np.random.default_rng(2)
    n, side = 400, 30.0
    points = rng.uniform(0, side, size=(n, 3))
    axes = [[1.0, 0.6, 0.3]] * n
    for name, quaternions in [("aligned", np.tile([1.0, 0, 0, 0], (n, 1))),
                              ("isotropic", random_quaternions(rng, n))]:
        folder = tmp_path / name
        write_folder(folder, points, axes, quaternions, [side] * 3)
        s = analyse(folder)
        for k, e in enumerate(np.eye(3)):
            nematic = freud.order.Nematic()
            nematic.compute(rotate(quaternions, np.tile(e, (n, 1))))
            assert s["nematic"][k]["order"] == pytest.approx(nematic.order, abs=FREUD), name
        if name == "aligned":
            assert s["nematic"][0]["order"] == pytest.approx(1.0, abs=1e-12)
        else:
            assert s["nematic"][0]["order"] < 0.15


def freud_hexatic(points, lengths, r_max):
    box = freud.box.Box(Lx=lengths[0], Ly=lengths[1], is2D=True)
    centred = np.c_[points - np.array(lengths) / 2, np.zeros(len(points))]
    h = freud.order.Hexatic(k=6)
    h.compute((box, centred), neighbors={"r_max": r_max})
    psi = h.particle_order
    return abs(np.mean(psi)), float(np.mean(np.abs(psi)))


def test_hexatic_order_matches_freud_on_a_crystal_and_on_random_points(tmp_path):
    rows, cols = 12, 12
    lengths = [2.0 * cols, np.sqrt(3) * rows]
    crystal = np.array([[2.0 * i + (j % 2), np.sqrt(3) * j] for j in range(rows)
                        for i in range(cols)]) + 0.3
    rng = np.random.default_rng(3)
    random = rng.uniform(0, 1, size=(400, 2)) * np.array(lengths)
    for name, points, radius in [("crystal", crystal, 1.0), ("random", random, 0.01)]:
        folder = tmp_path / name
        n = len(points)
        write_folder(folder, points, [[radius, radius]] * n, [0.0] * n, lengths)
        s = analyse(folder, "--bond-cutoff", "2.4")
        psi6, psi6_local = freud_hexatic(points, lengths, 2.4)
        assert s["bond_order"]["psi6"] == pytest.approx(psi6, abs=FREUD), name
        assert s["bond_order"]["psi6_local_mean"] == pytest.approx(psi6_local, abs=FREUD), name
        if name == "crystal":
            assert psi6 == pytest.approx(1.0, abs=FREUD)
            assert s["contacts"]["mean_contacts"] == 6.0
