"""Every mesh output format read back with meshio (Debian python3-meshio), against the summary
and against mesh.ply (ctest "python"). `solve` runs as a process, as a user runs it."""

import json
import os
import pathlib
import subprocess

import meshio
import numpy as np
import pytest

ROOT = pathlib.Path(os.environ.get("NDC_SOURCE_DIR", pathlib.Path(__file__).resolve().parents[3]))
BINARY = os.environ.get("NDC_BINARY", str(ROOT / "build" / "bin" / "ndcontour"))
PROBLEMS = ROOT / "experiments" / "problems"


def solve(tmp_path, problem, depth, *extra):
    out = tmp_path / pathlib.Path(problem).stem
    subprocess.run([BINARY, "solve", str(PROBLEMS / problem), "--depth", str(depth), "--out",
                    str(out), "--vtk", "--obj", *extra], check=True, capture_output=True)
    return out, json.loads((out / "summary.json").read_text())


def cells_of(mesh, kind):
    return np.concatenate([c.data for c in mesh.cells if c.type == kind])


@pytest.mark.parametrize("problem,depth,n", [("torus.toml", 4, 3), ("clifford-torus.toml", 3, 4),
                                             ("sphere-r6.toml", 3, 6)])
def test_surfaces_in_every_format(tmp_path, problem, depth, n):
    out, summary = solve(tmp_path, problem, depth)
    vertices, triangles = summary["mesh"]["vertices"], summary["mesh"]["triangles"]
    ply = meshio.read(out / "mesh.ply")
    vtu = meshio.read(out / "mesh.vtu")
    obj = meshio.read(out / "mesh.obj")
    for mesh in (ply, vtu, obj):
        assert mesh.points.shape == (vertices, 3)
        assert cells_of(mesh, "triangle").shape == (triangles, 3)
        assert np.array_equal(mesh.points, ply.points)
        assert np.array_equal(cells_of(mesh, "triangle"), cells_of(ply, "triangle"))
    # The coordinates in R^n as point data, equal to mesh.ply's u0..
    for j in range(n):
        assert np.array_equal(vtu.point_data[f"u{j}"], ply.point_data[f"u{j}"])
    assert set(np.unique(vtu.cell_data["class"][0])) <= {-1, 0, 1, 2}
    assert (vtu.cell_data["class"][0] >= 0).mean() > 0.5  # most simplices lie in base cells
    if summary["topology"]["certified"]:
        assert not vtu.cell_data["uncertified"][0].any()
    assert (vtu.point_data["singular"] == 0).all()  # no singular point on these


def test_ascii_ply_reads_the_same(tmp_path):
    out, _ = solve(tmp_path, "torus.toml", 3)
    binary = meshio.read(out / "mesh.ply")
    ascii_out, _ = solve(tmp_path / "ascii", "torus.toml", 3, "--ascii")
    text = meshio.read(ascii_out / "mesh.ply")
    assert np.array_equal(binary.points, text.points)
    assert np.array_equal(cells_of(binary, "triangle"), cells_of(text, "triangle"))


def test_curves_as_vtk_lines_and_obj_points(tmp_path):
    out, summary = solve(tmp_path, "space-curve-r4.toml", 4)
    vtu = meshio.read(out / "mesh.vtu")
    lines = cells_of(vtu, "line")
    assert lines.shape == (summary["mesh"]["edges"], 2)
    assert vtu.points.shape == (summary["mesh"]["vertices"], 3)
    assert all(f"u{j}" in vtu.point_data for j in range(4))
    # A closed curve: every vertex on two lines.
    assert (np.bincount(lines.ravel(), minlength=len(vtu.points)) == 2).all()
    # meshio's OBJ reader keeps the vertices of `l` records (it reads no line cells); the l
    # records themselves are checked as text.
    obj = meshio.read(out / "mesh.obj")
    assert np.array_equal(obj.points, vtu.points)
    records = [line.split() for line in (out / "mesh.obj").read_text().splitlines()
               if line.startswith("l ")]
    assert np.array_equal(np.array([[int(a), int(b)] for _, a, b in records]) - 1, lines)


def test_singular_points_are_flagged(tmp_path):
    # Viviani's curve: the unit sphere and a cylinder tangent to it at (1, 0, 0), where the curve
    # crosses itself; the mesh is joined at the located double point.
    problem = tmp_path / "viviani.toml"
    problem.write_text('name = "viviani"\nvariables = ["x", "y", "z"]\n'
                       'domain = [[-1.1, 1.1], [-1.1, 1.1], [-1.1, 1.1]]\n'
                       'equations = ["x^2 + y^2 + z^2 - 1", "(x - 0.5)^2 + y^2 - 0.25"]\n')
    out, summary = solve(tmp_path, problem, 5)
    located = summary["diagnostics"]["singular_points"]
    assert len(located) >= 1
    vtu = meshio.read(out / "mesh.vtu")
    flagged = np.flatnonzero(vtu.point_data["singular"] == 1)
    assert len(flagged) == len(located)
    # The flagged vertex is the one nearest to the located point.
    coordinates = np.stack([vtu.point_data[f"u{j}"] for j in range(3)], axis=1)
    gaps = np.abs(coordinates - np.array(located[0]["point"])).max(axis=1)
    assert gaps.argmin() in flagged and gaps.min() < 1e-3


def test_application_outputs(tmp_path):
    out, summary = solve(tmp_path, "convex-hull-sphere-cap.toml", 3, "--ascii")
    vtu = meshio.read(out / "mesh.vtu")
    assert vtu.points.shape[0] == summary["mesh"]["vertices"]
    assert "u0" in vtu.point_data and "x2" in vtu.point_data  # the second image (bitangent)
    # input.ply and ruled.ply carry a face property after the index list (`part`), which the
    # binary PLY reader of meshio 5.0 misreads (it takes binary rows as columns); ASCII reads.
    surfaces = meshio.read(out / "input.ply")
    assert cells_of(surfaces, "triangle").shape[0] == len(surfaces.cell_data["part"][0])
    assert meshio.read(out / "ruled.ply").points.shape[1] == 3
