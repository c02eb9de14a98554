#!/usr/bin/env python3
"""Colliding rubber rings: the rings at several times and the energy history.

usage: plot_rings.py RUN_DIR FIGURE.png NUMBERS.json
RUN_DIR holds results.h5 and history.csv of breccia-mps (energy: true). The top row shows
the particles at six times coloured by the von Mises stress; the bottom panel the kinetic,
stress-work (elastic), hourglass and contact energies and their sum, relative to the start.
NUMBERS.json: centre-of-mass velocities at the end, contact interval, energy error.
"""
import json
import sys

import h5py
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np


def main(run_dir, figure, numbers):
    hist = np.genfromtxt(f"{run_dir}/history.csv", delimiter=",", names=True)
    t = hist["time_s"]
    kinetic, work = hist["kinetic_energy_J"], hist["stress_work_J"]
    hourglass, contact = hist["hourglass_energy_J"], hist["contact_energy_J"]
    total = kinetic + work + hourglass + contact
    e0 = total[0]
    with h5py.File(f"{run_dir}/results.h5", "r") as f:
        x0 = f["/particles/position"][:]
        vol = f["/particles/volume"][:]
        names = sorted(f["/output"].keys())
        times = np.array([f["/output"][k].attrs["time_s"] for k in names])
        left = x0[:, 0] < 0
        wanted = [0.0, 0.25e-3, 0.5e-3, 0.75e-3, 1.0e-3, 1.25e-3, 1.5e-3, times[-1]]
        picks = sorted({int(np.argmin(np.abs(times - w))) for w in wanted})
        frames = []
        for k in picks:
            g = f["/output"][names[k]]
            x = x0 + g["displacement"][:]
            s = g["stress"][:]
            vm = np.sqrt(0.5 * ((s[:, 0] - s[:, 1]) ** 2 + (s[:, 1] - s[:, 2]) ** 2 + (s[:, 2] - s[:, 0]) ** 2)
                         + 3 * (s[:, 3] ** 2 + s[:, 4] ** 2 + s[:, 5] ** 2))
            frames.append((times[k], x, vm))
        v_end = f["/output"][names[-1]]["velocity"][:]
    v_left = float((v_end[left, 0] * vol[left]).sum() / vol[left].sum())
    v_right = float((v_end[~left, 0] * vol[~left]).sum() / vol[~left].sum())
    v0 = float(np.abs(hist["left_inner_velocity_x"][0])) if "left_inner_velocity_x" in hist.dtype.names else 50.268
    in_contact = t[contact > 0]

    fig = plt.figure(figsize=(15, 11))
    vmax = max(fr[2].max() for fr in frames) / 1e6
    columns = (len(frames) + 1) // 2
    for n, (time, x, vm) in enumerate(frames):
        ax = fig.add_subplot(3, columns, n + 1)
        sc = ax.scatter(x[:, 0] * 100, x[:, 1] * 100, c=vm / 1e6, s=1.0, cmap="viridis", vmin=0, vmax=vmax)
        ax.set_aspect("equal")
        # Frames follow the rings (they fly apart after the rebound); equal scales.
        half = max(10.0, 0.5 * (x[:, 0].max() - x[:, 0].min()) * 100 + 1.0)
        ax.set_xlim(-half, half)
        ax.set_ylim(-6, 6)
        ax.set_title(f"t = {time * 1e3:.2f} ms")
        ax.set_xlabel("x (cm)")
        if n % columns == 0:
            ax.set_ylabel("y (cm)")
    cax = fig.add_axes([0.92, 0.40, 0.01, 0.45])
    fig.colorbar(sc, cax=cax, label="von Mises stress (MPa)")
    ax = fig.add_subplot(3, 1, 3)
    ax.plot(t * 1e3, kinetic / e0, label="kinetic")
    ax.plot(t * 1e3, work / e0, label="stress work (elastic)")
    ax.plot(t * 1e3, hourglass / e0, label="hourglass")
    ax.plot(t * 1e3, contact / e0, label="contact penalty")
    ax.plot(t * 1e3, total / e0, "k", lw=2, label="sum")
    if in_contact.size:
        ax.axvspan(in_contact.min() * 1e3, in_contact.max() * 1e3, color="0.9", label="rings in contact")
    ax.set_xlabel("time (ms)")
    ax.set_ylabel("energy / initial kinetic energy")
    ax.set_ylim(-0.05, 1.1)
    ax.grid(alpha=0.3)
    ax.legend(loc="center right")
    ax.set_title(f"end: centre velocities {v_left:.1f} / {v_right:.1f} m/s (start +-{v0:.1f}); "
                 f"sum within {100 * np.max(np.abs(total / e0 - 1)):.2f}% of the start")
    fig.suptitle("Colliding rubber rings (Gray, Monaghan & Swift 2001), stress-based MPS, frictionless particle contact")
    fig.savefig(figure, dpi=110, bbox_inches="tight")
    out = {
        "centre_velocity_left_m_s": v_left,
        "centre_velocity_right_m_s": v_right,
        "initial_speed_m_s": v0,
        "rebound_ratio": -v_left / v0,
        "contact_start_ms": float(in_contact.min() * 1e3) if in_contact.size else None,
        "contact_end_ms": float(in_contact.max() * 1e3) if in_contact.size else None,
        "worst_energy_error": float(np.max(np.abs(total / e0 - 1))),
        "final_energy_error": float(total[-1] / e0 - 1),
        "particles": int(len(x0)),
    }
    with open(numbers, "w") as f:
        json.dump(out, f, indent=1)
    print(json.dumps(out))


if __name__ == "__main__":
    if len(sys.argv) != 4:
        sys.stderr.write(__doc__)
        sys.exit(2)
    main(*sys.argv[1:])
