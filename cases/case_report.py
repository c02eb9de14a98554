"""What the cases' report.py scripts share: reading a run's damage history, and its broken
bonds (results.h5's /bonds list and per-output `broken` bits, docs/formats.md).

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


def bits(packed, count):
    """The first `count` bits of a little-endian packed bit set (results.h5's bond flags)."""
    return np.unpackbits(np.asarray(packed, dtype=np.uint8), bitorder="little")[:count].astype(bool)


def broken_bond_fraction(offsets, neighbors, broken, counted=None):
    """Per particle, the fraction of its bonds that are fully broken. The bonds are results.h5's
    list (each pair once: bond b joins owner i, offsets[i] <= b < offsets[i+1], and neighbors[b]);
    `broken` flags each bond, `counted` (default all) the bonds that count at all. A bond counts
    for both its ends; a particle without counted bonds gets 0. Unlike the damage field this
    ignores the bonds' weights and a softening bond's partial damage: a bond in softening still
    holds the body together (docs/theory.md "Quasi-brittle bonds")."""
    n = len(offsets) - 1
    neighbors = np.asarray(neighbors, dtype=np.int64)
    owner = np.repeat(np.arange(n), np.diff(offsets))
    counted = np.ones(len(neighbors), dtype=bool) if counted is None else np.asarray(counted, dtype=bool)
    gone = counted & np.asarray(broken, dtype=bool)
    total = np.bincount(owner[counted], minlength=n) + np.bincount(neighbors[counted], minlength=n)
    lost = np.bincount(owner[gone], minlength=n) + np.bincount(neighbors[gone], minlength=n)
    return lost / np.maximum(total, 1)


def load_broken_fraction_history(run_dir):
    """broken_bond_fraction per output (K, N) of a run, over the bonds within the horizon (the
    fragment graph of breccia-post; partial-volume bonds whose cell only reaches into the
    horizon are left out)."""
    with h5py.File(os.path.join(run_dir, "results.h5"), "r") as f:
        offsets = f["bonds/offsets"][:]
        neighbors = f["bonds/neighbors"][:]
        counted = bits(f["bonds/within_horizon"][:], len(neighbors)) if "within_horizon" in f["bonds"] else None
        keys = sorted(f["output"].keys())
        return np.array([broken_bond_fraction(offsets, neighbors, bits(f["output"][k]["broken"][:], len(neighbors)),
                                              counted) for k in keys])
