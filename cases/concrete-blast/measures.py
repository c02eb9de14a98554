#!/usr/bin/python3
"""The issue's measures of a concrete-blast run (after breccia-post): large pieces (each more
than 2% of the block's mass) and their share of the mass, fine debris (fragments under 1 g),
radial cracks counted on a ring around the hole, damage on the side faces, and the share of
the mass in particles with damage >= 0.5 (broken_mass_share: a large piece of broken particles
held by softening bonds is a skeleton, not a sound piece).

Usage: measures.py RUN_DIR PARTICLES_H5 [--label TEXT] [--json OUT]
Radial cracks: particles in the ring 40-80 mm from the hole axis and 20-130 mm below the top
face are binned by angle (72 bins of 5 degrees); a crack is a run of consecutive bins whose mean
damage exceeds 0.5 between bins below it. A ring damaged all round counts as 'all' (no
distinct crack: crushed).
Radial cracks on the side faces: the same count along the four side faces unrolled into one
1.2 m loop (particles within 10 mm of a side face, 20-130 mm below the top face, 120 bins of
10 mm): the cracks that have reached the side faces. A crack that runs into a corner is one
run of bins across the corner.
"""
import argparse
import csv
import json
import math

import h5py
import numpy as np

HOLE_AXIS = (0.15, 0.15)   # m, the specimen's hole axis (specimen*.yaml)
TOP = 0.30                 # m, the top face
SIZE = 0.30                # m, the cube's edge


def count_cracks(mean):
    """Runs of bins with mean damage above 0.5 round a closed loop of bins: 'all' if every
    bin is damaged (no distinct crack), else the number of damaged runs."""
    cracked = np.asarray(mean) > 0.5
    if cracked.all():
        return "all"
    start = int(np.argmin(cracked))  # an undamaged bin: count rises from there round the loop
    c = np.roll(cracked, -start)
    return int(np.sum(c[1:] & ~c[:-1]) + (1 if c[0] else 0))


def binned_mean(values, bins, count):
    """Mean of values per bin (0 where a bin is empty)."""
    total = np.bincount(bins, weights=values, minlength=count)
    n = np.bincount(bins, minlength=count)
    return np.where(n > 0, total / np.maximum(n, 1), 0.0)


def ring_cracks(x, damage):
    """Radial cracks crossing the ring 40-80 mm from the hole axis, 20-130 mm below the top."""
    dx, dy = x[:, 0] - HOLE_AXIS[0], x[:, 1] - HOLE_AXIS[1]
    rad = np.hypot(dx, dy)
    depth = TOP - x[:, 2]
    ring = (rad > 0.04) & (rad < 0.08) & (depth > 0.02) & (depth < 0.13)
    ang = (np.degrees(np.arctan2(dy[ring], dx[ring])) + 360.0) % 360.0
    bins = np.minimum((ang / 5.0).astype(int), 71)
    return count_cracks(binned_mean(damage[ring], bins, 72))


def side_face_cracks(x, damage, strip=0.01, bin_width=0.01):
    """Cracks that reach the side faces: the four faces within `strip` of them, 20-130 mm below
    the top, unrolled into one loop (xmin: y, ymax: x, xmax: 300 mm - y, ymin: 300 mm - x,
    each face's particles by their nearest face) and binned along it."""
    dist = np.stack([x[:, 0], SIZE - x[:, 1], SIZE - x[:, 0], x[:, 1]])  # xmin, ymax, xmax, ymin
    face = np.argmin(dist, axis=0)
    depth = TOP - x[:, 2]
    near = (dist.min(axis=0) < strip) & (depth > 0.02) & (depth < 0.13)
    along = np.choose(face, [x[:, 1], x[:, 0], SIZE - x[:, 1], SIZE - x[:, 0]]) + face * SIZE
    count = int(round(4 * SIZE / bin_width))
    bins = np.minimum((along[near] / bin_width).astype(int), count - 1)
    return count_cracks(binned_mean(damage[near], bins, count))


def broken_mass_share(volume, damage):
    """Share of the block's mass (one material: its volume) in particles with damage >= 0.5,
    i.e. that have lost at least half their bonds' share. The fragments count only fully broken
    bonds as cuts (docs/theory.md "Quasi-brittle bonds"), so a large piece whose particles
    are held by bonds near the end of their softening counts as one piece: this share tells
    a sound piece from such a skeleton."""
    return float(np.sum(volume[damage >= 0.5]) / np.sum(volume))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("run")
    ap.add_argument("particles")
    ap.add_argument("--label", default="")
    ap.add_argument("--json")
    a = ap.parse_args()
    masses = []
    with open(f"{a.run}/post/fragments.csv") as f:
        for r in csv.DictReader(f):
            masses.append(float(r["mass_kg"]))
    masses = np.array(masses)
    total = masses.sum()
    large = masses[masses > 0.02 * total]
    debris = masses[masses < 1e-3]
    with h5py.File(a.particles) as p:
        x = p["particles/position"][:]
        volume = p["particles/volume"][:]
    with h5py.File(f"{a.run}/results.h5") as r:
        last = sorted(r["output"].keys())[-1]
        damage = r[f"output/{last}/damage"][:]
        time_s = float(r[f"output/{last}"].attrs.get("time_s", float("nan")))
    radial = ring_cracks(x, damage)
    side = (np.minimum.reduce([x[:, 0], SIZE - x[:, 0], x[:, 1], SIZE - x[:, 1]]) < 0.01)
    out = {
        "label": a.label,
        "time_s": time_s,
        "fragments": int(len(masses)),
        "large_pieces": int(len(large)),
        "large_mass_share": float(large.sum() / total),
        "largest_share": float(masses.max() / total),
        "debris_share_under_1g": float(debris.sum() / total),
        "radial_cracks_ring": radial,
        "radial_cracks_side_faces": side_face_cracks(x, damage),
        "side_face_damaged_share": float(np.mean(damage[side] > 0.5)),
        "broken_mass_share": broken_mass_share(volume, damage),
    }
    print(", ".join(f"{k} {v:.3g}" if isinstance(v, float) else f"{k} {v}" for k, v in out.items()))
    if a.json:
        with open(a.json, "w") as f:
            json.dump(out, f, indent=1)


if __name__ == "__main__":
    main()
