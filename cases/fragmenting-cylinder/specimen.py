"""Particles of cases/fragmenting-cylinder: a steel tube on the cubic lattice of spacing dx
(cell centres with R_in <= sqrt(x^2 + y^2) <= R_out and 0 <= z <= H; the lattice axis along a
cell corner, so the tube is symmetric under x -> -x, y -> -y).

    specimen.py OUT.h5 --spacing DX [--outer 0.025] [--inner 0.02] [--height 0.1]

Written with the writer of cases/granite-blast/specimen.py (docs/formats.md), no sets: the
case names its regions itself (`sets:` in case.yaml).
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
    p.add_argument("--outer", type=float, default=0.025)
    p.add_argument("--inner", type=float, default=0.02)
    p.add_argument("--height", type=float, default=0.1)
    a = p.parse_args()
    dx = a.spacing
    n = int(math.ceil(a.outer / dx))
    c = (np.arange(-n, n) + 0.5) * dx
    layers = int(round(a.height / dx))
    z = (np.arange(layers) + 0.5) * dx
    X, Y, Z = np.meshgrid(c, c, z, indexing="ij")
    r = np.hypot(X, Y)
    keep = (r >= a.inner) & (r <= a.outer)
    xyz = np.column_stack([X[keep], Y[keep], Z[keep]])
    write(a.out, xyz, dx, dx, {}, {}, f"tube R {a.inner}-{a.outer} m, height {a.height} m, dx {dx} m "
          "(cases/fragmenting-cylinder)", dimension=3)
    print(f"{a.out}: {len(xyz)} particles, spacing {dx} m")


if __name__ == "__main__":
    main()
