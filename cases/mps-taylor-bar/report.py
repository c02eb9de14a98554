"""Taylor bar convergence report (cases/mps-taylor-bar/run.sh).

usage: report.py OUT RUN_DIR [RUN_DIR ...]

For each run (a breccia-mps output folder of case.yaml at one resolution) it reads the last
output of results.h5, summary.json and history.csv and measures, as TEST(MpsSolid,
TaylorBarFinalLengthIsWithinFivePercentOfPublished) does:
  length      = highest particle centre + half the initial spacing (the centres sit half a
                spacing inside the surface),
  face radius = largest distance of a particle centre from the axis + half the spacing (the
                mushroom is widest at the impact face),
  peak equivalent plastic strain, and the energy balance (stress work + hourglass + contact +
  kinetic against the initial kinetic energy).
Writes OUT/taylor_convergence.{md,json,png}, with the shape at every snapshot as a second
table. A run still going is reported at its last snapshot flushed to results.h5.partial
(no energy balance then); the energy balance is read at the last row of history.csv. With three or more finished resolutions the observed
order of convergence of the face radius is fitted and the radius extrapolated (Richardson);
that is an extrapolation, not a measurement.
"""
import csv
import json
import math
import os
import shutil
import sys
import tempfile

import h5py
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

DIAMETER_M = 6.4e-3
END_S = 80e-6
REF = {"length_mm": (21.4, 21.5), "radius_mm": (7.0, 7.1), "eps_p": (2.5, 3.0)}


def shape_at(x0, output, h):
    """Length, face radius, peak plastic strain of one output group (the test's measures)."""
    x = x0 + output["displacement"][:]
    eps = output["eq_plastic_strain"][:] if "eq_plastic_strain" in output else np.zeros(len(x))
    return {
        "time_us": float(output.attrs["time_s"]) * 1e6,
        "length_mm": (x[:, 2].max() + 0.5 * h) * 1e3,
        "radius_mm": (np.hypot(x[:, 0], x[:, 1]).max() + 0.5 * h) * 1e3,
        "eps_p": float(eps.max()),
    }


def spacing_of(run_dir):
    """The spacing of the run (metres), from the case as run (case_as_run.yaml)."""
    with open(os.path.join(run_dir, "case_as_run.yaml")) as fh:
        for line in fh:
            if line.strip().startswith("spacing:"):
                return float(line.split(":", 1)[1].split("#")[0])
    raise SystemExit(f"report.py: no spacing in {run_dir}/case_as_run.yaml")


def measure(run_dir):
    """A finished run (summary.json, results.h5, history.csv) or, while one is still running,
    the snapshots flushed so far to results.h5.partial (read from a copy; no energy then)."""
    finished = os.path.exists(os.path.join(run_dir, "summary.json"))
    summary = json.load(open(os.path.join(run_dir, "summary.json"))) if finished else {}
    h = spacing_of(run_dir)
    path = os.path.join(run_dir, "results.h5")
    if not finished:
        copy = os.path.join(tempfile.mkdtemp(), "results.h5")
        shutil.copy(path + ".partial", copy)
        path = copy
    with h5py.File(path, "r") as f:
        x0 = f["particles/position"][:]
        keys = sorted(f["output"].keys())
        series = [shape_at(x0, f["output"][k], h) for k in keys]
        steps = int(f["output"][keys[-1]].attrs.get("step", -1))
    r = {
        "run": os.path.basename(os.path.normpath(run_dir)),
        "across": int(round(DIAMETER_M / h)),
        "spacing_mm": h * 1e3,
        "particles": len(x0),
        "steps": summary.get("steps", steps),
        "finished": finished and series[-1]["time_us"] >= END_S * 1e6 * (1 - 1e-6),
        "running": not finished,
        "energy_balance": float("nan"),
        "kinetic_fraction": float("nan"),
        "wall_s": summary.get("wall_time_s", float("nan")),
        "threads": summary.get("threads", 0),
        "series": series,
    }
    r.update({k: series[-1][k] for k in ("time_us", "length_mm", "radius_mm", "eps_p")})
    if finished:  # energy at the last history row (history_every steps before the end at most)
        rows = list(csv.DictReader(open(os.path.join(run_dir, "history.csv"))))
        e0, end = float(rows[0]["kinetic_energy_J"]), rows[-1]
        total = sum(float(end[k]) for k in ("kinetic_energy_J", "stress_work_J", "hourglass_energy_J", "contact_energy_J"))
        r["energy_balance"] = total / e0 - 1.0
        r["kinetic_fraction"] = float(end["kinetic_energy_J"]) / e0
    return r


def observed_order(h, f):
    """Order p and limit f* of f(h) = f* + C h^p through three (spacing, value) pairs, the
    spacing ratio need not be constant (p by bisection); None with a reason when no p fits."""
    (h1, f1), (h2, f2), (h3, f3) = sorted(zip(h, f), reverse=True)
    if (f2 - f1) * (f3 - f2) <= 0:
        return {"note": "not monotone in the spacing: no order fitted"}
    target = (f1 - f2) / (f2 - f3)
    g = lambda p: (h1**p - h2**p) / (h2**p - h3**p) - target
    lo, hi = 0.05, 8.0
    if g(lo) * g(hi) > 0:
        return {"note": "no order in 0.05..8 fits the three values"}
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if g(lo) * g(mid) <= 0:
            hi = mid
        else:
            lo = mid
    p = 0.5 * (lo + hi)
    return {"order": p, "limit_radius_mm": f3 - (f2 - f3) / (h2**p - h3**p) * h3**p}


def richardson(runs):
    """Observed order of the face radius at 80 us from the three finest finished runs."""
    done = sorted((r for r in runs if r["finished"]), key=lambda r: r["spacing_mm"], reverse=True)[-3:]
    if len(done) < 3:
        return None
    fit = observed_order([r["spacing_mm"] for r in done], [r["radius_mm"] for r in done])
    fit["from_across"] = [r["across"] for r in done]
    return fit


def richardson_at_common_time(runs):
    """The same at the latest snapshot that the three finest runs (finished or not) share."""
    chosen = sorted(runs, key=lambda r: r["spacing_mm"], reverse=True)[-3:]
    if len(chosen) < 3:
        return None
    common = set.intersection(*({round(p["time_us"]) for p in r["series"]} for r in chosen))
    if not common or max(common) == 0:
        return None
    t = max(common)
    radius = [next(p["radius_mm"] for p in r["series"] if round(p["time_us"]) == t) for r in chosen]
    fit = observed_order([r["spacing_mm"] for r in chosen], radius)
    fit.update({"time_us": t, "from_across": [r["across"] for r in chosen], "radius_mm": radius})
    return fit


def main():
    if len(sys.argv) < 3:
        sys.stderr.write(__doc__)
        sys.exit(2)
    out = sys.argv[1]
    os.makedirs(out, exist_ok=True)
    runs = [measure(d) for d in sys.argv[2:]
            if os.path.exists(os.path.join(d, "summary.json")) or os.path.exists(os.path.join(d, "results.h5.partial"))]
    if not runs:
        sys.exit("report.py: no run (summary.json or results.h5.partial) among " + " ".join(sys.argv[2:]))
    runs.sort(key=lambda r: r["across"])
    fit = richardson(runs)
    lines = [
        "| particles across | particles | L0 of the lattice | steps | reached | length (21.4-21.5 mm) "
        "| face radius (7.0-7.1 mm) | peak eps_p (2.5-3) | energy balance | kinetic left | wall (threads) |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    pct = lambda v: "-" if math.isnan(v) else f"{100 * v:+.2f}%"
    for r in runs:
        reached = f"{r['time_us']:.1f} us" + (" (running)" if r["running"] else "")
        lines.append(
            f"| {r['across']} | {r['particles']:,} | {r['series'][0]['length_mm']:.2f} mm | {r['steps']:,} | {reached} "
            f"| {r['length_mm']:.2f} mm ({100 * (r['length_mm'] / 21.45 - 1):+.1f}%) "
            f"| {r['radius_mm']:.2f} mm ({100 * (r['radius_mm'] / 7.05 - 1):+.1f}%) "
            f"| {r['eps_p']:.2f} | {pct(r['energy_balance'])} | {pct(r['kinetic_fraction']).lstrip('+')} "
            + ("| - |" if r["running"] else f"| {r['wall_s']:.0f} s ({r['threads']}) |")
        )
    if fit and "order" in fit:
        lines.append("")
        lines.append(
            f"Extrapolation (not a measurement): the face radius from {fit['from_across']} across converges with observed "
            f"order {fit['order']:.2f} in the spacing towards {fit['limit_radius_mm']:.2f} mm (published 7.0-7.1 mm)."
        )
    elif fit:
        lines.append("")
        lines.append("Extrapolation: " + fit["note"])
    # The shape at each snapshot (about every 10 us): how far a resolution has converged
    # before 80 us, and where a run that is still going stands against the others.
    lines += ["", "Face radius (mm) and length (mm) at the snapshots:", "",
              "| t (us) | " + " | ".join(f"{r['across']} across" for r in runs) + " |",
              "|---|" + "---|" * len(runs)]
    times = sorted({round(p["time_us"]) for r in runs for p in r["series"]})
    for t in times:
        cells = []
        for r in runs:
            near = [p for p in r["series"] if abs(p["time_us"] - t) < 0.6]
            cells.append(f"{near[0]['radius_mm']:.2f} / {near[0]['length_mm']:.2f}" if near else "-")
        lines.append(f"| {t} | " + " | ".join(cells) + " |")
    early = richardson_at_common_time(runs)
    if early and "order" in early and not (fit and "order" in fit and early["time_us"] >= 80):
        lines += ["", f"At {early['time_us']} us, the latest snapshot all of {early['from_across']} across reached, the face "
                  f"radii {', '.join(f'{v:.2f}' for v in early['radius_mm'])} mm converge with observed order "
                  f"{early['order']:.2f} towards {early['limit_radius_mm']:.2f} mm (an extrapolation, and not of the "
                  f"80-us radius)."]
    table = "\n".join(lines) + "\n"
    with open(os.path.join(out, "taylor_convergence.md"), "w") as fh:
        fh.write(table)
    with open(os.path.join(out, "taylor_convergence.json"), "w") as fh:
        json.dump({"runs": runs, "richardson": fit, "richardson_at_common_time": early, "reference": REF}, fh, indent=2)
    print(table)

    fig, axes = plt.subplots(1, 3, figsize=(15, 4.4))
    done = [r for r in runs if r["finished"]]
    n = np.array([r["across"] for r in done])
    for ax, key, label, band in (
        (axes[0], "radius_mm", "impact-face radius at 80 us (mm)", REF["radius_mm"]),
        (axes[1], "length_mm", "final length at 80 us (mm)", REF["length_mm"]),
    ):
        ax.axhspan(*band, color="tab:green", alpha=0.25, label=f"published {band[0]}-{band[1]} mm")
        ax.plot(n, [r[key] for r in done], "o-", color="tab:blue", label="MPS stress solid (finished runs)")
        if key == "radius_mm" and fit and "order" in fit:
            ax.axhline(fit["limit_radius_mm"], color="tab:blue", ls=":",
                       label=f"extrapolated (order {fit['order']:.2f}): {fit['limit_radius_mm']:.2f} mm")
        ax.set_xlabel("particles across the diameter")
        ax.set_ylabel(label)
        if len(n):
            ax.set_xticks(n)
            ax.set_xlim(n.min() - 4, n.max() + 4)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8, loc="best")
    axes[0].set_title("Taylor bar, Cu 227 m/s: face radius")
    axes[1].set_title("final length")
    ax = axes[2]
    for r in runs:
        t = [p["time_us"] for p in r["series"]]
        ax.plot(t, [p["radius_mm"] for p in r["series"]], "o-", ms=3,
                label=f"{r['across']} across" + (f" (running, {r['time_us']:.0f} us)" if r["running"] else ""))
    ax.axhspan(*REF["radius_mm"], xmin=0.9, color="tab:green", alpha=0.4, label="published at 80 us")
    ax.set_xlim(0, 88)
    ax.set_xlabel("time (us)")
    ax.set_ylabel("face radius (mm)")
    ax.set_title("face radius against time")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="lower right")
    fig.tight_layout()
    fig.savefig(os.path.join(out, "taylor_convergence.png"), dpi=120)


if __name__ == "__main__":
    main()
