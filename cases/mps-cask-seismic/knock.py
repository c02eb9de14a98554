#!/usr/bin/env python3
"""The canister's knock on the container (knock.yaml), from a run's history.csv.

Both bodies are free and nothing else acts, so the momentum is conserved: the container's
velocity V (its centroid's x, differenced) gives the knock's impulse J = M V, the canister's
velocity v = (P0 - M V) / m, and the coefficient of restitution of the knock
e = -(v - V) / v0 after it. The container's rotation rate w: I w = -(y - yc) J for a
horizontal impulse J at height y (without friction), so a knock above the container's
centroid turns it. Durations: the first contact episode (steps with penalty energy > 0) and
the knock's span, from its first episode to its last (below).
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
    ap.add_argument("--window", type=float, default=0.05, help="s; episodes that begin within it form the knock")
    ap.add_argument("--json")
    a = ap.parse_args()
    rows = list(csv.DictReader(open(f"{a.run}/history.csv")))
    t = [float(r["time_s"]) for r in rows]
    x = [float(r["container_x_m"]) for r in rows]
    y = [float(r["container_y_m"]) for r in rows]
    th = [float(r["container_angle_rad"]) for r in rows]
    ec = [float(r["contact_energy_J"]) for r in rows]
    ke0 = float(rows[0]["kinetic_energy_J"])
    m = 2 * ke0 / a.v0 ** 2  # the canister's mass
    # The container as it ran (its vertices and density; a --set may have turned it).
    body = yaml.safe_load(open(os.path.join(a.run, "case_as_run.yaml")))["contact"]["rigid_bodies"][0]
    M, (cx, cy), I = polygon_mass_properties([tuple(v) for v in body["vertices"]], float(body["density"]))
    # Contact episodes (steps with penalty energy), then the knock: the episodes that begin
    # within --window s of the first (a flat knock chatters for a few ms; an oblique one is a
    # corner's strike and then the face's). The velocities are taken over 5 ms from 2 ms after
    # the knock's last episode, and that interval must be free of contact; later contacts (the
    # canister back on a wall after its rebound) are not the knock and are left out.
    episodes = []
    for k in range(len(t)):
        if ec[k] > 0 and (k == 0 or ec[k - 1] == 0):
            episodes.append([k, k])
        if ec[k] > 0:
            episodes[-1][1] = k
    if not episodes:
        sys.exit(f"knock.py: {a.run}/history.csv: no contact (contact_energy_J stays 0)")
    knock = [ep for ep in episodes if t[ep[0]] < t[episodes[0][0]] + a.window]
    k0, k1 = knock[0][0], knock[-1][1]
    tail = [k for k in range(len(t)) if t[k1] + 0.002 <= t[k] <= t[k1] + 0.007]
    if not tail or t[tail[-1]] < t[k1] + 0.0069 or any(ec[k] > 0 for k in tail):
        sys.exit(f"knock.py: {a.run}: no contact-free 5 ms after the knock (ends {t[k1]:.4f} s); longer time.end?")
    V = (x[tail[-1]] - x[tail[0]]) / (t[tail[-1]] - t[tail[0]])
    w = (th[tail[-1]] - th[tail[0]]) / (t[tail[-1]] - t[tail[0]])
    J = M * V
    Jy = M * (y[tail[-1]] - y[tail[0]]) / (t[tail[-1]] - t[tail[0]])  # friction's, on the wall
    v = (m * a.v0 - J) / m
    e = -(v - V) / a.v0
    # torque_z = (x - xc) F_y - (y - yc) F_x; without friction (F_y = 0) I w = -(y - yc) J
    y_imp = cy - I * w / J if Jy == 0 or abs(Jy) < 1e-9 * abs(J) else None
    # Peak force: the container's acceleration (second difference of x).
    peak = 0.0
    for k in range(max(1, k0 - 2), min(len(t) - 1, k1 + 3)):
        dt = t[k + 1] - t[k]
        acc = (x[k + 1] - 2 * x[k] + x[k - 1]) / dt ** 2
        peak = max(peak, abs(M * acc))
    out = dict(canister_mass_kg=m, container_mass_kg=M, contact_start_s=t[k0], first_contact_s=t[knock[0][1]] - t[k0], knock_span_s=t[k1] - t[k0],
               knock_episodes=len(knock), later_episodes=len(episodes) - len(knock), impulse_Ns=J, impulse_over_2mv0=J / (2 * m * abs(a.v0)),
               restitution=e, vertical_impulse_Ns=Jy, peak_force_N=peak, impulse_height_m=y_imp,
               container_spin_rad_s=w)
    print(json.dumps(out, indent=1))
    if a.json:
        json.dump(out, open(a.json, "w"), indent=1)


if __name__ == "__main__":
    main()
