"""granite-blast report.py: hole_connected_reach on painted damage fields of a square lattice.

The answers are exact by construction: a straight radial run of damaged particles from the
hole wall reaches the radius of its outermost particle; a damaged patch that does not touch
that run does not count until a damaged particle joins them (8 neighbours).
"""
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(sys.argv[1], "cases"))
sys.path.insert(0, os.path.join(sys.argv[1], "cases", "granite-blast"))
import report  # noqa: E402

FAILURES = []


def check(ok, what):
    print(("ok   " if ok else "FAIL ") + what)
    if not ok:
        FAILURES.append(what)


dx, a = 0.5e-3, report.HOLE_RADIUS
g = np.arange(-20, 21) * dx
X, Y = np.meshgrid(g, g, indexing="ij")
x = np.column_stack([X.ravel(), Y.ravel()])
r = np.hypot(x[:, 0], x[:, 1])
keep = r >= a
x, r = x[keep], r[keep]
on_axis = np.abs(x[:, 1]) < 1e-12

damaged = np.zeros(len(x), dtype=bool)
check(report.hole_connected_reach(x, damaged, dx, a) == a, "no damage: the reach is the hole radius")

ray = on_axis & (x[:, 0] > 0) & (x[:, 0] <= 6e-3 + 1e-12)  # x = 1.5 ... 6 mm along +x
damaged |= ray
reach = report.hole_connected_reach(x, damaged, dx, a)
check(abs(reach - 6e-3) < 1e-12, f"a ray from the wall to x = 6 mm reaches 6 mm (got {reach * 1e3:.4f} mm)")

patch = on_axis & (x[:, 0] >= 7e-3 - 1e-12) & (x[:, 0] <= 9e-3 + 1e-12)  # 7 ... 9 mm: a gap at 6.5 mm
damaged |= patch
reach = report.hole_connected_reach(x, damaged, dx, a)
check(abs(reach - 6e-3) < 1e-12, f"a detached patch at 7-9 mm does not count (got {reach * 1e3:.4f} mm)")

# The gap closed by a particle one row off the axis (diagonal neighbours join).
bridge = (np.abs(x[:, 0] - 6.5e-3) < 1e-12) & (np.abs(x[:, 1] - dx) < 1e-12)
damaged |= bridge
reach = report.hole_connected_reach(x, damaged, dx, a)
check(abs(reach - 9e-3) < 1e-12, f"joined through a diagonal neighbour, the reach is 9 mm (got {reach * 1e3:.4f} mm)")

sys.exit(1 if FAILURES else 0)
