"""Write the 2D particles.h5 (docs/formats.md) of a double cantilever beam on a square lattice.

    specimen.py OUT.h5 --spacing dx --length L --arm-height H --thickness t [--grip G] [--band B]

Particles: the centres of the dx-square cells of the strip 0 <= x <= L, -H <= y <= H, so the
mid-plane y = 0 (where the crack runs) lies half a spacing from the rows on either side and
the lattice is mirror-symmetric about it. Sets: `load_top`, `load_bottom` (one particle per
arm on the load line x = dx/2, the one nearest the arm's mid-height, mirrored: a pin. Both
components prescribed: the two pins hold the rigid-body modes, and the arm rotates about its
pin. Prescribing y alone on the whole end column leaves x-translation and rotation of the body
free, and the run drifts into a growing rigid rotation), `grips` (both arms for x < G: kept
unbreakable so that the loading point cannot tear) and, only with --band, `arms` (particles
farther than B from the mid-plane: with `no_fail: [arms]` only bonds inside |y| < B can
break; the experiment on slender arms in README.md, which did not help). Lengths in metres.
The file writer is cases/granite-blast/specimen.py's.
"""
import argparse
import importlib.util
import os

import numpy as np

_spec = importlib.util.spec_from_file_location(
    "granite_specimen", os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "granite-blast", "specimen.py"))
granite = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(granite)


def main():
    p = argparse.ArgumentParser()
    p.add_argument("out")
    p.add_argument("--spacing", type=granite.spacing, required=True)
    p.add_argument("--length", type=float, required=True)
    p.add_argument("--arm-height", type=float, required=True)
    p.add_argument("--thickness", type=float, default=1e-3)
    p.add_argument("--grip", type=float, default=1e-3)
    p.add_argument("--band", type=float, default=float("inf"))
    a = p.parse_args()
    dx = a.spacing
    nx = int(round(a.length / dx))
    ny = int(round(a.arm_height / dx))
    if abs(nx * dx - a.length) > 1e-9 * a.length or abs(ny * dx - a.arm_height) > 1e-9 * a.arm_height:
        p.error("--length and --arm-height must be whole (positive) numbers of --spacing")
    X, Y = np.meshgrid((np.arange(nx) + 0.5) * dx, (np.arange(-ny, ny) + 0.5) * dx, indexing="xy")
    xy = np.column_stack([X.ravel(), Y.ravel()])
    # Row index (from the bottom) of the pin in the top arm, and its mirror in the bottom arm.
    pin_row = ny + (ny - 1) // 2
    sets = {"load_top": np.array([pin_row * nx]),
            "load_bottom": np.array([(2 * ny - 1 - pin_row) * nx]),
            "grips": np.nonzero(xy[:, 0] < a.grip)[0]}
    if np.isfinite(a.band):
        sets["arms"] = np.nonzero(np.abs(xy[:, 1]) > a.band)[0]
    src = f"double cantilever beam {a.length} x 2 x {a.arm_height} m, lattice dx {dx} m"
    granite.write(a.out, xy, dx, a.thickness, sets, {}, src)
    print(f"{a.out}: {len(xy)} particles ({nx} x {2 * ny}), sets " +
          ", ".join(f"{k} {len(v)}" for k, v in sets.items()))


if __name__ == "__main__":
    main()
