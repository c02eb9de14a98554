"""Measure crack path, branching and crack-tip speed of the glass-branching runs.

    report.py OUT RUN [RUN ...]      (RUN: a solver output folder under OUT)

Writes OUT/report.json and PNG pictures in OUT. Definitions (README.md):
- damaged particle: damage > DAMAGE_THRESHOLD and not already damaged at t = 0 (the notch
  faces start at damage ~0.4-0.5, which would otherwise mark the notch as crack);
- crack tip: the damaged particle farthest from the notch tip (50, 20) mm; the crack
  length is that distance; tip speed is the least-squares slope of the length over five
  consecutive outputs (about 3.6 us);
- branching: on the final damage field, a column of particles (constant x) crosses two
  or more separate damage bands (gap > 1.5 dx); the detection x is the first column from
  which all columns over the next 2 mm have two bands; the fork is where the separation of
  the two bands, fitted linearly over the 6 mm after detection, extrapolates to zero;
  the branching time is when the tip's x passes the fork.
"""
import json
import math
import os
import sys

import h5py
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
import case_report  # noqa: E402  (cases/case_report.py)

DAMAGE_THRESHOLD = 0.35
NOTCH_TIP = np.array([0.05, 0.02])
E, RHO, NU = 72e9, 2440.0, 1.0 / 3.0


def rayleigh_speed(nu, c_s):
    """Root of the Rayleigh equation (x = c_R/c_s) for Poisson's ratio nu (3D / plane strain form)."""
    k2 = (1 - 2 * nu) / (2 * (1 - nu))  # (c_s/c_p)^2
    f = lambda x: x**6 - 8 * x**4 + (24 - 16 * k2) * x**2 - 16 * (1 - k2)  # noqa: E731
    lo, hi = 0.5, 0.999
    for _ in range(100):
        mid = 0.5 * (lo + hi)
        if f(lo) * f(mid) <= 0:
            hi = mid
        else:
            lo = mid
    return 0.5 * (lo + hi) * c_s


C_S = math.sqrt(E / (2 * (1 + NU)) / RHO)
C_R = rayleigh_speed(NU, C_S)  # 3,102 m/s: the value Ha & Bobaru quote (benchmarks.md 1a)
C_R_PLANE_STRESS = rayleigh_speed(NU / (1 + NU), C_S)  # 3,058 m/s


# Module-level name: homalite-branching and inclusion-plate reuse this report and replace
# or call the loader.
load_run = case_report.load_damage_history


def finish_tip_speed_chart(fig_s, ax_s, c_r, c_r_label, path):
    """Labels, reference speeds and the experiments' band on the (crack length, tip speed) pair."""
    ax_s[0].set_ylabel("crack length from notch tip (mm)")
    ax_s[0].legend(fontsize=8)
    ax_s[0].grid(alpha=0.3)
    ax_s[1].axhline(c_r, color="k", lw=1, label=c_r_label)
    ax_s[1].axhline(0.6 * c_r, color="k", lw=1, ls="--", label="0.6 c_R")
    ax_s[1].axhspan(1500, 1580, color="0.8", label="soda-lime experiments (branching)")
    ax_s[1].set_ylim(0, 1.1 * c_r)
    ax_s[1].set_xlabel("time (us)")
    ax_s[1].set_ylabel("tip speed (m/s)")
    ax_s[1].legend(fontsize=7, loc="upper left")
    ax_s[1].grid(alpha=0.3)
    fig_s.tight_layout()
    fig_s.savefig(path, dpi=120)


def tip_history(x, times, damage, threshold=DAMAGE_THRESHOLD):
    initially = damage[0] > threshold
    dist = np.linalg.norm(x - NOTCH_TIP, axis=1)
    length, tip_x = [], []
    for d in damage:
        new = (d > threshold) & ~initially
        if new.any():
            k = np.argmax(np.where(new, dist, -1.0))
            length.append(dist[k])
            tip_x.append(x[k, 0])
        else:
            length.append(0.0)
            tip_x.append(NOTCH_TIP[0])
    length, tip_x = np.array(length), np.array(tip_x)
    # Least-squares slope over 5 outputs (~3.6 us): a fork widens the damage zone at once,
    # which a two-point difference reads as a spurious jump of the farthest particle.
    speed = np.full_like(length, np.nan)
    raw = np.full_like(length, np.nan)
    raw[1:-1] = (length[2:] - length[:-2]) / (times[2:] - times[:-2])
    for k in range(2, len(length) - 2):
        speed[k] = np.polyfit(times[k - 2:k + 3], length[k - 2:k + 3], 1)[0]
    return length, tip_x, speed, raw


def bands_per_column(x, damaged, dx):
    """For every lattice column right of the notch tip: the centres (y) of the damage bands."""
    columns = {}
    col = np.round(x[:, 0] / dx).astype(int)
    for c in np.unique(col[damaged]):
        ys = np.sort(x[damaged & (col == c), 1])
        if c * dx < NOTCH_TIP[0]:
            continue
        breaks = np.nonzero(np.diff(ys) > 1.5 * dx)[0]
        runs = np.split(ys, breaks + 1)
        columns[c * dx] = [float(r.mean()) for r in runs]
    return dict(sorted(columns.items()))


def branching(x, final_damage, initially, dx, threshold=DAMAGE_THRESHOLD):
    damaged = (final_damage > threshold) & ~initially
    cols = bands_per_column(x, damaged, dx)
    xs = np.array(list(cols.keys()))
    counts = np.array([len(v) for v in cols.values()])
    result = {"max_bands_on_a_vertical_line": int(counts.max()) if counts.size else 0}
    detect = None
    for i, xc in enumerate(xs):
        window = (xs >= xc) & (xs <= xc + 0.002)
        if counts[i] >= 2 and np.all(counts[window] >= 2):
            detect = xc
            break
    if detect is None:
        result["branched"] = False
        return result, cols
    result["branched"] = True
    result["detection_x_m"] = float(detect)
    sel = [(xc, v) for xc, v in cols.items() if detect <= xc <= detect + 0.006 and len(v) == 2]
    if len(sel) >= 3:
        xx = np.array([s[0] for s in sel])
        sep = np.array([abs(s[1][1] - s[1][0]) for s in sel])
        slope, icpt = np.polyfit(xx, sep, 1)
        fork = -icpt / slope if slope > 0 else detect
        fork = float(min(max(fork, NOTCH_TIP[0]), detect))
        result["fork_x_m"] = fork
        result["branch_half_angle_deg"] = float(math.degrees(math.atan(0.5 * slope)))
        result["fork_y_m"] = float(np.mean([0.5 * (s[1][0] + s[1][1]) for s in sel]))
    else:
        result["fork_x_m"] = float(detect)
    return result, cols


def analyse(out, name):
    run_dir = os.path.join(out, name)
    x, times, damage, summary = load_run(run_dir)
    dx = float(np.min(np.diff(np.unique(np.round(x[:, 0], 9)))))
    initially = damage[0] > DAMAGE_THRESHOLD
    length, tip_x, speed, raw = tip_history(x, times, damage)
    br, cols = branching(x, damage[-1], initially, dx)
    moved = np.nonzero(length > 2 * dx)[0]
    t_init = float(times[moved[0]]) if moved.size else None
    res = {
        "run": name,
        "particles": int(summary["particles"]),
        "dx_m": dx,
        "horizon_m": None,
        "steps": int(summary["steps"]),
        "dt_s": summary["dt_s"],
        "wall_s": round(summary["wall_s"] + summary["setup_wall_s"], 1),
        "initiation_time_s": t_init,
        "final_crack_length_m": float(length[-1]),
        "max_tip_speed_m_s": float(np.nanmax(speed)) if np.isfinite(speed).any() else 0.0,
        "max_tip_speed_two_point_m_s": float(np.nanmax(raw)) if np.isfinite(raw).any() else 0.0,
        "rayleigh_speed_m_s": C_R,
        "branching": br,
    }
    res["max_tip_speed_over_c_R"] = res["max_tip_speed_m_s"] / C_R
    with h5py.File(os.path.join(run_dir, "results.h5"), "r") as f:
        res["horizon_m"] = float(np.median(f["particles/horizon"][:]))
    if br.get("branched"):
        fork = br["fork_x_m"]
        past = np.nonzero(tip_x >= fork)[0]
        if past.size and past[0] > 0:
            k = past[0]
            t_b = np.interp(fork, [tip_x[k - 1], tip_x[k]], [times[k - 1], times[k]])
            res["branching_time_s"] = float(t_b)
            pre = (times > (t_init or 0)) & (times < t_b) & np.isfinite(speed)
            if pre.any():
                res["mean_speed_before_branching_m_s"] = float(
                    (np.interp(t_b, times, length) - np.interp(t_init, times, length)) / (t_b - t_init))
                res["max_speed_before_branching_m_s"] = float(np.nanmax(speed[pre]))
    hist = {"time_s": times.tolist(), "crack_length_m": length.tolist(), "tip_x_m": tip_x.tolist(),
            "tip_speed_m_s": [None if not np.isfinite(v) else float(v) for v in speed]}
    return res, hist, (x, times, damage, dx)


def draw_damage(ax, x, d, dx, title):
    ax.scatter(x[:, 0] * 1e3, x[:, 1] * 1e3, c=d, s=(72.0 * dx * 1e3 / 25.0) ** 2 * 6, marker="s",
               cmap="jet", vmin=0, vmax=1, linewidths=0)
    ax.set_aspect("equal")
    ax.set_xlim(0, 100)
    ax.set_ylim(0, 40)
    ax.set_title(title, fontsize=9)
    ax.set_xlabel("x (mm)")
    ax.set_ylabel("y (mm)")


def main(argv):
    if len(argv) < 3:
        sys.stderr.write(__doc__)
        sys.exit(2)
    out, names = argv[1], argv[2:]
    report = {"case": "glass-branching", "damage_threshold": DAMAGE_THRESHOLD,
              "rayleigh_speed_m_s": C_R, "rayleigh_speed_plane_stress_m_s": C_R_PLANE_STRESS, "runs": []}
    fig_p, axes_p = plt.subplots(len(names), 1, figsize=(7.5, 3.2 * len(names)), squeeze=False)
    fig_s, ax_s = plt.subplots(2, 1, figsize=(7.5, 7), sharex=True)
    for row, name in enumerate(names):
        res, hist, (x, times, damage, dx) = analyse(out, name)
        res["history"] = hist
        report["runs"].append(res)
        br = res["branching"]
        label = f"{name}: "
        label += (f"fork x = {br['fork_x_m'] * 1e3:.1f} mm" if br.get("branched") else "no branching")
        draw_damage(axes_p[row, 0], x, damage[-1], dx, f"{label}, t = {times[-1] * 1e6:.1f} us")
        if br.get("branched"):
            axes_p[row, 0].axvline(br["fork_x_m"] * 1e3, color="w", lw=0.8, ls="--")
        t_us = np.array(hist["time_s"]) * 1e6
        ax_s[0].plot(t_us, np.array(hist["crack_length_m"]) * 1e3, label=name)
        sp = np.array([np.nan if v is None else v for v in hist["tip_speed_m_s"]])
        ax_s[1].plot(t_us, sp, marker=".", label=name)
        if "branching_time_s" in res:
            ax_s[1].axvline(res["branching_time_s"] * 1e6, color=ax_s[1].lines[-1].get_color(), ls=":", lw=1)
        # snapshots of each run
        fig, axs = plt.subplots(2, 2, figsize=(10, 5.4))
        for ax, frac in zip(axs.flat, [0.25, 0.5, 0.75, 1.0]):
            k = min(len(times) - 1, int(round(frac * (len(times) - 1))))
            draw_damage(ax, x, damage[k], dx, f"t = {times[k] * 1e6:.1f} us")
        fig.suptitle(f"glass-branching {name}: damage", fontsize=10)
        fig.tight_layout()
        fig.savefig(os.path.join(out, f"snapshots_{name}.png"), dpi=110)
        plt.close(fig)
    fig_p.tight_layout()
    fig_p.savefig(os.path.join(out, "crack_paths.png"), dpi=120)
    finish_tip_speed_chart(fig_s, ax_s, C_R, "c_R = %.0f m/s" % C_R, os.path.join(out, "tip_speed.png"))
    with open(os.path.join(out, "report.json"), "w") as fh:
        json.dump(report, fh, indent=1)
    for r in report["runs"]:
        br = r["branching"]
        print(f"{r['run']}: particles {r['particles']}, wall {r['wall_s']} s, initiation "
              f"{(r['initiation_time_s'] or 0) * 1e6:.1f} us, max tip speed {r['max_tip_speed_m_s']:.0f} m/s "
              f"({r['max_tip_speed_over_c_R']:.2f} c_R), branched {br.get('branched')}, fork x "
              f"{br.get('fork_x_m', float('nan')) * 1e3:.1f} mm, t {r.get('branching_time_s', float('nan')) * 1e6:.1f} us, "
              f"mean speed before {r.get('mean_speed_before_branching_m_s', float('nan')):.0f} m/s, "
              f"max bands {br['max_bands_on_a_vertical_line']}")


if __name__ == "__main__":
    main(sys.argv)
