"""The Python module against ground truth and against the command line (ctest "python").

Run: PYTHONPATH=build/python python3 -m pytest -q tests/experiments/python  (ctest sets NDC_BINARY and
NDC_SOURCE_DIR; without them the paths default to build/bin/ndcontour and the checkout).
"""

import os
import pathlib
import subprocess
import threading
import time

import numpy as np
import pytest

import ndcontour

ROOT = pathlib.Path(os.environ.get("NDC_SOURCE_DIR", pathlib.Path(__file__).resolve().parents[3]))
BINARY = os.environ.get("NDC_BINARY", str(ROOT / "build" / "bin" / "ndcontour"))
PROBLEMS = ROOT / "experiments" / "problems"


def torus_residual(v, big=1.0, small=0.4):
    """|F| of the torus (x^2 + y^2 + z^2 + R^2 - r^2)^2 - 4 R^2 (x^2 + y^2) at the vertices."""
    x, y, z = v[:, 0], v[:, 1], v[:, 2]
    s = x * x + y * y + z * z + big * big - small * small
    return np.abs(s * s - 4 * big * big * (x * x + y * y))


def test_torus_from_a_path_matches_the_cli_and_lies_on_the_torus(tmp_path):
    r = ndcontour.solve(str(PROBLEMS / "torus.toml"), depth=4)
    assert r.n == 3 and r.k == 2
    assert r.vertices.shape[1] == 3 and r.vertices.dtype == np.float64
    assert r.simplices.shape[1] == 3 and r.simplices.dtype == np.int64
    assert r.simplices.min() >= 0 and r.simplices.max() < len(r.vertices)
    s = r.summary
    assert s["mesh"]["components"] == 1 and s["mesh"]["euler_characteristic"] == 0
    assert s["mesh"]["vertices"] == len(r.vertices)
    assert s["mesh"]["triangles"] == len(r.simplices)
    assert s["topology"]["certified"] is True
    assert torus_residual(r.vertices).max() < 1e-9
    # Consistently oriented: every directed edge of the closed surface is used once.
    assert s["mesh"]["orientable"] is True
    directed = np.concatenate([r.simplices[:, [0, 1]], r.simplices[:, [1, 2]],
                               r.simplices[:, [2, 0]]])
    assert len(np.unique(directed, axis=0)) == len(directed)
    # The same mesh as `ndcontour solve --json`.
    cli = subprocess.run([BINARY, "solve", str(PROBLEMS / "torus.toml"), "--depth", "4", "--json"],
                         capture_output=True, text=True, check=True)
    import json
    assert json.loads(cli.stdout)["mesh"] == s["mesh"]


def test_pathlike_toml_text_and_dict_give_the_same_sphere():
    path = PROBLEMS / "sphere.toml"
    text = path.read_text()
    problem = {
        "name": "sphere",
        "description": "The unit sphere S^2 in R^3.",
        "variables": ["x", "y", "z"],
        "domain": [[-1.2, 1.2], [-1.2, 1.2], [-1.2, 1.2]],
        "equations": ["x^2 + y^2 + z^2 - 1"],
        "expect": {"components": 1, "euler_characteristic": 2},
    }
    results = [ndcontour.solve(p, depth=4) for p in (path, text, problem)]
    for r in results:
        assert r.summary["mesh"]["euler_characteristic"] == 2
        expect = r.summary["expect"]
        assert expect["components"]["ok"] and expect["euler_characteristic"]["ok"]
        assert np.abs(np.linalg.norm(r.vertices, axis=1) - 1).max() < 1e-12
    assert all(np.array_equal(results[0].vertices, r.vertices) for r in results[1:])
    assert all(np.array_equal(results[0].simplices, r.simplices) for r in results[1:])


def test_a_curve_in_r4_is_a_closed_polyline():
    r = ndcontour.solve(PROBLEMS / "space-curve-r4.toml", depth=5)
    assert r.k == 1 and r.vertices.shape[1] == 4 and r.simplices.shape[1] == 2
    degree = np.bincount(r.simplices.ravel(), minlength=len(r.vertices))
    assert (degree == 2).all()  # closed: every vertex on two segments


@pytest.mark.parametrize("arguments,keywords", [
    (["--depth", "0"], {"depth": 0}),
    (["--bounding", "magic"], {"bounding": "magic"}),
    (["--scalar", "double", "--precision", "200"], {"scalar": "double", "precision": 200}),
    (["--tolerance", "-1"], {"tolerance": -1.0}),
])
def test_bad_settings_raise_the_cli_message(arguments, keywords):
    cli = subprocess.run([BINARY, "solve", str(PROBLEMS / "sphere.toml")] + arguments,
                         capture_output=True, text=True)
    assert cli.returncode == 2
    with pytest.raises(ndcontour.InputError) as error:
        ndcontour.solve(PROBLEMS / "sphere.toml", **keywords)
    assert str(error.value) == cli.stderr.strip()
    assert isinstance(error.value, ValueError)


def test_bad_problems_raise_the_cli_message(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text('name = "bad"\nvariables = ["x", "y"]\ndomain = [[0, 1], [0, 1]]\n'
                   'equations = ["x^2 + q"]\n')
    cli = subprocess.run([BINARY, "solve", str(bad)], capture_output=True, text=True)
    assert cli.returncode == 2
    with pytest.raises(ndcontour.InputError) as error:
        ndcontour.solve(str(bad))
    assert str(error.value) == cli.stderr.strip()
    with pytest.raises(ndcontour.InputError, match="no such file|cannot|not found|missing"):
        ndcontour.solve(str(tmp_path / "missing.toml"))
    with pytest.raises(ndcontour.InputError, match="not a TOML value"):
        ndcontour.solve({"name": "x", "variables": [object()]})
    with pytest.raises(TypeError, match="unexpected keyword argument 'detph'"):
        ndcontour.solve(PROBLEMS / "sphere.toml", detph=3)


def test_write_gives_the_files_of_solve_out(tmp_path):
    r = ndcontour.solve(PROBLEMS / "sphere.toml", depth=3)
    written = r.write(str(tmp_path / "run"), cells=True)
    names = sorted(os.path.basename(f) for f in written)
    assert "mesh.ply" in names and "summary.json" in names and "cells.csv" in names
    assert all(os.path.exists(f) for f in written)
    header = (tmp_path / "run" / "mesh.ply").read_bytes()[:200]
    assert header.startswith(b"ply\nformat binary_little_endian 1.0\n")
    r.write(str(tmp_path / "ascii"), ascii=True)
    assert (tmp_path / "ascii" / "mesh.ply").read_bytes().startswith(b"ply\nformat ascii 1.0\n")
    # The mesh files of every format are those of `solve --out` with the same flags.
    r.write(tmp_path / "all", vtk=True, vtk_legacy=True, obj=True)
    subprocess.run([BINARY, "solve", str(PROBLEMS / "sphere.toml"), "--depth", "3", "--out",
                    str(tmp_path / "cli"), "--vtk", "--vtk-legacy", "--obj"],
                   capture_output=True, check=True)
    for name in ["mesh.ply", "mesh.vtu", "mesh.vtk", "mesh.obj"]:
        assert (tmp_path / "all" / name).read_bytes() == (tmp_path / "cli" / name).read_bytes()


def test_the_gil_is_released_during_a_solve():
    ticks = []
    done = threading.Event()

    def ticker():
        while not done.is_set():
            ticks.append(time.perf_counter())
            time.sleep(0.005)

    thread = threading.Thread(target=ticker)
    start = time.perf_counter()
    thread.start()
    try:
        ndcontour.solve(PROBLEMS / "torus.toml", depth=6)
    finally:
        done.set()
        thread.join()
    elapsed = time.perf_counter() - start
    # The ticker ran all along: with the GIL held it would stop for the whole solve.
    assert elapsed > 0.1
    assert len(ticks) >= 0.5 * elapsed / 0.005 * 0.5
    gaps = np.diff(ticks)
    assert gaps.max() < max(0.05, elapsed / 4)


def test_mpfr_solve_from_python():
    r = ndcontour.solve(PROBLEMS / "circle.toml", depth=4, scalar="mpfr", precision=100)
    assert r.summary["settings"]["scalar"] == "mpfr"
    assert r.summary["mesh"]["components"] == 1
    # The precision the run used, as the CLI reports it for the same request.
    cli = subprocess.run([BINARY, "solve", str(PROBLEMS / "circle.toml"), "--depth", "4",
                          "--scalar", "mpfr", "--precision", "100", "--json"],
                         capture_output=True, text=True, check=True)
    import json
    assert r.summary["settings"] == json.loads(cli.stdout)["settings"]
    assert r.summary["settings"]["precision_bits"] >= 100


def test_threads_give_the_same_mesh_and_bad_counts_raise():
    one = ndcontour.solve(PROBLEMS / "clifford-torus.toml", depth=4, threads=1)
    two = ndcontour.solve(PROBLEMS / "clifford-torus.toml", depth=4, threads=2)
    assert np.array_equal(one.vertices, two.vertices)
    assert np.array_equal(one.simplices, two.simplices)
    assert one.summary["settings"]["threads"] == 1 and two.summary["settings"]["threads"] == 2
    for bad in (0, -1, 5000):
        with pytest.raises(ndcontour.InputError, match=r"--threads: .* is not an integer in 1\.\.4096"):
            ndcontour.solve(PROBLEMS / "sphere.toml", threads=bad)
    for bad in (1.5, "two", True):
        with pytest.raises(TypeError, match="threads must be an int"):
            ndcontour.solve(PROBLEMS / "sphere.toml", threads=bad)


# ---- Reliability (issue 40): types, paths, interrupts, timeouts, warnings ----------------------

OPTION_VALUES = {
    # option: (a right value, wrong-type values)
    "depth": (4, ["5", 4.0, True, [4]]),
    "max_depth": (6, ["6", 6.5, False]),
    "tolerance": (0.1, ["0.1", True, [0.1]]),
    "bounding": ("linearized", [1, 2.0, b"linearized"]),
    "subdivision": ("binary", [1, ["binary"]]),
    "projection": ("newton", [0, {"a": 1}]),
    "classification": ("paper", [1.5]),
    "connection": ("crossing", [True]),
    "scalar": ("double", [64]),
    "precision": (64, ["64", 64.0]),
    "jitter": (1, ["1", 1.0, True]),
    "max_memory": ("1G", [1.5, True, [1]]),
    "threads": (1, ["1", 1.0]),
    "timeout": (60, ["60", True]),
}


@pytest.mark.parametrize("option", sorted(OPTION_VALUES))
def test_every_option_of_the_wrong_type_raises_type_error_naming_it(option):
    right, wrong = OPTION_VALUES[option]
    for value in wrong:
        with pytest.raises(TypeError, match=option):
            ndcontour.solve(PROBLEMS / "circle.toml", **{option: value})
    # The right type works (a cheap solve).
    kwargs = {"depth": 3, option: right}
    if option == "max_depth":
        kwargs["depth"] = 4
    if option == "precision":
        kwargs["scalar"] = "mpfr"
    ndcontour.solve(PROBLEMS / "circle.toml", **kwargs)


def test_unknown_keyword_and_bad_values():
    with pytest.raises(TypeError, match="unexpected keyword argument 'detph'"):
        ndcontour.solve(PROBLEMS / "circle.toml", detph=4)
    with pytest.raises(ndcontour.InputError, match="depth"):
        ndcontour.solve(PROBLEMS / "circle.toml", depth=0)
    with pytest.raises(ndcontour.InputError, match="depth"):
        ndcontour.solve(PROBLEMS / "circle.toml", depth=2**40)
    with pytest.raises(ndcontour.InputError, match="timeout"):
        ndcontour.solve(PROBLEMS / "circle.toml", timeout=-1)


def test_write_takes_path_likes(tmp_path):
    r = ndcontour.solve(PROBLEMS / "circle.toml", depth=3)
    written = r.write(tmp_path / "as-path")
    assert all(pathlib.Path(f).exists() for f in written)
    with pytest.raises(TypeError, match="dir"):
        r.write(3)


def test_timeout_raises_timeout_error_promptly():
    start = time.perf_counter()
    with pytest.raises(TimeoutError, match="timeout"):
        ndcontour.solve(PROBLEMS / "torus.toml", depth=9, timeout=0.5)
    assert time.perf_counter() - start < 10
    # The next solve runs normally: the stop is cleared.
    assert ndcontour.solve(PROBLEMS / "circle.toml", depth=3).summary["mesh"]["components"] == 1


def test_ctrl_c_interrupts_a_solve_promptly():
    """SIGINT during a long solve raises KeyboardInterrupt within a second or so."""
    import signal
    timer = threading.Timer(0.5, lambda: signal.raise_signal(signal.SIGINT))
    start = time.perf_counter()
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            ndcontour.solve(PROBLEMS / "torus.toml", depth=9)
    finally:
        timer.cancel()
    assert time.perf_counter() - start < 10
    assert ndcontour.solve(PROBLEMS / "circle.toml", depth=3).summary["mesh"]["components"] == 1


def test_expect_mismatch_and_empty_zero_set_warn():
    wrong = {"name": "wrong", "variables": ["x", "y"], "domain": [[-2, 2], [-2, 2]],
             "equations": ["x^2 + y^2 - 1"], "expect": {"components": 2}}
    with pytest.warns(ndcontour.ExpectationWarning, match="expect components = 2, got 1"):
        ndcontour.solve(wrong, depth=4)
    right = dict(wrong, expect={"components": 1})
    import warnings
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        ndcontour.solve(right, depth=4)
    empty = {"name": "empty", "variables": ["x", "y", "z", "w"], "domain": [[-1, 1]] * 4,
             "equations": ["x*z - y*w - 5", "x - y"]}
    with pytest.warns(UserWarning, match="does not meet the domain"):
        r = ndcontour.solve(empty, depth=3)
    assert r.summary["diagnostics"]["empty_zero_set"] is True
    assert len(r.vertices) == 0 and r.summary["topology"]["certified"] is True


def test_bspline_outputs_share_the_knot_parameters(tmp_path):
    """Python's vertices, mesh.ply's u columns, cells.csv and uncertified.csv all use knot
    parameters (here [0, 1], knots 0 0.5 1), not span coordinates ([0, 2]), for B-spline
    variables."""
    import csv
    r = ndcontour.solve(PROBLEMS / "bisector-fig8c.toml", depth=3, max_depth=3)
    r.write(tmp_path, ascii=True, cells=True)
    lines = (tmp_path / "mesh.ply").read_text().splitlines()
    header = lines[:lines.index("end_header") + 1]
    names = [l.split()[-1] for l in header if l.startswith("property double")]
    count = int(next(l for l in header if l.startswith("element vertex")).split()[-1])
    rows = np.array([[float(x) for x in l.split()] for l in lines[len(header):len(header) + count]])
    u = rows[:, [names.index("u%d" % j) for j in range(r.n)]]
    assert np.allclose(u, r.vertices, rtol=0, atol=1e-12)
    assert r.vertices.min() >= -1e-9 and r.vertices.max() <= 1 + 1e-9
    assert r.vertices.max() > 0.75  # spread over the range, so span coordinates would show
    with open(tmp_path / "cells.csv") as f:
        for row in csv.DictReader(f):
            for j in range(r.n):
                assert -1e-9 <= float(row["c%d" % j]) <= 1 + 1e-9
                # A projected point may leave its cell (and the domain) a little.
                assert -0.25 <= float(row["p%d" % j]) <= 1.25
    if (tmp_path / "uncertified.csv").exists():
        with open(tmp_path / "uncertified.csv") as f:
            for row in csv.DictReader(f):
                for j in range(r.n):
                    assert -1e-9 <= float(row["lo%d" % j]) <= float(row["hi%d" % j]) <= 1 + 1e-9
