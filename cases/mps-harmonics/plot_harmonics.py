#!/usr/bin/env python3
"""Transmitted u1 at A and its amplitude spectrum, with and without the crack ([MPS harmonics], figs 2-3).

usage: plot_harmonics.py OUT RUN [RUN ...] [--no-window]   (RUN: crack_h0.25mm, intact_h0.25mm, ...)
Writes OUT/harmonics.png and OUT/ratios.csv (|U(nf)|/|U(f)| for n = 2, 3, 5, f = 2 MHz).
The spectrum is breccia-post's (one spectrum code, docs/postproc.md "Spectrum"): this script
runs `breccia-post RUN --spectrum A --frequency 2e6 --hann --gate 17e-6,28e-6 --resolution 0.05e6
--band 0.3e6` ($BRECCIA_BIN/breccia-post, or --post PATH) and reads RUN/post/spectrum_A.csv and
the ratios in RUN/post/post.json. That is: u1 at A gated to [17, 28] us, the direct transmitted
burst (arrival of the S wave at A: 64.5 mm / c_T = 20.1 us; burst 2.5 us), without the P waves
from the top corners (11.5 us) and the bottom reflection (42 us); mean removed; symmetric Hann
window over the gate; zero-padded to bins <= 0.05 MHz; peaks = the largest amplitude within
+-0.3 MHz of n x 2 MHz. --no-window: rectangular window over the whole record (same padding and
peaks), written to harmonics_no_window.png / ratios_no_window.csv.
"""
import csv
import json
import os
import subprocess
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

F0 = 2.0e6
GATE_US = (17.0, 28.0)
RESOLUTION_HZ = 0.05e6
BAND_HZ = 0.3e6


def load(out, run):
    data = np.genfromtxt(os.path.join(out, run, "history.csv"), delimiter=",", names=True)
    with open(os.path.join(out, run, "summary.json")) as f:
        summary = json.load(f)
    return data["time_s"], data["A_displacement_x"], summary


def post_spectrum(post, run_dir, window=True):
    """breccia-post's spectrum of u1 at A: (frequency_Hz, amplitude normalised at 2 MHz, {n: ratio})."""
    cmd = [post, run_dir, "--spectrum", "A", "--frequency", str(F0), "--resolution", str(RESOLUTION_HZ),
           "--band", str(BAND_HZ), "--no-plots", "--quiet"]
    if window:
        cmd += ["--hann", "--gate", f"{GATE_US[0] * 1e-6!r},{GATE_US[1] * 1e-6!r}"]
    subprocess.run(cmd, check=True)
    spec = np.genfromtxt(os.path.join(run_dir, "post", "spectrum_A.csv"), delimiter=",", names=True)
    with open(os.path.join(run_dir, "post", "post.json")) as f:
        entry = next(s for s in json.load(f)["spectra"] if s["probe"] == "A" and s["component"] == "ux")
    ratios = {h["order"]: h["ratio"] for h in entry["harmonics"]}
    return spec["frequency_Hz"], spec["normalised_ux"], ratios


def main():
    argv = sys.argv[1:]
    post = os.path.join(os.environ.get("BRECCIA_BIN", ""), "breccia-post")
    if "--post" in argv:
        k = argv.index("--post")
        post = argv[k + 1] if k + 1 < len(argv) else ""
        del argv[k:k + 2]
    args = [a for a in argv if not a.startswith("--")]
    window = "--no-window" not in argv
    if len(args) < 2 or not post or any(a.startswith("--") and a != "--no-window" for a in argv) \
            or any("_h" not in r for r in args[1:]):
        sys.stderr.write(__doc__)
        sys.exit(2)
    out, runs = args[0], args[1:]
    spacings = sorted({r.split("_h")[1] for r in runs}, key=lambda s: -float(s.replace("mm", "")))
    fig, axes = plt.subplots(2, len(spacings), figsize=(6.5 * len(spacings), 8), squeeze=False)
    rows = []
    for col, sp in enumerate(spacings):
        ax_t, ax_f = axes[0][col], axes[1][col]
        for kind, style in (("intact", dict(color="0.3", lw=1.2)), ("crack", dict(color="C3", lw=1.0))):
            run = f"{kind}_h{sp}"
            if run not in runs:
                continue
            t, u, summary = load(out, run)
            freq, normalised, ratios = post_spectrum(post, os.path.join(out, run), window)
            rows.append(dict(run=run, spacing_mm=sp.replace("mm", ""), particles=summary["particles"],
                             steps=summary["steps"], dt_s=summary["dt_s"], wall_time_s=round(summary["wall_time_s"], 1),
                             ratio_2f=f"{ratios[2]:.4f}", ratio_3f=f"{ratios[3]:.4f}", ratio_5f=f"{ratios[5]:.4f}"))
            label = "no crack" if kind == "intact" else "sliding crack"
            ax_t.plot(t * 1e6, u * 1e9, label=label, **style)
            ax_f.semilogy(freq / 1e6, normalised, label=f"{label}: 3f {ratios[3]:.3f}, 5f {ratios[5]:.3f}", **style)
        ax_t.set_xlim(15, 30)
        ax_t.set_xlabel("time (us)")
        ax_t.set_ylabel("u1 at A (nm)")
        ax_t.set_title(f"transmitted u1 at A, spacing {sp}")
        if window:
            ax_t.axvspan(*GATE_US, color="C0", alpha=0.06, label="FFT gate (Hann)")
        ax_t.legend(loc="lower left", fontsize=8)
        ax_f.set_xlim(0, 14)
        ax_f.set_ylim(1e-4, 2)
        for n in (1, 2, 3, 4, 5, 6):
            ax_f.axvline(n * F0 / 1e6, color="0.8", lw=0.8, zorder=0)
        ax_f.set_xlabel("frequency (MHz)")
        ax_f.set_ylabel("|U(f)| / |U(2 MHz)|")
        ax_f.set_title("amplitude spectrum normalised by the 2 MHz peak" + (" (Hann gate)" if window else ""))
        ax_f.legend(loc="upper right", fontsize=8)
    fig.tight_layout()
    name = "harmonics.png" if window else "harmonics_no_window.png"
    fig.savefig(os.path.join(out, name), dpi=110)
    with open(os.path.join(out, "ratios.csv" if window else "ratios_no_window.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
        w.writeheader()
        w.writerows(rows)
    for r in rows:
        print(r)


if __name__ == "__main__":
    main()
