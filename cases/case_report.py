"""What the cases' report.py scripts share: reading a run's damage history.

Imported by cases/*/report.py (each puts cases/ on sys.path). Kept to what several
reports read the same way; each case's measures stay in its own report.
"""
import json
import os

import h5py
import numpy as np


def load_damage_history(run_dir):
    """In-plane positions (N, 2), output times (s), damage per output (K, N) and summary.json."""
    with h5py.File(os.path.join(run_dir, "results.h5"), "r") as f:
        x = f["particles/position"][:, :2]
        keys = sorted(f["output"].keys())
        times = np.array([f["output"][k].attrs["time_s"] for k in keys])
        damage = np.array([f["output"][k]["damage"][:] for k in keys])
    with open(os.path.join(run_dir, "summary.json")) as fh:
        summary = json.load(fh)
    return x, times, damage, summary
