#!/usr/bin/python3
"""A gas load's histories (history.csv of breccia-solve): the gauge pressure the gas applies,
and the cavity's volume with the part of it in cracks, against time; the vent time marked."""
import argparse
import csv

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--history", required=True)
    ap.add_argument("--title", default="")
    ap.add_argument("--out", required=True)
    a = ap.parse_args()
    with open(a.history) as f:
        rows = list(csv.DictReader(f))
    col = lambda name: np.array([float(r[name]) for r in rows])
    t = col("time_s") * 1e6
    p = col("gas_pressure_Pa") / 1e6
    v = col("cavity_volume_m3") * 1e6
    vc = col("crack_gas_volume_m3") * 1e6
    vented = col("gas_vented")
    fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(7, 6.5), dpi=120, sharex=True)
    ax1.plot(t, p, lw=1.2, color="tab:red")
    ax1.set_ylabel("gas pressure (gauge) [MPa]")
    ax1.grid(alpha=0.3)
    ax2.plot(t, v, lw=1.2, label="cavity (hole + cracks)")
    ax2.plot(t, np.where(vc > 0, vc, np.nan), lw=1.0, ls="--", label="in cracks")
    ax2.set_yscale("log")  # the cracks can hold orders of magnitude more than the hole
    ax2.set_ylabel("volume [cm³] (log scale)")
    ax2.set_xlabel("time [µs]")
    ax2.grid(alpha=0.3)
    if vented.any():
        tv = t[np.argmax(vented > 0)]
        for ax in (ax1, ax2):
            ax.axvline(tv, color="k", lw=0.8, ls=":")
        ax1.annotate(f"vents at {tv:.0f} µs", (tv, ax1.get_ylim()[1] * 0.9), xytext=(4, 0),
                     textcoords="offset points", fontsize=9)
    ax2.legend(fontsize=9)
    ax1.set_title(a.title or "gas in the charge hole")
    fig.tight_layout()
    fig.savefig(a.out)


if __name__ == "__main__":
    main()
