#!/usr/bin/python3
"""Convert a mesh from another format (Exodus, Abaqus .inp, VTU, ...) to gmsh 4.1 .msh.

usage: /usr/bin/python3 scripts/convert_mesh.py IN OUT.msh

meshio reads the input. Cell sets (Abaqus ELSET, named sets) and integer cell-data arrays
that label regions (gmsh:physical, CellEntityIds, material, ...) become gmsh physical
groups, so that breccia-geometry sees named volumes and boundaries. A cell in several
sets goes to the smallest one (the most specific); cells in no set go to 'body' (top
dimension) or 'boundary'. Node sets have no place in a physical-groups-only .msh and are
dropped with a note. The file is written as OUT.msh.partial and renamed when complete.
Exit 2 with one message on bad input.
"""
import os
import sys

import numpy as np

# meshio cell type -> (gmsh element type, dimension); linear elements only (their node
# order is the same in meshio/VTK and gmsh).
GMSH_TYPES = {
    "vertex": (15, 0),
    "line": (1, 1),
    "triangle": (2, 2),
    "quad": (3, 2),
    "tetra": (4, 3),
    "hexahedron": (5, 3),
    "wedge": (6, 3),
    "pyramid": (7, 3),
}
LABEL_ARRAYS = ("gmsh:physical", "CellEntityIds", "cell_tags", "material", "medit:ref", "region")


class ConversionError(Exception):
    pass


def read_input(path):
    import meshio

    if not os.path.exists(path):
        raise ConversionError(f"{path}: file does not exist (expected a mesh file readable by meshio)")
    try:
        return meshio.read(path)
    # meshio raises ReadError, KeyError, ValueError... by format, and some readers (VTU)
    # call sys.exit on malformed files, hence SystemExit too.
    except (Exception, SystemExit) as e:
        why = str(e) if str(e) not in ("", "1", "None") else "malformed or unsupported content"
        raise ConversionError(f"{path}: meshio cannot read it: {why} (expected a mesh in a format meshio knows)")


def cell_blocks(mesh, path):
    blocks = []
    for block in mesh.cells:
        if block.type not in GMSH_TYPES:
            raise ConversionError(f"{path}: cell type '{block.type}' is not supported "
                                  f"(expected linear cells: {', '.join(GMSH_TYPES)})")
        blocks.append((block.type, np.asarray(block.data)))
    if not blocks:
        raise ConversionError(f"{path}: contains no cells (expected a volume or surface mesh)")
    return blocks


def labels_from_sets(mesh, blocks):
    """Per block, an array of group names (None where unassigned) from cell_sets."""
    labels = [np.full(len(data), None, dtype=object) for _, data in blocks]
    sets = {name: ids for name, ids in mesh.cell_sets.items() if not name.startswith("gmsh:")}
    sizes = {name: sum(len(np.asarray(i)) for i in ids if i is not None) for name, ids in sets.items()}
    # Largest first, so that smaller (more specific) sets overwrite.
    for name in sorted(sets, key=lambda n: -sizes[n]):
        for b, ids in enumerate(sets[name]):
            if ids is not None and len(ids):
                labels[b][np.asarray(ids, dtype=int)] = name
    return labels


def labels_from_arrays(mesh, blocks, labels):
    """Fill unassigned cells from an integer labelling array, if the input has one."""
    for key in LABEL_ARRAYS:
        if key not in mesh.cell_data:
            continue
        names = {int(tag): name for name, (tag, *_rest) in getattr(mesh, "field_data", {}).items()}
        for b, values in enumerate(mesh.cell_data[key]):
            values = np.asarray(values).astype(int).ravel()
            for i in np.nonzero(labels[b] == None)[0]:  # noqa: E711 (numpy object compare)
                labels[b][i] = names.get(values[i], f"{key.replace(':', '_')}_{values[i]}")
        return


def write_msh41(path, points, groups):
    """groups: list of (name, dim, [(gmsh_type, connectivity 0-based)]). ASCII msh 4.1."""
    points = np.asarray(points, dtype=float)
    if points.shape[1] == 2:
        points = np.hstack([points, np.zeros((len(points), 1))])
    top_dim = max(dim for _, dim, _ in groups)
    entity_tag = {}
    per_dim = {0: [], 1: [], 2: [], 3: []}
    for phys, (name, dim, _) in enumerate(groups, start=1):
        per_dim[dim].append(phys)
        entity_tag[phys] = len(per_dim[dim])
    with open(path, "w") as f:
        f.write("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n")
        f.write(f"$PhysicalNames\n{len(groups)}\n")
        for phys, (name, dim, _) in enumerate(groups, start=1):
            f.write(f'{dim} {phys} "{name}"\n')
        f.write("$EndPhysicalNames\n$Entities\n")
        f.write(" ".join(str(len(per_dim[d])) for d in range(4)) + "\n")
        for d in range(4):
            for phys in per_dim[d]:
                _, _, blocks = groups[phys - 1]
                used = np.unique(np.concatenate([c.ravel() for _, c in blocks]))
                lo, hi = points[used].min(axis=0), points[used].max(axis=0)
                if d == 0:
                    f.write(f"{entity_tag[phys]} {lo[0]:.16g} {lo[1]:.16g} {lo[2]:.16g} 1 {phys}\n")
                else:
                    f.write(f"{entity_tag[phys]} " + " ".join(f"{v:.16g}" for v in (*lo, *hi)) + f" 1 {phys} 0\n")
        f.write("$EndEntities\n")
        # All nodes in one block on the first top-dimension entity: valid msh 4.1, and
        # gmsh reclassifies nodes when it needs to.
        n = len(points)
        f.write(f"$Nodes\n1 {n} 1 {n}\n{top_dim} {entity_tag[per_dim[top_dim][0]]} 0 {n}\n")
        f.write("\n".join(str(i) for i in range(1, n + 1)) + "\n")
        np.savetxt(f, points, fmt="%.16g")
        f.write("$EndNodes\n")
        blocks = [(entity_tag[phys], dim, t, c) for phys, (_, dim, bl) in enumerate(groups, start=1) for t, c in bl]
        total = sum(len(c) for *_, c in blocks)
        f.write(f"$Elements\n{len(blocks)} {total} 1 {total}\n")
        next_tag = 1
        for tag, dim, gmsh_type, conn in blocks:
            f.write(f"{dim} {tag} {gmsh_type} {len(conn)}\n")
            rows = np.hstack([np.arange(next_tag, next_tag + len(conn))[:, None], conn + 1])
            np.savetxt(f, rows, fmt="%d")
            next_tag += len(conn)
        f.write("$EndElements\n")


def convert(src, dst):
    if not dst.endswith(".msh"):
        raise ConversionError(f"{dst}: output must end in .msh (expected OUT.msh)")
    mesh = read_input(src)
    blocks = cell_blocks(mesh, src)
    labels = labels_from_sets(mesh, blocks)
    labels_from_arrays(mesh, blocks, labels)
    top_dim = max(GMSH_TYPES[t][1] for t, _ in blocks)
    grouped = {}
    for (ctype, data), lab in zip(blocks, labels):
        gmsh_type, dim = GMSH_TYPES[ctype]
        for name in dict.fromkeys(lab):
            mask = lab == name
            label = name if name is not None else ("body" if dim == top_dim else "boundary")
            key = (label, dim)
            grouped.setdefault(key, []).append((gmsh_type, data[mask]))
    names_dims = {}
    for label, dim in grouped:
        if label in names_dims:
            raise ConversionError(f"{src}: set '{label}' holds cells of dimensions {names_dims[label]} and {dim} "
                                  "(expected one dimension per set)")
        names_dims[label] = dim
    if mesh.point_sets:
        print(f"convert_mesh: note: node sets dropped (no place in a physical-groups-only .msh): "
              f"{', '.join(mesh.point_sets)}", file=sys.stderr)
    groups = [(label, dim, bl) for (label, dim), bl in sorted(grouped.items(), key=lambda kv: (-kv[0][1], kv[0][0]))]
    partial = dst + ".partial"
    try:
        write_msh41(partial, mesh.points, groups)
        os.replace(partial, dst)
    finally:
        if os.path.exists(partial):
            os.remove(partial)
    cells = sum(len(c) for _, d, bl in groups if d == top_dim for _, c in bl)
    print(f"convert_mesh: {src} -> {dst}: {len(mesh.points)} nodes, {cells} cells of dimension {top_dim}, "
          f"groups: {', '.join(f'{n} ({d}D)' for n, d, _ in groups)}")


def main(argv):
    if len(argv) != 3 or argv[1] in ("-h", "--help"):
        print(__doc__.strip().splitlines()[2], file=sys.stderr)
        return 2
    try:
        convert(argv[1], argv[2])
    except ConversionError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
