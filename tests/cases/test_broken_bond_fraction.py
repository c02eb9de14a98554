"""cases/case_report.py: broken_bond_fraction and bits on a hand-made bond list.

Exact answers by construction. Particles 0-3, bonds (each pair once, from its lower index):
0-1, 0-2, 1-2, 2-3. Particle 0 has bonds {0-1, 0-2}, 1 {0-1, 1-2}, 2 {0-2, 1-2, 2-3}, 3 {2-3}.
"""
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(sys.argv[1], "cases"))
import case_report  # noqa: E402

FAILURES = []


def check(ok, what):
    print(("ok   " if ok else "FAIL ") + what)
    if not ok:
        FAILURES.append(what)


offsets = np.array([0, 2, 3, 4, 4])
neighbors = np.array([1, 2, 2, 3], dtype=np.int32)

f = case_report.broken_bond_fraction(offsets, neighbors, np.zeros(4, dtype=bool))
check(np.array_equal(f, [0, 0, 0, 0]), f"nothing broken: all 0 (got {f})")

broken = np.array([False, True, False, True])  # 0-2 and 2-3
f = case_report.broken_bond_fraction(offsets, neighbors, broken)
check(np.allclose(f, [1 / 2, 0, 2 / 3, 1]), f"0-2 and 2-3 broken: 1/2, 0, 2/3, 1 (got {f})")

# Bond 2-3 not counted (e.g. a partial-volume bond): particle 3 has no counted bond left.
counted = np.array([True, True, True, False])
f = case_report.broken_bond_fraction(offsets, neighbors, broken, counted)
check(np.allclose(f, [1 / 2, 0, 1 / 2, 0]), f"2-3 not counted: 1/2, 0, 1/2, 0 (got {f})")

# results.h5 packs the flags little-endian, 8 to a byte; 11 bonds need 2 bytes.
flags = np.array([1, 0, 0, 1, 0, 0, 0, 0, 1, 1, 0], dtype=bool)
packed = np.packbits(flags, bitorder="little")
check(np.array_equal(case_report.bits(packed, len(flags)), flags), "bits() unpacks little-endian packed flags")

sys.exit(1 if FAILURES else 0)
