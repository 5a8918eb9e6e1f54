#!/usr/bin/env python3
"""Writes the VTK fixtures of this directory with the tools users have: VTK 9 itself
(vtkUnstructuredGridWriter, vtkXMLUnstructuredGridWriter), PyVista and meshio.

    pip install vtk pyvista meshio
    python3 make_fixtures.py        # rewrites every *.vtk, *.vtu and reference.json here

Every mesh is built here, in numpy, and `reference.json` records it independently of any
writer: points, each cell's points in VTK's order *and* in Gmsh's order (from this script's
own edge and face lists), and the point data. The Rust tests read each file and compare with
it. Coordinates and data are multiples of 1/256, exact in binary and in short decimals, so
every file must give the very same numbers.
"""

import json
import os
import sys

import meshio
import numpy as np
import pyvista as pv
import vtk
from vtk.util.numpy_support import numpy_to_vtk

HERE = os.path.dirname(os.path.abspath(__file__))

# ---------------------------------------------------------------------------------------
# Meshes: a 2 x 2 x 1 block of hexes (each cut into 6 tets for the tet meshes), its points
# moved a little so no two elements are alike; quadratic meshes add shared edge, face and
# centre points.

CORNERS = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1)]
# Hex edges and faces as pairs/quads of local corners.
HEX_EDGES_VTK = [(0, 1), (1, 2), (2, 3), (3, 0), (4, 5), (5, 6), (6, 7), (7, 4),
                 (0, 4), (1, 5), (2, 6), (3, 7)]
HEX_EDGES_GMSH = [(0, 1), (0, 3), (0, 4), (1, 2), (1, 5), (2, 3), (2, 6), (3, 7),
                  (4, 5), (4, 7), (5, 6), (6, 7)]
HEX_FACES_VTK = [(0, 4, 7, 3), (1, 2, 6, 5), (0, 1, 5, 4), (3, 7, 6, 2), (0, 3, 2, 1),
                 (4, 5, 6, 7)]
HEX_FACES_GMSH = [(0, 1, 2, 3), (0, 1, 5, 4), (0, 3, 7, 4), (1, 2, 6, 5), (2, 3, 7, 6),
                  (4, 5, 6, 7)]
TET_EDGES_VTK = [(0, 1), (1, 2), (2, 0), (0, 3), (1, 3), (2, 3)]
TET_EDGES_GMSH = [(0, 1), (1, 2), (2, 0), (0, 3), (2, 3), (1, 3)]
# Six positive tets of the unit cube around its 0-6 diagonal.
CUBE_TETS = [(0, 1, 2, 6), (0, 2, 3, 6), (0, 3, 7, 6), (0, 7, 4, 6), (0, 4, 5, 6), (0, 5, 1, 6)]


class Points:
    """Points by a key (a sorted tuple of the grid corners they sit between)."""

    def __init__(self):
        self.index = {}
        self.xyz = []

    def at(self, key, xyz):
        if key not in self.index:
            self.index[key] = len(self.xyz)
            self.xyz.append(xyz)
        return self.index[key]


def grid_point(i, j, k):
    # Moved by multiples of 1/32 so the block is not regular (still convex cells). Centres
    # of faces and cells are then multiples of 1/256: VTK's ASCII writer keeps 11 digits.
    x = i + ((i * 7 + j * 3 + k * 5) % 5 - 2) / 32
    y = j + ((i * 3 + j * 5 + k * 7) % 5 - 2) / 32
    z = k + ((i * 5 + j * 7 + k * 3) % 5 - 2) / 32
    return (x, y, z)


def mesh(kind):
    pts = Points()
    vtk_cells, gmsh_cells = [], []
    for ci in range(2):
        for cj in range(2):
            corner_keys = [((ci + a, cj + b, c),) for (a, b, c) in CORNERS]
            corners = [pts.at(key, grid_point(*key[0])) for key in corner_keys]

            def between(keys):
                key = tuple(sorted(k for ks in keys for k in ks))
                xyz = tuple(np.mean([pts.xyz[pts.index[k]] for k in keys], axis=0))
                return pts.at(key, xyz)

            def point(local):
                return corners[local]

            if kind in ("tet4", "tet10"):
                for tet in CUBE_TETS:
                    ids = [point(l) for l in tet]
                    keys = [corner_keys[l] for l in tet]
                    if kind == "tet4":
                        vtk_cells.append(ids)
                        gmsh_cells.append(ids)
                    else:
                        mid = {frozenset(e): between([keys[e[0]], keys[e[1]]]) for e in TET_EDGES_VTK}
                        vtk_cells.append(ids + [mid[frozenset(e)] for e in TET_EDGES_VTK])
                        gmsh_cells.append(ids + [mid[frozenset(e)] for e in TET_EDGES_GMSH])
            else:
                ids = [point(l) for l in range(8)]
                if kind == "hex8":
                    vtk_cells.append(ids)
                    gmsh_cells.append(ids)
                    continue
                mid = {frozenset(e): between([corner_keys[e[0]], corner_keys[e[1]]])
                       for e in HEX_EDGES_VTK}
                vtk_cell = ids + [mid[frozenset(e)] for e in HEX_EDGES_VTK]
                gmsh_cell = ids + [mid[frozenset(e)] for e in HEX_EDGES_GMSH]
                if kind == "hex27":
                    face = {tuple(sorted(f)): between([corner_keys[l] for l in f])
                            for f in HEX_FACES_VTK}
                    centre = between(corner_keys)
                    vtk_cell += [face[tuple(sorted(f))] for f in HEX_FACES_VTK] + [centre]
                    gmsh_cell += [face[tuple(sorted(f))] for f in HEX_FACES_GMSH] + [centre]
                vtk_cells.append(vtk_cell)
                gmsh_cells.append(gmsh_cell)
    xyz = np.array(pts.xyz, dtype=np.float64)
    # Nodal data: a linear function (exact in binary), and a vector to be ignored.
    weight = xyz[:, 0] + 2 * xyz[:, 1] + 4 * xyz[:, 2]
    thickness = 0.25 + xyz[:, 2] / 4
    return xyz, np.array(vtk_cells), np.array(gmsh_cells), weight, thickness


VTK_TYPE = {"tet4": 10, "tet10": 24, "hex8": 12, "hex20": 25, "hex27": 29}
MESHIO_TYPE = {"tet4": "tetra", "tet10": "tetra10", "hex8": "hexahedron",
               "hex20": "hexahedron20", "hex27": "hexahedron27"}


# ---------------------------------------------------------------------------------------
# Writers

def vtk_grid(xyz, cells, kind, weight, thickness):
    """A vtkUnstructuredGrid as a VTK user would have it: `weight` the active scalars,
    `wall thickness` (a name with a space) another point array, a 3-component vector with
    component names, cell data, dataset field data (a number and a string array)."""
    points = vtk.vtkPoints()
    points.SetData(numpy_to_vtk(xyz, deep=True))
    grid = vtk.vtkUnstructuredGrid()
    grid.SetPoints(points)
    for c in cells:
        ids = vtk.vtkIdList()
        for i in c:
            ids.InsertNextId(int(i))
        grid.InsertNextCell(VTK_TYPE[kind], ids)
    w = numpy_to_vtk(weight, deep=True)
    w.SetName("weight")
    grid.GetPointData().SetScalars(w)
    t = numpy_to_vtk(thickness, deep=True)
    t.SetName("wall thickness")
    grid.GetPointData().AddArray(t)
    v = numpy_to_vtk(xyz * 2, deep=True)
    v.SetName("displacement")
    for k, n in enumerate("xyz"):
        v.SetComponentName(k, "d" + n)
    grid.GetPointData().AddArray(v)
    ids = numpy_to_vtk(np.arange(len(cells), dtype=np.int64) + 100, deep=True)
    ids.SetName("vtkOriginalIndices")
    grid.GetCellData().AddArray(ids)
    time = numpy_to_vtk(np.array([0.5]), deep=True)
    time.SetName("TimeValue")
    grid.GetFieldData().AddArray(time)
    notes = vtk.vtkStringArray()
    notes.SetName("notes")
    notes.InsertNextValue("made by make_fixtures.py")
    notes.InsertNextValue("")
    grid.GetFieldData().AddArray(notes)
    # Ranges computed, as any pipeline does: VTK then writes METADATA/INFORMATION blocks.
    grid.GetPoints().GetData().GetRange(-1)
    v.GetRange(-1)
    return grid


def write_vtk_legacy(grid, path, binary, version):
    w = vtk.vtkUnstructuredGridWriter()
    w.SetInputData(grid)
    w.SetFileName(path)
    if binary:
        w.SetFileTypeToBinary()
    else:
        w.SetFileTypeToASCII()
    if version == "4.2":
        w.SetFileVersion(w.VTK_LEGACY_READER_VERSION_4_2)
    assert w.Write() == 1, path


def write_vtk_xml(grid, path, mode, compressor, encode=True, header64=False, block=None):
    w = vtk.vtkXMLUnstructuredGridWriter()
    w.SetInputData(grid)
    w.SetFileName(path)
    {"ascii": w.SetDataModeToAscii, "binary": w.SetDataModeToBinary,
     "appended": w.SetDataModeToAppended}[mode]()
    {"none": w.SetCompressorTypeToNone, "zlib": w.SetCompressorTypeToZLib,
     "lz4": w.SetCompressorTypeToLZ4, "lzma": w.SetCompressorTypeToLZMA}[compressor]()
    w.SetEncodeAppendedData(encode)
    if header64:
        w.SetHeaderTypeToUInt64()
    if block:
        w.SetBlockSize(block)  # several compressed blocks per array
    assert w.Write() == 1, path


def main():
    out = HERE
    for f in os.listdir(out):
        if f.endswith((".vtk", ".vtu")):
            os.remove(os.path.join(out, f))
    reference = {
        "tools": {
            "vtk": vtk.vtkVersion.GetVTKVersion(),
            "pyvista": pv.__version__,
            "meshio": meshio.__version__,
            "numpy": np.__version__,
            "python": sys.version.split()[0],
        },
        "meshes": {},
        "files": {},
    }
    for kind in ["tet4", "hex8", "tet10", "hex20", "hex27"]:
        xyz, vtk_cells, gmsh_cells, weight, thickness = mesh(kind)
        reference["meshes"][kind] = {
            "points": xyz.tolist(),
            "cells_vtk": vtk_cells.tolist(),
            "cells_gmsh": gmsh_cells.tolist(),
            "vtk_cell_type": VTK_TYPE[kind],
            "point_data": {"weight": weight.tolist(), "wall thickness": thickness.tolist(),
                           "thickness": thickness.tolist()},
        }
        quadratic = kind not in ("tet4", "hex8")
        files = {}

        def add(name, tool, what, arrays):
            files[f"{kind}_{name}"] = {"mesh": kind, "tool": tool, "variant": what,
                                       "point_data": arrays}

        # VTK itself.
        grid = vtk_grid(xyz, vtk_cells, kind, weight, thickness)
        both = ["weight", "wall thickness"]
        legacy = [("ascii", False, "5.1"), ("binary", True, "5.1")]
        if not quadratic:
            legacy += [("ascii42", False, "4.2"), ("binary42", True, "4.2")]
        for name, binary, version in legacy:
            path = f"{kind}_vtk9_{name}.vtk"
            write_vtk_legacy(grid, os.path.join(out, path), binary, version)
            add(f"vtk9_{name}.vtk", "vtk", f"legacy {version} {'BINARY' if binary else 'ASCII'}", both)
        xml = [("lz4", "binary", "lz4", True, False, None),
               ("appended_lz4", "appended", "lz4", False, False, 256)]
        if not quadratic:
            xml += [
                ("ascii", "ascii", "none", True, False, None),
                ("base64", "binary", "none", True, False, None),
                ("zlib", "binary", "zlib", True, False, None),
                ("lz4_uint64", "binary", "lz4", True, True, 200),
                ("appended_raw", "appended", "none", False, False, None),
                ("appended_base64", "appended", "none", True, False, None),
                ("appended_zlib", "appended", "zlib", False, False, 256),
                ("appended_base64_lz4", "appended", "lz4", True, False, 256),
                ("lzma", "binary", "lzma", True, False, None),
            ]
        for name, mode, comp, enc, h64, block in xml:
            path = f"{kind}_vtk9_{name}.vtu"
            write_vtk_xml(grid, os.path.join(out, path), mode, comp, enc, h64, block)
            add(f"vtk9_{name}.vtu", "vtk", f"XML {mode} {comp}" + (" UInt64" if h64 else "")
                + (f" blocks of {block} B" if block else "") + ("" if enc else " raw"), both)

        # PyVista (its own defaults: legacy binary, .vtu zlib).
        pgrid = pv.UnstructuredGrid({VTK_TYPE[kind]: vtk_cells}, xyz)
        pgrid.point_data["weight"] = weight
        pgrid.point_data["displacement"] = xyz * 2
        pgrid.point_data["wall thickness"] = thickness
        pgrid.points  # noqa: B018  (ranges computed as on any plot)
        pgrid.bounds  # noqa: B018
        for name, ext, kw in [("pyvista.vtk", "vtk", {}), ("pyvista_ascii.vtk", "vtk", {"binary": False}),
                              ("pyvista.vtu", "vtu", {})]:
            if quadratic and name == "pyvista_ascii.vtk":
                continue
            pgrid.save(os.path.join(out, f"{kind}_{name}"), **kw)
            add(name, "pyvista", f"{ext} {kw or 'default'}", both)

        # meshio: legacy with FIELD point data, and .vtu.
        m = meshio.Mesh(xyz, [(MESHIO_TYPE[kind], vtk_cells)],
                        point_data={"weight": weight, "thickness": thickness,
                                    "displacement": xyz * 2},
                        cell_data={"region": [np.arange(len(vtk_cells), dtype=np.int32) % 2]})
        mio = [("meshio_ascii.vtk", dict(binary=False)), ("meshio_binary.vtk", dict(binary=True)),
               ("meshio.vtu", dict())]
        if not quadratic:
            mio += [("meshio_ascii42.vtk", dict(binary=False, fmt_version="4.2")),
                    ("meshio_binary42.vtk", dict(binary=True, fmt_version="4.2")),
                    ("meshio_ascii.vtu", dict(binary=False)),
                    ("meshio_lzma.vtu", dict(compression="lzma"))]
        for name, kw in mio:
            path = os.path.join(out, f"{kind}_{name}")
            if name.endswith(".vtk"):
                meshio.vtk.write(path, m, **kw)
            else:
                meshio.vtu.write(path, m, **kw)
            add(name, "meshio", f"{name.rsplit('.', 1)[1]} {kw}", ["weight", "thickness"])
        reference["files"].update(files)
    with open(os.path.join(out, "reference.json"), "w") as f:
        json.dump(reference, f, indent=1, sort_keys=True)
        f.write("\n")
    print(f"{len(reference['files'])} files, tools {reference['tools']}")


if __name__ == "__main__":
    main()
