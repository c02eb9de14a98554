"""Measure branching, fork and crack-tip speed of the homalite-branching run.

    report.py OUT RUN

Reuses the measurements of cases/glass-branching/report.py (damage threshold, tip history,
5-output least-squares tip speed, band counting on lattice columns, fork extrapolation;
definitions in that README); only particles right of the notch tip count. The glass plate is 100 mm long and its band windows are 2 mm
(detection) and 6 mm (fork fit); this plate is 400 mm long, so positions and times are
handed to those functions scaled by 1/4 (speeds unchanged) and scaled back here: the
windows become 8 mm and 24 mm. Writes OUT/report.json, crack_path.png, tip_speed.png.
"""
import importlib.util
import json
import math
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

SCALE = 0.25  # this plate / the glass plate
NOTCH_TIP = np.array([0.2, 0.1])
E, RHO, NU = 4.55e9, 1230.0, 1.0 / 3.0
C_S = math.sqrt(E / (2 * (1 + NU)) / RHO)
C_R = gb.rayleigh_speed(NU, C_S)                      # 1,098 m/s (nu = 1/3)
C_R_PLANE_STRESS = gb.rayleigh_speed(NU / (1 + NU), C_S)  # 1,083 m/s

gb.NOTCH_TIP = NOTCH_TIP * SCALE
gb.C_R = C_R
_load = gb.load_run


def _scaled_load(run_dir):
    x, times, damage, summary = _load(run_dir)
    # Only particles right of the notch tip can be crack growth: the lone particle at the left
    # edge on the notch row loses most of its few bonds when the notch opens (seen at dx = 2
    # and 4 mm), which the farthest-particle tip measure would otherwise read as the tip.
    damage = np.where(x[:, 0] >= NOTCH_TIP[0], damage, 0.0)
    return x * SCALE, times * SCALE, damage, summary


gb.load_run = _scaled_load


def analyse(out, name):
    res, hist, (x, times, damage, dx) = gb.analyse(out, name)
    back = 1.0 / SCALE
    for key in ("dx_m", "initiation_time_s", "final_crack_length_m", "branching_time_s"):
        if res.get(key) is not None:
            res[key] *= back
    for key in ("detection_x_m", "fork_x_m", "fork_y_m"):
        if key in res["branching"]:
            res["branching"][key] *= back
    for key in ("time_s", "crack_length_m", "tip_x_m"):
        hist[key] = [v * back for v in hist[key]]
    res["history"] = hist
    res["rayleigh_speed_m_s"] = C_R
    if "mean_speed_before_branching_m_s" in res:
        res["mean_speed_before_branching_over_c_R"] = res["mean_speed_before_branching_m_s"] / C_R
    return res, x * back, times * back, damage, dx * back


def main(argv):
    if len(argv) != 3:
        sys.stderr.write(__doc__)
        sys.exit(2)
    out, name = argv[1], argv[2]
    res, x, times, damage, dx = analyse(out, name)
    report = {"case": "homalite-branching", "damage_threshold": gb.DAMAGE_THRESHOLD,
              "rayleigh_speed_m_s": C_R, "rayleigh_speed_plane_stress_m_s": C_R_PLANE_STRESS, "runs": [res]}
    br = res["branching"]
    fig, axs = plt.subplots(2, 2, figsize=(10, 5.6))
    for ax, frac in zip(axs.flat, [0.4, 0.6, 0.8, 1.0]):
        k = min(len(times) - 1, int(round(frac * (len(times) - 1))))
        ax.scatter(x[:, 0] * 1e3, x[:, 1] * 1e3, c=damage[k], s=(72.0 * dx * 1e3 / 100.0) ** 2 * 6, marker="s",
                   cmap="jet", vmin=0, vmax=1, linewidths=0)
        if br.get("branched") and k == len(times) - 1:
            ax.axvline(br["fork_x_m"] * 1e3, color="w", lw=0.8, ls="--")
        ax.set_aspect("equal")
        ax.set_title(f"t = {times[k] * 1e6:.0f} us", fontsize=9)
        ax.set_xlabel("x (mm)")
        ax.set_ylabel("y (mm)")
    fig.suptitle(f"homalite-branching, dx = {dx * 1e3:.0f} mm: damage", fontsize=10)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "crack_path.png"), dpi=110)
    plt.close(fig)
    h = res["history"]
    fig, ax = plt.subplots(2, 1, figsize=(7.5, 6.5), sharex=True)
    t_us = np.array(h["time_s"]) * 1e6
    ax[0].plot(t_us, np.array(h["crack_length_m"]) * 1e3)
    ax[0].set_ylabel("crack length from notch tip (mm)")
    sp = np.array([np.nan if v is None else v for v in h["tip_speed_m_s"]])
    ax[1].plot(t_us, sp, marker=".")
    ax[1].axhline(C_R, color="k", lw=1, label=f"c_R = {C_R:.0f} m/s")
    ax[1].axhline(0.6 * C_R, color="k", lw=1, ls="--", label="0.6 c_R")
    ax[1].axhspan(0.4 * C_R, 0.5 * C_R, color="0.85", label="Homalite-100 experiments, 0.4-0.5 c_R")
    if "branching_time_s" in res:
        ax[1].axvline(res["branching_time_s"] * 1e6, color="r", ls=":", lw=1, label="branching")
    ax[1].set_ylim(0, 1.1 * C_R)
    ax[1].set_xlabel("time (us)")
    ax[1].set_ylabel("tip speed (m/s)")
    ax[1].legend(fontsize=7, loc="upper left")
    for a in ax:
        a.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "tip_speed.png"), dpi=110)
    plt.close(fig)
    with open(os.path.join(out, "report.json"), "w") as fh:
        json.dump(report, fh, indent=1)
    print(f"{name}: particles {res['particles']}, dx {dx * 1e3:.0f} mm, wall {res['wall_s']} s, initiation "
          f"{(res['initiation_time_s'] or 0) * 1e6:.1f} us, max tip speed {res['max_tip_speed_m_s']:.0f} m/s "
          f"({res['max_tip_speed_over_c_R']:.2f} c_R), branched {br.get('branched')}, fork x "
          f"{br.get('fork_x_m', float('nan')) * 1e3:.1f} mm, t {res.get('branching_time_s', float('nan')) * 1e6:.1f} us, "
          f"mean speed before {res.get('mean_speed_before_branching_m_s', float('nan')):.0f} m/s, "
          f"max bands {br['max_bands_on_a_vertical_line']}")


if __name__ == "__main__":
    main(sys.argv)
