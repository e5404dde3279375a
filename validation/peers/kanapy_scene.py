"""The ellipack scene of Kanapy's packing: the same items, a periodic cube, Kanapy's fill fraction.

Usage (after kanapy_example.py --out DIR; needs only the standard library):

    python kanapy_scene.py DIR [--seed 1] [--time-limit 900] [--no-orientations] [--fixed]

Reads DIR/kanapy.json and DIR/kanapy.csv and writes:

- DIR/items.csv: one row per Kanapy particle, header a, b, c, qw, qx, qy, qz: Kanapy's final
  semi-axes (after its growth) in Kanapy's own order, not sorted: a is the body-x axis,
  the long one of a prolate particle (b = c) and the short one of the few oblate ones
  (aspect ratio < 1). Kept in that order so that the quaternion, Kanapy's orientation in
  the convention of docs/files.md (Hamilton, column k carries semi-axis k), still fits
  them. ellipack starts each item at that orientation; with --no-orientations the columns
  are left out and the start is isotropic.
- DIR/ellipack.toml: `[container] kind = "periodic"` with `packing_fraction` = Kanapy's
  fill fraction, and `[solver] start = "random"`. ellipack's cell is a cube whose volume is
  the items' volume over that fraction, so it has the volume of Kanapy's box; should
  Kanapy's box not be a cube, the shapes differ (a note says so).
  With --fixed the items keep their start orientations through the compression, as
  Kanapy's particles do (Kanapy only translates them); without it they may turn.
"""

import argparse
import csv
import json
import math
from pathlib import Path


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("dir", type=Path, help="the folder of kanapy_example.py --out")
    parser.add_argument("--seed", type=int, default=1, help="ellipack's seed")
    parser.add_argument("--time-limit", type=float, default=900.0,
                        help="ellipack's [solver] time_limit in seconds")
    parser.add_argument("--no-orientations", action="store_true",
                        help="leave Kanapy's orientations out (isotropic start)")
    parser.add_argument("--fixed", action="store_true",
                        help="hold each item's start orientation through the compression")
    args = parser.parse_args()
    if args.fixed and args.no_orientations:
        parser.error("--fixed keeps Kanapy's orientations: it needs them in items.csv")

    summary = json.loads((args.dir / "kanapy.json").read_text())
    with open(args.dir / "kanapy.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    if len(rows) != summary["n_particles"]:
        raise SystemExit(f"kanapy.csv has {len(rows)} rows, kanapy.json says "
                         f"{summary['n_particles']} particles")

    columns = ["a", "b", "c"] + ([] if args.no_orientations else ["qw", "qx", "qy", "qz"])
    with open(args.dir / "items.csv", "w", newline="") as f:
        f.write(",".join(columns) + "\n")
        for row in rows:
            values = [float(row[k]) for k in columns]
            if not args.no_orientations:
                # ellipack holds quaternions to |q|^2 = 1 within 1e-6: renormalise what
                # went through text.
                norm = math.sqrt(sum(v * v for v in values[3:]))
                values[3:] = [v / norm for v in values[3:]]
            f.write(",".join(repr(v) for v in values) + "\n")

    # Recomputed from the semi-axes written, so that the cell ellipack makes from this
    # fraction has Kanapy's box volume to rounding.
    volume = sum(4.0 / 3.0 * math.pi * float(r["a"]) * float(r["b"]) * float(r["c"])
                 for r in rows)
    lengths = summary["box_lengths"]
    box_volume = math.prod(lengths)
    fraction = volume / box_volume
    cubic = all(math.isclose(x, lengths[0]) for x in lengths)
    sched = summary["schedule"]

    lines = [
        f"# Kanapy {summary['kanapy_version']}'s packing of its example descriptor, for ellipack:",
        f"# {summary['n_particles']} items ({'Kanapy orientations' if not args.no_orientations else 'isotropic start'}"
        f"{', held fixed' if args.fixed else ''}) from items.csv, at Kanapy's fill fraction.",
        f"# Kanapy: seed {summary['seed']}, nsteps {sched['nsteps']}, fill_factor "
        f"{sched['fill_factor']}, box {' x '.join(f'{x:g}' for x in lengths)} (periodic).",
    ]
    if not cubic:
        lines.append("# Kanapy's box is not cubic: ellipack's cell is the cube of the same volume "
                     f"(side {box_volume ** (1.0 / 3.0):.6g}).")
    lines += [
        f"# ellipack pack {args.dir / 'ellipack.toml'} --out OUT",
        "dimension = 3",
        f"seed = {args.seed}",
        "",
        "[container]",
        'kind = "periodic"',
        f"packing_fraction = {fraction!r}",
        "",
        "[[shapes]]",
        'file = "items.csv"',
    ]
    if args.fixed:
        lines.append("orientation = { fixed = true }")
    lines += [
        "",
        "[solver]",
        'start = "random"',
        f"time_limit = {args.time_limit!r}",
        "",
        "[output]",
        "pictures = false",
        "",
    ]
    (args.dir / "ellipack.toml").write_text("\n".join(lines))
    print(f"wrote {args.dir / 'items.csv'} and {args.dir / 'ellipack.toml'}: "
          f"{len(rows)} items, packing_fraction {fraction:.6f}"
          + ("" if cubic else " (Kanapy's box is not cubic: same volume, cubic cell)"))


if __name__ == "__main__":
    main()
