"""Crushed zone and radial cracks of the granite-blast run.

    report.py OUT RUN [RUN ...]

Damaged particle: damage > 0.35. Crushed zone: rings of width dx around the hole, counted
outwards from the hole wall while at least half of a ring's particles are damaged; its
radius is the outer edge of the last such ring. Radial cracks at radius r: particles in the
ring r +- dx sorted by angle; a crack is a run of damaged particles, runs separated by an
angular gap larger than 2 dx / r. Reach: the largest radius of the damaged particles joined to the
hole wall through damaged neighbours (the tip of the longest radial crack from the hole).

The same measures are taken twice: from the damage field, and from the broken-bond fraction
(the fraction of a particle's bonds fully broken, `broken` bits of results.h5; key "broken" of
each snapshot), with the same threshold. Without softening bonds the two agree (the damage is
the weighted broken fraction); with softening bonds the damage also counts the share a bond
has lost while it softens, which the broken fraction leaves out.
Writes OUT/report.json, OUT/damage_<RUN>.png (at 11.25 and 18.75 us, the end, and the end zoomed on the
hole), OUT/cracks_vs_radius.png.
"""
import json
import math
import os
import re
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
import case_report  # noqa: E402  (cases/case_report.py)

DAMAGE_THRESHOLD = 0.35
HOLE_RADIUS, OUTER_RADIUS = 0.0012875, 0.036
SNAPSHOT_TIMES_US = (11.25, 18.75)  # the seed's two described instants
COUNT_RADII_MM = (3, 5, 7.5, 10, 15, 20, 25, 30)


def crushed_radius(r, damaged, dx):
    edge = HOLE_RADIUS
    k = 0
    while True:
        ring = (r >= HOLE_RADIUS + k * dx) & (r < HOLE_RADIUS + (k + 1) * dx)
        if ring.sum() == 0 or damaged[ring].mean() < 0.5:
            return edge
        edge = HOLE_RADIUS + (k + 1) * dx
        k += 1


def cracks_at(r, theta, damaged, radius, dx):
    ring = np.abs(r - radius) <= dx
    if ring.sum() == 0:
        return 0
    order = np.argsort(theta[ring])
    th, dm = theta[ring][order], damaged[ring][order]
    if dm.all():
        return -1  # fully damaged ring: inside the crushed zone
    if not dm.any():
        return 0
    th_d = th[dm]
    gaps = np.diff(np.concatenate([th_d, [th_d[0] + 2 * math.pi]]))
    # An undamaged particle between two damaged ones separates two cracks only when the
    # angular gap exceeds 2 dx / r (one lattice cell at this radius is dx / r).
    return int(np.sum(gaps > 2 * dx / radius))


def hole_connected_reach(x, damaged, dx, hole_radius):
    """Radius reached by the damage that connects to the hole: the damaged particles joined to
    the hole wall through damaged neighbours (8 neighbours on the square lattice), and the
    largest radius among them (the hole radius when no wall particle is damaged). The tip of
    the longest radial crack that starts at the hole lies at this radius; damage that formed
    away from the hole (e.g. under the reflected wave) does not count until it joins."""
    ij = np.round((x - x.min(axis=0)) / dx).astype(int)
    grid = -np.ones(ij.max(axis=0) + 1, dtype=int)
    grid[ij[:, 0], ij[:, 1]] = np.arange(len(x))
    r = np.hypot(x[:, 0], x[:, 1])
    seen = np.zeros(len(x), dtype=bool)
    stack = list(np.nonzero(damaged & (r < hole_radius + dx))[0])
    seen[stack] = True
    reach = hole_radius
    while stack:
        p = stack.pop()
        reach = max(reach, float(r[p]))
        for di in (-1, 0, 1):
            for dj in (-1, 0, 1):
                a, b = ij[p, 0] + di, ij[p, 1] + dj
                if 0 <= a < grid.shape[0] and 0 <= b < grid.shape[1]:
                    q = grid[a, b]
                    if q >= 0 and damaged[q] and not seen[q]:
                        seen[q] = True
                        stack.append(q)
    return reach


def measures(x, r, theta, damaged, dx):
    """Crushed zone, farthest damaged particle, reach from the hole and radial cracks of one
    output's damaged particles."""
    return {"crushed_radius_m": crushed_radius(r, damaged, dx),
            "max_damaged_radius_m": float(r[damaged].max()) if damaged.any() else 0.0,
            "hole_connected_reach_m": hole_connected_reach(x, damaged, dx, HOLE_RADIUS),
            "cracks_at_radius_mm": {str(q): cracks_at(r, theta, damaged, q * 1e-3, dx) for q in COUNT_RADII_MM}}


def analyse(out, name):
    run = os.path.join(out, name)
    x, times, damage, summary = case_report.load_damage_history(run)
    broken = case_report.load_broken_fraction_history(run)
    g0 = float(re.search(r"fracture_energy:\s*([0-9.eE+-]+)", open(os.path.join(run, "case_as_run.yaml")).read()).group(1))
    dx = float(np.min(np.diff(np.unique(np.round(x[:, 0], 9)))))
    r = np.hypot(x[:, 0], x[:, 1])
    theta = np.arctan2(x[:, 1], x[:, 0])
    res = {"run": name, "mean_fracture_energy_J_m2": g0, "particles": summary["particles"], "dx_m": dx,
           "steps": summary["steps"], "dt_s": summary["dt_s"],
           "wall_s": round(summary["wall_s"] + summary["setup_wall_s"], 1), "snapshots": []}
    for k in range(len(times)):
        dmg = damage[k] > DAMAGE_THRESHOLD
        snap = {"time_s": float(times[k]), **measures(x, r, theta, dmg, dx),
                "outer_rim_damaged_fraction": float(dmg[r > OUTER_RADIUS - 3 * dx].mean()),
                "broken": measures(x, r, theta, broken[k] > DAMAGE_THRESHOLD, dx)}
        res["snapshots"].append(snap)
    res["final"] = res["snapshots"][-1]
    res["crushed_radius_over_hole_radius"] = res["final"]["crushed_radius_m"] / HOLE_RADIUS
    return res, (x, times, damage, dx)


def main(argv):
    if len(argv) < 3:
        sys.stderr.write(__doc__)
        sys.exit(2)
    out, names = argv[1], argv[2:]
    report = {"case": "granite-blast", "damage_threshold": DAMAGE_THRESHOLD, "hole_radius_m": HOLE_RADIUS,
              "outer_radius_m": OUTER_RADIUS, "runs": []}
    fig_c, ax_c = plt.subplots(figsize=(6, 4))
    for name in names:
        res, (x, times, damage, dx) = analyse(out, name)
        report["runs"].append(res)
        picks = [int(np.argmin(np.abs(times * 1e6 - t))) for t in SNAPSHOT_TIMES_US] + [len(times) - 1]
        fig, axs = plt.subplots(1, 4, figsize=(18, 4.9))
        size = (72.0 * dx * 1e3 / 18.0) ** 2 * 9
        # The fourth panel: the last output again, zoomed on the hole, so that damage of a few
        # hole radii (e.g. with the rate law) is readable; half-width 1.3 x the farthest damaged
        # particle, at least 4 mm.
        zoom_mm = max(4.0, 1.3e3 * res["final"]["max_damaged_radius_m"])
        for ax, k, half in zip(axs, picks + [picks[-1]], [None] * 3 + [zoom_mm]):
            scale = 1.0 if half is None else (36.0 / half) ** 2
            ax.scatter(x[:, 0] * 1e3, x[:, 1] * 1e3, c=damage[k], s=size * scale, marker="s", cmap="jet", vmin=0,
                       vmax=1, linewidths=0)
            ax.set_aspect("equal")
            ax.set_title(f"t = {times[k] * 1e6:.1f} us" + ("" if half is None else f", zoom +-{half:.1f} mm"),
                         fontsize=10)
            if half is not None:
                ax.set_xlim(-half, half)
                ax.set_ylim(-half, half)
            ax.set_xlabel("x (mm)")
        axs[0].set_ylabel("y (mm)")
        fig.suptitle(f"granite-blast {name} (mean G0 {res['mean_fracture_energy_J_m2']:g} J/m2, dx = {dx * 1e3:g} mm): "
                     "damage", fontsize=10)
        fig.tight_layout()
        fig.savefig(os.path.join(out, f"damage_{name}.png"), dpi=110)
        plt.close(fig)
        c = res["final"]["cracks_at_radius_mm"]
        ax_c.plot(COUNT_RADII_MM, [max(v, 0) for v in c.values()], "o-", label=f"{name}, t = {times[-1] * 1e6:.0f} us")
        f = res["final"]
        print(f"{name}: particles {res['particles']}, wall {res['wall_s']} s, crushed radius "
              f"{f['crushed_radius_m'] * 1e3:.2f} mm ({res['crushed_radius_over_hole_radius']:.1f} x hole), "
              f"cracks at radius {f['cracks_at_radius_mm']}, max damaged radius {f['max_damaged_radius_m'] * 1e3:.1f} mm, "
              f"reach from the hole {f['hole_connected_reach_m'] * 1e3:.2f} mm")
        b = f["broken"]
        print(f"{name} from broken bonds only: crushed radius {b['crushed_radius_m'] * 1e3:.2f} mm, cracks at radius "
              f"{b['cracks_at_radius_mm']}, max radius {b['max_damaged_radius_m'] * 1e3:.1f} mm, "
              f"reach from the hole {b['hole_connected_reach_m'] * 1e3:.2f} mm")
    ax_c.set_xlabel("radius (mm)")
    ax_c.set_ylabel("radial cracks crossing the circle")
    ax_c.grid(alpha=0.3)
    ax_c.legend(fontsize=8)
    fig_c.tight_layout()
    fig_c.savefig(os.path.join(out, "cracks_vs_radius.png"), dpi=120)
    with open(os.path.join(out, "report.json"), "w") as fh:
        json.dump(report, fh, indent=1)


if __name__ == "__main__":
    main(sys.argv)
