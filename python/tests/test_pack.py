"""The packer on small scenes, checked independently with NumPy; scenes as dict, TOML text and
file; writing and reading a folder; progress and Ctrl-C."""

import os
import signal
import subprocess
import sys
import textwrap
import time

import numpy as np
import pytest

import ellipack

SCENE_2D = {
    "dimension": 2,
    "seed": 5,
    "container": {"kind": "circle"},
    "shapes": [{"count": 5, "semi_axes": [2.0, 1.0]}, {"count": 2, "semi_axes": [1.0, 1.0]}],
    "solver": {"time_limit": 600.0, "threads": 1, "local_minimisations": 6},
}

SCENE_3D = {
    "dimension": 3,
    "seed": 2,
    "container": {"kind": "ball"},
    "shapes": [{"count": 5, "semi_axes": [1.0, 0.75, 0.5]}],
    "solver": {"time_limit": 600.0, "threads": 1, "local_minimisations": 4},
}


# ---- an independent check of non-overlap, from the arrays alone --------------------------------


def rotation_2d(theta):
    c, s = np.cos(theta), np.sin(theta)
    return np.array([[c, -s], [s, c]])


def rotation_3d(q):
    """The active rotation of the quaternion (w, x, y, z), normalised."""
    w, x, y, z = q / np.linalg.norm(q)
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ])


def forms(packing):
    rotations = (
        [rotation_2d(t) for t in packing.angles]
        if packing.dimension == 2
        else [rotation_3d(q) for q in packing.quaternions]
    )
    return [R @ np.diag(a * a) @ R.T for R, a in zip(rotations, packing.semi_axes)]


def best_f(r, Q1, Q2):
    """A lower bound of μ² = max f(λ): f on a grid of λ, then golden-section refinement around
    the best grid point. Any λ with f(λ) > 1 proves that the interiors are disjoint."""
    def f(lam):
        Q = (1 - lam) * Q1 + lam * Q2
        return lam * (1 - lam) * r @ np.linalg.solve(Q, r)

    grid = np.linspace(0.0, 1.0, 401)
    values = [f(t) for t in grid]
    k = int(np.argmax(values))
    lo, hi = grid[max(k - 1, 0)], grid[min(k + 1, 400)]
    g = (np.sqrt(5) - 1) / 2
    for _ in range(60):
        a, b = hi - g * (hi - lo), lo + g * (hi - lo)
        if f(a) < f(b):
            lo = a
        else:
            hi = b
    return max(max(values), f((lo + hi) / 2))


def check_independently(packing):
    centres = packing.centres
    Q = forms(packing)
    m = len(packing)
    assert centres.shape == (m, packing.dimension)
    worst = np.inf
    for i in range(m):
        for j in range(i + 1, m):
            worst = min(worst, best_f(centres[j] - centres[i], Q[i], Q[j]))
    assert worst > 1.0, f"two items overlap: max f(λ) = {worst}"
    # Every item inside the container (a ball or disc about the origin): the farthest point of
    # item i from the centre, sampled densely on its boundary.
    container = packing.container
    assert container["kind"] in ("circle", "ball")
    radius = container["radius"]
    rng = np.random.default_rng(0)
    for i in range(m):
        u = rng.normal(size=(20000, packing.dimension))
        u /= np.linalg.norm(u, axis=1)[:, None]
        # Points of the boundary: c + L u with L Lᵀ = Q.
        L = np.linalg.cholesky(Q[i])
        points = centres[i] + u @ L.T
        assert np.linalg.norm(points, axis=1).max() <= radius * (1 + 1e-12)
    # The density from the arrays.
    a = packing.semi_axes
    if packing.dimension == 2:
        density = np.pi * a.prod(axis=1).sum() / (np.pi * radius**2)
    else:
        density = a.prod(axis=1).sum() / radius**3
    assert density == pytest.approx(packing.density, rel=1e-12)


# ---- the tests ----------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def packed_2d():
    seen = []
    packing = ellipack.pack(SCENE_2D, progress=seen.append)
    return packing, seen


def test_pack_2d_gives_a_certified_packing(packed_2d):
    packing, seen = packed_2d
    assert packing.dimension == 2 and len(packing) == 7
    assert packing.quaternions is None and packing.angles.shape == (7,)
    assert packing.certificate["overlapping_pairs"] == 0
    assert packing.certificate["containment_violations"] == 0
    assert packing.certificate["min_mu2"] >= 1.0
    assert not packing.interrupted
    check_independently(packing)
    assert ellipack.verify(packing) == {
        "certified": True,
        "overlapping_pairs": [],
        "outside": [],
        "min_mu2": packing.certificate["min_mu2"],
    }
    # The progress callback heard every local minimisation, in order.
    assert [p["local_minimisations"] for p in seen] == list(range(1, len(seen) + 1))
    assert len(seen) >= 6
    assert max(p["best_density"] for p in seen) == pytest.approx(packing.density, rel=1e-9)
    assert packing.history.count("\n") == len(seen) + 1


def test_pack_3d_gives_a_certified_packing():
    packing = ellipack.pack(SCENE_3D, progress=False)
    assert packing.dimension == 3 and packing.quaternions.shape == (5, 4)
    assert packing.angles is None
    check_independently(packing)
    assert ellipack.verify(packing)["certified"]


def test_periodic_cells_reach_the_densest_lattice_packing():
    """A variable periodic cell of two ellipses (2, 1) packs at the hexagonal density
    π/√12; the container is the cell (lengths and tilts), verified on every image."""
    scene = {
        "dimension": 2,
        "seed": 2,
        "container": {"kind": "periodic", "cell": "variable"},
        "shapes": [{"count": 2, "semi_axes": [2.0, 1.0]}],
        "solver": {"time_limit": 600.0, "threads": 1, "local_minimisations": 8},
    }
    packing = ellipack.pack(scene, progress=False)
    assert packing.container["kind"] == "periodic"
    assert len(packing.container["lengths"]) == 2 and len(packing.container["tilts"]) == 1
    hexagonal = np.pi / np.sqrt(12.0)
    assert hexagonal * (1 - 1e-4) <= packing.density <= hexagonal * (1 + 1e-9)
    assert ellipack.verify(packing)["certified"]


SCENE_2D_TOML = """
dimension = 2
seed = 5
container = { kind = "circle" }
shapes = [{ count = 5, semi_axes = [2.0, 1.0] }, { count = 2, semi_axes = [1.0, 1.0] }]
solver = { time_limit = 600.0, threads = 1, local_minimisations = 6 }
"""


def test_dict_toml_text_and_file_are_the_same_scene(tmp_path, packed_2d):
    packing, _ = packed_2d
    text = SCENE_2D_TOML
    from_text = ellipack.pack(text, progress=False)
    path = tmp_path / "scene.toml"
    path.write_text(text)
    from_file = ellipack.pack(path, progress=False)
    from_str_path = ellipack.pack(str(path), progress=False)
    for other in (from_text, from_file, from_str_path):
        assert np.array_equal(other.centres, packing.centres)
        assert np.array_equal(other.angles, packing.angles)


def test_write_and_read_back(tmp_path, packed_2d):
    packing, _ = packed_2d
    out = tmp_path / "run" / "out"
    packing.write(out)
    assert sorted(os.listdir(out)) == ["history.csv", "packing.csv", "packing.xyz", "summary.json"]
    back = ellipack.read_packing(out)
    assert np.array_equal(back.centres, packing.centres)
    assert np.array_equal(back.semi_axes, packing.semi_axes)
    assert np.array_equal(back.angles, packing.angles)
    assert back.container == packing.container
    assert back.summary == packing.summary
    assert back.history is None
    # Overwriting keeps one set: the new packing without xyz replaces the old files.
    back.write(out, xyz=False)
    assert sorted(os.listdir(out)) == ["packing.csv", "summary.json"]
    with pytest.raises(FileNotFoundError, match="packing.csv"):
        ellipack.read_packing(tmp_path / "nothing")
    (out / "summary.json").write_text("{}")
    with pytest.raises(ValueError, match="summary.json"):
        ellipack.read_packing(out)


def test_scene_errors_name_the_line_and_key():
    bad = dict(SCENE_2D, container={"kind": "ball"})
    # A dict has no lines: its messages name the key.
    with pytest.raises(ValueError, match=r"<scene>: `container.kind`: a ball is a 3D"):
        ellipack.pack(bad, progress=False)
    with pytest.raises(ValueError, match=r"<scene>: line 2, column 1: `dimnsion`"):
        ellipack.pack("\ndimnsion = 2\n", progress=False)
    with pytest.raises(ValueError, match=r"`solver.tim_limit`: unknown field"):
        ellipack.pack(dict(SCENE_2D, solver={"tim_limit": 1.0}), progress=False)
    with pytest.raises(ValueError, match=r"`shapes\[1\].semi_axes\[0\]`: invalid type"):
        shapes = [SCENE_2D["shapes"][0], {"count": 1, "semi_axes": ["a"]}]
        ellipack.pack(dict(SCENE_2D, shapes=shapes), progress=False)
    bad = dict(SCENE_2D, shapes=[{"count": 0, "semi_axes": [1.0, 1.0]}])
    with pytest.raises(ValueError, match=r"`shapes\[0\].count`"):
        ellipack.pack(bad, progress=False)
    with pytest.raises(ValueError, match="time limit"):
        ellipack.pack(SCENE_2D, time_limit=0.0, progress=False)
    with pytest.raises(TypeError, match="no TOML form"):
        ellipack.pack(dict(SCENE_2D, seed=None), progress=False)
    with pytest.raises(TypeError, match="scene"):
        ellipack.pack(42, progress=False)
    with pytest.raises(FileNotFoundError, match="no scene file"):
        ellipack.pack("no/such/scene.toml", progress=False)
    with pytest.raises(ValueError, match="seed"):
        ellipack.pack(SCENE_2D, seed=-1, progress=False)
    with pytest.raises(ValueError, match="threads"):
        ellipack.pack(SCENE_2D, threads=-2, progress=False)


def test_an_exception_in_progress_stops_the_run_and_is_raised():
    def fail(p):
        raise RuntimeError("stop here")

    start = time.monotonic()
    with pytest.raises(RuntimeError, match="stop here"):
        ellipack.pack(dict(SCENE_2D, solver={"time_limit": 600.0, "threads": 1}), progress=fail)
    # Stopped by the exception, long before its time limit on any machine.
    assert time.monotonic() - start < 300.0


def test_keyboard_interrupt_in_progress_returns_the_best_packing():
    def interrupt(p):
        if p["local_minimisations"] == 2:
            raise KeyboardInterrupt

    start = time.monotonic()
    packing = ellipack.pack(dict(SCENE_2D, solver={"time_limit": 600.0, "threads": 1}),
                            progress=interrupt)
    assert time.monotonic() - start < 300.0
    assert packing.interrupted
    check_independently(packing)


def test_packing_from_arrays_and_verify_name_the_offenders():
    p = ellipack.packing_from_arrays(
        {"kind": "circle", "radius": 3.0},
        [[0.0, 0.0], [1.5, 0.0], [0.0, 2.5]],
        [[1.0, 1.0], [1.0, 1.0], [1.0, 1.0]],
        [0.0, 0.0, 0.0],
    )
    v = ellipack.verify(p)
    assert not v["certified"]
    assert [(i, j) for i, j, _ in v["overlapping_pairs"]] == [(0, 1)]
    assert v["overlapping_pairs"][0][2] == pytest.approx(0.5625, rel=1e-14)
    assert [i for i, _ in v["outside"]] == [2]
    assert v["outside"][0][1] == pytest.approx(3.5 / 3.0, rel=1e-14)
    with pytest.raises(ValueError, match="item 1"):
        ellipack.packing_from_arrays({"kind": "circle", "radius": 3.0}, [[0, 0], [1, 1]],
                                     [[1, 1], [1, -1]], [0, 0])


CTRL_C_CHILD = textwrap.dedent(
    """
    import signal, sys
    import ellipack
    # What an interactive interpreter has; a process started in the background by a
    # non-interactive shell inherits SIGINT ignored instead.
    signal.signal(signal.SIGINT, signal.default_int_handler)
    scene = {"dimension": 2, "seed": 1, "container": {"kind": "circle"},
             "shapes": [{"count": 12, "semi_axes": [2.0, 1.0]}],
             "solver": {"time_limit": 120.0, "threads": 1}}
    def progress(p):
        if p["local_minimisations"] == 1:
            print("started", flush=True)
    packing = ellipack.pack(scene, progress=progress)
    v = ellipack.verify(packing)
    print("returned", packing.interrupted, v["certified"], len(packing),
          packing.summary["wall_seconds"], flush=True)
    packing.write(sys.argv[1])
    print("alive", flush=True)
    """
)


def test_ctrl_c_stops_the_run_and_returns_the_packing(tmp_path):
    child = subprocess.Popen(
        [sys.executable, "-c", CTRL_C_CHILD, str(tmp_path / "out")],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        assert child.stdout.readline().strip() == "started"
        time.sleep(0.5)
        child.send_signal(signal.SIGINT)
        # A guard against a hang only: the run stops at the signal, whatever the speed.
        out, err = child.communicate(timeout=300)
    finally:
        child.kill()
    assert child.returncode == 0, err
    lines = out.split("\n")
    returned = lines[0].split()
    assert returned[:4] == ["returned", "True", "True", "12"], out
    assert lines[1] == "alive"
    check_independently(ellipack.read_packing(tmp_path / "out"))


def test_tqdm_shows_progress_when_installed(monkeypatch):
    """With progress=None, a tqdm bar (here a stand-in module) hears every local
    minimisation and is closed at the end."""
    import types

    bars = []

    class Bar:
        def __init__(self, **kwargs):
            self.updates, self.closed, self.postfix = 0, False, None
            bars.append(self)

        def update(self, k):
            self.updates += k

        def set_postfix(self, **kwargs):
            self.postfix = kwargs

        def close(self):
            self.closed = True

    auto = types.ModuleType("tqdm.auto")
    auto.tqdm = Bar
    package = types.ModuleType("tqdm")
    package.auto = auto
    monkeypatch.setitem(sys.modules, "tqdm", package)
    monkeypatch.setitem(sys.modules, "tqdm.auto", auto)
    packing = ellipack.pack(SCENE_2D)
    assert len(bars) == 1 and bars[0].closed
    assert bars[0].updates == packing.summary["local_minimisations"]
    assert bars[0].postfix["best"] == f"{packing.density:.5f}"


def test_the_independent_check_catches_an_overlap_and_an_item_outside():
    container = {"kind": "circle", "radius": 3.0}
    axes = [[1.0, 0.5], [1.0, 0.5]]
    # Two ellipses whose interiors overlap by 1e-3 along x: every f(λ) < 1.
    touching = ellipack.packing_from_arrays(container, [[-1.0, 0], [0.999, 0]], axes, [0, 0])
    with pytest.raises(AssertionError, match="overlap"):
        check_independently(touching)
    # Apart, but one sticks out of the disc by 1e-3.
    outside = ellipack.packing_from_arrays(container, [[-1.0, 0], [2.001, 0]], axes, [0, 0])
    with pytest.raises(AssertionError):
        check_independently(outside)
    apart = ellipack.packing_from_arrays(container, [[-1.0, 0], [1.001, 0]], axes, [0, 0])
    check_independently(apart)


def traced_peak(call):
    """The peak of memory that Python and NumPy allocate during `call()` (not the Rust part's),
    and what it returned or raised."""
    import tracemalloc

    tracemalloc.start()
    try:
        try:
            result = call()
        except Exception as e:  # noqa: BLE001 - returned for the caller to check
            result = e
        return tracemalloc.get_traced_memory()[1], result
    finally:
        tracemalloc.stop()


def test_packing_from_arrays_reads_the_arrays_in_place_after_checking_them():
    """No conversion to Python lists, no copy of float64 C-contiguous arrays, and every check
    of shapes, dtypes and the item count before anything is converted."""
    m = 200_000
    cube = {"kind": "cuboid", "half_sides": [200.0, 200.0, 200.0]}
    centres, axes = np.zeros((m, 3)), np.ones((m, 3))
    turns = np.tile([1.0, 0.0, 0.0, 0.0], (m - 1, 1))
    peak, error = traced_peak(lambda: ellipack.packing_from_arrays(cube, centres, axes, turns))
    assert isinstance(error, ValueError)
    assert str(error) == "200000 centres, 200000 semi-axes and 199999 orientations: one of each per item"
    assert peak < 1_000_000
    # Integers are converted only once the shapes fit the container.
    int_centres, int_axes = np.zeros((m, 2), dtype=np.int64), np.ones((m, 3), dtype=np.int64)
    angles = np.zeros(m)
    peak, error = traced_peak(lambda: ellipack.packing_from_arrays(
        {"kind": "circle", "radius": 5.0}, int_centres, int_axes, angles))
    assert isinstance(error, ValueError) and peak < 1_000_000
    assert str(error) == "semi_axes: expected shape (m, 2) for a 2D container, got shape (200000, 3)"
    with pytest.raises(TypeError, match="orientations: expected real numbers"):
        ellipack.packing_from_arrays(cube, centres, axes, np.ones((m, 4), dtype=complex))
    # More items than any scene holds, given as broadcast views that take no memory.
    many = ellipack._ellipack._MAX_ITEMS + 1
    peak, error = traced_peak(lambda: ellipack.packing_from_arrays(
        cube, np.broadcast_to(np.zeros(3), (many, 3)), np.broadcast_to(np.ones(3), (many, 3)),
        np.broadcast_to([1.0, 0, 0, 0], (many, 4))))
    assert isinstance(error, ValueError) and str(error) == f"{many} items, more than {many - 1}"
    assert peak < 1_000_000

    # 8000 unit spheres on a grid 2.5 apart: read in place, certified.
    g = np.arange(20) * 2.5 - 23.75
    grid = np.stack(np.meshgrid(g, g, g, indexing="ij"), axis=-1).reshape(-1, 3)
    k = len(grid)
    ones, identity = np.ones((k, 3)), np.tile([1.0, 0, 0, 0], (k, 1))
    peak, packing = traced_peak(lambda: ellipack.packing_from_arrays(
        {"kind": "cuboid", "half_sides": [25.0, 25.0, 25.0]}, grid, ones, identity))
    assert isinstance(packing, ellipack.Packing), packing
    assert len(packing) == k and packing.certificate["overlapping_pairs"] == 0
    assert packing.certificate["containment_violations"] == 0
    assert peak < 200_000
    assert np.array_equal(packing.centres, grid)


def test_a_fixed_container_not_filled_raises_not_reached_with_the_configuration(tmp_path):
    """7 unit discs fill at most 7/9 of a circle: at 0.8 the run ends after its local
    minimisations with ellipack.NotReached, a ValueError carrying the least overlapping
    configuration."""
    scene = {
        "dimension": 2,
        "seed": 1,
        "container": {"kind": "circle", "packing_fraction": 0.8},
        "shapes": [{"count": 7, "semi_axes": [1.0, 1.0]}],
        "solver": {"time_limit": 600.0, "threads": 1, "local_minimisations": 2},
    }
    assert issubclass(ellipack.NotReached, ValueError)
    with pytest.raises(ellipack.NotReached, match="packing fraction 0.8000 not reached") as caught:
        ellipack.pack(scene, progress=False)
    unfinished = caught.value.packing
    assert isinstance(unfinished, ellipack.Packing) and len(unfinished) == 7
    assert unfinished.density == pytest.approx(0.8, rel=1e-12)
    assert unfinished.summary["not_reached"] is True
    v = ellipack.verify(unfinished)
    assert not v["certified"]
    assert len(v["overlapping_pairs"]) == unfinished.certificate["overlapping_pairs"]
    assert unfinished.history.count("\n") >= 2
    unfinished.write(tmp_path / "unfinished")
    assert ellipack.read_packing(tmp_path / "unfinished").summary["not_reached"] is True
