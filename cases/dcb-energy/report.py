"""Report of cases/dcb-energy: dissipated energy against G0 x crack area while the crack grows,
and crack length against opening compared with beam theory.

    report.py OUT RUN [RUN ...]

Reads OUT/RUN/case_as_run.yaml, OUT/RUN/history.csv and OUT/RUN/post_steps/<step>.json (breccia-post
at every output, written by run.sh). Writes OUT/report.json, OUT/dcb_energy.png and
OUT/dcb_crack_length.png.
"""
import csv
import glob
import json
import os
import sys

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
import yaml

E, G0, THICKNESS, ARM_HEIGHT = 72e9, 3.8, 1e-3, 2e-3
LOAD_LINE = 0.05e-3      # the pins' x (first lattice column)
PRECRACK_FACES_END = 2.0e-3  # the pre-crack cuts the mid-plane faces up to here (tip at 2.037 mm)
RAMP = 20e-6
EI = E * THICKNESS * ARM_HEIGHT**3 / 12.0  # one arm


def beam_crack_length(opening, chi):
    """Crack length (from the load line) at G = G0 for a total opening: corrected beam theory,
    compliance of each arm (a + chi H)^3 / (3 EI), G = P^2 (a + chi H)^2 / (b EI)."""
    return (9.0 * EI * opening**2 / (4.0 * THICKNESS * G0)) ** 0.25 - chi * ARM_HEIGHT


def load_run(out, name):
    case = yaml.safe_load(open(os.path.join(out, name, "case_as_run.yaml")))
    rate = float(case["boundary"][0]["value"][1])
    rows = []
    for path in sorted(glob.glob(os.path.join(out, name, "post_steps", "*.json"))):
        p = json.load(open(path))
        c, e = p["cracks"], p["energy"]
        t = p["time_s"]
        area = c["smoothed_fracture_area_m2"]
        rows.append({
            "step": p["step"], "time_s": t,
            "opening_m": 2 * rate * (t - 0.5 * RAMP) if t > RAMP else rate * t * t / RAMP,
            "fracture_face_area_m2": c["fracture_area_m2"],
            "smoothed_fracture_area_m2": area,
            "crack_length_m": PRECRACK_FACES_END - LOAD_LINE + area / THICKNESS,
            "separating_fracture_area_m2": c["separating_fracture_area_m2"],  # 0: still one piece
            "dissipated_J": e["dissipated_J"],
            "G0_times_area_J": e["G0_times_crack_area_J"],
            "ratio": e["ratio"] if area > 0 else None,
            "ratio_face_area": e["ratio_face_area"] if area > 0 else None,
        })
    hist = list(csv.DictReader(open(os.path.join(out, name, "history.csv"))))
    ht = np.array([float(h["time_s"]) for h in hist])
    for r in rows:
        h = hist[int(np.argmin(abs(ht - r["time_s"])))]
        r["kinetic_over_strain"] = float(h["kinetic_J"]) / max(float(h["strain_J"]), 1e-300)
    return rate, rows


def main():
    if len(sys.argv) < 3:
        sys.stderr.write(__doc__)
        sys.exit(2)
    out, names = sys.argv[1], sys.argv[2:]
    report = {"G0_J_m2": G0, "runs": {}}
    fig, ax = plt.subplots(1, 2, figsize=(11, 4.2))
    fig2, ax2 = plt.subplots(figsize=(6, 4.2))
    for name in names:
        rate, rows = load_run(out, name)
        grown = [r for r in rows if r["smoothed_fracture_area_m2"] >= 1e-3 * THICKNESS]
        summary = {"rate_per_arm_m_s": rate, "outputs": rows}
        if grown:
            ratios = [r["ratio"] for r in grown]
            summary.update({"ratio_min_after_1mm_growth": min(ratios), "ratio_max_after_1mm_growth": max(ratios),
                            "last": grown[-1]})
            print(f"{name}: ratio D / (G0 x smoothed area) over {len(grown)} outputs with >= 1 mm growth: "
                  f"{min(ratios):.3f} - {max(ratios):.3f}; last: growth {grown[-1]['smoothed_fracture_area_m2'] / THICKNESS * 1e3:.2f} mm, "
                  f"ratio {grown[-1]['ratio']:.3f}, face-area ratio {grown[-1]['ratio_face_area']:.3f}")
        report["runs"][name] = summary
        g = np.array([r["smoothed_fracture_area_m2"] / THICKNESS * 1e3 for r in rows])
        label = f"{rate:g} m/s per arm"
        ax[0].plot(g, [r["dissipated_J"] * 1e6 for r in rows], "o-", ms=3, label=f"dissipated D, {label}")
        ax[0].plot(g, [r["G0_times_area_J"] * 1e6 for r in rows], "k--", lw=0.8)
        sel = [i for i, r in enumerate(rows) if r["ratio"] is not None and g[i] > 0.3]
        ax[1].plot(g[sel], [rows[i]["ratio"] for i in sel], "o-", ms=3, label=f"smoothed area, {label}")
        ax[1].plot(g[sel], [rows[i]["ratio_face_area"] for i in sel], "x:", ms=4, label=f"face area, {label}")
        ax2.plot([r["opening_m"] * 1e6 for r in rows if r["smoothed_fracture_area_m2"] > 0],
                 [r["crack_length_m"] * 1e3 for r in rows if r["smoothed_fracture_area_m2"] > 0], "o", ms=4,
                 label=f"Breccia PMB, {label}")
    ax[0].plot([], [], "k--", lw=0.8, label="G0 x smoothed crack area")
    ax[0].set(xlabel="crack growth (smoothed fracture area / thickness) [mm]", ylabel="energy [uJ]",
              title="Dissipated energy and G0 x crack area")
    ax[0].legend(fontsize=8)
    ax[1].axhspan(0.9, 1.1, color="0.9", label="1 +- 10 %")
    ax[1].axhline(1.0, color="k", lw=0.6)
    ax[1].set(xlabel="crack growth [mm]", ylabel="D / (G0 x area)", title="Energy ratio", ylim=(0.5, 1.3))
    ax[1].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "dcb_energy.png"), dpi=130)
    d = np.linspace(1e-6, ax2.get_xlim()[1] * 1e-6, 200)
    for chi, style in ((0.0, "k:"), (0.64, "k--"), (0.91, "k-.")):
        ax2.plot(d * 1e6, beam_crack_length(d, chi) * 1e3, style, lw=1,
                 label=f"beam theory at G = G0, a + {chi:g} H" if chi else "simple beam theory at G = G0")
    ax2.set(xlabel="opening at the pins [um]", ylabel="crack length from the load line [mm]",
            title="DCB crack length against opening", ylim=(0, None))
    ax2.legend(fontsize=8)
    fig2.tight_layout()
    fig2.savefig(os.path.join(out, "dcb_crack_length.png"), dpi=130)
    with open(os.path.join(out, "report.json"), "w") as f:
        json.dump(report, f, indent=1)


if __name__ == "__main__":
    main()
