"""Softening ring against Zhou, Molinari & Ramesh (2006) at two or more resolutions.

    zmr_compare.py OUT_PNG LABEL=REPORT_JSON [LABEL=REPORT_JSON ...]
    zmr_compare.py OUT_PNG --sizes zmr_sizes.json

Each REPORT_JSON is report.py's output for one resolution of run.sh's zmr variants;
zmr_sizes.json holds the sizes the README's table quotes, gathered from several such reports
(runs of different end times and dates: each entry says which). Prints a
markdown table (mean fragment size against the ZMR formula at each e = rate / e0, and the
change between consecutive resolutions) and draws size against e with the ZMR formula and
Grady's 1982 energy balance.
"""
import json
import math
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from report import grady_size, zmr_size, zmr_e  # noqa: E402


def main(argv):
    sizes = len(argv) > 2 and argv[2] == "--sizes"
    if len(argv) < 3 or (len(argv) != 4 if sizes else any("=" not in a for a in argv[2:])):
        sys.stderr.write(__doc__)
        sys.exit(2)
    out_png = argv[1]
    series = []
    if argv[2] == "--sizes":
        table = json.load(open(argv[3]))
        for label, entries in table["series"].items():
            runs = [{"strain_rate_per_s": e["rate_per_s"], "mean_size_m": e["size_mm"] * 1e-3,
                     "tensile_strength_Pa": table["tensile_strength_Pa"],
                     "zhou_molinari_ramesh_size_m": zmr_size(e["rate_per_s"], 0.0, table["tensile_strength_Pa"])}
                    for e in entries]
            series.append((label, sorted(runs, key=lambda r: r["strain_rate_per_s"])))
    for label, path in (a.split("=", 1) for a in (argv[2:] if argv[2] != "--sizes" else [])):
        runs = [r for r in json.load(open(path))["runs"] if "mean_size_m" in r and r.get("tensile_strength_Pa")]
        runs.sort(key=lambda r: r["strain_rate_per_s"])
        if not runs:
            print(f"zmr_compare.py: {path} ({label}): no run with a tensile strength (expected report.py's "
                  "report.json of a zmr variant, softening bonds)", file=sys.stderr)
            sys.exit(2)
        series.append((label, runs))
    strength = series[0][1][0]["tensile_strength_Pa"]
    print("| e | rate (1/s) | ZMR size | " + " | ".join(f"{l}: size, / ZMR" for l, _ in series) + " | change |")
    print("|---" * (4 + len(series)) + "|")
    rates = sorted({round(r["strain_rate_per_s"], 6) for _, rs in series for r in rs})
    for q in rates:
        cells, sizes = [], []
        for _, rs in series:
            r = next((r for r in rs if abs(r["strain_rate_per_s"] - q) < 1e-6 * q), None)
            sizes.append(r["mean_size_m"] if r else None)
            cells.append(f"{r['mean_size_m'] * 1e3:.2f} mm, {r['mean_size_m'] / r['zhou_molinari_ramesh_size_m']:.2f}"
                         if r else "-")
        have = [s for s in sizes if s]
        change = " / ".join(f"{b / a - 1:+.0%}" for a, b in zip(have, have[1:])) if len(have) > 1 else "-"
        print(f"| {zmr_e(q, strength):.2g} | {q:.4g} | {zmr_size(q, 0.0, strength) * 1e3:.2f} mm | "
              + " | ".join(cells) + f" | {change} |")
    fig, ax = plt.subplots(figsize=(6.2, 4.5))
    e = np.logspace(-1.3, 1.3, 60)
    e0 = rates[0] / zmr_e(rates[0], strength)
    ax.loglog(e, [zmr_size(x * e0, 0.0, strength) * 1e3 for x in e], "k--",
              label=f"Zhou, Molinari & Ramesh 2006 (sigma_t {strength / 1e6:g} MPa)")
    ax.loglog(e, [grady_size(x * e0) * 1e3 for x in e], "k-", lw=1, label="Grady 1982 energy balance (upper bound)")
    for (label, rs), marker in zip(series, "osd^v<>"):
        ax.loglog([zmr_e(r["strain_rate_per_s"], strength) for r in rs], [r["mean_size_m"] * 1e3 for r in rs],
                  marker, label=f"Breccia, softening bonds, {label}")
    ax.set_xlabel("e = strain rate / e0,  e0 = c sigma_t^3 / (E^2 G0)")
    ax.set_ylabel("mean fragment size (mm)")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=6.5, loc="upper right", framealpha=0.85)
    fig.tight_layout()
    fig.savefig(out_png, dpi=120)


if __name__ == "__main__":
    main(sys.argv)
