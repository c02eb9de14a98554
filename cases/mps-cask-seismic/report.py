"""Report of cases/mps-cask-seismic: the container's tilt, uplift and sliding against time.

    report.py OUT RECORD RUN [RUN ...]

Reads OUT/RUN/history.csv (container_x_m, container_y_m, container_angle_rad,
floor_displacement_m and the energy columns). Measures, from the rigid container's pose:
  tilt    its rotation (deg);
  uplift  the higher bottom corner's height above the floor (m; 0 while both rest on it);
  sliding the base midpoint's horizontal displacement relative to the floor (m).
Energy balance: kinetic + stress work + hourglass + contact + gravity + friction dissipation
+ contact damping (the dashpots of a restitution below 1) - ground work, against the ground work. Writes OUT/report.json and OUT/cask_response.png.
"""
import csv
import json
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

# The container polygon of case.yaml: centroid and base corners.
VERTICES = [(-1.7, 0), (1.7, 0), (1.7, 5.9), (0.95, 5.9), (0.95, 0.5), (-0.95, 0.5), (-0.95, 5.9), (-1.7, 5.9)]


def centroid(vs):
    a = cx = cy = 0.0
    for (x0, y0), (x1, y1) in zip(vs, vs[1:] + vs[:1]):
        c = x0 * y1 - x1 * y0
        a += c
        cx += (x0 + x1) * c
        cy += (y0 + y1) * c
    return cx / (3 * a), cy / (3 * a)


def analyse(out, name):
    rows = list(csv.DictReader(open(os.path.join(out, name, "history.csv"))))
    col = lambda k: np.array([float(r[k]) for r in rows])  # noqa: E731
    t, cx, cy, ang = col("time_s"), col("container_x_m"), col("container_y_m"), col("container_angle_rad")
    floor = col("floor_displacement_m")
    c0x, c0y = centroid(VERTICES)
    corners = [(-1.7 - c0x, -c0y), (1.7 - c0x, -c0y)]
    ys = [cy + np.sin(ang) * lx + np.cos(ang) * ly for lx, ly in corners]
    uplift = np.maximum(0.0, np.maximum(ys[0], ys[1]))
    base_x = cx + np.cos(ang) * (0 - c0x) - np.sin(ang) * (0 - c0y)
    sliding = base_x - floor
    energy = {}
    if "ground_work_J" in rows[0]:
        parts = ["kinetic_energy_J", "stress_work_J", "contact_energy_J", "gravity_energy_J", "friction_dissipation_J",
                 "contact_damping_J", "material_damping_J"]
        total = sum(col(k) for k in parts if k in rows[0]) + col("hourglass_energy_J") - col("ground_work_J")
        work = col("ground_work_J")
        energy = {"ground_work_J_end": float(work[-1]), "imbalance_J_end": float(total[-1] - total[0]),
                  "max_abs_imbalance_over_max_ground_work": float(np.max(np.abs(total - total[0])) /
                                                                   max(np.max(np.abs(work)), 1e-30))}
    summary = json.load(open(os.path.join(out, name, "summary.json")))
    res = {"run": name, "particles": summary.get("particles"), "steps": summary.get("steps"),
           "peak_tilt_deg": float(np.degrees(np.max(np.abs(ang)))),
           "peak_uplift_m": float(np.max(uplift)),
           "peak_sliding_m": float(np.max(np.abs(sliding))),
           "final_sliding_m": float(sliding[-1]), **energy}
    return res, (t, np.degrees(ang), uplift, sliding)


def main(argv):
    if len(argv) < 4:
        sys.stderr.write(__doc__)
        sys.exit(2)
    out, record, names = argv[1], argv[2], argv[3:]
    rec = np.loadtxt(record, delimiter=",", skiprows=1)
    runs, series = [], []
    for n in names:
        r, s = analyse(out, n)
        runs.append(r)
        series.append(s)
        print(f"{n}: peak tilt {r['peak_tilt_deg']:.3f} deg, peak uplift {r['peak_uplift_m'] * 1e3:.1f} mm, "
              f"peak sliding {r['peak_sliding_m'] * 1e3:.1f} mm (final {r['final_sliding_m'] * 1e3:.1f} mm)"
              + (f", energy imbalance {r['max_abs_imbalance_over_max_ground_work']:.2%} of the ground work"
                 if "max_abs_imbalance_over_max_ground_work" in r else ""))
    json.dump({"case": "mps-cask-seismic", "record": os.path.basename(record), "runs": runs},
              open(os.path.join(out, "report.json"), "w"), indent=1)
    fig, ax = plt.subplots(4, 1, figsize=(8, 10), sharex=True)
    ax[0].plot(rec[:, 0], rec[:, 1], "k-", lw=0.6)
    ax[0].set_ylabel("floor acceleration (g)")
    ax[0].set_title("synthetic record (record.py)" if os.path.basename(record) == "record.csv" else os.path.basename(record),
                    fontsize=9)
    for (t, tilt, up, sl), n in zip(series, names):
        ax[1].plot(t, tilt, lw=0.8, label=n)
        ax[2].plot(t, up * 1e3, lw=0.8, label=n)
        ax[3].plot(t, sl * 1e3, lw=0.8, label=n)
    ax[1].set_ylabel("tilt (deg)")
    ax[2].set_ylabel("uplift (mm)")
    ax[3].set_ylabel("sliding (mm)")
    ax[3].set_xlabel("time (s)")
    for a in ax[1:]:
        a.grid(alpha=0.3)
        a.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "cask_response.png"), dpi=110)


if __name__ == "__main__":
    main(sys.argv)
