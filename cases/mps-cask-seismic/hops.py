#!/usr/bin/env python3
"""The container's peak tilt and its hops, from runs of knock_pulse.yaml (or the case).

    hops.py RUN [RUN ...] [--from 0.54]

Per run: the peak of |container_angle_rad| (deg) and when, and the share of the history rows
between --from (s; the knock_pulse knock comes at ~0.556 s) and that peak in which the floor
carries nothing (floor_force_N = 0: no corner of the container on the floor, it is airborne),
with the largest floor force there. README, "The knock under a sustained floor acceleration"."""
import argparse
import csv
import math


def hops(run, start):
    rows = list(csv.DictReader(open(f"{run}/history.csv")))
    t = [float(r["time_s"]) for r in rows]
    angle = [abs(float(r["container_angle_rad"])) for r in rows]
    force = [float(r["floor_force_N"]) for r in rows]
    k = max(range(len(rows)), key=lambda i: angle[i])
    window = [i for i in range(len(rows)) if start < t[i] < t[k]]
    airborne = sum(1 for i in window if force[i] == 0.0) / max(len(window), 1)
    return math.degrees(angle[k]), t[k], airborne, max((force[i] for i in window), default=0.0)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("runs", nargs="+")
    ap.add_argument("--from", dest="start", type=float, default=0.54)
    a = ap.parse_args()
    for run in a.runs:
        peak, when, airborne, fmax = hops(run, a.start)
        print(f"{run}: peak tilt {peak:.4f} deg at {when:.3f} s; airborne {airborne:.1%} of the rows from "
              f"{a.start} s to the peak; largest floor force {fmax / 1e3:.0f} kN")


if __name__ == "__main__":
    main()
