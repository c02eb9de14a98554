#!/usr/bin/python3
"""Cumulative passing by mass vs fragment size (log x) with the Rosin-Rammler and Swebrec fits.

Called by breccia-post; reads size_distribution.csv (size_m, passing, ...) and the fitted
parameters from the command line.
"""
import argparse
import csv

import matplotlib
import matplotlib.ticker

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--data", required=True)
    ap.add_argument("--rosin-rammler", nargs=2, type=float, metavar=("XC_M", "N"))
    ap.add_argument("--swebrec", nargs=3, type=float, metavar=("XMAX_M", "X50_M", "B"))
    ap.add_argument("--size-label", default="sieve size")
    # The fragment count: the CSV holds one row per distinct size (a sieve step), fewer.
    ap.add_argument("--fragments", type=int)
    ap.add_argument("--out", required=True)
    a = ap.parse_args()
    with open(a.data) as f:
        rows = list(csv.DictReader(f))
    x = np.array([float(r["size_m"]) for r in rows]) * 1e3
    p = np.array([float(r["passing"]) for r in rows]) * 100
    fig, ax = plt.subplots(figsize=(7, 4.5), dpi=120)
    ax.step(x, p, where="post", color="k", lw=1.2)
    count = a.fragments if a.fragments is not None else len(x)
    ax.plot(x, p, "ko", ms=3, label=f"fragments (n = {count})")
    xs = np.logspace(np.log10(x.min() * 0.5), np.log10(x.max() * 1.2), 300)
    if a.rosin_rammler:
        xc, n = a.rosin_rammler
        ax.plot(xs, 100 * (1 - np.exp(-((xs / (xc * 1e3)) ** n))), "C0-",
                label=f"Rosin-Rammler: $x_c$ = {xc*1e3:.3g} mm, n = {n:.3g}")
    if a.swebrec:
        xmax, x50, b = a.swebrec[0] * 1e3, a.swebrec[1] * 1e3, a.swebrec[2]
        with np.errstate(divide="ignore", invalid="ignore"):
            sw = np.where(xs < xmax, 1 / (1 + (np.log(xmax / xs) / np.log(xmax / x50)) ** b), 1.0)
        ax.plot(xs, 100 * sw, "C3--",
                label=f"Swebrec: $x_{{max}}$ = {xmax:.3g} mm, $x_{{50}}$ = {x50:.3g} mm, b = {b:.3g}")
    ax.set_xscale("log")
    ax.xaxis.set_major_formatter(matplotlib.ticker.FormatStrFormatter("%g"))
    # Minor labels (2, 3, ... 9) help within a decade or so; over a wider range they collide.
    lo, hi = ax.get_xlim()
    if hi / lo < 30:
        ax.xaxis.set_minor_formatter(matplotlib.ticker.FormatStrFormatter("%g"))
        ax.tick_params(axis="x", which="minor", labelsize=7)
    else:
        ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
    ax.set_ylim(0, 102)
    ax.set_xlabel(f"fragment {a.size_label} [mm]")
    ax.set_ylabel("cumulative passing by mass [%]")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(loc="upper left", fontsize=8)
    ax.set_title("Fragment size distribution")
    fig.tight_layout()
    fig.savefig(a.out)


if __name__ == "__main__":
    main()
