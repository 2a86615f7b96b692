"""mesh.vtu opened by ParaView itself (ctest "paraview"; docs/contracts.md 4.4).

Run by ParaView's Python (Debian `paraview` and `python3-paraview`, headless: nothing is
rendered, so no display is needed):

    pvpython tests/experiments/paraview_test.py NDCONTOUR_BINARY SOURCE_DIR

Solves a surface (the torus, depth 4) and a curve (circle-r5, depth 3) with --vtk, opens each
mesh.vtu with paraview.simple.OpenDataFile, fetches the grid and checks its point and cell
counts against summary.json, its cell types, and that the arrays (u0 .., the variables' names,
singular, class, uncertified) are present with one value per point or cell. A 3-manifold: a
3-sphere in R^4 given as arrays (tests/experiments/sphere_mesh.py) written as mesh.vtu, binary
and ASCII, by the Python package next to the binary (BUILD/python, as the ctest `python` uses
it), is read as tetrahedra (VTK_TETRA) with the vertices and simplices given; and where `solve`
meshes k = 3, the 3-sphere sphere3-r4 (depth 3) solved with --vtk too. Exits 1 with one line per
failure.
"""

import json
import os
import subprocess
import sys
import tempfile

from paraview import servermanager
from paraview.simple import OpenDataFile, UpdatePipeline

# (problem file, depth, VTK cell type, summary field counting the cells)
CASES = [("torus.toml", 4, 5, "triangles"), ("circle-r5.toml", 3, 3, "edges")]
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from sphere_mesh import kuhn_sphere  # noqa: E402 (after its folder is on the path)
failures = []


def check(condition, message):
    if not condition:
        failures.append(message)


def solve(binary, source, problem, depth, out):
    subprocess.run([binary, "solve", os.path.join(source, "experiments", "problems", problem),
                    "--depth", str(depth), "--vtk", "--out", out], check=True,
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    with open(os.path.join(out, "summary.json")) as f:
        return json.load(f)


def array(data, name):
    """The array `name` of point or cell data as a list (None when absent)."""
    a = data.GetArray(name)
    return None if a is None else [a.GetValue(i) for i in range(a.GetNumberOfTuples())]


def face_count(ply):
    """The `element face` count of a mesh.ply header."""
    with open(ply, "rb") as f:
        for line in f:
            words = line.split()
            if words[:2] == [b"element", b"face"]:
                return int(words[2])
            if words[:1] == [b"end_header"]:
                return 0


def read_grid(path):
    reader = OpenDataFile(path)
    check(reader is not None, f"{path}: ParaView found no reader for it")
    if reader is None:
        return None
    UpdatePipeline(proxy=reader)
    return servermanager.Fetch(reader)


def check_tetrahedra(binary, scratch):
    """The 3-sphere given as arrays, written by the package: tetrahedra as given."""
    sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(binary)), "python"))
    try:
        import ndcontour
        import numpy as np
    except ImportError as e:
        print(f"paraview_test: no Python package beside the binary ({e}): k = 3 given not checked")
        return 0
    vertices, simplices = kuhn_sphere(3)
    result = ndcontour._core._result_from_arrays(np.array(vertices), np.array(simplices),
                                                 ["x", "y", "z", "w"], "s3")
    for ascii in (False, True):
        out = os.path.join(scratch, "s3-" + ("ascii" if ascii else "binary"))
        result.write(out, ascii=ascii, vtk=True)
        grid = read_grid(os.path.join(out, "mesh.vtu"))
        if grid is None:
            continue
        summary = {"variables": ["x", "y", "z", "w"],
                   "mesh": {"vertices": len(vertices), "tetrahedra": len(simplices)}}
        check_grid(out, grid, summary, 10, "tetrahedra")
        for c, simplex in enumerate(simplices[:50]):
            ids = grid.GetCell(c).GetPointIds()
            got = tuple(ids.GetId(i) for i in range(ids.GetNumberOfIds()))
            check(got == simplex, f"{out}: cell {c} is {got}, given {simplex}")
        w = grid.GetPointData().GetArray("w")
        check(all(w.GetValue(v) == vertices[v][3] for v in range(len(vertices))),
              f"{out}: point data w is not the fourth coordinate")
    return 2


def check_solved_tetrahedra(binary, source, scratch):
    """sphere3-r4 solved with --vtk, where this build's solve meshes k = 3."""
    out = os.path.join(scratch, "sphere3-r4")
    done = subprocess.run([binary, "solve", os.path.join(source, "experiments", "problems",
                                                         "sphere3-r4.toml"),
                           "--depth", "3", "--vtk", "--out", out],
                          stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    if done.returncode != 0:
        print("paraview_test: sphere3-r4 not solved (" + done.stderr.strip()[-200:] + ")")
        return 0
    with open(os.path.join(out, "summary.json")) as f:
        summary = json.load(f)
    summary["mesh"]["tetrahedra"] = face_count(os.path.join(out, "mesh.ply"))
    grid = read_grid(os.path.join(out, "mesh.vtu"))
    if grid is not None:
        check_grid("sphere3-r4", grid, summary, 10, "tetrahedra")
    return 1


def check_grid(problem, grid, summary, cell_type, count_field):
    points, cells = summary["mesh"]["vertices"], summary["mesh"][count_field]
    check(grid.GetClassName() == "vtkUnstructuredGrid", f"{problem}: {grid.GetClassName()}")
    check(grid.GetNumberOfPoints() == points,
          f"{problem}: {grid.GetNumberOfPoints()} points, summary.json says {points}")
    check(grid.GetNumberOfCells() == cells,
          f"{problem}: {grid.GetNumberOfCells()} cells, summary.json says {cells}")
    types = {grid.GetCellType(c) for c in range(grid.GetNumberOfCells())}
    check(types == {cell_type}, f"{problem}: cell types {types}, not {{{cell_type}}}")
    # Point data: u0 .., the variables' names (the same values) and singular.
    point_data, cell_data = grid.GetPointData(), grid.GetCellData()
    names = summary["variables"]
    for j, name in enumerate(names):
        u = array(point_data, f"u{j}")
        check(u is not None and len(u) == points, f"{problem}: point data u{j}")
        check(array(point_data, name) == u, f"{problem}: point data {name} is not u{j}")
    singular = array(point_data, "singular")
    check(singular is not None and len(singular) == points, f"{problem}: point data singular")
    for name in ("class", "uncertified"):
        values = array(cell_data, name)
        check(values is not None and len(values) == cells, f"{problem}: cell data {name}")
    # The points are mesh.vtu's x y z: the first three coordinates of these problems.
    for v in (0, points - 1):
        x = grid.GetPoint(v)
        for c in range(3):
            check(x[c] == point_data.GetArray(f"u{c}").GetValue(v),
                  f"{problem}: point {v} coordinate {c} is not u{c}")


def main():
    binary, source = sys.argv[1], sys.argv[2]
    with tempfile.TemporaryDirectory(prefix="ndc-paraview-") as scratch:
        for problem, depth, cell_type, count_field in CASES:
            out = os.path.join(scratch, problem.replace(".toml", ""))
            summary = solve(binary, source, problem, depth, out)
            reader = OpenDataFile(os.path.join(out, "mesh.vtu"))
            check(reader is not None, f"{problem}: ParaView found no reader for mesh.vtu")
            if reader is None:
                continue
            UpdatePipeline(proxy=reader)
            check_grid(problem, servermanager.Fetch(reader), summary, cell_type, count_field)
        meshes = len(CASES) + check_tetrahedra(binary, scratch)
        meshes += check_solved_tetrahedra(binary, source, scratch)
    for failure in failures:
        print("paraview_test: " + failure, file=sys.stderr)
    print(f"paraview_test: {meshes} meshes, {len(failures)} failures")
    sys.exit(1 if failures else 0)


main()
