"""Pictures of the ring-impact runs: plot_ring.py OUT RUN [RUN ...]

For each run OUT/RUN (results.h5 of breccia-mps with fracture): ring_<RUN>_frames.png, the
deformed ring at six times coloured by damage (fraction of cut bonds), and
ring_<RUN>_fragments.png, the last state coloured by fragment. OUT/ring_summary.json
collects the counts (fragments of >= 10 particles, failed particles, cut bonds, first
failure time from history.csv).
"""
import csv
import json
import os
import sys

import h5py
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

FLOOR_Y_MM = -27.5


def load(run_dir):
    with h5py.File(os.path.join(run_dir, "results.h5"), "r") as f:
        x0 = f["particles/position"][:, :2]
        frames = []
        for name in sorted(f["output"].keys()):
            g = f["output"][name]
            frames.append({
                "t_us": float(g.attrs["time_s"]) * 1e6,
                "x": x0 + g["displacement"][:, :2],
                "damage": g["damage"][:] if "damage" in g else np.zeros(len(x0)),
                "fragment": g["fragment"][:] if "fragment" in g else np.zeros(len(x0), dtype=int),
            })
    return frames


def first_failure_us(run_dir):
    with open(os.path.join(run_dir, "history.csv")) as f:
        for row in csv.DictReader(f):
            if int(row["failed_particles"]) > 0:
                return float(row["time_s"]) * 1e6
    return None


def main():
    if len(sys.argv) < 3:
        sys.stderr.write(__doc__)
        sys.exit(2)
    out, runs = sys.argv[1], sys.argv[2:]
    summary = {}
    for run in runs:
        d = os.path.join(out, run)
        frames = load(d)
        pick = np.unique(np.linspace(0, len(frames) - 1, 6).round().astype(int))
        fig, axes = plt.subplots(2, 3, figsize=(13, 8.5), constrained_layout=True)
        for ax, k in zip(axes.flat, pick):
            fr = frames[k]
            sc = ax.scatter(fr["x"][:, 0] * 1e3, fr["x"][:, 1] * 1e3, c=fr["damage"], s=3, cmap="inferno_r",
                            vmin=0, vmax=0.5)
            ax.axhline(FLOOR_Y_MM, color="0.4", lw=2)
            ax.set_title(f"t = {fr['t_us']:.0f} us")
            ax.set_aspect("equal")
            ax.set_xlim(-45, 45)
            ax.set_ylim(-32, 45)
            ax.set_xlabel("x (mm)")
            ax.set_ylabel("y (mm)")
        for ax in list(axes.flat)[len(pick):]:
            ax.axis("off")
        fig.colorbar(sc, ax=axes, label="damage (fraction of cut bonds)", shrink=0.8)
        fig.suptitle(f"PMMA ring, R = 25 mm, wall 5 mm, onto a rigid floor: run {run}")
        fig.savefig(os.path.join(out, f"ring_{run}_frames.png"), dpi=110)
        plt.close(fig)

        last = frames[-1]
        labels = last["fragment"]
        sizes = np.bincount(labels)
        big = np.flatnonzero(sizes >= 10)
        fig, ax = plt.subplots(figsize=(7, 6.5), constrained_layout=True)
        small = ~np.isin(labels, big)
        ax.scatter(last["x"][small, 0] * 1e3, last["x"][small, 1] * 1e3, s=3, c="0.7", label="pieces < 10 particles")
        cmap = plt.get_cmap("tab20")
        for n, lab in enumerate(big):
            m = labels == lab
            ax.scatter(last["x"][m, 0] * 1e3, last["x"][m, 1] * 1e3, s=3, color=cmap(n % 20),
                       label=f"fragment {n + 1}: {sizes[lab]} particles" if n < 12 else None)
        ax.axhline(FLOOR_Y_MM, color="0.4", lw=2)
        ax.set_aspect("equal")
        ax.set_xlabel("x (mm)")
        ax.set_ylabel("y (mm)")
        ax.set_title(f"run {run}, t = {last['t_us']:.0f} us: {len(big)} fragments of >= 10 particles")
        ax.legend(fontsize=7, loc="center", markerscale=3)
        fig.savefig(os.path.join(out, f"ring_{run}_fragments.png"), dpi=110)
        plt.close(fig)

        with open(os.path.join(d, "summary.json")) as f:
            s = json.load(f)
        summary[run] = {
            "fragments_ge_10_particles": int(len(big)),
            "fragment_sizes": [int(sizes[b]) for b in big],
            "pieces_below_10_particles": int(np.sum(sizes < 10)),
            "failed_particles": s.get("failed_particles"),
            "cut_bonds": s.get("cut_bonds"),
            "first_failure_us": first_failure_us(d),
            "wall_time_s": s.get("wall_time_s"),
            "particles": s.get("particles"),
        }
        print(run, json.dumps(summary[run]))
    with open(os.path.join(out, "ring_summary.json"), "w") as f:
        json.dump(summary, f, indent=2)


if __name__ == "__main__":
    main()
