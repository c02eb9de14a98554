"""Particles of the fin-drop cask section (cases/mps-fin-drop, README.md): a steel ring with
one radial fin pointing down (-y), on the square lattice of spacing dx (cell centres).

    specimen.py OUT.h5 --spacing DX [--outer 0.4] [--wall 0.06] [--fin-length 0.2] [--fin-thickness 0.015]
                [--imperfection 0] [--imperfection-shape bow|sway] [--tip-radius 0]

(case.yaml's fin: --spacing 0.00375 --fin-length 0.2 --fin-thickness 0.015 --imperfection 0.1.)

The fin is the cells with |x| < t/2 and -(R + L) < y < -(R - wall/2) (rooted half-way into the
wall); the ring the cells with R - wall <= r <= R. `--imperfection A` gives the fin an initial
lateral out-of-straightness, the geometric imperfection of a real fin (0, the default: a
straight fin): the fin's particles below the ring's outer surface (s = -R - y from 0 to L) are
moved along +x (the downhill side of the inclined targets of case.yaml) by
  bow:  A t sin(pi s / L)             a half sine, A t at mid-length (the default shape);
  sway: A t (1 - cos(pi s / L)) / 2   the tip offset by A t, square to the ring at the root and
                                      parallel to it at the tip: the fin's lowest buckling mode
                                      if the cask could move sideways freely (its inertia keeps
                                      it from doing so within an impact, README.md).
`--tip-radius r` rounds the tip's two corners with radius r (at most t/2, a semicircular tip;
0, the default: a square tip): the cells of the last r of the fin outside the rounded corners
are left out (at a spacing of t/4 and r = t/2 the tip row's two outer cells), so the tip
touches the target on a narrow face it can roll on rather than on its full width. Set `fin`: the fin's particles below the
ring's outer surface (y < -R * cos(asin(t / 2R))). Written with the writer of
cases/granite-blast/specimen.py (docs/formats.md).
"""
import argparse
import math
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "granite-blast"))
from specimen import spacing, write  # noqa: E402


def main():
    p = argparse.ArgumentParser()
    p.add_argument("out")
    p.add_argument("--spacing", type=spacing, required=True)
    p.add_argument("--outer", type=float, default=0.4)
    p.add_argument("--wall", type=float, default=0.06)
    p.add_argument("--fin-length", type=float, default=0.2)
    p.add_argument("--fin-thickness", type=float, default=0.015)
    p.add_argument("--imperfection", type=float, default=0.0,
                   help="the fin's initial lateral out-of-straightness, its amplitude as a fraction of the thickness")
    p.add_argument("--imperfection-shape", choices=["bow", "sway"], default="bow")
    p.add_argument("--tip-radius", type=float, default=0.0, help="the radius of the fin tip's rounded corners (m)")
    a = p.parse_args()
    dx, R, L, t = a.spacing, a.outer, a.fin_length, a.fin_thickness
    n = int(math.ceil((R + L) / dx)) + 1
    c = (np.arange(-n, n) + 0.5) * dx
    X, Y = np.meshgrid(c, c, indexing="xy")
    r = np.hypot(X, Y)
    ring = (r >= R - a.wall) & (r <= R)
    fin = (np.abs(X) < t / 2) & (Y > -(R + L)) & (Y < -(R - a.wall / 2))
    if not 0 <= a.tip_radius <= t / 2:
        p.error(f"--tip-radius {a.tip_radius}: expected 0 to half the fin's thickness ({t / 2} m)")
    rc = a.tip_radius
    corner = (Y < -(R + L) + rc) & (np.abs(X) > t / 2 - rc)  # the corner squares, rounded off below
    fin &= ~(corner & (np.hypot(np.abs(X) - (t / 2 - rc), Y - (-(R + L) + rc)) > rc))
    keep = ring | fin
    xy = np.column_stack([X[keep], Y[keep]])
    root = -R * math.cos(math.asin(t / (2 * R)))
    fin_set = np.nonzero((np.abs(xy[:, 0]) < t / 2) & (xy[:, 1] < root))[0]
    if not 0 <= a.imperfection <= 1:
        p.error(f"--imperfection {a.imperfection}: expected a fraction of the fin's thickness in [0, 1]")
    s = np.clip(-R - xy[fin_set, 1], 0.0, L)  # distance below the ring's outer surface on the fin's axis
    shape = (1 - np.cos(math.pi * s / L)) / 2 if a.imperfection_shape == "sway" else np.sin(math.pi * s / L)
    xy[fin_set, 0] += a.imperfection * t * shape
    write(a.out, xy, dx, 1.0, {"fin": fin_set}, {},
          f"fin-drop cask section: ring R {R} m wall {a.wall} m, fin {L} x {t} m ({a.imperfection_shape} {a.imperfection} t, tip radius {rc} m), dx {dx} m "
          "(cases/mps-fin-drop)")
    print(f"{a.out}: {len(xy)} particles ({len(fin_set)} in the fin below the ring, {a.imperfection_shape} {a.imperfection} t), spacing {dx} m")


if __name__ == "__main__":
    main()
