#!/usr/bin/env python3
"""Tetrahedron quality of one or more gmsh meshes: a histogram of the radius ratio, side by side.

The radius ratio q = 3 r_in / R_circ is 1 for the regular tetrahedron and 0 for a flat one
(the measure gmsh's optimiser and most mesh papers report as "gamma"-like shape quality; see
Shewchuk, "What is a good linear element?", 2002). Particles sit at tet centroids with the tet
volumes, so slivers (q near 0) give particles whose volume is far from their spacing cubed.

Usage: scripts/mesh_quality.py A.msh [B.msh ...] [--labels a,b] [--png hist.png]
Prints one row per mesh (tets, min, 1st percentile, mean, share under 0.2 and 0.5) and the
histogram in bins of 0.1; --png writes the histograms as one chart.
"""
import argparse
import os
import sys

import meshio
import numpy as np


def radius_ratio(points, tets):
    a, b, c, d = (points[tets[:, k]] for k in range(4))
    ab, ac, ad = b - a, c - a, d - a
    vol6 = np.abs(np.einsum("ij,ij->i", ab, np.cross(ac, ad)))  # 6 V
    # Inscribed radius: 3V / total face area.
    def area(p, q, r):
        return 0.5 * np.linalg.norm(np.cross(q - p, r - p), axis=1)
    faces = area(a, b, c) + area(a, b, d) + area(a, c, d) + area(b, c, d)
    r_in = (vol6 / 2.0) / faces
    # Circumradius: |ab^2 (ac x ad) + ac^2 (ad x ab) + ad^2 (ab x ac)| / (2 * 6V).
    num = (np.einsum("ij,ij->i", ab, ab)[:, None] * np.cross(ac, ad)
           + np.einsum("ij,ij->i", ac, ac)[:, None] * np.cross(ad, ab)
           + np.einsum("ij,ij->i", ad, ad)[:, None] * np.cross(ab, ac))
    r_circ = np.linalg.norm(num, axis=1) / (2.0 * vol6)
    return 3.0 * r_in / r_circ


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("meshes", nargs="+")
    ap.add_argument("--labels", help="comma-separated labels, one per mesh")
    ap.add_argument("--png", help="write the histograms to this PNG")
    args = ap.parse_args()
    labels = args.labels.split(",") if args.labels else args.meshes
    if len(labels) != len(args.meshes):
        ap.error("--labels needs one label per mesh")
    for path in args.meshes:
        if not os.path.isfile(path):
            ap.error(f"mesh {path} not found (expected a gmsh .msh file)")
    bins = np.linspace(0.0, 1.0, 11)
    rows = []
    print("mesh                          tets     min    p1     mean   <0.2     <0.5")
    for path, label in zip(args.meshes, labels):
        m = meshio.read(path)
        tets = np.concatenate([c.data for c in m.cells if c.type == "tetra"])
        q = radius_ratio(m.points, tets)
        hist, _ = np.histogram(q, bins=bins)
        rows.append((label, hist / len(q)))
        print(f"{label:28s} {len(q):8d}  {q.min():.3f}  {np.percentile(q, 1):.3f}  {q.mean():.3f}"
              f"  {np.mean(q < 0.2) * 100:5.2f}%  {np.mean(q < 0.5) * 100:5.2f}%")
    print("\nshare of tets per radius-ratio bin (%):")
    print("bin        " + "  ".join(f"{l[:12]:>12s}" for l, _ in rows))
    for k in range(len(bins) - 1):
        print(f"{bins[k]:.1f}-{bins[k + 1]:.1f}    " + "  ".join(f"{h[k] * 100:12.2f}" for _, h in rows))
    if args.png:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, ax = plt.subplots(figsize=(7, 4.2))
        width = 0.1 / (len(rows) + 1)
        for i, (label, h) in enumerate(rows):
            ax.bar(bins[:-1] + (i + 0.5) * width, h * 100, width=width, label=label, align="edge")
        ax.set_xlabel("radius ratio 3 r_in / R_circ (1 = regular tetrahedron)")
        ax.set_ylabel("share of tetrahedra (%)")
        ax.set_title("Tetrahedron quality")
        ax.legend()
        ax.grid(alpha=0.3)
        fig.tight_layout()
        fig.savefig(args.png, dpi=120)


if __name__ == "__main__":
    main()
