"""Report of cases/fragmenting-cylinder: fragments of the tube and a picture.

    report.py OUT

Reads OUT/run (results.h5, summary.json) and OUT/run/post/fragments.csv (breccia-post
--fragments: connected pieces of the intact bond graph). Writes OUT/report.json,
OUT/fragments.png (the tube at the end, coloured by fragment, seen from the side and from
above) and OUT/fragment_masses.png (cumulative mass fraction against fragment mass).
"""
import json
import os
import sys

import h5py
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def main(argv):
    if len(argv) < 2:
        sys.stderr.write(__doc__)
        sys.exit(2)
    out = argv[1]
    run = os.path.join(out, "run")
    fr = np.atleast_1d(np.genfromtxt(os.path.join(run, "post", "fragments.csv"), delimiter=",", names=True))
    mass = np.sort(fr["mass_kg"])[::-1]
    total = mass.sum()
    summary = json.load(open(os.path.join(run, "summary.json")))
    with h5py.File(os.path.join(run, "results.h5"), "r") as f:
        x0 = f["particles/position"][:]
        last = f["output"][sorted(f["output"].keys())[-1]]
        u = last["displacement"][:]
        t_end = float(last.attrs["time_s"])
    cur = x0 + u
    big = mass[mass >= 0.01 * total]
    rep = {"case": "fragmenting-cylinder", "particles": summary["particles"], "end_time_s": t_end,
           "fragments": int(len(mass)), "fragments_over_1_percent": int(len(big)),
           "largest_mass_fraction": float(mass[0] / total),
           "mass_fraction_in_fragments_over_1_percent": float(big.sum() / total),
           "single_particle_fragments": int(np.sum(fr["particle_count"] == 1)),
           "wall_s": summary.get("wall_s")}
    json.dump(rep, open(os.path.join(out, "report.json"), "w"), indent=1)
    print(f"fragments {rep['fragments']} ({rep['fragments_over_1_percent']} over 1% of the mass, holding "
          f"{rep['mass_fraction_in_fragments_over_1_percent']:.1%}); largest {rep['largest_mass_fraction']:.1%}; "
          f"single particles {rep['single_particle_fragments']}; t = {t_end * 1e6:.0f} us")
    # Colour by fragment: breccia-post's fragments.vtu holds fragment_id per particle.
    colour = np.zeros(len(cur))
    try:
        import meshio
        m = meshio.read(os.path.join(run, "post", "fragments.vtu"))
        colour = np.asarray(m.point_data["fragment_id"]).ravel() % 20
    except Exception:  # noqa: BLE001 - picture only
        pass
    fig, ax = plt.subplots(1, 2, figsize=(11, 5.5))
    ax[0].scatter(cur[:, 0] * 1e3, cur[:, 2] * 1e3, c=colour, cmap="tab20", s=0.3, linewidths=0)
    ax[0].set_xlabel("x (mm)")
    ax[0].set_ylabel("z (mm)")
    ax[0].set_title(f"side, t = {t_end * 1e6:.0f} us", fontsize=9)
    ax[1].scatter(cur[:, 0] * 1e3, cur[:, 1] * 1e3, c=colour, cmap="tab20", s=0.3, linewidths=0)
    ax[1].set_xlabel("x (mm)")
    ax[1].set_ylabel("y (mm)")
    ax[1].set_title(f"from above: {rep['fragments_over_1_percent']} fragments over 1% of the mass", fontsize=9)
    for a in ax:
        a.set_aspect("equal")
    fig.tight_layout()
    fig.savefig(os.path.join(out, "fragments.png"), dpi=110)
    fig, ax = plt.subplots(figsize=(6, 4))
    ax.semilogx(mass * 1e3, np.cumsum(mass) / total, "o-", ms=2)
    ax.set_xlabel("fragment mass (g), largest first")
    ax.set_ylabel("cumulative mass fraction")
    ax.grid(alpha=0.3, which="both")
    fig.tight_layout()
    fig.savefig(os.path.join(out, "fragment_masses.png"), dpi=110)


if __name__ == "__main__":
    main(sys.argv)
