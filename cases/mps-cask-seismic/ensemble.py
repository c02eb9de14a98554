"""Ensemble summary of cases/mps-cask-seismic (ensemble.sh): for each run name, the peak tilt
over the members OUT/m*/report.json: mean, sample standard deviation, the standard error of the
mean (sd / sqrt(n)), median, range. Writes OUT/ensemble.json.

    ensemble.py OUT
"""
import glob
import json
import math
import os
import sys


def main(out):
    tilts = {}
    for path in sorted(glob.glob(os.path.join(out, "m*", "report.json"))):
        member = os.path.basename(os.path.dirname(path))
        for r in json.load(open(path))["runs"]:
            tilts.setdefault(r["run"], {})[member] = r["peak_tilt_deg"]
    summary = {}
    for name, by_member in sorted(tilts.items()):
        v = list(by_member.values())
        n = len(v)
        mean = sum(v) / n
        sd = math.sqrt(sum((x - mean) ** 2 for x in v) / (n - 1)) if n > 1 else float("nan")
        ordered = sorted(v)
        median = (ordered[(n - 1) // 2] + ordered[n // 2]) / 2
        summary[name] = {"members": n, "mean_deg": mean, "sd_deg": sd, "se_deg": sd / math.sqrt(n), "median_deg": median,
                         "min_deg": min(v), "max_deg": max(v), "peak_tilt_deg": by_member}
        print(f"{name}: {n} members, peak tilt mean {mean:.4f} deg, sd {sd:.4f}, se of the mean "
              f"{sd / math.sqrt(n):.4f}, median {median:.4f}, range {min(v):.4f}-{max(v):.4f}")
    json.dump(summary, open(os.path.join(out, "ensemble.json"), "w"), indent=1)


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.stderr.write(__doc__)
        sys.exit(2)
    main(sys.argv[1])
