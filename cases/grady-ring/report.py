"""Mean fragment size of the expanding-ring runs against Grady (1982).

    report.py OUT RUN [RUN ...]

Fragments: breccia-post's fragments.csv (connected pieces of the intact bond graph).
Kept fragments: at least two particle columns long (>= 2 x particles across the width);
smaller pieces are dust from the width of PD crack bands, reported as a mass fraction.
Mean size s_PD: mean arc length of the kept fragments (area / ring width). Grady (1982),
brittle: s = (sqrt(24) K_Ic / (rho c rate))^(2/3), c = sqrt(E/rho). Writes OUT/report.json,
OUT/fragment_size.png and OUT/fragments.png.
"""
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

E, RHO, K_IC = 72e9, 2440.0, 0.75e6
C_BAR = math.sqrt(E / RHO)


def grady_size(rate):
    return (math.sqrt(24.0) * K_IC / (RHO * C_BAR * rate)) ** (2.0 / 3.0)


def zmr_size(rate, horizon, strength=None):
    """Zhou, Molinari & Ramesh (2006, Appl Phys Lett 88:261918), cohesive fragmentation:
    s = L0 * 4.5 / (1 + 4.5 e^(2/3)), L0 = E G0 / sigma_t^2, e = rate / e0,
    e0 = c sigma_t^3 / (E^2 G0) (= sigma_t c / (E L0)). With softening bonds sigma_t is the
    material's tensile_strength. Without one (critical-stretch bonds), sigma_t = E s0 with the
    plane-stress s0 = sqrt(4 pi G0 / (9 E delta)), so L0 = 9 delta / (4 pi): the PD material
    length is then tied to the horizon."""
    g0 = K_IC ** 2 / E
    sigma = strength if strength else E * math.sqrt(4.0 * math.pi * g0 / (9.0 * E * horizon))
    length = E * g0 / sigma ** 2
    rate0 = C_BAR * sigma ** 3 / (E ** 2 * g0)
    return length * 4.5 / (1.0 + 4.5 * (rate / rate0) ** (2.0 / 3.0))


def zmr_e(rate, strength):
    g0 = K_IC ** 2 / E
    return rate / (C_BAR * strength ** 3 / (E ** 2 * g0))


def ring_geometry(x):
    """Particles across the width (the polar lattice's circles) and the mean radius."""
    radii = np.hypot(x[:, 0], x[:, 1])
    return {"across": len(np.unique(np.round(radii, 9))), "radius": float(radii.mean())}


def kept_fragments(csv_path, ring, thickness):
    """breccia-post's fragments.csv -> (rows, particle counts, kept mask, arc lengths, ring width).
    Kept: at least two particle columns long (>= 2 x the particles across the width)."""
    fr = np.atleast_1d(np.genfromtxt(csv_path, delimiter=",", names=True))
    count = fr["particle_count"]
    kept = count >= 2 * ring["across"]
    # The ring's width from its own particles (volume over mean circumference), so rings of
    # any width (run.sh WIDTH) are measured alike.
    width = float(fr["volume_m3"].sum()) / (2 * math.pi * ring["radius"] * thickness)
    arc = fr["volume_m3"] / (width * thickness)
    return fr, count, kept, arc, width


def analyse(out, name):
    run = os.path.join(out, name)
    text = open(os.path.join(run, "case_as_run.yaml")).read()
    rate = float(re.search(r"strain_rate:\s*([0-9.eE+-]+)", text).group(1))
    m = re.search(r"tensile_strength:\s*([0-9.eE+-]+)\s*MPa", text)
    strength = float(m.group(1)) * 1e6 if m else None
    with h5py.File(os.path.join(run, "results.h5"), "r") as f:
        x = f["particles/position"][:, :2]
        thickness = float(f.attrs["thickness_m"])
        last = sorted(f["output"].keys())[-1]
        u = f["output"][last]["displacement"][:, :2]
        horizon = float(np.median(f["particles/horizon"][:]))
        t_end = float(f["output"][last].attrs["time_s"])
    ring = ring_geometry(x)
    across, radius = ring["across"], ring["radius"]
    fr, count, kept, arc, width = kept_fragments(os.path.join(run, "post", "fragments.csv"), ring, thickness)
    with open(os.path.join(run, "summary.json")) as fh:
        summary = json.load(fh)
    res = {"run": name, "strain_rate_per_s": rate, "particles": int(summary["particles"]),
           "particles_across_width": across, "ring_width_m": width, "end_time_s": t_end,
           "wall_s": round(summary["wall_s"] + summary["setup_wall_s"], 1),
           "fragments_all": int(len(count)), "fragments_kept": int(kept.sum()),
           "dust_mass_fraction": float(1.0 - fr["mass_kg"][kept].sum() / fr["mass_kg"].sum()),
           "horizon_m": horizon, "grady_size_m": grady_size(rate),
           "tensile_strength_Pa": strength, "ring_radius_m": radius,
           "zhou_molinari_ramesh_size_m": zmr_size(rate, horizon, strength),
           "circumference_over_all_fragments_m": float(2 * math.pi * radius / len(count))}
    if strength:
        res["zmr_e"] = zmr_e(rate, strength)
    if kept.any():
        res["mean_size_m"] = float(arc[kept].mean())
        res["circumference_over_count_m"] = float(2 * math.pi * radius / kept.sum())
        res["size_over_grady"] = res["mean_size_m"] / res["grady_size_m"]
    return res, (x, u)


def main(argv):
    if len(argv) < 3:
        sys.stderr.write(__doc__)
        sys.exit(2)
    out, names = argv[1], argv[2:]
    runs, fields = [], []
    for n in names:
        r, f = analyse(out, n)
        runs.append(r)
        fields.append(f)
    report = {"case": "grady-ring", "c_bar_m_s": C_BAR, "K_Ic_Pa_sqrt_m": K_IC, "runs": runs}
    ok = [r for r in runs if "mean_size_m" in r and r["dust_mass_fraction"] < 0.5]
    if len(ok) >= 2:
        slope, icpt = np.polyfit(np.log([r["strain_rate_per_s"] for r in ok]), np.log([r["mean_size_m"] for r in ok]), 1)
        report["fitted_exponent"] = float(slope)
        report["grady_exponent"] = -2.0 / 3.0
        report["fit_uses_runs"] = [r["run"] for r in ok]
    with open(os.path.join(out, "report.json"), "w") as fh:
        json.dump(report, fh, indent=1)

    fig, ax = plt.subplots(figsize=(6, 4.5))
    rates = np.logspace(np.log10(min(r["strain_rate_per_s"] for r in runs)) - 0.2,
                        np.log10(max(r["strain_rate_per_s"] for r in runs)) + 0.2, 50)
    ax.loglog(rates, [grady_size(q) * 1e3 for q in rates], "k-", label="Grady (1982), slope -2/3")
    have = [r for r in runs if "mean_size_m" in r]
    ax.loglog([r["strain_rate_per_s"] for r in have], [r["mean_size_m"] * 1e3 for r in have], "o",
              label="Breccia PD, mean arc of kept fragments")
    strength = runs[0]["tensile_strength_Pa"]
    ax.loglog(rates, [zmr_size(q, runs[0]["horizon_m"], strength) * 1e3 for q in rates], "k--", lw=1,
              label=(f"Zhou-Molinari-Ramesh 2006, sigma_t {strength / 1e6:g} MPa" if strength else
                     "Zhou-Molinari-Ramesh 2006 with PD's L0 = 9 delta/(4 pi)"))
    if "fitted_exponent" in report:
        ax.set_title(f"fitted exponent {report['fitted_exponent']:.2f} (Grady -0.67)", fontsize=9)
    ax.axhline(2 * 3.015 * (runs[0]["ring_width_m"] / runs[0]["particles_across_width"]) * 1e3,
               color="0.5", ls=":", label="2 x horizon")
    ax.set_xlabel("strain rate (1/s)")
    ax.set_ylabel("mean fragment size (mm)")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "fragment_size.png"), dpi=120)

    pick = [0, len(runs) - 1] if len(runs) > 1 else [0]
    fig, axs = plt.subplots(1, len(pick), figsize=(5 * len(pick), 5), squeeze=False)
    for ax, k in zip(axs[0], pick):
        x, u = fields[k]
        cur = x + u
        # Colour by fragment: neighbouring kept fragments alternate colours.
        fr = os.path.join(out, runs[k]["run"], "post", "fragments.vtu")
        colour = None
        try:
            import meshio
            m = meshio.read(fr)
            colour = np.asarray(m.point_data["fragment_id"]).ravel() % 10
        except Exception:  # noqa: BLE001 - picture only; fall back to plain dots
            colour = np.zeros(len(x))
        ax.scatter(cur[:, 0] * 1e3, cur[:, 1] * 1e3, c=colour, cmap="tab10", s=0.5, linewidths=0)
        ax.set_aspect("equal")
        r = runs[k]
        ax.set_title(f"rate {r['strain_rate_per_s']:.0e}/s, t = {r['end_time_s'] * 1e6:.1f} us: "
                     f"{r['fragments_kept']} fragments", fontsize=9)
        ax.set_xlabel("x (mm)")
        ax.set_ylabel("y (mm)")
    fig.tight_layout()
    fig.savefig(os.path.join(out, "fragments.png"), dpi=120)
    for r in runs:
        print(f"{r['run']}: kept {r['fragments_kept']} / {r['fragments_all']}, dust {r['dust_mass_fraction']:.2f}, "
              f"mean size {r.get('mean_size_m', float('nan')) * 1e3:.2f} mm, Grady {r['grady_size_m'] * 1e3:.2f} mm, "
              f"ZMR {r['zhou_molinari_ramesh_size_m'] * 1e3:.2f} mm, "
              f"wall {r['wall_s']} s")
    if "fitted_exponent" in report:
        print(f"fitted exponent {report['fitted_exponent']:.3f} (Grady -0.667)")


if __name__ == "__main__":
    main(sys.argv)
