"""What the cases' specimen.py scripts share: writing particles.h5 (docs/formats.md) and its
content_id.

Imported by cases/*/specimen.py (each puts cases/ on sys.path). Each case's geometry stays in
its own specimen.py.
"""
import argparse
import math
import os
import sys

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


def spacing(text):
    """argparse type of the specimen scripts' --spacing: a finite length > 0 (m)."""
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"expected a finite lattice spacing > 0 (m), got '{text}'")
    return value


def write_particles(path, pos, vol, spacing, dimension, thickness, source, sets=None, surfaces=None):
    """pos (n, 3) positions, vol and spacing (n,), one material "default". sets: name -> particle
    indices; surfaces: name -> {area, normal, centroid, particle}. Written to path + ".partial",
    then moved to path, so a file at path is always complete."""
    n = len(vol)
    if n == 0:  # a spacing larger than the specimen, or dimensions that leave nothing
        print(f"{os.path.basename(sys.argv[0])}: no particles for {source}: expected a --spacing smaller than "
              "the specimen's dimensions (and positive dimensions); nothing written", file=sys.stderr)
        sys.exit(2)
    # The folder too (the case READMEs write run/particles.h5 before the solver makes run/).
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
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
        f["particles/spacing"] = spacing
        f["particles/material_id"] = np.zeros(n, dtype=np.int32)
        f.create_dataset("materials/names", data=[b"default"], dtype=h5py.string_dtype(encoding="ascii"))
        f.create_group("sets")
        for name, idx in (sets or {}).items():
            f["sets"][name] = np.asarray(idx, dtype=np.int64)
        f.create_group("surfaces")
        for name, s in (surfaces or {}).items():
            g = f["surfaces"].create_group(name)
            for key in ("area", "normal", "centroid", "particle"):
                g[key] = s[key]
    os.replace(path + ".partial", path)
