"""The package's front (ctest "python"): solve()'s signature and help, numpy and nameless dicts,
the R^3 image, the progress callback and bar, and `pip install .` into a fresh virtual environment
(docs/python.md, "Install").
"""

import inspect
import io
import json
import os
import pathlib
import pydoc
import subprocess
import sys
import warnings

import numpy as np
import pytest

import ndcontour

ROOT = pathlib.Path(os.environ.get("NDC_SOURCE_DIR", pathlib.Path(__file__).resolve().parents[3]))
BINARY = pathlib.Path(os.environ.get("NDC_BINARY", ROOT / "build" / "bin" / "ndcontour")).resolve()
PROBLEMS = ROOT / "experiments" / "problems"
SPHERE = {"variables": ["x", "y", "z"], "domain": [[-2, 2]] * 3,
          "equations": ["x^2 + y^2 + z^2 - 1"]}
STAGES = ["subdivision", "projection", "connection", "analysis"]


def test_the_signature_names_every_option_with_the_cli_defaults():
    signature = inspect.signature(ndcontour.solve)
    keywords = [p for p in signature.parameters.values() if p.kind is p.KEYWORD_ONLY]
    names = [p.name for p in keywords]
    assert names == ["depth", "max_depth", "tolerance", "bounding", "subdivision", "projection",
                     "classification", "connection", "scalar", "precision", "jitter",
                     "max_memory", "threads", "timeout", "progress"]
    # The defaults shown are the ones the pipeline uses (ndc::Settings).
    for name, value in ndcontour._core.defaults().items():
        assert signature.parameters[name].default == value, name
    assert all(p.annotation is not p.empty for p in keywords)
    assert signature.return_annotation in ("Result", ndcontour.Result)
    text = pydoc.render_doc(ndcontour.solve)
    for word in ["depth", "progress", "Returns", "InputError", "ExpectationWarning"]:
        assert word in text
    assert "vertices" in pydoc.render_doc(ndcontour.Result)
    assert ndcontour.Result.__module__ == "ndcontour"
    assert (pathlib.Path(ndcontour.__file__).parent / "py.typed").exists()
    assert (pathlib.Path(ndcontour.__file__).parent / "_core.pyi").exists()


def test_numpy_values_and_a_nameless_dict_give_the_plain_mesh():
    plain = ndcontour.solve(dict(SPHERE, name="sphere"), depth=3, progress=False)
    problem = {"variables": np.array(["x", "y", "z"]),
               "domain": np.array([[-2.0, 2.0]] * 3),
               "equations": ["x^2 + y^2 + z^2 - 1"],
               "expect": {"components": np.int64(1), "euler_characteristic": np.int32(2)}}
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a failed expectation would warn
        r = ndcontour.solve(problem, depth=np.int64(3), progress=False)
    assert r.summary["problem"] == "problem"
    assert np.array_equal(r.vertices, plain.vertices)
    assert r.summary["expect"]["components"]["ok"] is True
    assert r.variables == ["x", "y", "z"]


def test_the_image_is_the_ply_x_y_z_of_an_application(tmp_path):
    r = ndcontour.solve(PROBLEMS / "bisector-fig8a.toml", depth=4, progress=False)
    assert r.image.shape == (len(r.vertices), 3) and r.image.dtype == np.float64
    assert r.image2 is None
    assert not np.allclose(r.image, r.vertices[:, :3])  # the bisector in R^3, not (u, v, s)
    r.write(tmp_path, ascii=True)
    lines = (tmp_path / "mesh.ply").read_text().splitlines()
    start = lines.index("end_header") + 1
    ply = np.array([[float(t) for t in line.split()[:3]]
                    for line in lines[start:start + len(r.vertices)]])
    assert np.array_equal(ply, r.image)
    hull = ndcontour.solve(PROBLEMS / "convex-hull-sphere-cap.toml", depth=3, progress=False)
    assert hull.image2.shape == (len(hull.vertices), 3)
    # Without an application: the first three coordinates.
    torus = ndcontour.solve(PROBLEMS / "torus.toml", depth=3, progress=False)
    assert np.array_equal(torus.image, torus.vertices)


def test_progress_calls_end_every_stage_once_in_order():
    calls = []
    ndcontour.solve(PROBLEMS / "torus.toml", depth=5, progress=lambda s, f: calls.append((s, f)))
    assert all(isinstance(s, str) and 0.0 <= f <= 1.0 for s, f in calls)
    ended = [s for s, f in calls if f == 1.0]
    assert [s.split(",")[0] for s in ended if s.split(",")[0] in STAGES] == STAGES
    assert len(ended) == len(set(ended))


def test_a_progress_callable_that_raises_stops_the_run():
    def stop(stage, fraction):
        raise RuntimeError("stop at " + stage)

    with pytest.raises(RuntimeError, match="stop at"):
        ndcontour.solve(PROBLEMS / "torus.toml", depth=4, progress=stop)
    # The next solve runs normally.
    assert ndcontour.solve(PROBLEMS / "torus.toml", depth=3, progress=False).summary["mesh"][
        "components"] == 1


def test_the_bar_is_drawn_on_request_and_not_on_a_pipe(capsys):
    ndcontour.solve(SPHERE, depth=3, progress=True)
    err = capsys.readouterr().err
    for stage in STAGES:
        assert stage + " [" + "#" * 30 + "] 100%" in err
    ndcontour.solve(SPHERE, depth=3)  # standard error is not a terminal here
    assert capsys.readouterr().err == ""
    with pytest.raises(TypeError, match="progress must be callable"):
        ndcontour.solve(SPHERE, depth=3, progress="yes")


def _venv_python(tmp_path):
    """A fresh virtual environment that sees the system's numpy, or a skip where the system has
    no venv module (Debian python3-venv)."""
    try:
        import ensurepip  # noqa: F401
        import venv  # noqa: F401
    except ImportError:
        pytest.skip("python3-venv is not installed (scripts/setup.sh installs it)")
    env_dir = tmp_path / "venv"
    subprocess.run([sys.executable, "-m", "venv", "--system-site-packages", str(env_dir)],
                   check=True, capture_output=True)
    return env_dir / "bin" / "python"


def test_pip_install_into_a_fresh_venv_and_run_the_example(tmp_path):
    build = BINARY.parent.parent
    if not (build / "CMakeCache.txt").exists():
        pytest.skip("no CMake build folder above " + str(BINARY))
    python = _venv_python(tmp_path)
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PIP_CONFIG_FILE")}
    env["PIP_NO_INPUT"] = "1"
    # --no-index: nothing from the network; build-dir: this test's build, which is current.
    install = subprocess.run(
        [str(python), "-m", "pip", "install", "--no-index", "--config-settings",
         "build-dir=" + str(build), str(ROOT)],
        capture_output=True, text=True, env=env, cwd=tmp_path, timeout=900)
    assert install.returncode == 0, install.stdout + install.stderr
    probe = ("import inspect, json, ndcontour; r = ndcontour.solve(%r, depth=3); "
             "print(json.dumps([ndcontour.__file__, ndcontour.__version__, "
             "list(inspect.signature(ndcontour.solve).parameters), r.summary['mesh']]))"
             % str(PROBLEMS / "torus.toml"))
    run = subprocess.run([str(python), "-c", probe], capture_output=True, text=True, env=env,
                         cwd=tmp_path, check=True)
    where, version, parameters, mesh = json.loads(run.stdout)
    assert pathlib.Path(where).is_relative_to(tmp_path / "venv")
    assert version == ndcontour.__version__
    assert "progress" in parameters and "threads" in parameters
    assert mesh["components"] == 1 and mesh["euler_characteristic"] == 0
    example = subprocess.run([str(python), str(ROOT / "examples" / "python_solve.py"),
                              str(tmp_path / "out")], capture_output=True, text=True, env=env,
                             cwd=tmp_path, timeout=600)
    assert example.returncode == 0, example.stdout + example.stderr
    assert (tmp_path / "out").is_dir()
