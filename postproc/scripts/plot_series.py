#!/usr/bin/python3
"""Probe time series (--kind probe: time_s, components) or amplitude spectra
(--kind spectrum: frequency_Hz, amplitude_<c>, normalised_<c>) written by breccia-post."""
import argparse
import csv

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

UNITS = {"u": ("displacement", "m"), "v": ("velocity", "m/s"), "a": ("acceleration", "m/s²"),
         "s": ("stress", "Pa"), "e": ("strain", "-"), "f": ("force", "N"), "d": ("damage", "-")}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--kind", choices=["probe", "spectrum"], required=True)
    ap.add_argument("--data", required=True)
    ap.add_argument("--title", default="")
    ap.add_argument("--out", required=True)
    a = ap.parse_args()
    with open(a.data) as f:
        reader = csv.reader(f)
        header = next(reader)
        data = np.array([[float(v) for v in r] for r in reader if r])
    fig, ax = plt.subplots(figsize=(7, 4.5), dpi=120)
    if a.kind == "probe":
        t = data[:, 0] * 1e6
        kinds = set()
        for k, name in enumerate(header[1:], start=1):
            ax.plot(t, data[:, k], lw=1, label=name)
            kinds.add(UNITS.get(name[:1], ("value", "SI"))[0:2])
        label = " / ".join(f"{q} [{u}]" for q, u in sorted(kinds)) or "value"
        ax.set_xlabel("time [µs]")
        ax.set_ylabel(label)
    else:
        f_mhz = data[:, 0] / 1e6
        for k, name in enumerate(header):
            if name.startswith("normalised_"):
                ax.semilogy(f_mhz[1:], np.maximum(data[1:, k], 1e-12), lw=1, label=name[len("normalised_"):])
        ax.set_xlabel("frequency [MHz]")
        ax.set_ylabel("amplitude / amplitude at reference frequency [-]")
        ax.set_ylim(1e-6, 2)
        # The reference frequency reads 1 in every normalised column; mark its harmonics.
        norm_cols = [k for k, n in enumerate(header) if n.startswith("normalised_")]
        if norm_cols:
            ref = f_mhz[np.argmin(np.abs(data[:, norm_cols[0]] - 1.0))]
            if ref > 0:
                for order in range(1, 6):
                    ax.axvline(order * ref, color="0.5", ls=":", lw=0.8)
                    ax.text(order * ref, 1.3, f"{order}f", ha="center", fontsize=7, color="0.3")
                ax.set_xlim(0, min(f_mhz[-1], 8 * ref))
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title(a.title)
    fig.tight_layout()
    fig.savefig(a.out)


if __name__ == "__main__":
    main()
