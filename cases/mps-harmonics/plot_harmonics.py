#!/usr/bin/env python3
"""Transmitted u1 at A and its amplitude spectrum, with and without the crack (seed 000, figs 2-3).

usage: plot_harmonics.py OUT RUN [RUN ...]   (RUN: crack_h0.25mm, intact_h0.25mm, ...)
Writes OUT/harmonics.png, OUT/spectrum_full_record.png and OUT/ratios.csv (|U(3f)|/|U(f)|,
|U(5f)|/|U(f)|, also 2f, with f = 2 MHz).
Spectrum: FFT of u1(t) at A, zero-padded to 0.05 MHz resolution; by default a Hann window
over the gate [17, 28] us that holds the direct transmitted burst (arrival of the S wave
at A: 64.5 mm / c_T = 20.1 us; burst 2.5 us) and excludes the P waves from the top corners
(11.5 us) and the bottom reflection (42 us). --no-window: rectangular over the whole record.
"""
import csv
import json
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

F0 = 2.0e6
GATE_US = (17.0, 28.0)


def load(out, run):
    data = np.genfromtxt(os.path.join(out, run, "history.csv"), delimiter=",", names=True)
    with open(os.path.join(out, run, "summary.json")) as f:
        summary = json.load(f)
    return data["time_s"], data["A_displacement_x"], summary


def spectrum(t, u, window=True):
    dt = t[1] - t[0]
    if window:
        m = (t >= GATE_US[0] * 1e-6) & (t <= GATE_US[1] * 1e-6)
        seg = u[m] * np.hanning(m.sum())
    else:
        seg = u
    nfft = int(2 ** np.ceil(np.log2(1.0 / (0.05e6 * dt))))
    amp = np.abs(np.fft.rfft(seg, nfft))
    freq = np.fft.rfftfreq(nfft, dt)
    return freq, amp


def peak(freq, amp, f, half_band=0.3e6):
    m = (freq > f - half_band) & (freq < f + half_band)
    return amp[m].max()


def main():
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    window = "--no-window" not in sys.argv
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
            freq, amp = spectrum(t, u, window)
            a1 = peak(freq, amp, F0)
            ratios = {n: peak(freq, amp, n * F0) / a1 for n in (2, 3, 5)}
            rows.append(dict(run=run, spacing_mm=sp.replace("mm", ""), particles=summary["particles"],
                             steps=summary["steps"], dt_s=summary["dt_s"], wall_time_s=round(summary["wall_time_s"], 1),
                             ratio_2f=f"{ratios[2]:.4f}", ratio_3f=f"{ratios[3]:.4f}", ratio_5f=f"{ratios[5]:.4f}"))
            label = "no crack" if kind == "intact" else "sliding crack"
            ax_t.plot(t * 1e6, u * 1e9, label=label, **style)
            ax_f.semilogy(freq / 1e6, amp / a1, label=f"{label}: 3f {ratios[3]:.3f}, 5f {ratios[5]:.3f}", **style)
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
