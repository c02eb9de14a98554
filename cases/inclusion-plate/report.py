"""Measure the crack paths of the inclusion-plate runs.

    report.py OUT RUN [RUN ...]      (RUN: a solver output folder under OUT)

Damaged particle, crack-tip history and band counting are those of
cases/glass-branching/report.py (damage > 0.35 and not already at t = 0; bands on a lattice
column separated by more than 1.5 dx), with the notch tip at (0.3, 1.5) mm. Per run:
- branching: the largest number of separate damage bands on one vertical line right of the
  notch tip (1: one crack; >= 2: branches);
- crack share in inclusions: the fraction of the damaged particles that are inclusion
  particles, against the inclusion area fraction (a crack that avoids inclusions stays well
  below it); inclusions cut: inclusions with more than a quarter of their particles damaged;
- crack reach: the largest x of a damaged particle (3 mm: through the plate); max tip speed.
Writes OUT/report.json and OUT/crack_paths.png.
"""
import importlib.util
import json
import os
import sys

import h5py
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

_spec = importlib.util.spec_from_file_location(
    "glass_report", os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "glass-branching", "report.py"))
gb = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(gb)
gb.NOTCH_TIP = np.array([0.3e-3, 1.5e-3])
C_R = gb.C_R  # the matrix is glass-like (same E, rho, nu as glass-branching): 3,102 m/s


def analyse(out, name):
    x, times, damage, summary = gb.load_run(os.path.join(out, name))
    with h5py.File(os.path.join(out, "particles.h5"), "r") as f:
        material = f["particles/material_id"][:]
        centres = f["inclusions/centre"][:]
        radius = f["inclusions"].attrs["radius_m"]
    dx = float(np.min(np.diff(np.unique(np.round(x[:, 0], 12)))))
    initially = damage[0] > gb.DAMAGE_THRESHOLD
    crack = (damage[-1] > gb.DAMAGE_THRESHOLD) & ~initially
    length, tip_x, speed, _ = gb.tip_history(x, times, damage)
    cols = gb.bands_per_column(x, crack, dx)
    plate = (x[:, 1] >= 0) & (x[:, 1] <= 3e-3)
    owner = np.argmin(np.hypot(x[:, None, 0] - centres[None, :, 0], x[:, None, 1] - centres[None, :, 1]), axis=1)
    cut = 0
    for k in range(len(centres)):
        mine = (material == 1) & (owner == k)
        cut += int(mine.any() and crack[mine].mean() > 0.25)
    res = {
        "run": name, "particles": int(summary["particles"]), "dx_m": dx, "steps": int(summary["steps"]),
        "dt_s": summary["dt_s"], "end_time_s": float(times[-1]),
        "wall_s": round(summary["wall_s"] + summary["setup_wall_s"], 1),
        "damaged_particles": int(crack.sum()),
        "max_bands_on_a_vertical_line": max((len(v) for v in cols.values()), default=0),
        "inclusion_area_fraction": float((material[plate] == 1).mean()),
        "crack_share_in_inclusions": float((material[crack] == 1).mean()) if crack.any() else 0.0,
        "inclusions": int(len(centres)), "inclusions_cut": cut,
        "crack_reach_x_m": float(x[crack, 0].max()) if crack.any() else 0.0,
        "max_tip_speed_m_s": float(np.nanmax(speed)) if np.isfinite(speed).any() else 0.0,
        "history": {"time_s": times.tolist(), "crack_length_m": length.tolist()},
    }
    res["max_tip_speed_over_c_R"] = res["max_tip_speed_m_s"] / C_R
    moved = np.nonzero(length > 2 * dx)[0]
    res["initiation_time_s"] = float(times[moved[0]]) if moved.size else None
    return res, x, damage[-1], material, dx, times[-1]


def main(argv):
    if len(argv) < 3:
        sys.stderr.write(__doc__)
        sys.exit(2)
    out, names = argv[1], argv[2:]
    report = {"case": "inclusion-plate", "damage_threshold": gb.DAMAGE_THRESHOLD, "rayleigh_speed_m_s": C_R,
              "runs": []}
    fig, axs = plt.subplots(1, len(names), figsize=(5.2 * len(names), 5), squeeze=False)
    for ax, name in zip(axs[0], names):
        res, x, d, material, dx, t_end = analyse(out, name)
        report["runs"].append(res)
        size = (72.0 * dx * 1e3 / 3.3 * 4) ** 2
        ax.scatter(x[:, 0] * 1e3, x[:, 1] * 1e3, c=np.where(material == 1, 0.6, 0.85), s=size, marker="s",
                   cmap="gray", vmin=0, vmax=1, linewidths=0)
        hit = d > gb.DAMAGE_THRESHOLD
        ax.scatter(x[hit, 0] * 1e3, x[hit, 1] * 1e3, c=d[hit], s=size, marker="s", cmap="autumn_r", vmin=0.35,
                   vmax=1, linewidths=0)
        ax.set_aspect("equal")
        ax.set_title(f"{name} m/s, t = {t_end * 1e6:.1f} us: {res['max_bands_on_a_vertical_line']} band(s), "
                     f"{res['inclusions_cut']} inclusion(s) cut", fontsize=8)
        ax.set_xlabel("x (mm)")
        ax.set_ylabel("y (mm)")
        print(f"{name}: particles {res['particles']}, steps {res['steps']}, wall {res['wall_s']} s, initiation "
              f"{(res['initiation_time_s'] or 0) * 1e6:.2f} us, bands {res['max_bands_on_a_vertical_line']}, reach "
              f"{res['crack_reach_x_m'] * 1e3:.2f} mm, crack share in inclusions {res['crack_share_in_inclusions']:.3f}"
              f" (area {res['inclusion_area_fraction']:.3f}), cut {res['inclusions_cut']}/{res['inclusions']}, "
              f"max tip speed {res['max_tip_speed_m_s']:.0f} m/s ({res['max_tip_speed_over_c_R']:.2f} c_R)")
    fig.tight_layout()
    fig.savefig(os.path.join(out, "crack_paths.png"), dpi=110)
    with open(os.path.join(out, "report.json"), "w") as fh:
        json.dump(report, fh, indent=1)


if __name__ == "__main__":
    main(sys.argv)
