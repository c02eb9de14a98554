#!/usr/bin/env python3
"""Chart of the correspondence zero-energy-mode study (docs/atlas.md, "Correspondence").

Reads the rows breccia-atlas writes for `--models correspondence` (stability.csv format) and
the time series of the non-affine energy ratio, and draws docs/atlas/stability_correspondence.png:
top, the ratio against time at m = 3 for each stabilisation coefficient G; bottom, the measured
(m, G) plane, colour = the largest ratio seen, text = where the run-time detector fired.

usage: stability_correspondence_chart.py [--rows docs/atlas/stability_correspondence_rows.csv]
           [--series docs/atlas/stability_correspondence_series.csv] [--out docs/atlas/stability_correspondence.png]
"""
import argparse
import csv
import math
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

LIMIT = 1.0  # kMaxNonAffineRatio in solver/include/breccia/solver/correspondence_kernels.hpp


def g_of(model):
    return 0.0 if model == "corr_none" else float(model.split("_G")[1])


def g_label(g):
    return "none" if g == 0 else f"{g:g}"


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--rows", default="docs/atlas/stability_correspondence_rows.csv")
    ap.add_argument("--series", default="docs/atlas/stability_correspondence_series.csv")
    ap.add_argument("--out", default="docs/atlas/stability_correspondence.png")
    a = ap.parse_args()
    for option, path in (("--rows", a.rows), ("--series", a.series)):
        if not os.path.isfile(path):
            ap.error(f"{option}: {path} not found (expected breccia-atlas's table; run from the repository root or give "
                     "its path)")
    all_rows = list(csv.DictReader(open(a.rows)))
    rows = [r for r in all_rows if r["study"].startswith("zero_energy_")]
    series = list(csv.DictReader(open(a.series)))
    scenarios = ["noise", "impact"]
    titles = {"noise": "random particle velocities (+-1 m/s)", "impact": "impact: one column at 5 m/s"}
    fig, axes = plt.subplots(2, 2, figsize=(13, 10))
    for col, sc in enumerate(scenarios):
        ax = axes[0][col]
        gs = sorted({float(s["G"]) for s in series if s["scenario"] == sc})
        cmap = plt.get_cmap("viridis")
        for k, g in enumerate(gs):
            pts = [s for s in series if s["scenario"] == sc and float(s["G"]) == g and float(s["m"]) == 3.0]
            if not pts:
                continue
            t = [float(s["time_s"]) * 1e6 for s in pts]
            r = [max(float(s["nonaffine_ratio"]), 1e-4) for s in pts]
            ax.plot(t, r, color="black" if g == 0 else cmap(k / max(1, len(gs) - 1)), lw=2 if g == 0 else 1.3,
                    label=f"G = {g_label(g)}")
        ax.axhline(LIMIT, color="red", ls="--", lw=1.2, label=f"detector limit {LIMIT:g}")
        ax.set_yscale("log")
        ax.set_xlabel("time [us]")
        ax.set_ylabel("non-affine energy (unit penalty) / (kinetic + strain)")
        ax.set_title(f"{titles[sc]}, m = 3 (run continued past the detector)")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8, ncol=2)

        ax = axes[1][col]
        mine = [r for r in rows if r["study"] == "zero_energy_" + sc]
        ms = sorted({float(r["m"]) for r in mine})
        gvals = sorted({g_of(r["model"]) for r in mine})
        grid = np.full((len(ms), len(gvals)), np.nan)
        for r in mine:
            i, j = ms.index(float(r["m"])), gvals.index(g_of(r["model"]))
            grid[i, j] = math.log10(max(float(r["energy_scatter"]), 1e-3))
        # Diverging about the detector's limit: green below it, red above.
        norm = matplotlib.colors.TwoSlopeNorm(vmin=-1, vcenter=0, vmax=3)
        im = ax.imshow(grid, origin="lower", cmap="RdYlGn_r", norm=norm, aspect="auto")
        for r in mine:
            i, j = ms.index(float(r["m"])), gvals.index(g_of(r["model"]))
            stopped = r["status"] == "unstable"
            text = (f"STOPPED\nat step {r['steps']}" if stopped else "ran to end") + f"\nmax {float(r['energy_scatter']):.3g}"
            ax.text(j, i, text, ha="center", va="center", fontsize=7, color="black")
        ax.set_xticks(range(len(gvals)), [g_label(g) for g in gvals])
        ax.set_yticks(range(len(ms)), [f"{m:g}" for m in ms])
        ax.set_xlabel("stabilisation coefficient G (penalty on Y - F xi)")
        ax.set_ylabel("horizon ratio m = delta / dx")
        ax.set_title(f"{sc}: largest non-affine ratio, and the detector's verdict")
        fig.colorbar(im, ax=ax, label="log10 of the largest ratio (detector limit 1 -> 0)")
    fig.suptitle("Correspondence PD, 2D plane strain square 20 mm, dx 1 mm, dt = 0.8 x 2/omega_max: zero-energy modes "
                 "without stabilisation", fontsize=11)
    fig.tight_layout()
    fig.savefig(a.out, dpi=90)
    print("wrote", a.out)
    write_markdown(all_rows, os.path.dirname(a.out))


def summary(rows, scenario):
    """Per G: the largest ratio over m, and how many of the m values the detector stopped."""
    mine = [r for r in rows if r["study"] == "zero_energy_" + scenario]
    out = []
    for g in sorted({g_of(r["model"]) for r in mine}):
        at = [r for r in mine if g_of(r["model"]) == g]
        stopped = sum(r["status"] == "unstable" for r in at)
        out.append(f"G {g_label(g)}: max {max(float(r['energy_scatter']) for r in at):.3g}, stopped {stopped}/{len(at)}")
    return "; ".join(out)


def write_markdown(rows, folder):
    """The failure-mode table row and the section that scripts/atlas_charts.py puts in docs/atlas.md."""
    ms = sorted({float(r["m"]) for r in rows if r["study"].startswith("zero_energy_")})
    row = ("| correspondence zero-energy (hourglass) modes | particle-scale non-affine motion that leaves every F "
           "unchanged is not resisted: ratio of the non-affine energy (unit penalty) to kinetic + strain energy, "
           f"largest over m = {', '.join(f'{m:g}' for m in ms)} and 1000 steps: noise: {summary(rows, 'noise')}; "
           f"impact: {summary(rows, 'impact')} | `zero_energy_mode_message` (solver/src/correspondence.cpp), "
           "called by `instability_message` at every history step: ratio above 1 stops the run (exit 3, last good "
           "output kept) naming the zero-energy (hourglass) modes, the ratio, the worst particle and "
           "`model.stabilisation`; G >= 1 bounds the ratio by 1/G | "
           "`CorrespondenceZeroEnergyModes.UnstabilisedNoiseIsStoppedByTheZeroEnergyDetector`, "
           "`CorrespondenceZeroEnergyModes.UnstabilisedImpactIsStoppedByTheZeroEnergyDetector`, "
           "`CorrespondenceZeroEnergyModes.CliExitsWithCodeThreeAndKeepsTheHistory`, "
           "`CorrespondenceZeroEnergyModes.StabilisedImpactRunsToTheEndConservingEnergy`, "
           "`CorrespondenceZeroEnergyModes.StabilisedNoiseRunsToTheEndWithoutTrippingTheDetector` |")
    with open(os.path.join(folder, "stability_correspondence_row.md"), "w") as fh:
        fh.write(row + "\n")
    print("wrote", os.path.join(folder, "stability_correspondence_row.md"))
    dt = sorted((float(r["dt_factor"]), r["status"]) for r in rows if r["study"] == "dt_factor")
    stable = [f for f, st in dt if st == "completed"]
    unstable = [f for f, st in dt if st == "unstable"]
    dt_line = (f"The dt study (a) on correspondence (penalty G = 1, lattice): stable up to f = {max(stable):g}, "
               f"unstable from f = {min(unstable):g}, stopped by the energy check as PMB and LPS: the power-iteration "
               "stable step includes the penalty's stiffness." if stable and unstable else "")
    section = f"""### Correspondence zero-energy modes (measured)

Reproduce: `build/bin/breccia-atlas --only-stability --models correspondence --kinds lattice
--stability-studies pd --stability-csv docs/atlas/stability_correspondence_rows.csv` (about 7.5 min
on 2 shared cores, 26 s on 2 quiet ones on 2026-12-07; it also runs studies (a) and (b) for correspondence and writes the time series
`docs/atlas/stability_correspondence_series.csv`; `--quick`: m = 2, 3, 4, G = none, 0.01, 0.1, 1,
400 steps) then `/usr/bin/python3 scripts/stability_correspondence_chart.py`.

A free 2D plane-strain square (20 mm, dx 1 mm, lattice, dt = 0.8 x 2/omega_max) set moving in two
ways that feed the particle-scale modes: **noise**, random velocities (+-1 m/s per component,
fixed seed), and **impact**, one column starting at 5 m/s. Each (m, G) runs 1000 steps; every 5
steps the solver's own check (`instability_message`, which holds the zero-energy detector) gives its
verdict, and the run goes on past it so that the chart shows what the detector saw. Measure: the
ratio R of the non-affine energy under a unit penalty, sum_i V_i (h_i/2) sum_j w |Y - F_i xi|^2 V_j,
to the kinetic + strain energy (docs/theory.md, correspondence).

What was found (rerun 2026-12-07 with the St Venant-Kirchhoff material, docs/theory.md; the
same verdict in every row as with the small-strain law before it, the ratios within a few per
cent): without stabilisation R does not grow exponentially (at these strains, about 1e-4, the
model is linear to first order): it jumps within tens of steps to ~500-1900 under noise, ~2.6-6.4 after the impact, and
stays there: the particle-scale motion is never restored. With the penalty R falls as about 1/G
(noise: R ~ 0.3/G to 0.7/G), as energy conservation requires; G >= 1 kept R <= 0.71 in every run.
Between G = 0.003 and 0.03 the impact sits at the limit (R 0.9-1.8, stopped in 10 of 12 runs, not
monotonic in G at m = 2): there the detector's verdict is marginal. The energy ratio column of
the rows (1.04-1.57) is velocity Verlet's shadow-energy offset of the initial particle-scale
velocities, not growth: LPS shows +20 % on the same impact, and at a quarter of the step the
penalty model conserves energy to 1 % (`StabilisedImpactRunsToTheEndConservingEnergy`).
{dt_line}

![Correspondence zero-energy modes](atlas/stability_correspondence.png)
"""
    with open(os.path.join(folder, "stability_correspondence_section.md"), "w") as fh:
        fh.write(section)
    print("wrote", os.path.join(folder, "stability_correspondence_section.md"))




if __name__ == "__main__":
    main()
