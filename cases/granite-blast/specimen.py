"""Write a 2D particles.h5 (docs/formats.md) for an annulus on a square lattice.

    specimen.py OUT.h5 --outer R --inner r --spacing dx --thickness t [--inner-surface NAME]

Particles: the centres of the dx-square lattice cells (lattice aligned with the centre
(0, 0)) whose centre lies in r <= |x| <= R. Sets: `outer` (particles within dx of R) and,
when r > 0, `hole` (within dx of r). Surface `hole`: one facet per hole-wall particle
(facet = the arc share of that particle, normal pointing into the hole), so a pressure on it
pushes the wall outwards with the exact total force p * 2 pi r * t. Lengths in metres.
"""
import argparse
import math
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from case_specimen import spacing, write_particles  # noqa: E402,F401  (cases/case_specimen.py; spacing: --spacing's type for the other specimen scripts)


def annulus(outer, inner, dx):
    n = int(math.ceil(outer / dx)) + 1
    c = (np.arange(-n, n) + 0.5) * dx
    X, Y = np.meshgrid(c, c, indexing="xy")
    r = np.hypot(X, Y)
    keep = (r <= outer) & (r >= inner)
    return np.column_stack([X[keep], Y[keep]]), r[keep]


def write(path, xy, dx, thickness, sets, surfaces, source, dimension=2):
    """xy: (n, 2) positions in 2D (volume dx^2 thickness), or (n, 3) with dimension=3 (dx^3)."""
    n = len(xy)
    pos = np.zeros((n, 3))
    pos[:, : xy.shape[1]] = xy
    vol = np.full(n, dx * dx * (thickness if dimension == 2 else dx))
    write_particles(path, pos, vol, np.full(n, dx), dimension, thickness, source, sets, surfaces)


def main():
    p = argparse.ArgumentParser()
    p.add_argument("out")
    p.add_argument("--outer", type=float, required=True)
    p.add_argument("--inner", type=float, default=0.0)
    p.add_argument("--spacing", type=spacing, required=True)
    p.add_argument("--thickness", type=float, required=True)
    p.add_argument("--inner-surface", default="hole")
    a = p.parse_args()
    dx = a.spacing
    xy, r = annulus(a.outer, a.inner, dx)
    if len(xy) == 0:
        p.error(f"--spacing {dx} --outer {a.outer} --inner {a.inner}: no particles; expected 0 <= inner < outer "
                "and a spacing smaller than the annulus")
    sets = {"outer": np.nonzero(r > a.outer - dx)[0]}
    # The rim as a surface too (a vent surface of the gas load): equal shares of the
    # circumference along the outward radial direction.
    rim = sets["outer"]
    nrm_out = xy[rim] / r[rim, None]
    surfaces = {"outer": {
        "area": np.full(len(rim), 2 * math.pi * a.outer * a.thickness / len(rim)),
        "normal": np.column_stack([nrm_out, np.zeros(len(rim))]),
        "centroid": np.column_stack([nrm_out * a.outer, np.zeros(len(rim))]),
        "particle": rim.astype(np.int64),
    }}
    if a.inner > 0:
        wall = np.nonzero(r < a.inner + dx)[0]
        sets[a.inner_surface] = wall
        # Each wall particle carries an equal share of the hole circumference along its own
        # radial direction: total force p 2 pi r t, zero net force by symmetry.
        m = len(wall)
        if m == 0:
            p.error(f"--spacing {dx}: no particle on the hole wall (r < {a.inner} + spacing); expected a finer spacing")
        nrm = -xy[wall] / r[wall, None]
        surfaces[a.inner_surface] = {
            "area": np.full(m, 2 * math.pi * a.inner * a.thickness / m),
            "normal": np.column_stack([nrm, np.zeros(m)]),
            "centroid": np.column_stack([-nrm * a.inner, np.zeros(m)]),
            "particle": wall.astype(np.int64),
        }
    src = f"annulus R {a.outer} m, r {a.inner} m, square lattice spacing {dx} m"
    write(a.out, xy, dx, a.thickness, sets, surfaces, src)
    print(f"{a.out}: {len(xy)} particles, sets " + ", ".join(f"{k} {len(v)}" for k, v in sets.items()))


if __name__ == "__main__":
    main()
