"""mesh.vtu opened by ParaView itself (ctest "paraview"; docs/contracts.md 4.4).

Run by ParaView's Python (Debian `paraview` and `python3-paraview`, headless: nothing is
rendered, so no display is needed):

    pvpython tests/experiments/paraview_test.py NDCONTOUR_BINARY SOURCE_DIR

Solves a surface (the torus, depth 4) and a curve (circle-r5, depth 3) with --vtk, opens each
mesh.vtu with paraview.simple.OpenDataFile, fetches the grid and checks its point and cell
counts against summary.json, its cell types, and that the arrays (u0 .., the variables' names,
singular, class, uncertified) are present with one value per point or cell. Exits 1 with one
line per failure.
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
    for failure in failures:
        print("paraview_test: " + failure, file=sys.stderr)
    print(f"paraview_test: {len(CASES)} meshes, {len(failures)} failures")
    sys.exit(1 if failures else 0)


main()
