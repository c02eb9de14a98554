#!/usr/bin/python3
"""Where the concrete-blast block's damage and the gas's work come from, in time (after
breccia-solve; history.csv and results.h5 of one run).

Usage: diagnose.py RUN_DIR PARTICLES_H5 [--json OUT]
Prints, from history.csv: the gas work by the time the gas vents and at the end, the part done
on the hole's wall (the integral of p dV over the wall's own volume change, cavity less crack
volume, trapezoid over the history samples) against the rest (on crack faces), and the
wetted particles; from each output of results.h5: the share of particles softening
(0.05 < damage < 0.5) and broken (damage >= 0.5) in rings about the hole axis, and the radial
cracks on the ring and on the side faces (measures.py). Last, the block's expansion rate from
its final velocities (least squares v_r = rate r about the hole axis) and Grady's (1982)
fragment size for it, s = (sqrt(24) K_Ic / (rho c rate))^(2/3), K_Ic = sqrt(E G0), c = sqrt(E/rho)
(docs/references.md [Grady 1982]; E and rho of case.yaml, G0 of the run's case_as_run.yaml).
At the end also: the particles faster than 300 m/s (count, mass, share of the kinetic energy),
and the sound pieces (components of unbroken bonds between particles with damage < 0.9) over
2% of the mass.
"""
import argparse
import csv
import json
import math
import os
import re
import sys

import h5py
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import measures  # noqa: E402

E, RHO = 34.2e9, 2320.0  # case.yaml
BLOCK_MASS = 62.6  # kg, the meshed block (README)


def p_wave_radius(t_us):
    """Radius [mm] from the hole axis that the wall's P wave reaches by t (uniaxial-strain speed
    sqrt(M/rho), M = E (1 - nu)/((1 + nu)(1 - 2 nu)), nu 1/4 of case.yaml; from the wall at 10 mm)."""
    m = E * 0.75 / (1.25 * 0.5)
    return 10.0 + math.sqrt(m / RHO) * t_us * 1e-3


def damage_front(rad, band, damage, width=0.01):
    """Outermost radius [mm] (10 mm rings about the hole axis, 20-130 mm below the top, out to
    the inscribed 150 mm) in which at least half of the particles have damage above 0.05."""
    front = 10.0
    for lo in np.arange(0.01, 0.15, width):
        m = band & (rad >= lo) & (rad < lo + width)
        if m.any() and np.mean(damage[m] > 0.05) >= 0.5:
            front = (lo + width) * 1e3
    return front


def fast_particles(x, vol, v, speed=300.0):
    """The particles faster than `speed` [m/s] at the end: count, mass, their share of the
    kinetic energy, and how many started within 16 mm of the hole axis (the wall's zone)."""
    m = RHO * vol
    sp = np.linalg.norm(v, axis=1)
    ke = 0.5 * m * sp ** 2
    fast = sp > speed
    near = np.hypot(x[:, 0] - measures.HOLE_AXIS[0], x[:, 1] - measures.HOLE_AXIS[1]) < 0.016
    out = {"fast_count": int(fast.sum()), "fast_mass_kg": float(m[fast].sum()),
           "fast_kinetic_share": float(ke[fast].sum() / max(ke.sum(), 1e-300)), "fast_from_hole_zone": int((fast & near).sum())}
    print(f"particles faster than {speed:.0f} m/s at the end: {out['fast_count']} ({out['fast_mass_kg'] * 1e3:.1f} g, "
          f"{out['fast_from_hole_zone']} from within 16 mm of the axis), {out['fast_kinetic_share']:.0%} of the kinetic energy")
    return out


def sound_pieces(r, key, vol, threshold=0.9):
    """Pieces of sound particles at output `key`: components of the unbroken within-horizon bonds
    between particles with damage below `threshold` (the fragments of breccia-post with the
    particles that have lost most of their bonds' share left out). Returns those over 2% of the
    mass and their share, and the mass share at or above the threshold."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components
    off, nb = r["bonds/offsets"][:], r["bonds/neighbors"][:]
    bits = lambda name: np.unpackbits(r[name][:], bitorder="little")[:len(nb)].astype(bool)  # noqa: E731
    src = np.repeat(np.arange(len(off) - 1), np.diff(off))
    ok = r[f"output/{key}/damage"][:] < threshold
    keep = bits("bonds/within_horizon") & ~bits(f"output/{key}/broken") & ok[src] & ok[nb]
    n = len(ok)
    _, label = connected_components(coo_matrix((np.ones(keep.sum()), (src[keep], nb[keep])), shape=(n, n)), directed=False)
    share = np.sort(np.bincount(label[ok], weights=vol[ok]))[::-1] / vol.sum()
    big = share[share > 0.02]
    out = {"sound_pieces_over_2pct": int(len(big)), "sound_pieces_share": float(big.sum()),
           "mass_share_damage_over_threshold": float(vol[~ok].sum() / vol.sum())}
    print(f"sound pieces (damage < {threshold}): {len(big)} over 2% holding {big.sum():.1%}; "
          f"{out['mass_share_damage_over_threshold']:.1%} of the mass at damage >= {threshold}")
    return out


def fracture_energy(run):
    """G0 [J/m2] of the run's material, from the case as it ran (a --set may change it)."""
    for line in open(f"{run}/case_as_run.yaml"):
        m = re.match(r"\s*fracture_energy:\s*([0-9.eE+-]+)\s*J/m2", line)
        if m:
            return float(m.group(1))
    raise SystemExit(f"diagnose.py: {run}/case_as_run.yaml: no materials[0].fracture_energy in J/m2")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("run")
    ap.add_argument("particles")
    ap.add_argument("--json")
    a = ap.parse_args()
    h = list(csv.DictReader(open(f"{a.run}/history.csv")))
    col = lambda k: np.array([float(r[k]) for r in h])  # noqa: E731
    t, p, work = col("time_s") * 1e6, col("gas_pressure_Pa"), col("gas_work_J")
    wall = col("cavity_volume_m3") - col("crack_gas_volume_m3")
    wall_work = np.concatenate([[0.0], np.cumsum(0.5 * (p[1:] + p[:-1]) * np.diff(wall))])
    vented = col("gas_vented") > 0
    iv = int(np.argmax(vented)) if vented.any() else len(t) - 1
    out = {"vent_us": float(t[iv]) if vented.any() else None,
           "gas_work_at_vent_J": float(work[iv]), "gas_work_end_J": float(work[-1]),
           "wall_work_end_J": float(wall_work[-1]), "end_us": float(t[-1]),
           "wetted_at_vent": int(col("gas_wetted_particles")[iv]),
           "gas_mass_fraction_end": float(col("gas_mass_fraction")[-1])}
    print(f"gas work {work[-1]:.0f} J at {t[-1]:.0f} us; at the vent ({t[iv]:.1f} us) {work[iv]:.0f} J "
          f"({work[iv] / work[-1]:.0%}); on the wall {wall_work[-1]:.0f} J ({wall_work[-1] / work[-1]:.1%}), "
          f"the rest on crack faces; wetted at the vent {out['wetted_at_vent']}; gas mass left {out['gas_mass_fraction_end']:.3f}")
    with h5py.File(a.particles) as f:
        x = f["particles/position"][:]
        vol = f["particles/volume"][:] if "particles/volume" in f else None
    rad = np.hypot(x[:, 0] - measures.HOLE_AXIS[0], x[:, 1] - measures.HOLE_AXIS[1])
    depth = measures.TOP - x[:, 2]
    band = (depth > 0.02) & (depth < 0.13)
    rings = [(0.01, 0.03), (0.03, 0.06), (0.06, 0.10), (0.10, 0.15)]
    out["outputs"] = []
    with h5py.File(f"{a.run}/results.h5") as r:
        keys = sorted(r["output"].keys(), key=lambda k: float(r[f"output/{k}"].attrs["time_s"]))
        print("t [us] | softening / broken share, r = 10-30, 30-60, 60-100, 100-150 mm | cracks ring, side faces"
              " | damage front, P wave from the wall")
        for k in keys:
            d = r[f"output/{k}/damage"][:]
            tk = float(r[f"output/{k}"].attrs["time_s"]) * 1e6
            shares = [(float(np.mean((d[m] > 0.05) & (d[m] < 0.5))), float(np.mean(d[m] >= 0.5)))
                      for m in [(rad > lo) & (rad < hi) & band for lo, hi in rings]]
            ring, faces = measures.ring_cracks(x, d), measures.side_face_cracks(x, d)
            front = damage_front(rad, band, d)
            out["outputs"].append({"t_us": tk, "softening_broken": shares, "ring": ring, "side_faces": faces,
                                   "damage_front_mm": front, "p_wave_mm": p_wave_radius(tk)})
            print(f"{tk:6.1f} | " + "  ".join(f"{s:.2f}/{b:.2f}" for s, b in shares) + f" | {ring}, {faces}"
                  f" | front {front:.0f} mm, P wave {p_wave_radius(tk):.0f} mm")
        v = r[f"output/{keys[-1]}/velocity"][:]
        out.update(fast_particles(x, vol, v))
        out.update(sound_pieces(r, keys[-1], vol))
    er = np.stack([x[:, 0] - measures.HOLE_AXIS[0], x[:, 1] - measures.HOLE_AXIS[1]], axis=1) / np.maximum(rad, 1e-9)[:, None]
    vr = np.sum(v[:, :2] * er, axis=1)
    w = vol if vol is not None else np.ones(len(x))
    rate = float(np.sum(w * vr * rad) / np.sum(w * rad * rad))
    k_ic, c = math.sqrt(E * fracture_energy(a.run)), math.sqrt(E / RHO)
    s = (math.sqrt(24) * k_ic / (RHO * c * rate)) ** (2 / 3) if rate > 0 else float("inf")
    out.update({"expansion_rate_per_s": rate, "grady_size_m": s, "grady_cube_mass_share": RHO * s ** 3 / BLOCK_MASS})
    print(f"expansion rate {rate:.0f} /s at the end: Grady's fragment size {s * 1e3:.0f} mm "
          f"(a cube of it: {RHO * s ** 3 / BLOCK_MASS:.2%} of the block; a large piece is > 2%)")
    if a.json:
        with open(a.json, "w") as f:
            json.dump(out, f, indent=1)


if __name__ == "__main__":
    main()
