"""Report of cases/mps-fin-drop: the fin's plastic hinges, plastic strain maps, the impact
force and the energy balance at each inclination.

    report.py OUT RUN [RUN ...]

Inclination: from the floor normal n of OUT/RUN/case_as_run.yaml, a = atan2(n_x, n_y) (case.yaml:
n = (sin a, cos a)), so any run folder of this case will do, whatever its name.
Shape: the fin's centre line at the end (each station's mean current position), its curvature
(the turning of the line between stations, less that of the initial line, which is not straight
for a bowed fin (specimen.py --bow); smoothed over one fin thickness), and its bends:
local maxima of |curvature| above 30% of the largest and 1 /m, at least two thicknesses
apart; two bends of opposite sign are the S-shape of a double hinge, one bend a single hinge.
Plastic hinges: along the fin (the particles of set `fin`, stations = rows of the reference lattice
from the root at the ring's surface to the tip), the largest equivalent plastic strain across
the fin's thickness at each station at the end of the run; a hinge is a local maximum of that
profile above half the fin's largest strain, HINGE_MIN_STRAIN and 1.5 times the profile's median
(localised: a fin crushed evenly has none), separated from the next by at least two fin
thicknesses (a hinge spreads over about one thickness); report.json also lists every peak
above HINGE_MIN_STRAIN (`strain_peaks_*`) with the bar the hinges clear. The ring's
wall at the root counts as station 0 (the largest strain of the ring within one fin thickness
of the root). Energy: kinetic + stress work (elastic + plastic) + hourglass + contact +
gravity + friction dissipation against the initial kinetic energy (history.csv). Tip slip: the
tip row's mean displacement along the target (positive downhill, +x side), which tells a tip held
by friction (a few mm) from one that slides. Writes OUT/report.json,
OUT/fin_drop_plastic.png (deformed shapes coloured by plastic strain), OUT/fin_drop_profiles.png
(plastic strain along the fin) and OUT/fin_drop_force.png (floor force against time).
"""
import csv
import json
import math
import os
import re
import sys

import h5py
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

HINGE_MIN_STRAIN = 0.02


def analyse(out, name):
    run = os.path.join(out, name)
    as_run = os.path.join(run, "case_as_run.yaml")
    if not os.path.exists(as_run):
        print(f"report.py: {as_run} not found (expected a breccia-mps run folder of this case: its floor "
              "normal gives the inclination, and the friction and particles come from it too)", file=sys.stderr)
        sys.exit(2)
    text = open(as_run).read()
    floor = re.search(r"floor:\s*\{([^}]*)\}", text).group(1)
    normal, point = (np.array([float(v) for v in re.search(key + r":\s*\[([^\]]*)\]", floor).group(1).split(",")])
                     for key in ("normal", "point"))
    # The inclination as the case defines it (case.yaml, run.sh): the target's normal n = (sin a, cos a)
    # turned by a from the fin's axis (0, 1).
    angle = round(math.degrees(math.atan2(normal[0], normal[1])), 6) + 0.0
    friction = float(re.search(r"static_friction:\s*([-0-9.eE+]+)", floor).group(1)) if "static_friction" in floor else 0.0
    particles = os.path.normpath(os.path.join(run, re.search(r"particles:\s*(\S+)", text).group(1)))
    with h5py.File(particles, "r") as f:
        fin = f["sets/fin"][:]
    with h5py.File(os.path.join(run, "results.h5"), "r") as f:
        x0 = f["particles/position"][:, :2]
        last = f["output"][sorted(f["output"].keys())[-1]]
        u = last["displacement"][:, :2]
        ep = last["eq_plastic_strain"][:]
        t_end = float(last.attrs["time_s"])
    dx = float(np.min(np.diff(np.unique(np.round(x0[fin, 1], 9)))))
    rows = np.unique(np.round(x0[fin, 1], 9))[::-1]  # from the root (highest y) to the tip
    in_row = [fin[np.abs(x0[fin, 1] - y) < 1e-9] for y in rows]
    thickness = max(np.ptp(x0[r, 0]) for r in in_row) + dx  # per row: a bowed fin is no wider
    root_y = rows[0] + dx / 2
    profile = np.array([ep[r].max() for r in in_row])
    station = root_y - rows  # distance from the root
    ring_root = np.nonzero((np.abs(x0[:, 0]) < thickness) & (x0[:, 1] > root_y) & (x0[:, 1] < root_y + thickness))[0]
    prof = np.concatenate([[ep[ring_root].max() if len(ring_root) else 0.0], profile])
    pos = np.concatenate([[0.0], station])
    # The fin's bent shape: each station's mean current position; its curvature from the
    # turning of the centre line between neighbouring stations, smoothed over one thickness.
    cur = x0 + u
    centre = np.array([cur[r].mean(axis=0) for r in in_row])
    centre0 = np.array([x0[r].mean(axis=0) for r in in_row])

    def turning(line):
        seg = np.diff(line, axis=0)
        return np.diff(np.unwrap(np.arctan2(seg[:, 1], seg[:, 0]))) / dx  # 1/m, at the interior stations

    kappa = turning(centre) - turning(centre0)
    tangent = np.array([normal[1], -normal[0]])  # along the target, downhill (+x side)
    tip_slip = float((centre[-1] - centre0[-1]) @ tangent)
    width = max(1, int(round(thickness / dx)))
    kappa = np.convolve(kappa, np.ones(width) / width, mode="same")
    kpos = station[1:-1]
    kmax = float(np.max(np.abs(kappa))) if len(kappa) else 0.0
    bends = []  # (position, curvature): local maxima of |kappa| above 30% of the largest
    for k in range(len(kappa)):
        a = abs(kappa[k])
        if a < 0.3 * kmax or a < 1.0:
            continue
        if (k > 0 and abs(kappa[k - 1]) > a) or (k + 1 < len(kappa) and abs(kappa[k + 1]) > a):
            continue
        if bends and kpos[k] - bends[-1][0] < 2 * thickness:
            if a > abs(bends[-1][1]):
                bends[-1] = (kpos[k], kappa[k])
            continue
        bends.append((kpos[k], kappa[k]))
    peak = prof.max()
    floor_strain = max(0.5 * peak, HINGE_MIN_STRAIN, 1.5 * float(np.median(prof)))

    def peaks(bar):  # local maxima of the profile at least bar, two thicknesses apart
        found = []
        for k in range(len(prof)):
            lo, hi = prof[k - 1] if k > 0 else -1.0, prof[k + 1] if k + 1 < len(prof) else -1.0
            if prof[k] >= lo and prof[k] >= hi and prof[k] >= bar:
                if found and pos[k] - found[-1][0] < 2 * thickness:
                    if prof[k] > found[-1][1]:
                        found[-1] = (pos[k], prof[k])
                    continue
                found.append((pos[k], prof[k]))
        return found

    hinges = peaks(floor_strain)
    # All the profile's peaks above HINGE_MIN_STRAIN, hinge or not: shows a peak that misses
    # the localisation bar (strain spread along the whole fin) next to the hinges.
    strain_peaks = peaks(HINGE_MIN_STRAIN)
    hist = list(csv.DictReader(open(os.path.join(run, "history.csv"))))
    col = lambda k: np.array([float(h[k]) for h in hist])  # noqa: E731
    t = col("time_s")
    parts = ["kinetic_energy_J", "stress_work_J", "hourglass_energy_J", "contact_energy_J", "gravity_energy_J",
             "friction_dissipation_J"]
    total = sum(col(k) for k in parts if k in hist[0])
    e0 = float(col("kinetic_energy_J")[0])
    force = col("floor_force_N") if "floor_force_N" in hist[0] else None
    res = {"run": name, "angle_deg": angle, "spacing_m": dx, "end_time_s": t_end,
           "fin_thickness_m": thickness, "friction": friction, "tip_slip_m": round(tip_slip, 5),
           "bend_count": len(bends), "bends_m_from_root": [round(float(p), 4) for p, _ in bends],
           "bend_curvatures_per_m": [round(float(c), 2) for _, c in bends],
           "shape": ("straight (crushed)" if not bends else "single bend" if len(bends) == 1
                     else "S-shape (double bend)" if len(bends) == 2 and bends[0][1] * bends[1][1] < 0
                     else f"{len(bends)} bends"),
           "hinge_count": len(hinges),
           "hinges_m_from_root": [round(float(p), 4) for p, _ in hinges],
           "hinge_strains": [round(float(s), 4) for _, s in hinges],
           "hinge_bar_strain": round(float(floor_strain), 4),
           "strain_peaks_m_from_root": [round(float(p), 4) for p, _ in strain_peaks],
           "strain_peak_strains": [round(float(s), 4) for _, s in strain_peaks],
           "max_fin_plastic_strain": float(peak),
           "initial_kinetic_J": e0, "energy_error_max_over_initial": float(np.max(np.abs(total - total[0])) / e0),
           "plastic_and_elastic_work_end_J": float(col("stress_work_J")[-1]),
           "peak_floor_force_N_per_m": float(force.max()) if force is not None else None}
    return res, (x0, u, ep, pos, prof, t, force, fin, normal, point)


def main(argv):
    if len(argv) < 3:
        sys.stderr.write(__doc__)
        sys.exit(2)
    out, names = argv[1], argv[2:]
    runs, data = [], []
    for n in names:
        r, d = analyse(out, n)
        runs.append(r)
        data.append(d)
        print(f"{n}: {r['shape']}: bends at {r['bends_m_from_root']} m from the root (curvature "
              f"{r['bend_curvatures_per_m']} 1/m); plastic hinges {r['hinge_count']} at {r['hinges_m_from_root']} m "
              f"(strains {r['hinge_strains']}; bar {r['hinge_bar_strain']}; all peaks "
              f"{list(zip(r['strain_peaks_m_from_root'], r['strain_peak_strains']))}), tip slip {r['tip_slip_m'] * 1e3:.1f} mm, energy error {r['energy_error_max_over_initial']:.2%}"
              + (f", peak floor force {r['peak_floor_force_N_per_m'] / 1e6:.2f} MN/m" if r["peak_floor_force_N_per_m"] else ""))
    json.dump({"case": "mps-fin-drop", "runs": runs}, open(os.path.join(out, "report.json"), "w"), indent=1)
    fig, axs = plt.subplots(1, len(runs), figsize=(3.8 * len(runs), 5.0), squeeze=False)
    vmax = max(0.05, max(float(d[2][d[7]].max()) for d in data))  # one colour scale: the fins' largest strain
    for ax, r, (x0, u, ep, *_rest, fin, normal, point) in zip(axs[0], runs, data):
        cur = x0 + u
        # The fin and the ring's wall around its root (a window of 1.2 fin lengths).
        centre = np.array([np.mean(cur[fin, 0]), np.max(x0[fin, 1])])
        half = 0.6 * (np.ptp(x0[fin, 1]) + r["spacing_m"])
        near = (np.abs(cur[:, 0] - centre[0]) < half) & (cur[:, 1] < centre[1] + 0.2 * half) & (cur[:, 1] > centre[1] - 2 * half)
        size = 1500 * r["spacing_m"]  # markers a little under a particle wide at this window's scale
        sc = ax.scatter(cur[near, 0], cur[near, 1], c=ep[near], s=size, cmap="inferno", vmin=0, vmax=vmax)
        tangent = np.array([normal[1], -normal[0]])
        ends = np.array([point - 2.0 * tangent, point + 2.0 * tangent])  # far past the window
        ax.plot(ends[:, 0], ends[:, 1], color="tab:blue", lw=2)  # the target
        ax.set_xlim(centre[0] - half, centre[0] + half)
        ax.set_ylim(centre[1] - 2 * half, centre[1] + 0.2 * half)
        ax.set_aspect("equal")
        ax.set_title(f"{r['angle_deg']:g} deg: {r['shape']}\n{r['hinge_count']} plastic hinge(s); tip slip "
                     f"{r['tip_slip_m'] * 1e3:.0f} mm", fontsize=9)
        ax.set_xlabel("x (m, cask frame; target in blue)")
    fig.colorbar(sc, ax=list(axs[0]), shrink=0.8, label="equivalent plastic strain")
    fig.savefig(os.path.join(out, "fin_drop_plastic.png"), dpi=110, bbox_inches="tight")
    fig, ax = plt.subplots(figsize=(6, 4))
    for r, (_x0, _u, _ep, pos, prof, *_rest) in zip(runs, data):
        ax.plot(pos * 1e3, prof, "o-", ms=3, label=f"{r['angle_deg']:g} deg")
        for h in r["hinges_m_from_root"]:
            ax.axvline(h * 1e3, color=ax.lines[-1].get_color(), ls=":", lw=0.8)
    ax.set_xlabel("distance from the fin's root (mm; 0 = ring wall)")
    ax.set_ylabel("largest plastic strain across the fin")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "fin_drop_profiles.png"), dpi=110)
    fig, ax = plt.subplots(figsize=(6, 4))
    for r, (*_rest, t, force, _fin, _normal, _point) in zip(runs, data):
        if force is not None:
            ax.plot(t * 1e3, force / 1e6, lw=0.8, label=f"{r['angle_deg']:g} deg")
    ax.set_xlabel("time (ms)")
    ax.set_ylabel("floor force (MN per m of cask)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "fin_drop_force.png"), dpi=110)


if __name__ == "__main__":
    main(sys.argv)
