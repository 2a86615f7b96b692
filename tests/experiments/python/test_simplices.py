"""Result.simplices for every k (docs/python.md): an (M, k + 1) int64 array of vertex rows, for a
curve and a surface solved, and for a 3- and a 4-sphere given as arrays (tests/experiments/
sphere_mesh.py), whose mesh.ply (the plain-text format of any k with ascii=True,
docs/contracts.md 4.4) holds the same numbers; the formats that cannot hold a k-simplex are
refused with InputError (VTK for k >= 4, OBJ for k >= 3). When `solve` meshes a 3-manifold, the
3-sphere x^2 + y^2 + z^2 + w^2 = 0.5 is checked too."""

import os
import pathlib
import sys

import ndcontour
import numpy as np
import pytest

ROOT = pathlib.Path(os.environ.get("NDC_SOURCE_DIR", pathlib.Path(__file__).resolve().parents[3]))
sys.path.insert(0, str(ROOT / "tests" / "experiments"))
from sphere_mesh import kuhn_sphere  # noqa: E402 (after its folder is on the path)


def read_ascii_ply(path):
    """The documented text of mesh.ply: the header, one row `x y z u0 ..` per vertex, one row
    `k+1 i0 .. ik` per simplex (or `i0 i1` per edge)."""
    lines = path.read_text().splitlines()
    end = lines.index("end_header")
    header = lines[:end]
    assert header[:2] == ["ply", "format ascii 1.0"]
    counts = {w[1]: int(w[2]) for w in (line.split() for line in header) if w[0] == "element"}
    rows = lines[end + 1:]
    vertices = np.array([[float(x) for x in row.split()] for row in rows[:counts["vertex"]]])
    faces = [[int(x) for x in row.split()] for row in rows[counts["vertex"]:]]
    assert len(rows) == counts["vertex"] + counts.get("face", counts.get("edge", 0))
    return header, vertices, faces


@pytest.mark.parametrize("problem,depth,k", [("circle-r5.toml", 3, 1), ("sphere.toml", 3, 2)])
def test_solved_simplices(problem, depth, k):
    r = ndcontour.solve(str(ROOT / "experiments" / "problems" / problem), depth=depth)
    assert r.k == k and r.simplices.dtype == np.int64
    assert r.simplices.shape == (len(r.simplices), k + 1) and len(r.simplices) > 0
    assert 0 <= r.simplices.min() and r.simplices.max() < len(r.vertices)


@pytest.mark.parametrize("k", [3, 4])
def test_given_sphere(tmp_path, k):
    vertices, simplices = kuhn_sphere(k, g=2)
    names = ["a", "b", "c", "d", "e"][:k + 1]
    r = ndcontour._core._result_from_arrays(np.array(vertices), np.array(simplices), names)
    assert (r.n, r.k) == (k + 1, k)
    assert r.simplices.dtype == np.int64 and r.simplices.shape == (len(simplices), k + 1)
    assert np.array_equal(r.simplices, np.array(simplices))
    assert np.array_equal(r.vertices, np.array(vertices))
    # mesh.ply as text: a face of k + 1 indices per simplex, the vertex rows x y z u0 ...
    r.write(tmp_path / "text", ascii=True)
    header, rows, faces = read_ascii_ply(tmp_path / "text" / "mesh.ply")
    assert "property list uchar int vertex_indices" in header
    assert "comment variables " + " ".join(names) in header
    assert np.array_equal(rows[:, 3:], np.array(vertices))
    assert np.array_equal(rows[:, :3], np.array(vertices)[:, :3])
    assert faces == [[k + 1, *s] for s in simplices]
    # The binary mesh.ply: its size is the header plus the records (docs/contracts.md 4.4).
    r.write(tmp_path / "binary")
    data = (tmp_path / "binary" / "mesh.ply").read_bytes()
    head = data.index(b"end_header\n") + len(b"end_header\n")
    assert len(data) == head + 8 * len(vertices) * (3 + k + 1) + len(simplices) * (1 + 4 * (k + 1))
    # The formats without a cell for a k-simplex.
    with pytest.raises(ndcontour.InputError, match="OBJ has no cell for a %d-simplex" % k):
        r.write(tmp_path / "obj", obj=True)
    if k >= 4:
        for option in ("vtk", "vtk_legacy"):
            with pytest.raises(ndcontour.InputError, match="VTK has no cell for a 4-simplex"):
                r.write(tmp_path / option, **{option: True})
    else:
        assert str(tmp_path / "vtk" / "mesh.vtu") in r.write(tmp_path / "vtk", vtk=True)


def test_given_arrays_checked():
    with pytest.raises(ValueError, match="1 <= k < n"):
        ndcontour._core._result_from_arrays(np.zeros((4, 3)), np.zeros((1, 4), dtype=int))
    with pytest.raises(ValueError, match="out of range"):
        ndcontour._core._result_from_arrays(np.zeros((4, 4)), np.array([[0, 1, 2, 4]]))


def test_solved_three_sphere():
    problem = {"name": "s3", "variables": ["x", "y", "z", "w"], "domain": [[-1, 1]] * 4,
               "equations": ["x^2+y^2+z^2+w^2-0.5"]}
    try:
        r = ndcontour.solve(problem, depth=3)
    except ndcontour.InputError as e:
        pytest.skip(f"this build's solve does not mesh a 3-manifold: {e}")
    assert r.k == 3 and r.simplices.shape == (len(r.simplices), 4) and len(r.simplices) > 0
    assert np.abs(np.square(r.vertices).sum(axis=1) - 0.5).max() < 1e-6
