"""Measure the crack angle of the Kalthoff-Winkler runs.

    report.py OUT RUN

Damaged particle: damage > 0.35 and not damaged at t = 0 (notch faces). For each notch tip
(50, 75) and (50, 125) mm the crack angle is the direction of the principal axis of the
damaged particles at 5-25 mm from the tip on the outer side (away from the impact strip),
measured from the notch axis (+x) towards the outside; the path angle is that of the line
from the tip to the farthest damaged particle on that side. Writes OUT/report.json and
OUT/crack_path.png.
"""
import json
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
import case_report  # noqa: E402  (cases/case_report.py)

DAMAGE_THRESHOLD = 0.35
TIPS = {"lower": (np.array([0.05, 0.075]), -1.0), "upper": (np.array([0.05, 0.125]), 1.0)}
R_MIN, R_MAX = 0.005, 0.025
PUBLISHED_ANGLE_DEG = 70.0  # Kalthoff & Winkler 1988 experiment (benchmarks.md section 2)


def crack_angles(x, damage, initially, tip, side):
    rel = x - tip
    rel[:, 1] *= side  # mirror the lower notch onto the upper one
    r = np.linalg.norm(rel, axis=1)
    dmg = (damage > DAMAGE_THRESHOLD) & ~initially & (rel[:, 1] > -0.002)
    ring = dmg & (r >= R_MIN) & (r <= R_MAX)
    out = {"damaged_particles_in_ring": int(ring.sum())}
    if ring.sum() >= 3:
        p = rel[ring]
        # Principal axis through the tip (the crack starts at the tip): largest eigenvector
        # of the second-moment tensor about the tip.
        w, v = np.linalg.eigh(p.T @ p)
        axis = v[:, np.argmax(w)]
        if axis @ p.mean(axis=0) < 0:
            axis = -axis
        out["initial_angle_deg"] = float(math.degrees(math.atan2(axis[1], axis[0])))
    if dmg.any():
        far = np.argmax(np.where(dmg, r, -1))
        out["path_angle_deg"] = float(math.degrees(math.atan2(rel[far, 1], rel[far, 0])))
        out["crack_length_m"] = float(r[far])
    return out


def main(argv):
    if len(argv) != 3:
        sys.stderr.write(__doc__)
        sys.exit(2)
    out, name = argv[1], argv[2]
    run = os.path.join(out, name)
    x, times, damage, summary = case_report.load_damage_history(run)
    initially = damage[0] > DAMAGE_THRESHOLD
    dx = float(np.min(np.diff(np.unique(np.round(x[:, 0], 9)))))
    res = {"case": "kalthoff-winkler", "run": name, "particles": summary["particles"], "dx_m": dx,
           "steps": summary["steps"], "end_time_s": float(times[-1]),
           "wall_s": round(summary["wall_s"] + summary["setup_wall_s"], 1),
           "published_angle_deg": PUBLISHED_ANGLE_DEG, "notches": {}}
    # Initiation: first output with new damage within 3 mm of a tip.
    for label, (tip, side) in TIPS.items():
        res["notches"][label] = crack_angles(x, damage[-1], initially, tip, side)
        near = np.linalg.norm(x - tip, axis=1) < 0.003
        hit = [k for k in range(len(times)) if ((damage[k] > DAMAGE_THRESHOLD) & ~initially & near).any()]
        res["notches"][label]["initiation_time_s"] = float(times[hit[0]]) if hit else None
    angles = [n["initial_angle_deg"] for n in res["notches"].values() if "initial_angle_deg" in n]
    res["mean_initial_angle_deg"] = float(np.mean(angles)) if angles else None
    paths = [n["path_angle_deg"] for n in res["notches"].values() if "path_angle_deg" in n]
    res["mean_path_angle_deg"] = float(np.mean(paths)) if paths else None
    with open(os.path.join(out, "report.json"), "w") as fh:
        json.dump(res, fh, indent=1)

    fig, ax = plt.subplots(figsize=(5.2, 8))
    size = (72.0 * dx * 1e3 / 30.0) ** 2 * 8
    ax.scatter(x[:, 0] * 1e3, x[:, 1] * 1e3, c=damage[-1], s=size, marker="s", cmap="jet", vmin=0, vmax=1,
               linewidths=0)
    for label, (tip, side) in TIPS.items():
        a = math.radians(PUBLISHED_ANGLE_DEG)
        ax.plot([tip[0] * 1e3, tip[0] * 1e3 + 40 * math.cos(a)], [tip[1] * 1e3, tip[1] * 1e3 + side * 40 * math.sin(a)],
                "w--", lw=1)
        ang = res["notches"][label].get("initial_angle_deg")
        if ang is not None:
            ax.text(tip[0] * 1e3 - 45, tip[1] * 1e3 + side * 8, f"{ang:.0f} deg", color="w", fontsize=9)
    ax.set_aspect("equal")
    ax.set_xlabel("x (mm), impact along +x")
    ax.set_ylabel("y (mm)")
    ax.set_title(f"Kalthoff-Winkler {name}: damage at {times[-1] * 1e6:.0f} us\n(dashed: 70 deg, experiment)",
                 fontsize=9)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "crack_path.png"), dpi=120)
    print(f"{name}: particles {res['particles']}, wall {res['wall_s']} s, initial angle lower/upper "
          f"{res['notches']['lower'].get('initial_angle_deg')}/{res['notches']['upper'].get('initial_angle_deg')} deg, "
          f"mean {res['mean_initial_angle_deg']}, path {res['mean_path_angle_deg']}")


if __name__ == "__main__":
    main(sys.argv)
