"""Kanapy's documented RVE example, packed by Kanapy, written out for a side-by-side with ellipack.

Usage (in a venv with `pip install kanapy`):

    python kanapy_example.py --out DIR [--seed 1] [--nsteps 1000] [--fill-factor 0.65]

The descriptor is the one of Kanapy's example `examples/RVE_generation/create_rve.py`
(the version of the orix era, kanapy >= 6.5): elongated grains in a periodic 40 um cube
(30^3 voxels), equivalent-sphere diameter lognormal (s = 0.8, scale = 14, loc = 0, cut to
[6, 16]), aspect ratio lognormal (s = 0.8, scale = 2.5, loc = 0, cut to [0.85, 3.2]),
tilt angle von Mises (kappa = 1, loc = pi/2, cut to [0, pi]). The script runs what that
example runs up to and including `Microstructure.pack()` (Kanapy's default schedule:
1000 growth steps, fill factor 0.65), and no voxelization.

Written:

- DIR/kanapy.csv: one row per particle at the end of Kanapy's packing (periodic images
  dropped), columns x, y, z, a, b, c, qw, qx, qy, qz.
  * (x, y, z): the centre, wrapped into [0, L) per axis (Kanapy's box is [0, L]^3).
  * (a, b, c): Kanapy's semi-axes in its body frame, after growth. a lies along the body
    x axis and is the long axis when the aspect ratio exceeds 1 (b = c, a prolate
    spheroid); an aspect ratio below 1 (the cut-off allows down to 0.85) makes a the short
    axis, an oblate spheroid. The order is kept as Kanapy has it, not sorted.
  * (qw, qx, qy, qz): the unit quaternion Kanapy stores, scalar first. Its Hamilton
    rotation matrix R (v -> q v q*, column k = body axis k in world axes) maps body to
    world: world = R body + centre. This is the convention of Kanapy's overlap test
    (`collisions.collide_detect`) and of its OVITO dumps. For a tilt angle t Kanapy builds
    q = (cos t/2, 0, 0, sin t/2): a rotation by t about +z, so the body x axis (the long
    one) lies in the world xy plane at angle t from +x.
    Caveat: Kanapy's surface points, bounding boxes and voxelization use `body @ R`, that
    is R^T, the conjugate quaternion (the long axis at -t from +x). kanapy.json reports
    the overlaps under both readings.
- DIR/kanapy.json: versions, descriptor, seed, schedule, particle count, box, fill
  fractions, growth, timings, overlap counts.

Reproducibility: Kanapy draws aspect ratios and tilt angles from NumPy's global state
(scipy `rvs`) and positions from the standard library's `random`; both are seeded here.
The equivalent diameters are not random: Kanapy fills the box volume by binning the
lognormal, so the particle count is fixed by the descriptor.
"""

import argparse
import contextlib
import io
import json
import math
import os
import platform
import random
import re
import sys
import time
from pathlib import Path

# The packing is single-threaded Python; a BLAS thread pool would only blur the CPU time
# and compete with whatever else runs on the machine.
for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402

# Kanapy's default growth schedule (RVE_creator nsteps, particle_grow fill_factor).
DEFAULT_NSTEPS = 1000
DEFAULT_FILL_FACTOR = 0.65

SOURCE = (
    "Kanapy examples/RVE_generation/create_rve.py (orix-era version, kanapy >= 6.5); "
    "README: 'Kanapy comes with several examples', `kanapy copyExamples`"
)


def descriptor():
    """Kanapy's documented example of elongated grains, as a Kanapy descriptor dict."""
    side, nvox = 40, 30
    return {
        "Grain type": "Elongated",
        "Equivalent diameter": {
            "sig": 0.8, "scale": 14.0, "loc": 0.0, "cutoff_min": 6.0, "cutoff_max": 16.0,
        },
        "Aspect ratio": {
            "sig": 0.8, "scale": 2.5, "loc": 0.0, "cutoff_min": 0.85, "cutoff_max": 3.2,
        },
        "Tilt angle": {
            "kappa": 1.0, "loc": 0.5 * math.pi, "cutoff_min": 0.0, "cutoff_max": math.pi,
        },
        "RVE": {"sideX": side, "sideY": side, "sideZ": side, "Nx": nvox, "Ny": nvox, "Nz": nvox},
        "Simulation": {"periodicity": True, "output_units": "um"},
    }


def rotation(q):
    """Hamilton rotation matrix of a unit quaternion (w, x, y, z): columns are body axes."""
    w, x, y, z = q
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ])


def contact_function(r, cov_i, cov_j):
    """Perram-Wertheim: max over l in [0, 1] of l (1 - l) r^T [(1 - l) C_i + l C_j]^-1 r.

    C = R diag(a^2) R^T. The ellipsoids overlap iff the maximum is below 1. The function
    is concave in l, so a golden-section search finds its maximum; this check is
    independent of Kanapy's own (Wang et al.'s algebraic condition).
    """
    def f(lam):
        m = (1.0 - lam) * cov_i + lam * cov_j
        return lam * (1.0 - lam) * float(r @ np.linalg.solve(m, r))

    lo, hi = 0.0, 1.0
    g = (math.sqrt(5.0) - 1.0) / 2.0
    x1, x2 = hi - g * (hi - lo), lo + g * (hi - lo)
    f1, f2 = f(x1), f(x2)
    for _ in range(80):
        if f1 < f2:
            lo, x1, f1 = x1, x2, f2
            x2 = lo + g * (hi - lo)
            f2 = f(x2)
        else:
            hi, x2, f2 = x2, x1, f1
            x1 = hi - g * (hi - lo)
            f1 = f(x1)
    return max(f1, f2)


def overlaps(centres, axes, rotations, lengths):
    """Overlapping pairs (every periodic image, the particle's own included) and min F."""
    n = len(centres)
    covs = [r @ np.diag(np.square(ax)) @ r.T for r, ax in zip(rotations, axes)]
    reach = np.max(axes, axis=1)
    shifts = [np.array([i, j, k]) * lengths
              for i in (-1, 0, 1) for j in (-1, 0, 1) for k in (-1, 0, 1)]
    count, worst = 0, math.inf
    for i in range(n):
        for j in range(i, n):
            for s in shifts:
                if i == j and not s.any():
                    continue
                r = centres[j] + s - centres[i]
                if np.linalg.norm(r) >= reach[i] + reach[j]:
                    continue
                value = contact_function(r, covs[i], covs[j])
                worst = min(worst, value)
                if value < 1.0:
                    count += 1
    return count, worst


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", required=True, type=Path, help="output folder")
    parser.add_argument("--seed", type=int, default=1, help="seed of random and numpy.random")
    parser.add_argument("--nsteps", type=int, default=DEFAULT_NSTEPS,
                        help=f"Kanapy's packing steps (its default: {DEFAULT_NSTEPS})")
    parser.add_argument("--fill-factor", type=float, default=None,
                        help=f"Kanapy's growth target (its default: {DEFAULT_FILL_FACTOR})")
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)

    import kanapy as knpy
    import scipy

    random.seed(args.seed)
    np.random.seed(args.seed)
    desc = descriptor()
    ms = knpy.Microstructure(descriptor=desc, name="kanapy_create_rve_example")
    ms.init_RVE(nsteps=args.nsteps)
    pdata = ms.rve.particle_data[0]
    # Kanapy's particle_generator halves these diameters into its starting semi-axes.
    start_axes = 0.5 * np.column_stack([pdata["Major_diameter"], pdata["Minor_diameter1"],
                                        pdata["Minor_diameter2"]])

    # Kanapy prints its own overlap count after packing; keep a copy to record it.
    log = io.StringIO()

    class Tee(io.TextIOBase):
        def write(self, s):
            sys.__stdout__.write(s)
            log.write(s)
            return len(s)

    with contextlib.redirect_stdout(Tee()):
        wall0, cpu0 = time.perf_counter(), time.process_time()
        ms.pack(fill_factor=args.fill_factor)
        wall, cpu = time.perf_counter() - wall0, time.process_time() - cpu0
    match = re.search(r"(\d+) overlapping particles detected after packing", log.getvalue())
    kanapy_overlaps = int(match.group(1)) if match else None

    # Periodic copies carry string ids; the particles themselves carry integer ids.
    parts = sorted((p for p in ms.particles if isinstance(p.id, (int, np.integer))),
                   key=lambda p: p.id)
    lengths = np.array(ms.rve.size, dtype=float)
    centres = np.array([p.get_pos() for p in parts]) % lengths
    axes = np.array([p.get_coeffs() for p in parts])
    quats = np.array([p.quat for p in parts], dtype=float)
    quats /= np.linalg.norm(quats, axis=1)[:, None]
    init_axes = np.array([[p.oria, p.orib, p.oric] for p in parts])

    with open(args.out / "kanapy.csv", "w") as f:
        f.write("x,y,z,a,b,c,qw,qx,qy,qz\n")
        for c, ax, q in zip(centres, axes, quats):
            f.write(",".join(repr(float(v)) for v in (*c, *ax, *q)) + "\n")

    box_volume = float(np.prod(lengths))
    volumes = 4.0 / 3.0 * math.pi * np.prod(axes, axis=1)
    start_volumes = 4.0 / 3.0 * math.pi * np.prod(start_axes, axis=1)
    growth = axes / init_axes
    rot = [rotation(q) for q in quats]
    n_over, f_min = overlaps(centres, axes, rot, lengths)
    n_over_t, f_min_t = overlaps(centres, axes, [r.T for r in rot], lengths)
    aspect = axes[:, 0] / axes[:, 1]
    tilt = np.degrees(2.0 * np.arctan2(quats[:, 3], quats[:, 0]))

    summary = {
        "kanapy_version": knpy.__version__,
        "python": platform.python_version(),
        "numpy": np.__version__,
        "scipy": scipy.__version__,
        "descriptor_source": SOURCE,
        "descriptor": desc,
        "seed": args.seed,
        "schedule": {
            "nsteps": args.nsteps,
            "fill_factor": args.fill_factor if args.fill_factor is not None
            else DEFAULT_FILL_FACTOR,
            "kanapy_default": args.nsteps == DEFAULT_NSTEPS and args.fill_factor in
            (None, DEFAULT_FILL_FACTOR),
            "iterations": int(ms.simbox.sim_ts),
            "k_rep": 0.0,
            "k_att": 0.0,
        },
        "n_particles": len(parts),
        "box_lengths": lengths.tolist(),
        "box_volume": box_volume,
        "cubic": bool(np.allclose(lengths, lengths[0])),
        "periodic": bool(ms.rve.periodic),
        "fill_fraction": float(volumes.sum() / box_volume),
        "fill_fraction_note": (
            "sum of (4/3) pi a b c over the final semi-axes / box volume. Kanapy grows the "
            "particles during packing: it starts them at nsteps^(-1/3) of the descriptor's "
            "size and scales them by (t/nsteps)^(1/3) until t reaches about "
            "fill_factor * nsteps, so the final semi-axes are the descriptor's times "
            "about fill_factor^(1/3)"),
        "fill_fraction_descriptor": float(start_volumes.sum() / box_volume),
        "growth_factor_final_over_descriptor": {
            "min": float(growth.min()), "max": float(growth.max())},
        "semi_axes": {
            "a_min": float(axes[:, 0].min()), "a_max": float(axes[:, 0].max()),
            "b_min": float(axes[:, 1].min()), "b_max": float(axes[:, 1].max()),
            "aspect_a_over_b_min": float(aspect.min()),
            "aspect_a_over_b_max": float(aspect.max()),
            "prolate_count": int((aspect > 1.0).sum()),
            "oblate_count": int((aspect < 1.0).sum()),
        },
        "tilt_deg_min_max": [float(tilt.min()), float(tilt.max())],
        "timing": {
            "step": "Microstructure.pack() (particle generation, growth, final overlap scan)",
            "wall_s": wall,
            "cpu_s": cpu,
            "clocks": "time.perf_counter and time.process_time around ms.pack()",
            "machine": platform.processor() or platform.machine(),
            "cpus": os.cpu_count(),
        },
        "overlaps": {
            "kanapy_reported": kanapy_overlaps,
            "kanapy_reported_note": "Kanapy's own count after packing (collide_detect, "
                                    "pairs within bounding spheres, its periodic copies)",
            "pairs_overlapping_R": n_over,
            "min_contact_function_R": f_min,
            "pairs_overlapping_RT": n_over_t,
            "min_contact_function_RT": f_min_t,
            "note": "Perram-Wertheim contact function over every periodic image (own "
                    "included), written here; F < 1 is an overlap. R: the orientation in "
                    "kanapy.csv (Kanapy's collision test); RT: its transpose (Kanapy's "
                    "bounding boxes and voxelization)",
        },
        "orientation_convention": (
            "qw,qx,qy,qz scalar first, Hamilton, body to world: world = R(q) body + centre; "
            "a along body x. Kanapy: q = (cos t/2, 0, 0, sin t/2), t the tilt angle"),
    }
    with open(args.out / "kanapy.json", "w") as f:
        json.dump(summary, f, indent=2)
        f.write("\n")
    print(f"wrote {args.out / 'kanapy.csv'} and {args.out / 'kanapy.json'}: "
          f"{len(parts)} particles, fill {summary['fill_fraction']:.4f}, "
          f"pack {wall:.1f} s wall, {cpu:.1f} s CPU")


if __name__ == "__main__":
    main()
