"""Measure crack path, branching and crack-tip speed of the 3D glass-slab runs.

    report_3d.py OUT RUN [RUN ...]      (RUN: a solver output folder under OUT)

Writes OUT/report_3d.json, OUT/crack_paths_3d.png, OUT/tip_speed_3d.png and
OUT/snapshots_3d_<RUN>.png. The measurements are report.py's (README.md, "Measurements"),
applied to the slab's mid-plane: the damage of the two particle layers next to z = t/2
(an even number of layers has no layer on the mid-plane; the two are mirror images of each
other about it, so their mean is the mid-plane value). The same measures on the two face
layers (z = dx/2 and t - dx/2) tell whether the crack front runs straight through the
thickness or tunnels ahead in the middle.

Rayleigh speed: 3D (or plane strain) Rayleigh equation at nu = 1/4, the only Poisson's
ratio a 3D bond-based PMB represents: c_s = sqrt(E / (2 (1 + nu) rho)) = 3,436 m/s,
c_R = 0.9194 c_s = 3,159 m/s.
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

sys.dont_write_bytecode = True  # no __pycache__ in the case folder
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import report  # noqa: E402  (the 2D case's measurements, reused on the mid-plane)

NU_3D = 0.25
C_S_3D = math.sqrt(report.E / (2 * (1 + NU_3D)) / report.RHO)
C_R_3D = report.rayleigh_speed(NU_3D, C_S_3D)
# A particle next to a plane crack in 3D keeps the bonds that do not cross it: the share
# that crosses is the spherical cap beyond the plane, 0.32 / 0.38 / 0.41 of the family at
# m = 2 / 3 / 4 for the first layer, 0.04 / 0.16 / 0.23 for the second (measured on the
# notch: 0.33 / 0.38 / 0.41 and 0.05 / 0.16 / 0.24). 0.25 separates the two; report.py's
# 2D value 0.35, where the first layer reaches 0.4-0.5, would sit on the 3D m = 2 value.
DAMAGE_THRESHOLD_3D = 0.25
# Snapshot times: Bobaru & Zhang's figure times are not in our sources (benchmarks.md 1a,
# gap); quarters of the 43 us run, the end time of the CabanaPD and PDMATLAB2D decks.
SNAPSHOT_TIMES_S = [10.75e-6, 21.5e-6, 32.25e-6, 43e-6]


def load_layers(run_dir):
    """Damage history of the mid-plane and of the two face layers, as 2D lattice fields."""
    with h5py.File(os.path.join(run_dir, "results.h5"), "r") as f:
        x = f["particles/position"][:]
        keys = sorted(f["output"].keys())
        times = np.array([f["output"][k].attrs["time_s"] for k in keys])
        damage = np.array([f["output"][k]["damage"][:] for k in keys])
        horizon = float(np.median(f["particles/horizon"][:]))
    with open(os.path.join(run_dir, "summary.json")) as fh:
        summary = json.load(fh)
    z_levels = np.unique(np.round(x[:, 2], 9))
    layer = np.searchsorted(z_levels, np.round(x[:, 2], 9))
    n = z_levels.size
    mid = [n // 2 - 1, n // 2] if n % 2 == 0 else [n // 2]

    def plane(layers):
        # The lattice runs x fastest, then y, then z: every layer holds the same (x, y) in
        # the same order, so layers average element by element.
        sel = [np.nonzero(layer == k)[0] for k in layers]
        return x[sel[0], :2], np.mean([damage[:, s] for s in sel], axis=0)

    planes = {"mid_plane": plane(mid), "face_z0": plane([0]), "face_z1": plane([n - 1])}
    dx = float(np.min(np.diff(np.unique(np.round(x[:, 0], 9)))))
    geometry = {"layers": int(n), "thickness_m": float(n * dx), "dx_m": dx, "horizon_m": horizon}
    return planes, times, geometry, summary, damage, x


def measure(xy, times, damage, dx):
    """report.py's tip history and branching measures on one (x, y) layer."""
    initially = damage[0] > DAMAGE_THRESHOLD_3D
    length, tip_x, speed, raw = report.tip_history(xy, times, damage, DAMAGE_THRESHOLD_3D)
    br, _ = report.branching(xy, damage[-1], initially, dx, DAMAGE_THRESHOLD_3D)
    moved = np.nonzero(length > 2 * dx)[0]
    t_init = float(times[moved[0]]) if moved.size else None
    res = {"initiation_time_s": t_init, "final_crack_length_m": float(length[-1]),
           "max_tip_speed_m_s": float(np.nanmax(speed)) if np.isfinite(speed).any() else 0.0,
           "max_tip_speed_two_point_m_s": float(np.nanmax(raw)) if np.isfinite(raw).any() else 0.0,
           "branching": br}
    res["max_tip_speed_over_c_R"] = res["max_tip_speed_m_s"] / C_R_3D
    if br.get("branched") and t_init is not None:
        past = np.nonzero(tip_x >= br["fork_x_m"])[0]
        if past.size and past[0] > 0:
            k = past[0]
            t_b = float(np.interp(br["fork_x_m"], [tip_x[k - 1], tip_x[k]], [times[k - 1], times[k]]))
            res["branching_time_s"] = t_b
            if t_b > t_init:
                res["mean_speed_before_branching_m_s"] = float(
                    (np.interp(t_b, times, length) - np.interp(t_init, times, length)) / (t_b - t_init))
                pre = (times > t_init) & (times < t_b) & np.isfinite(speed)
                if pre.any():
                    res["max_speed_before_branching_m_s"] = float(np.nanmax(speed[pre]))
    hist = {"time_s": times.tolist(), "crack_length_m": length.tolist(), "tip_x_m": tip_x.tolist(),
            "tip_speed_m_s": [None if not np.isfinite(v) else float(v) for v in speed]}
    return res, hist


def analyse(out, name):
    run_dir = os.path.join(out, name)
    planes, times, geometry, summary, damage, x = load_layers(run_dir)
    dx = geometry["dx_m"]
    res = {"run": name, "particles": int(summary["particles"]), **geometry,
           "steps": int(summary["steps"]), "dt_s": summary["dt_s"], "threads": summary.get("threads"),
           "wall_s": round(summary["wall_s"] + summary["setup_wall_s"], 1),
           "bond_updates_per_s": summary.get("bond_updates_per_s"), "rayleigh_speed_m_s": C_R_3D}
    xy, d = planes["mid_plane"]
    mid, hist = measure(xy, times, d, dx)
    res.update(mid)
    res["history"] = hist
    faces = {}
    for label in ("face_z0", "face_z1"):
        xy, d = planes[label]
        r, _ = measure(xy, times, d, dx)
        faces[label] = {k: r[k] for k in ("initiation_time_s", "final_crack_length_m", "max_tip_speed_m_s")}
        faces[label]["branching"] = r["branching"]
        faces[label]["branching_time_s"] = r.get("branching_time_s")
    res["faces"] = faces
    # Through-thickness straightness: of the (x, y) columns with newly damaged particles, the
    # share damaged in every layer (1: the crack runs through the thickness everywhere).
    final = (damage[-1] > DAMAGE_THRESHOLD_3D) & ~(damage[0] > DAMAGE_THRESHOLD_3D)
    xy_key = np.round(x[:, 0] / dx).astype(np.int64) * 1_000_000 + np.round(x[:, 1] / dx).astype(np.int64)
    _, col = np.unique(xy_key, return_inverse=True)
    hits = np.bincount(col, weights=final.astype(float))
    layers = geometry["layers"]
    damaged_cols = hits > 0
    res["columns_damaged_in_all_layers_share"] = (
        float(np.mean(hits[damaged_cols] == layers)) if damaged_cols.any() else 0.0)
    return res, planes, times


def frame_at(times, t):
    return int(np.argmin(np.abs(times - t)))


def main(argv):
    if len(argv) < 3:
        sys.stderr.write(__doc__)
        sys.exit(2)
    out, names = argv[1], argv[2:]
    rep = {"case": "glass-branching 3D slab", "damage_threshold": DAMAGE_THRESHOLD_3D,
           "poisson_ratio": NU_3D, "shear_speed_m_s": C_S_3D, "rayleigh_speed_m_s": C_R_3D, "runs": []}
    fig_p, axes_p = plt.subplots(len(names), 1, figsize=(7.5, 3.3 * len(names)), squeeze=False)
    fig_s, ax_s = plt.subplots(2, 1, figsize=(7.5, 7), sharex=True)
    for row, name in enumerate(names):
        res, planes, times = analyse(out, name)
        rep["runs"].append(res)
        xy, d = planes["mid_plane"]
        dx = res["dx_m"]
        br = res["branching"]
        label = f"fork x = {br['fork_x_m'] * 1e3:.1f} mm" if br.get("branched") else "no branching"
        report.draw_damage(axes_p[row, 0], xy, d[-1], dx,
                           f"3D slab {name}, mid-plane: {label}, t = {times[-1] * 1e6:.1f} us")
        fig_p.colorbar(axes_p[row, 0].collections[0], ax=axes_p[row, 0], label="damage", fraction=0.025, pad=0.02)
        if br.get("branched"):
            axes_p[row, 0].axvline(br["fork_x_m"] * 1e3, color="w", lw=0.8, ls="--", label="fork x")
            axes_p[row, 0].legend(fontsize=7, loc="lower left")
        t_us = np.array(res["history"]["time_s"]) * 1e6
        ax_s[0].plot(t_us, np.array(res["history"]["crack_length_m"]) * 1e3, label=f"{name} (mid-plane)")
        sp = np.array([np.nan if v is None else v for v in res["history"]["tip_speed_m_s"]])
        ax_s[1].plot(t_us, sp, marker=".", label=f"{name} (mid-plane)")
        if "branching_time_s" in res:
            ax_s[1].axvline(res["branching_time_s"] * 1e6, color=ax_s[1].lines[-1].get_color(), ls=":", lw=1,
                            label="branching time")
        # Damage at the snapshot times: mid-plane (top row) and the face z = 0 (bottom row).
        fig, axs = plt.subplots(2, len(SNAPSHOT_TIMES_S), figsize=(16, 4.6))
        for c, t in enumerate(SNAPSHOT_TIMES_S):
            k = frame_at(times, t)
            for r, (plane, where) in enumerate([("mid_plane", "mid-plane"), ("face_z0", "face z = 0")]):
                pxy, pd = planes[plane]
                report.draw_damage(axs[r, c], pxy, pd[k], dx, f"{where}, t = {times[k] * 1e6:.1f} us")
        fig.subplots_adjust(left=0.04, right=0.93, bottom=0.1, top=0.88, wspace=0.25, hspace=0.45)
        cax = fig.add_axes([0.945, 0.15, 0.01, 0.65])
        fig.colorbar(axs[0, 0].collections[0], cax=cax, label="damage (share of broken bonds)")
        fig.suptitle(f"glass-branching 3D slab {name}: damage, 100 x 40 x {res['thickness_m'] * 1e3:.0f} mm, "
                     f"dx = {dx * 1e3:.3g} mm, delta = {res['horizon_m'] * 1e3:.3g} mm", fontsize=11)
        fig.savefig(os.path.join(out, f"snapshots_3d_{name}.png"), dpi=100)
        plt.close(fig)
    fig_p.tight_layout()
    fig_p.savefig(os.path.join(out, "crack_paths_3d.png"), dpi=120)
    report.finish_tip_speed_chart(fig_s, ax_s, C_R_3D, "c_R = %.0f m/s (nu = 1/4)" % C_R_3D,
                                  os.path.join(out, "tip_speed_3d.png"))
    with open(os.path.join(out, "report_3d.json"), "w") as fh:
        json.dump(rep, fh, indent=1)
    for r in rep["runs"]:
        br = r["branching"]
        faces = ", ".join(f"{k} fork {v['branching'].get('fork_x_m', float('nan')) * 1e3:.1f} mm"
                          for k, v in r["faces"].items())
        print(f"{r['run']} (3D, {r['particles']} particles, {r['layers']} layers): wall {r['wall_s']} s, initiation "
              f"{(r['initiation_time_s'] or 0) * 1e6:.1f} us, max tip speed {r['max_tip_speed_m_s']:.0f} m/s "
              f"({r['max_tip_speed_over_c_R']:.2f} c_R), branched {br.get('branched')}, fork x "
              f"{br.get('fork_x_m', float('nan')) * 1e3:.1f} mm, t {r.get('branching_time_s', float('nan')) * 1e6:.1f} us, "
              f"mean speed before {r.get('mean_speed_before_branching_m_s', float('nan')):.0f} m/s (max "
              f"{r.get('max_speed_before_branching_m_s', float('nan')):.0f} m/s), "
              f"half-angle {br.get('branch_half_angle_deg', float('nan')):.1f} deg, "
              f"max bands {br['max_bands_on_a_vertical_line']}; {faces}; columns damaged through the "
              f"thickness {r['columns_damaged_in_all_layers_share']:.2f}")


if __name__ == "__main__":
    main(sys.argv)
