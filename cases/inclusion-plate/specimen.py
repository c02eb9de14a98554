"""Write the 2D particles.h5 of the inclusion plate: a square lattice with two materials.

    specimen.py OUT.h5 --spacing dx [--fraction 0.2 --radius 0.15e-3 --seed 1]

Lattice: nodes i dx (x: 0 ... 3 mm) and j dx (y: -3 dx ... 3 mm + 3 dx), i.e. the 3 x 3 mm
plate plus 3 loading rows above and below (201 x 207 = 41,607 particles at dx = 15 um, the
seed's count). Inclusions: non-overlapping circles of one radius at random centres (numpy
seed), drawn until their area reaches the fraction of the plate; they keep one radius clear
of the loaded rows and of the notch line y = 1.5 mm for x < 0.3 mm + radius, so the notch tip
sits in matrix. Materials by name: 0 `matrix`, 1 `inclusion`. Sets: `load_rows_bottom`,
`load_rows_top` (the loading rows). The file writer is cases/granite-blast/specimen.py's.
"""
import argparse
import importlib.util
import math
import os

import h5py
import numpy as np

_spec = importlib.util.spec_from_file_location(
    "granite_specimen", os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "granite-blast", "specimen.py"))
granite = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(granite)

SIDE = 3e-3
NOTCH = 0.3e-3
ROWS = 3


def inclusions(fraction, radius, seed):
    rng = np.random.default_rng(seed)
    target = math.ceil(fraction * SIDE * SIDE / (math.pi * radius * radius))
    centres = []
    for _ in range(200000):
        if len(centres) == target:
            break
        c = rng.uniform([radius, 2 * radius], [SIDE - radius, SIDE - 2 * radius])
        if c[0] < NOTCH + 2 * radius and abs(c[1] - SIDE / 2) < 1.5 * radius:
            continue
        # Gap of 0.1 radius between inclusions: touching circles would merge into one particle cluster.
        if all(np.hypot(*(c - o)) >= 2.1 * radius for o in centres):
            centres.append(c)
    if len(centres) < target:
        raise SystemExit(f"specimen: only {len(centres)} of {target} inclusions fit")
    return np.array(centres)


def main():
    p = argparse.ArgumentParser()
    p.add_argument("out")
    p.add_argument("--spacing", type=granite.spacing, required=True)
    p.add_argument("--fraction", type=float, default=0.2)
    p.add_argument("--radius", type=float, default=0.15e-3)
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--thickness", type=float, default=1e-3)
    a = p.parse_args()
    dx = a.spacing
    n = int(round(SIDE / dx))
    if n < 1:
        p.error(f"--spacing {dx}: expected a spacing below the plate's side ({SIDE} m)")
    X, Y = np.meshgrid(np.arange(n + 1) * dx, np.arange(-ROWS, n + ROWS + 1) * dx, indexing="xy")
    xy = np.column_stack([X.ravel(), Y.ravel()])
    sets = {"load_rows_bottom": np.nonzero(xy[:, 1] < -0.5 * dx)[0],
            "load_rows_top": np.nonzero(xy[:, 1] > SIDE + 0.5 * dx)[0]}
    centres = inclusions(a.fraction, a.radius, a.seed)
    d = np.min(np.hypot(xy[:, None, 0] - centres[None, :, 0], xy[:, None, 1] - centres[None, :, 1]), axis=1)
    inside = d <= a.radius
    src = (f"inclusion plate 3 x 3 mm, dx {dx} m, {len(centres)} inclusions r {a.radius} m "
           f"(fraction {a.fraction}, seed {a.seed})")
    granite.write(a.out, xy, dx, a.thickness, sets, {}, src)
    with h5py.File(a.out, "a") as f:  # content_id covers positions and volumes only
        f["particles/material_id"][:] = inside.astype(np.int32)
        del f["materials/names"]
        f.create_dataset("materials/names", data=[b"matrix", b"inclusion"], dtype=h5py.string_dtype(encoding="ascii"))
        f["inclusions/centre"] = centres
        f["inclusions"].attrs["radius_m"] = a.radius
    print(f"{a.out}: {len(xy)} particles, {len(centres)} inclusions, particle area fraction "
          f"{inside[(xy[:, 1] >= 0) & (xy[:, 1] <= SIDE)].mean():.3f}")


if __name__ == "__main__":
    main()
