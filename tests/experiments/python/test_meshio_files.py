"""The mesh files as meshio (Debian python3-meshio 5.x) reads them (ctest "python";
docs/contracts.md 4.4): the binary, zlib-compressed mesh.vtu and the ASCII one of --ascii give
the same numbers; a curve is read from mesh.vtk (legacy VTK) as well as mesh.vtu; every file
carries the problem's variable names beside u0 ..; `solve` runs as a process. A 3-manifold's
tetrahedra (VTK_TETRA) are read from both VTK files, written from a mesh given as arrays."""

import json
import os
import pathlib
import subprocess
import sys

import meshio
import ndcontour
import numpy as np
import pytest

ROOT = pathlib.Path(os.environ.get("NDC_SOURCE_DIR", pathlib.Path(__file__).resolve().parents[3]))
BINARY = os.environ.get("NDC_BINARY", str(ROOT / "build" / "bin" / "ndcontour"))
PROBLEMS = ROOT / "experiments" / "problems"
sys.path.insert(0, str(ROOT / "tests" / "experiments"))
from sphere_mesh import kuhn_sphere  # noqa: E402 (after its folder is on the path)


def solve(out, problem, depth, *extra):
    subprocess.run([BINARY, "solve", str(PROBLEMS / problem), "--depth", str(depth), "--out",
                    str(out), "--vtk", "--vtk-legacy", "--obj", *extra], check=True,
                   capture_output=True)
    return json.loads((out / "summary.json").read_text())


def cells_of(mesh, kind):
    blocks = [c.data for c in mesh.cells if c.type == kind]
    return np.concatenate(blocks) if blocks else np.zeros((0, 0), dtype=int)


def check_arrays(mesh, summary, cells):
    """u0 .., the variables' names (the same values), singular; class and uncertified."""
    points = summary["mesh"]["vertices"]
    for j, name in enumerate(summary["variables"]):
        assert mesh.point_data[f"u{j}"].shape == (points,)
        assert np.array_equal(mesh.point_data[name], mesh.point_data[f"u{j}"])
    assert mesh.point_data["singular"].shape == (points,)
    for name in ("class", "uncertified"):
        assert np.concatenate(mesh.cell_data[name]).shape == (cells,)


def test_surface_files(tmp_path):
    summary = solve(tmp_path / "torus", "torus.toml", 4)
    out = tmp_path / "torus"
    assert summary["variables"] == ["x", "y", "z"]
    vertices, triangles = summary["mesh"]["vertices"], summary["mesh"]["triangles"]
    ply = meshio.read(out / "mesh.ply")
    for name in ("mesh.vtu", "mesh.vtk", "mesh.obj", "mesh.ply"):
        mesh = meshio.read(out / name)
        assert mesh.points.shape == (vertices, 3), name
        assert np.array_equal(mesh.points, ply.points), name
        assert np.array_equal(cells_of(mesh, "triangle"), cells_of(ply, "triangle")), name
        assert cells_of(mesh, "triangle").shape == (triangles, 3), name
    for name in ("mesh.vtu", "mesh.vtk"):
        check_arrays(meshio.read(out / name), summary, triangles)
    # The binary mesh.vtu is compressed; --ascii writes the same numbers as text.
    binary = (out / "mesh.vtu").read_text()
    assert 'compressor="vtkZLibDataCompressor"' in binary and 'format="binary"' in binary
    solve(tmp_path / "ascii", "torus.toml", 4, "--ascii")
    text = (tmp_path / "ascii" / "mesh.vtu").read_text()
    assert "compressor" not in text and 'format="binary"' not in text
    assert len(binary) < len(text) / 2
    a, b = meshio.read(out / "mesh.vtu"), meshio.read(tmp_path / "ascii" / "mesh.vtu")
    assert np.array_equal(a.points, b.points)
    assert np.array_equal(cells_of(a, "triangle"), cells_of(b, "triangle"))
    for name in a.point_data:
        assert np.array_equal(a.point_data[name], b.point_data[name]), name
    # mesh.ply names the variables in a comment; its properties stay u0 ...
    header = (out / "mesh.ply").read_bytes().split(b"end_header")[0].decode()
    assert "\ncomment variables x y z\n" in header
    assert set(ply.point_data) == {"u0", "u1", "u2"}


def test_curve_files(tmp_path):
    out = tmp_path / "circle"
    summary = solve(out, "circle-r5.toml", 3)
    vertices, edges = summary["mesh"]["vertices"], summary["mesh"]["edges"]
    vtu, vtk = meshio.read(out / "mesh.vtu"), meshio.read(out / "mesh.vtk")
    for mesh in (vtu, vtk):
        assert mesh.points.shape == (vertices, 3)
        assert cells_of(mesh, "line").shape == (edges, 2)
        check_arrays(mesh, summary, edges)
    assert np.array_equal(vtu.points, vtk.points)
    assert np.array_equal(cells_of(vtu, "line"), cells_of(vtk, "line"))
    for name in vtu.point_data:
        assert np.array_equal(vtu.point_data[name], vtk.point_data[name]), name
    # A closed curve: every vertex on two lines.
    assert (np.bincount(cells_of(vtk, "line").ravel(), minlength=vertices) == 2).all()
    # meshio's OBJ reader reads the vertices of a curve's mesh.obj but not its `l` records.
    assert meshio.read(out / "mesh.obj").points.shape == (vertices, 3)
    # The CSV headers: the contract's columns, then the names.
    header = (out / "singular.csv").read_text().splitlines()[0]
    assert header == "point,sigma_min,u0,u1,u2,u3,u4,x1,x2,x3,x4,x5"


def test_tetrahedra_files(tmp_path):
    """A 3-sphere in R^4 (Kuhn's triangulation of the 4-cube's boundary, tests/experiments/
    sphere_mesh.py) written by ndcontour's writers: meshio reads tetrahedra from the binary and
    the ASCII mesh.vtu and from mesh.vtk, the same as the arrays given; --obj is refused."""
    vertices, simplices = kuhn_sphere(3)
    result = ndcontour._core._result_from_arrays(np.array(vertices), np.array(simplices),
                                                 ["x", "y", "z", "w"], "s3")
    summary = {"variables": ["x", "y", "z", "w"], "mesh": {"vertices": len(vertices)}}
    for encoding, ascii in (("binary", False), ("ascii", True)):
        out = tmp_path / encoding
        result.write(out, ascii=ascii, vtk=True, vtk_legacy=True)
        for name in ("mesh.vtu", "mesh.vtk"):
            mesh = meshio.read(out / name)
            assert [c.type for c in mesh.cells] == ["tetra"], name
            assert np.array_equal(cells_of(mesh, "tetra"), np.array(simplices)), name
            assert np.array_equal(mesh.points, np.array(vertices)[:, :3]), name
            check_arrays(mesh, summary, len(simplices))
            assert np.array_equal(mesh.point_data["w"], np.array(vertices)[:, 3]), name
    with pytest.raises(ndcontour.InputError, match="OBJ has no cell for a 3-simplex"):
        result.write(tmp_path / "obj", obj=True)
