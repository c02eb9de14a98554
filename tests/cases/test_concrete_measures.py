#!/usr/bin/python3
"""The concrete-blast case's crack counts (cases/concrete-blast/measures.py) on synthetic
damage fields whose answer is known by construction: a 5 mm lattice filling the 300 mm cube,
damage 1 within 4 mm of chosen half-planes that start on the hole axis (radial cracks) and
stop at a chosen radius; and the broken mass share on three particles. Exit 1 on any wrong count."""
import importlib.util
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
spec = importlib.util.spec_from_file_location(
    "measures", os.path.join(HERE, "..", "..", "cases", "concrete-blast", "measures.py"))
measures = importlib.util.module_from_spec(spec)
spec.loader.exec_module(measures)

g = np.arange(0.0025, 0.3, 0.005)
x = np.stack(np.meshgrid(g, g, g, indexing="ij"), axis=-1).reshape(-1, 3)
dx, dy = x[:, 0] - 0.15, x[:, 1] - 0.15
rad = np.hypot(dx, dy)
in_hole_span = x[:, 2] > 0.15  # the hole is 150 mm deep from the top


def cracks(angles_deg, reach=1.0):
    """Damage of radial half-planes at these angles, out to `reach` from the axis."""
    d = np.zeros(len(x))
    for a in np.radians(angles_deg):
        along = dx * np.cos(a) + dy * np.sin(a)
        across = np.abs(-dx * np.sin(a) + dy * np.cos(a))
        d[(along > 0) & (across < 0.004) & (rad < reach) & in_hole_span] = 1.0
    return d


failures = []


def expect(name, got, want):
    print(f"{name}: {got} (expected {want})")
    if got != want:
        failures.append(name)


d = cracks([10, 100, 220])
expect("three cracks to the faces, ring", measures.ring_cracks(x, d), 3)
expect("three cracks to the faces, side faces", measures.side_face_cracks(x, d), 3)
# Into the four corners: each crack meets two faces at their shared edge, one run of bins.
d = cracks([45, 135, 225, 315])
expect("four cracks into the corners, side faces", measures.side_face_cracks(x, d), 4)
# Cracks that stop at 100 mm cross the ring and do not reach the faces (the nearest is 150 mm).
d = cracks([0, 120, 240], reach=0.1)
expect("three short cracks, ring", measures.ring_cracks(x, d), 3)
expect("three short cracks, side faces", measures.side_face_cracks(x, d), 0)
expect("intact, side faces", measures.side_face_cracks(x, np.zeros(len(x))), 0)
expect("damaged throughout, side faces", measures.side_face_cracks(x, np.ones(len(x))), "all")
expect("damaged throughout, ring", measures.ring_cracks(x, np.ones(len(x))), "all")
# The broken share weighs particles by volume: two particles of three by count, a quarter by volume.
expect("broken mass share", measures.broken_mass_share(np.array([1.0, 1.0, 6.0]), np.array([0.5, 0.99, 0.49])), 0.25)
sys.exit(1 if failures else 0)
