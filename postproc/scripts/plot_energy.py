#!/usr/bin/python3
"""Energy balance from history.csv: external work vs kinetic + strain + dissipated."""
import argparse
import csv

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--history", required=True)
    ap.add_argument("--out", required=True)
    a = ap.parse_args()
    with open(a.history) as f:
        rows = list(csv.DictReader(f))
    col = lambda name: np.array([float(r[name]) for r in rows])
    t = col("time_s") * 1e6
    k, u, d, w = col("kinetic_J"), col("strain_J"), col("dissipated_J"), col("external_work_J")
    fig, ax = plt.subplots(figsize=(7, 4.5), dpi=120)
    ax.plot(t, w, "k-", lw=2, label="external work")
    ax.plot(t, k + u + d, "C3--", lw=1.5, label="kinetic + strain + dissipated")
    ax.plot(t, k, "C0-", lw=1, label="kinetic")
    ax.plot(t, u, "C1-", lw=1, label="strain")
    ax.plot(t, d, "C2-", lw=1, label="dissipated")
    ax.set_xlabel("time [µs]")
    ax.set_ylabel("energy [J]")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title("Energy balance")
    fig.tight_layout()
    fig.savefig(a.out)


if __name__ == "__main__":
    main()
