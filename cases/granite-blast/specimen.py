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

import h5py
import numpy as np


def fnv1a64(*arrays):
    """content_id of common/src/particle_file.cpp: FNV-1a 64 over the raw bytes."""
    h = 1469598103934665603
    for a in arrays:
        for byte in np.ascontiguousarray(a).tobytes():
            h ^= byte
            h = (h * 1099511628211) & 0xFFFFFFFFFFFFFFFF
    return f"{h:016x}"


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
    with h5py.File(path + ".partial", "w") as f:
        f.attrs["format"] = np.bytes_("breccia-particles")
        f.attrs["format_version"] = np.int64(1)
        f.attrs["dimension"] = np.int64(dimension)
        f.attrs["thickness_m"] = float(thickness)
        f.attrs["units"] = np.bytes_("SI (m, m3, kg, s)")
        f.attrs["source"] = np.bytes_(source)
        f.attrs["content_id"] = np.bytes_(fnv1a64(pos, vol))
        f["particles/position"] = pos
        f["particles/volume"] = vol
        f["particles/spacing"] = np.full(n, dx)
        f["particles/material_id"] = np.zeros(n, dtype=np.int32)
        f.create_dataset("materials/names", data=[b"default"], dtype=h5py.string_dtype(encoding="ascii"))
        f.create_group("sets")
        for name, idx in sets.items():
            f["sets"][name] = np.asarray(idx, dtype=np.int64)
        f.create_group("surfaces")
        for name, s in surfaces.items():
            g = f["surfaces"].create_group(name)
            for key in ("area", "normal", "centroid", "particle"):
                g[key] = s[key]
    import os
    os.replace(path + ".partial", path)


def main():
    p = argparse.ArgumentParser()
    p.add_argument("out")
    p.add_argument("--outer", type=float, required=True)
    p.add_argument("--inner", type=float, default=0.0)
    p.add_argument("--spacing", type=float, required=True)
    p.add_argument("--thickness", type=float, required=True)
    p.add_argument("--inner-surface", default="hole")
    a = p.parse_args()
    dx = a.spacing
    xy, r = annulus(a.outer, a.inner, dx)
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
