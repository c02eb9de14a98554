#!/usr/bin/env python3
"""The canister's knock on the container (knock.yaml), from a run's history.csv.

Both bodies are free and nothing else acts, so the momentum is conserved: the container's
velocity V (its centroid's x, differenced) gives the knock's impulse J = M V, the canister's
velocity v = (P0 - M V) / m, and the coefficient of restitution of the knock
e = -(v - V) / v0 after it. The container's rotation rate w gives the height at which the
impulse acted: I w = -J (y_impact - y_centroid) (a horizontal force to -x above the centroid
turns the container counter-clockwise... sign: torque_z = -(y - yc) F_x). Duration: the steps
with contact energy (penalty) > 0 in the first contact episode.
usage: knock.py RUN_DIR [--v0 -0.5] [--json out.json]"""
import argparse, csv, json, math, os, sys

import yaml



def polygon_mass_properties(verts, rho):
    """Area, centroid and polar moment of area about the centroid (shoelace sums)."""
    a = cx = cy = ixx = iyy = 0.0
    n = len(verts)
    for k in range(n):
        x0, y0 = verts[k]
        x1, y1 = verts[(k + 1) % n]
        c = x0 * y1 - x1 * y0
        a += c / 2
        cx += (x0 + x1) * c / 6
        cy += (y0 + y1) * c / 6
        ixx += (y0 * y0 + y0 * y1 + y1 * y1) * c / 12
        iyy += (x0 * x0 + x0 * x1 + x1 * x1) * c / 12
    cx /= a
    cy /= a
    j = ixx + iyy - a * (cx * cx + cy * cy)
    return rho * a, (cx, cy), rho * j


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("run")
    ap.add_argument("--v0", type=float, default=-0.5)
    ap.add_argument("--json")
    a = ap.parse_args()
    rows = list(csv.DictReader(open(f"{a.run}/history.csv")))
    t = [float(r["time_s"]) for r in rows]
    x = [float(r["container_x_m"]) for r in rows]
    th = [float(r["container_angle_rad"]) for r in rows]
    ec = [float(r["contact_energy_J"]) for r in rows]
    ke0 = float(rows[0]["kinetic_energy_J"])
    m = 2 * ke0 / a.v0 ** 2  # the canister's mass
    # The container as it ran (its vertices and density; a --set may have turned it).
    body = yaml.safe_load(open(os.path.join(a.run, "case_as_run.yaml")))["contact"]["rigid_bodies"][0]
    M, (cx, cy), I = polygon_mass_properties([tuple(v) for v in body["vertices"]], float(body["density"]))
    on = [k for k in range(len(t)) if ec[k] > 0]
    if not on:
        sys.exit(f"knock.py: {a.run}/history.csv: no contact (contact_energy_J stays 0)")
    k0 = on[0]
    k1 = k0
    while k1 + 1 < len(t) and ec[k1 + 1] > 0:
        k1 += 1
    # End of the first episode: the container's velocity after it (mean over the last 5 ms of
    # the run: it no longer changes once the canister has left the wall).
    tail = [k for k in range(len(t)) if t[k] > t[-1] - 0.005]
    V = (x[tail[-1]] - x[tail[0]]) / (t[tail[-1]] - t[tail[0]])
    w = (th[tail[-1]] - th[tail[0]]) / (t[tail[-1]] - t[tail[0]])
    J = M * V
    v = (m * a.v0 - J) / m
    e = -(v - V) / a.v0
    # torque_z = (x - xc) F_y - (y - yc) F_x; F_y = 0 (frictionless): I w = -(y - yc) J
    y_imp = cy - I * w / J
    # Peak force: the container's acceleration (second difference of x).
    peak = 0.0
    for k in range(max(1, k0 - 2), min(len(t) - 1, k1 + 3)):
        dt = t[k + 1] - t[k]
        acc = (x[k + 1] - 2 * x[k] + x[k - 1]) / dt ** 2
        peak = max(peak, abs(M * acc))
    # Later episodes (the canister's vibration can bring it back on the wall).
    episodes = 1 + sum(1 for k in range(k1 + 1, len(t)) if ec[k] > 0 and ec[k - 1] == 0)
    out = dict(canister_mass_kg=m, container_mass_kg=M, contact_start_s=t[k0], duration_s=t[k1] - t[k0],
               contact_episodes=episodes, impulse_Ns=J, impulse_over_2mv0=J / (2 * m * abs(a.v0)),
               restitution=e, peak_force_N=peak, impulse_height_m=y_imp,
               container_spin_rad_s=w)
    print(json.dumps(out, indent=1))
    if a.json:
        json.dump(out, open(a.json, "w"), indent=1)


if __name__ == "__main__":
    main()
