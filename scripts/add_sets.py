"""Add named particle sets to a lattice particles.h5 written by breccia-place.

    add_sets.py particles.h5 NAME:x0,y0,x1,y1 [NAME:...]

Each set is the particles whose reference position lies in the box (metres, inclusive).
Positions and volumes are untouched, so the file's content_id stays valid.
"""
import sys

import h5py
import numpy as np


def main(argv):
    if len(argv) < 3:
        sys.exit(__doc__)
    with h5py.File(argv[1], "a") as f:
        x = f["particles/position"][:]
        for spec in argv[2:]:
            name, box = spec.split(":")
            lo_x, lo_y, hi_x, hi_y = (float(v) for v in box.split(","))
            inside = (x[:, 0] >= lo_x) & (x[:, 0] <= hi_x) & (x[:, 1] >= lo_y) & (x[:, 1] <= hi_y)
            idx = np.nonzero(inside)[0].astype(np.int64)
            if idx.size == 0:
                sys.exit(f"add_sets: set '{name}' would be empty (box {box})")
            if name in f["sets"]:
                del f["sets"][name]
            f["sets"].create_dataset(name, data=idx)
            print(f"set {name}: {idx.size} particles")


if __name__ == "__main__":
    main(sys.argv)
