"""Particles of the fin-drop cask section (cases/mps-fin-drop, README.md): a steel ring with
one radial fin pointing down (-y), on the square lattice of spacing dx (cell centres).

    specimen.py OUT.h5 --spacing DX [--outer 0.4] [--wall 0.06] [--fin-length 0.15] [--fin-thickness 0.02]
                [--bow 0]

The fin is the cells with |x| < t/2 and -(R + L) < y < -(R - wall/2) (rooted half-way into the
wall); the ring the cells with R - wall <= r <= R. `--bow A` gives the fin an initial lateral
bow, the geometric imperfection of a real fin: the fin's particles below the ring's outer
surface (s = -R - y from 0 to L) are moved along +x by A t sin(pi s / L) (a half sine, its
largest offset A times the thickness at mid-length; 0, the default: a straight fin). Set `fin`: the fin's particles below the
ring's outer surface (y < -R * cos(asin(t / 2R))). Written with the writer of
cases/granite-blast/specimen.py (docs/formats.md).
"""
import argparse
import math
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "granite-blast"))
from specimen import write  # noqa: E402


def main():
    p = argparse.ArgumentParser()
    p.add_argument("out")
    p.add_argument("--spacing", type=float, required=True)
    p.add_argument("--outer", type=float, default=0.4)
    p.add_argument("--wall", type=float, default=0.06)
    p.add_argument("--fin-length", type=float, default=0.15)
    p.add_argument("--fin-thickness", type=float, default=0.02)
    p.add_argument("--bow", type=float, default=0.0,
                   help="initial lateral bow of the fin, its amplitude at mid-length as a fraction of the thickness")
    a = p.parse_args()
    dx, R, L, t = a.spacing, a.outer, a.fin_length, a.fin_thickness
    n = int(math.ceil((R + L) / dx)) + 1
    c = (np.arange(-n, n) + 0.5) * dx
    X, Y = np.meshgrid(c, c, indexing="xy")
    r = np.hypot(X, Y)
    ring = (r >= R - a.wall) & (r <= R)
    fin = (np.abs(X) < t / 2) & (Y > -(R + L)) & (Y < -(R - a.wall / 2))
    keep = ring | fin
    xy = np.column_stack([X[keep], Y[keep]])
    root = -R * math.cos(math.asin(t / (2 * R)))
    fin_set = np.nonzero((np.abs(xy[:, 0]) < t / 2) & (xy[:, 1] < root))[0]
    if a.bow < 0 or a.bow > 1:
        sys.exit(f"specimen.py: --bow {a.bow}: expected a fraction of the fin's thickness in [0, 1]")
    s = -R - xy[fin_set, 1]  # distance below the ring's outer surface on the fin's axis
    xy[fin_set, 0] += a.bow * t * np.sin(math.pi * np.clip(s, 0.0, L) / L)
    write(a.out, xy, dx, 1.0, {"fin": fin_set}, {},
          f"fin-drop cask section: ring R {R} m wall {a.wall} m, fin {L} x {t} m (bow {a.bow} t), dx {dx} m "
          "(cases/mps-fin-drop)")
    print(f"{a.out}: {len(xy)} particles ({len(fin_set)} in the fin below the ring, bow {a.bow} t), spacing {dx} m")


if __name__ == "__main__":
    main()
