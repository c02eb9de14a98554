"""Report of cases/first-case: how the plate broke, in numbers and one picture.

    report.py OUT

Reads OUT/run (results.h5, summary.json), OUT/run/post/post.json and fragments.csv
(breccia-post --cracks --fragments --energy). Writes OUT/report.json and OUT/plate.png:
the plate seen from above at the end, coloured by damage (left) and by fragment (right).
"""
import json
import os
import sys

import h5py
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from case_report import bits  # noqa: E402  (cases/case_report.py)


def halves_without_the_crack_bands(h5, last, damage_below=0.5):
    """Mass fractions and reference centroid x of the two largest pieces left when the
    particles that lost at least half their bonds (damage >= damage_below: the crack bands
    and the debris) are taken out, the rest joined by intact bonds.

    breccia-post's fragments join every particle with an intact bond left: at 2.5 mm, one chain
    of debris particles holding 1-4% of their bonds (damage 0.96-0.99, loose in the crack band)
    can join the halves or not depending on the last digit of dt (a 0.04% change flips it).
    Without the crack bands the halves are the same piece of the plate whichever dt: each
    39.6-39.9% and 37.9-38.2% of the mass at dt 0.78-0.825 us (eight runs, 2026-12-03)."""
    offsets = h5["bonds/offsets"][:]
    neighbors = h5["bonds/neighbors"][:]
    intact = ~bits(last["broken"][:], len(neighbors))
    if "within_horizon" in h5["bonds"]:
        intact &= bits(h5["bonds/within_horizon"][:], len(neighbors))
    damage = last["damage"][:]
    owner = np.repeat(np.arange(len(offsets) - 1), np.diff(offsets))
    kept = damage < damage_below
    edge = intact & kept[owner] & kept[neighbors]
    i, j = owner[edge], neighbors[edge].astype(np.int64)
    # Connected components by label propagation with pointer jumping (numpy only).
    label = np.arange(len(damage))
    while True:
        low = np.minimum(label[i], label[j])
        new = label.copy()
        np.minimum.at(new, i, low)
        np.minimum.at(new, j, low)
        new = new[new]
        if np.array_equal(new, label):
            break
        label = new
    mass = h5["particles/volume"][:] * h5["particles/density"][:]
    piece_mass = np.bincount(label[kept], weights=mass[kept], minlength=len(damage))
    largest = np.argsort(piece_mass)[::-1][:2]
    x0 = h5["particles/position"][:, 0]
    x = [float(np.average(x0[kept & (label == p)], weights=mass[kept & (label == p)])) for p in largest]
    return [float(piece_mass[p] / mass.sum()) for p in largest], x


def main(argv):
    if len(argv) < 2:
        sys.stderr.write(__doc__)
        sys.exit(2)
    out = argv[1]
    run = os.path.join(out, "run")
    post = json.load(open(os.path.join(run, "post", "post.json")))
    summary = json.load(open(os.path.join(run, "summary.json")))
    fr = np.atleast_1d(np.genfromtxt(os.path.join(run, "post", "fragments.csv"), delimiter=",", names=True))
    share = np.sort(fr["mass_kg"])[::-1] / fr["mass_kg"].sum()
    with h5py.File(os.path.join(run, "results.h5"), "r") as f:
        x0 = f["particles/position"][:]
        last = f["output"][sorted(f["output"].keys())[-1]]
        damage = last["damage"][:]
        cur = x0 + last["displacement"][:]
        t_end = float(last.attrs["time_s"])
        core_share, core_x = halves_without_the_crack_bands(f, last)
    rep = {"case": "first-case", "particles": summary["particles"], "end_time_s": t_end,
           "fragments": int(len(share)), "fragments_over_1_percent": int(np.sum(share >= 0.01)),
           "largest_two_mass_fractions": [float(s) for s in share[:2]],
           # where the two largest pieces came from (reference centroid x; the hole is at 30 mm)
           "largest_two_reference_x_m": [float(v) for v in fr["reference_centroid_x_m"][np.argsort(fr["mass_kg"])[::-1][:2]]],
           # the same with the crack bands left out (damage >= 0.5): halves_without_the_crack_bands
           "largest_two_mass_fractions_without_crack_bands": core_share,
           "largest_two_reference_x_m_without_crack_bands": core_x,
           "single_particle_fragments": int(np.sum(fr["particle_count"] == 1)),
           "crack_area_m2": post["cracks"]["smoothed_fracture_area_m2"],
           "dissipated_J": post["energy"]["dissipated_J"],
           "dissipated_over_G0_area": post["energy"]["ratio"],
           "wall_s": summary.get("wall_s")}
    json.dump(rep, open(os.path.join(out, "report.json"), "w"), indent=1)
    print(f"{rep['particles']} particles, t = {t_end * 1e6:.0f} us: {rep['fragments']} fragments, "
          f"{rep['fragments_over_1_percent']} over 1% of the mass; the two largest hold "
          f"{share[0]:.1%} and {share[1] if len(share) > 1 else 0:.1%}; crack area "
          f"{rep['crack_area_m2'] * 1e6:.0f} mm2; dissipated {rep['dissipated_J']:.3f} J")
    # Fragment of each particle from breccia-post's fragments.vtu: from a mesh it holds the
    # source tetrahedra with cell data (fragment_id, displacement), so the particles are the
    # cells' centroids moved by their displacement; from a lattice, points with point data.
    frag_xy, frag_id = cur, np.zeros(len(cur))
    try:
        import meshio
        m = meshio.read(os.path.join(run, "post", "fragments.vtu"))
        if "fragment_id" in m.cell_data:
            cells = np.concatenate([c.data for c in m.cells])
            frag_xy = m.points[cells].mean(axis=1) + np.concatenate(m.cell_data["displacement"])
            frag_id = np.concatenate(m.cell_data["fragment_id"])
        else:
            frag_id = np.asarray(m.point_data["fragment_id"]).ravel()
    except Exception:  # noqa: BLE001 - the picture only
        pass
    fig, ax = plt.subplots(1, 2, figsize=(11, 4))
    order = np.argsort(damage)  # damaged particles drawn last, on top
    sc = ax[0].scatter(x0[order, 0] * 1e3, x0[order, 1] * 1e3, c=damage[order], cmap="inferno", vmin=0, vmax=1,
                       s=3, linewidths=0)
    fig.colorbar(sc, ax=ax[0], label="damage")
    ax[0].set_title(f"damage at t = {t_end * 1e6:.0f} us (reference positions)", fontsize=9)
    ax[1].scatter(frag_xy[:, 0] * 1e3, frag_xy[:, 1] * 1e3, c=frag_id % 20, cmap="tab20", s=3, linewidths=0)
    ax[1].set_title(f"fragments (deformed): {rep['fragments_over_1_percent']} over 1% of the mass", fontsize=9)
    for a in ax:
        a.set_aspect("equal")
        a.set_xlabel("x (mm)")
        a.set_ylabel("y (mm)")
    fig.tight_layout()
    fig.savefig(os.path.join(out, "plate.png"), dpi=80)


if __name__ == "__main__":
    main(sys.argv)
