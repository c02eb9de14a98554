#!/usr/bin/python3
"""convert_mesh.py keeps labelled regions as gmsh physical groups, and gmsh can read the result.

usage: test_convert_mesh.py CONVERT_SCRIPT BRECCIA_MESH WORKDIR
A unit cube split into 6 tetrahedra (Kuhn split) is written as VTU with a 'material'
label and as Abaqus .inp with two element sets; each is converted, then read back by gmsh
through breccia-mesh (which validates a .msh and reports its groups).
"""
import os
import subprocess
import sys

import meshio
import numpy as np

script, breccia_mesh, workdir = sys.argv[1:4]
os.makedirs(workdir, exist_ok=True)
failures = []


def check(condition, message):
    if not condition:
        failures.append(message)
        print("FAIL:", message)


corners = np.array([[x, y, z] for z in (0, 1) for y in (0, 1) for x in (0, 1)], dtype=float)
# Kuhn (Freudenthal) split of the cube into 6 tets of volume 1/6 each, all sharing 0-7.
tets = np.array([[0, 1, 3, 7], [0, 1, 5, 7], [0, 2, 3, 7], [0, 2, 6, 7], [0, 4, 5, 7], [0, 4, 6, 7]])
bottom = np.array([[0, 1, 3], [0, 3, 2]])


def run_convert(src, dst):
    return subprocess.run([sys.executable, script, src, dst], capture_output=True, text=True)


def groups_via_gmsh(msh):
    out = subprocess.run([breccia_mesh, msh, "-o", msh + ".rewritten.msh", "--quiet"], capture_output=True, text=True)
    check(out.returncode == 0, f"gmsh (via breccia-mesh) could not read {msh}: {out.stderr}")
    groups = {}
    for line in out.stdout.splitlines():
        parts = line.split()
        if len(parts) == 7 and parts[1] == "dim" and parts[6] == "elements":
            groups[parts[0]] = (int(parts[2]), int(parts[5]))
    return groups, out.stdout


# VTU with an integer region label: material 1 for the first 4 tets, 2 for the last 2.
vtu = os.path.join(workdir, "cube.vtu")
meshio.write(vtu, meshio.Mesh(corners, [("tetra", tets), ("triangle", bottom)],
                              cell_data={"material": [np.array([1, 1, 1, 1, 2, 2]), np.array([3, 3])]}))
res = run_convert(vtu, os.path.join(workdir, "cube_vtu.msh"))
check(res.returncode == 0, f"VTU conversion failed: {res.stderr}")
groups, text = groups_via_gmsh(os.path.join(workdir, "cube_vtu.msh"))
check(groups.get("material_1") == (3, 4), f"material_1 should hold 4 tets, got {groups.get('material_1')}\n{text}")
check(groups.get("material_2") == (3, 2), f"material_2 should hold 2 tets, got {groups.get('material_2')}")
check(groups.get("material_3") == (2, 2), f"material_3 should hold the 2 bottom triangles, got {groups.get('material_3')}")
# The whole cube, so the tets' volumes must sum to 1 (exact up to print rounding).
check("volume          1 m3" in text, f"converted cube volume is not 1 m3:\n{text}")

# Abaqus .inp with element sets, one nested in the other: the smaller set wins.
inp = os.path.join(workdir, "cube.inp")
meshio.write(inp, meshio.Mesh(corners, [("tetra", tets)],
                              cell_sets={"ALL": [np.arange(6)], "CORE": [np.array([0, 1])]}))
res = run_convert(inp, os.path.join(workdir, "cube_inp.msh"))
check(res.returncode == 0, f"Abaqus conversion failed: {res.stderr}")
groups, text = groups_via_gmsh(os.path.join(workdir, "cube_inp.msh"))
check(groups.get("CORE") == (3, 2) and groups.get("ALL") == (3, 4), f"element sets not kept: {groups}\n{text}")

# Bad input: clear message and exit 2.
garbage = os.path.join(workdir, "garbage.vtu")
with open(garbage, "w") as f:
    f.write("not a mesh\n")
res = run_convert(garbage, os.path.join(workdir, "garbage.msh"))
check(res.returncode == 2 and "garbage.vtu" in res.stderr and "meshio cannot read" in res.stderr,
      f"garbage input should exit 2 naming the file, got {res.returncode}: {res.stderr}")
check(not os.path.exists(os.path.join(workdir, "garbage.msh")), "a failed conversion left an output file")

print("FAILED" if failures else "all convert_mesh checks passed")
sys.exit(1 if failures else 0)
