#!/usr/bin/env python3
"""Stand-in outputs on a real bond list, for timing breccia-post when the solve cannot finish.

Takes a results.h5 that breccia-solve has started (format 2: particles, the bond list
/bonds, output 0) and writes DIR/results.h5 with the same static part and OUTPUTS output
groups whose broken bits grow, from the charge-hole axis outwards with scatter, to
FINAL_FRACTION of all bonds (0.976: 29.6 of 30.3 million in the full concrete run of
2026-11-23). Displacements are a radial push away from the axis. This is a workload of the
same size as the real run's (particles, bonds, broken bonds, outputs), NOT its physics:
use it for timing only. docs/performance.md, "Post-processing".

usage: make_standin_run.py SOURCE_RESULTS_H5 OUT_DIR [--outputs 10] [--final-fraction 0.976]
       [--every 200] [--last-step 1649] [--dt 4.2445e-7] [--axis 0.15 0.15] [--z 0.15 0.3]
"""
import argparse
import os
import sys

import h5py
import numpy as np


def write(group, name, data):
    """As breccia-solve writes big arrays: chunks of 65536 rows, deflate level 1."""
    kwargs = {}
    if data.size > 65536:
        kwargs = {"chunks": (min(data.shape[0], 65536),) + data.shape[1:], "compression": "gzip",
                  "compression_opts": 1}
    group.create_dataset(name, data=data, **kwargs)


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("source")
    p.add_argument("out_dir")
    p.add_argument("--outputs", type=int, default=10)
    p.add_argument("--final-fraction", type=float, default=0.976)
    p.add_argument("--every", type=int, default=200)
    p.add_argument("--last-step", type=int, default=1649)
    p.add_argument("--dt", type=float, default=4.2445e-7)
    p.add_argument("--axis", type=float, nargs=2, default=[0.15, 0.15], help="hole axis x y [m]")
    p.add_argument("--z", type=float, nargs=2, default=[0.15, 0.30], help="hole bottom and top z [m]")
    p.add_argument("--seed", type=int, default=1)
    a = p.parse_args()
    src = h5py.File(a.source, "r")
    if int(src.attrs["format_version"]) != 2 or "bonds" not in src:
        sys.exit(f"error: {a.source}: /@format_version: expected 2 with /bonds (breccia-solve results)")
    os.makedirs(a.out_dir, exist_ok=True)
    dst = h5py.File(os.path.join(a.out_dir, "results.h5"), "w")
    for k, v in src.attrs.items():
        dst.attrs[k] = v
    for name in ("particles", "materials", "precrack_bonds", "bonds"):
        if name in src:
            src.copy(src[name], dst, name=name)
    dst.create_group("output")

    pos = src["particles/position"][:]
    off = src["bonds/offsets"][:]
    nb = src["bonds/neighbors"][:]
    n, b = pos.shape[0], nb.shape[0]
    i = np.repeat(np.arange(n, dtype=np.int64), np.diff(off))
    # Distance of each bond's midpoint from the hole (a segment on the axis), plus scatter.
    mid = 0.5 * (pos[i] + pos[nb])
    z = np.clip(mid[:, 2], a.z[0], a.z[1])
    d = np.sqrt((mid[:, 0] - a.axis[0]) ** 2 + (mid[:, 1] - a.axis[1]) ** 2 + (mid[:, 2] - z) ** 2)
    del mid, z
    rng = np.random.default_rng(a.seed)
    score = d / d.max() + 0.3 * rng.random(b)
    rank = np.empty(b, dtype=np.int64)
    rank[np.argsort(score, kind="stable")] = np.arange(b)
    del score
    degree = np.bincount(i, minlength=n) + np.bincount(nb, minlength=n)
    r_xy = np.hypot(pos[:, 0] - a.axis[0], pos[:, 1] - a.axis[1])
    radial = np.zeros_like(pos)
    radial[:, 0] = (pos[:, 0] - a.axis[0]) / np.maximum(r_xy, 1e-12)
    radial[:, 1] = (pos[:, 1] - a.axis[1]) / np.maximum(r_xy, 1e-12)
    steps = [min(k * a.every, a.last_step) for k in range(a.outputs - 1)] + [a.last_step]
    for k, step in enumerate(steps):
        frac = a.final_fraction * np.sqrt(k / (a.outputs - 1)) if a.outputs > 1 else a.final_fraction
        broken = rank < int(round(frac * b))
        g = dst.create_group(f"output/{k:06d}")
        t = step * a.dt
        g.attrs["step"] = np.int64(step)
        g.attrs["time_s"] = t
        g.attrs["broken_count"] = np.int64(broken.sum())
        hits = np.bincount(i, weights=broken, minlength=n) + np.bincount(nb, weights=broken, minlength=n)
        write(g, "damage", hits / np.maximum(degree, 1))
        u = radial * (2e-3 * frac)
        write(g, "displacement", u)
        write(g, "velocity", u / t if t > 0 else np.zeros_like(u))
        write(g, "broken", np.packbits(broken, bitorder="little"))
        print(f"output {k}: step {step}, {int(broken.sum())} of {b} bonds broken", flush=True)
    dst.attrs["output_count"] = np.int64(len(steps))
    dst.attrs["complete"] = np.int64(1)
    dst.close()


if __name__ == "__main__":
    main()
