#!/usr/bin/python3
"""Pictures of a concrete-blast run: damage on the four side faces (unfolded, as one would
photograph them) and on a horizontal section through the charge hole at mid-depth of the hole,
coloured by the damage of the last output; and the large fragments (> 2% of the mass) on the
same section, each its own colour.

Usage: pictures.py RUN_DIR PARTICLES_H5 OUT.png [--title TEXT]
"""
import argparse

import h5py
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

SIZE = 0.30
SECTION_Z = 0.225  # m: half way down the hole (150 mm deep from the top face)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("run")
    ap.add_argument("particles")
    ap.add_argument("out")
    ap.add_argument("--title", default="")
    a = ap.parse_args()
    with h5py.File(a.particles) as p:
        x = p["particles/position"][:]
        spacing = p["particles/spacing"][:]
    with h5py.File(f"{a.run}/results.h5") as r:
        last = sorted(r["output"].keys())[-1]
        damage = r[f"output/{last}/damage"][:]
        t = float(r[f"output/{last}"].attrs["time_s"])
    frag = None
    try:
        import meshio
        m = meshio.read(f"{a.run}/post/fragments.vtu")
        for name, data in m.point_data.items():
            if "fragment" in name:
                frag = np.asarray(data).ravel()
        if frag is None:
            for name, blocks in m.cell_data.items():
                if "fragment" in name:
                    frag = np.concatenate([np.asarray(b).ravel() for b in blocks])
    except Exception:
        frag = None
    fig, axes = plt.subplots(2, 3, figsize=(14, 9), dpi=110, layout="constrained")
    faces = [("x = 0", x[:, 0] < 0.012, 1, 2), ("x = 300 mm", x[:, 0] > SIZE - 0.012, 1, 2),
             ("y = 0", x[:, 1] < 0.012, 0, 2), ("y = 300 mm", x[:, 1] > SIZE - 0.012, 0, 2)]
    for ax, (name, sel, h, v) in zip(axes.ravel()[:4], faces):
        sc = ax.scatter(x[sel, h] * 1e3, x[sel, v] * 1e3, c=damage[sel], s=(spacing[sel] * 1e3) ** 2 * 0.9,
                        cmap="inferno_r", vmin=0, vmax=1, marker="s", linewidths=0)
        ax.set_title(f"side face {name}")
        ax.set_aspect("equal")
        ax.set_xlim(0, 300)
        ax.set_ylim(0, 300)
        ax.set_xlabel("mm")
    sec = np.abs(x[:, 2] - SECTION_Z) < 0.5 * spacing + 1e-4
    ax = axes.ravel()[4]
    ax.scatter(x[sec, 0] * 1e3, x[sec, 1] * 1e3, c=damage[sec], s=(spacing[sec] * 1e3) ** 2 * 0.9,
               cmap="inferno_r", vmin=0, vmax=1, marker="s", linewidths=0)
    ax.set_title(f"section z = {SECTION_Z * 1e3:.0f} mm: damage")
    ax.set_aspect("equal")
    ax = axes.ravel()[5]
    if frag is not None and len(frag) == len(x):
        ids, counts = np.unique(frag, return_counts=True)
        big = ids[np.argsort(-counts)[:20]]
        colour = np.full(len(x), -1.0)
        for k, f in enumerate(big):
            colour[frag == f] = k
        s = sec & (colour >= 0)
        ax.scatter(x[sec & (colour < 0), 0] * 1e3, x[sec & (colour < 0), 1] * 1e3, c="0.85", s=2, marker="s")
        ax.scatter(x[s, 0] * 1e3, x[s, 1] * 1e3, c=colour[s], cmap="tab20", vmin=0, vmax=19,
                   s=(spacing[s] * 1e3) ** 2 * 0.9, marker="s", linewidths=0)
        ax.set_title("section: the 20 largest fragments (grey: smaller)")
    else:
        ax.set_title("section: fragments (fragments.vtu not readable)")
    ax.set_aspect("equal")
    fig.colorbar(sc, ax=axes.ravel()[4], shrink=0.8, label="damage")
    fig.suptitle(a.title or f"concrete block at t = {t * 1e6:.0f} us")
    fig.savefig(a.out)


if __name__ == "__main__":
    main()
