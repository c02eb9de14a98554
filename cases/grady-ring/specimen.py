"""Write a 2D particles.h5 (docs/formats.md) for a thin ring on a polar lattice.

    specimen.py OUT.h5 --radius R --width w --spacing dx --thickness t

Particles sit on concentric circles (radial spacing dx, nw = w/dx circles) with the same
number of particles on every circle (arc spacing ~dx at the mean radius), each carrying the
exact area of its annular sector. A polar lattice keeps the ring free of the staircase
corners a square lattice would give (those would seed fragmentation at fixed places).
Lengths in metres.
"""
import argparse
import math
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from case_specimen import spacing as spacing_arg, write_particles  # noqa: E402  (cases/case_specimen.py)


def main():
    p = argparse.ArgumentParser()
    p.add_argument("out")
    p.add_argument("--radius", type=float, required=True, help="mean radius")
    p.add_argument("--width", type=float, required=True)
    p.add_argument("--spacing", type=spacing_arg, required=True)
    p.add_argument("--thickness", type=float, required=True)
    a = p.parse_args()
    nw = max(1, int(round(a.width / a.spacing)))
    dr = a.width / nw
    n_theta = int(round(2 * math.pi * a.radius / a.spacing))
    if n_theta < 1 or a.width <= 0 or a.radius - 0.5 * a.width < 0:
        p.error(f"--spacing {a.spacing} --radius {a.radius} --width {a.width}: expected 0 < width <= 2 radius "
                "and a spacing below the ring's circumference")
    dtheta = 2 * math.pi / n_theta
    r_in = a.radius - 0.5 * a.width
    pos, vol, spacing = [], [], []
    for k in range(nw):
        r0, r1 = r_in + k * dr, r_in + (k + 1) * dr
        rc = 0.5 * (r0 + r1)
        th = (np.arange(n_theta) + 0.5) * dtheta
        pos.append(np.column_stack([rc * np.cos(th), rc * np.sin(th), np.zeros(n_theta)]))
        area = 0.5 * (r1 * r1 - r0 * r0) * dtheta
        vol.append(np.full(n_theta, area * a.thickness))
        spacing.append(np.full(n_theta, math.sqrt(area)))
    pos, vol, spacing = np.vstack(pos), np.concatenate(vol), np.concatenate(spacing)
    n = len(vol)
    source = f"polar ring R {a.radius} m, width {a.width} m, {nw} x {n_theta} particles"
    write_particles(a.out, pos, vol, spacing, 2, a.thickness, source)
    print(f"{a.out}: {n} particles ({nw} circles x {n_theta}), arc spacing {2 * math.pi * a.radius / n_theta:.3e} m")


if __name__ == "__main__":
    main()
