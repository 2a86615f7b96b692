"""The build backend of `pip install .` (PEP 517; pyproject.toml names it).

It needs nothing from the network and no Python package beyond the standard library: it runs
CMake (Debian cmake, pybind11-dev, python3-dev and the libraries scripts/setup.sh installs) to
build the extension `ndcontour._core` for the interpreter running pip, and zips the package
(experiments/python/ndcontour/ and the extension) into a wheel. docs/python.md, "Install".

Config settings (``pip install . --config-settings KEY=VALUE``):
    build-dir  the CMake build folder (default: build-python/ in the source tree, kept, so that
               a second install only rebuilds what changed). An existing build of this source,
               such as scripts/build.sh's build/, is reused when its Python is this one.
    jobs       parallel compile jobs (default: the machine's processors).
"""

from __future__ import annotations

import base64
import hashlib
import os
import pathlib
import re
import subprocess
import sys
import sysconfig
import zipfile

ROOT = pathlib.Path(__file__).resolve().parents[2]
PACKAGE = ROOT / "experiments" / "python" / "ndcontour"


def _version() -> str:
    """The project's version, from CMakeLists.txt's project() (the one place it is written)."""
    text = (ROOT / "CMakeLists.txt").read_text()
    found = re.search(r"project\(ndcontour\s+VERSION\s+([0-9.]+)", text)
    if not found:
        raise RuntimeError("ndcontour_build: no project(ndcontour VERSION ...) in CMakeLists.txt")
    return found.group(1)


def _metadata() -> str:
    """The wheel's METADATA (core metadata 2.1) from pyproject.toml's [project]."""
    import tomllib  # Python >= 3.11, as requires-python says

    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    lines = ["Metadata-Version: 2.1", "Name: " + project["name"], "Version: " + _version(),
             "Summary: " + project["description"],
             "Requires-Python: " + project["requires-python"]]
    lines += ["Requires-Dist: " + d for d in project.get("dependencies", [])]
    readme = (ROOT / "README.md").read_text()
    return "\n".join(lines) + "\nDescription-Content-Type: text/markdown\n\n" + readme


def _tag() -> str:
    """The wheel tag of this interpreter: cpXY-cpXY-PLATFORM."""
    python = "cp%d%d" % sys.version_info[:2]
    platform = sysconfig.get_platform().replace("-", "_").replace(".", "_")
    return "%s-%s-%s" % (python, python, platform)


def _cached(build: pathlib.Path, key: str) -> str | None:
    cache = build / "CMakeCache.txt"
    if not cache.exists():
        return None
    for line in cache.read_text(errors="replace").splitlines():
        if line.startswith(key + ":"):
            return line.split("=", 1)[1]
    return None


def _same_python(build: pathlib.Path) -> bool:
    """Whether `build` builds the extension for this interpreter (same version and ABI)."""
    cached = _cached(build, "Python_EXECUTABLE")
    if not cached:
        return False
    probe = [cached, "-c", "import sysconfig; print(sysconfig.get_config_var('EXT_SUFFIX'))"]
    try:
        suffix = subprocess.run(probe, capture_output=True, text=True, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return False
    return suffix == sysconfig.get_config_var("EXT_SUFFIX")


def _run(command: list[str]) -> None:
    print("ndcontour_build: " + " ".join(command), file=sys.stderr, flush=True)
    subprocess.run(command, check=True)


def _build_extension(settings: dict) -> pathlib.Path:
    """Configures (if needed) and builds the target ndcontour_python; returns the extension."""
    build = pathlib.Path(settings.get("build-dir") or ROOT / "build-python")
    if not build.is_absolute():
        build = ROOT / build
    if build.resolve() == ROOT:
        raise RuntimeError("ndcontour_build: build-dir is the source folder; CMake builds "
                           "out of the source tree (e.g. build-dir=build-python)")
    reuse = (build / "CMakeCache.txt").exists() and _same_python(build)
    if not reuse:
        # The interpreter running pip: a venv's python finds its base's headers by sysconfig.
        _run(["cmake", "-S", str(ROOT), "-B", str(build), "-DCMAKE_BUILD_TYPE=Release",
              "-DPython_EXECUTABLE=" + sys.executable])
    jobs = str(settings.get("jobs") or os.cpu_count() or 1)
    _run(["cmake", "--build", str(build), "--target", "ndcontour_python", "-j", jobs])
    found = sorted((build / "python" / "ndcontour").glob("_core*" + sysconfig.get_config_var(
        "EXT_SUFFIX")))
    if not found:
        raise RuntimeError("ndcontour_build: the build made no extension for this Python in "
                           + str(build / "python" / "ndcontour"))
    return found[0]


def _record_line(name: str, data: bytes) -> str:
    digest = base64.urlsafe_b64encode(hashlib.sha256(data).digest()).rstrip(b"=").decode()
    return "%s,sha256=%s,%d" % (name, digest, len(data))


def _dist_info() -> dict[str, bytes]:
    """The dist-info folder's METADATA and WHEEL, by archive name."""
    dist_info = "ndcontour-%s.dist-info" % _version()
    return {dist_info + "/METADATA": _metadata().encode(),
            dist_info + "/WHEEL": ("Wheel-Version: 1.0\nGenerator: ndcontour_build\n"
                                   "Root-Is-Purelib: false\nTag: %s\n" % _tag()).encode()}


def _write_wheel(directory: str, files: dict[str, bytes]) -> str:
    """Zips `files` (archive name -> bytes) with the dist-info into a wheel in `directory`."""
    dist_info = "ndcontour-%s.dist-info" % _version()
    files = dict(files)
    files.update(_dist_info())
    record = [_record_line(name, data) for name, data in files.items()]
    record.append(dist_info + "/RECORD,,")
    files[dist_info + "/RECORD"] = ("\n".join(record) + "\n").encode()
    name = "ndcontour-%s-%s.whl" % (_version(), _tag())
    with zipfile.ZipFile(os.path.join(directory, name), "w", zipfile.ZIP_DEFLATED) as wheel:
        for archive_name, data in files.items():
            info = zipfile.ZipInfo(archive_name, date_time=(2020, 1, 1, 0, 0, 0))
            info.external_attr = (0o755 if archive_name.endswith(".so") else 0o644) << 16
            info.compress_type = zipfile.ZIP_DEFLATED
            wheel.writestr(info, data)
    return name


# --- PEP 517 hooks ----------------------------------------------------------------------------

def get_requires_for_build_wheel(config_settings=None):
    return []


def prepare_metadata_for_build_wheel(metadata_directory, config_settings=None):
    # The metadata without building: pip asks for it before it builds.
    for name, data in _dist_info().items():
        path = pathlib.Path(metadata_directory) / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(data)
    return "ndcontour-%s.dist-info" % _version()


def build_wheel(wheel_directory, config_settings=None, metadata_directory=None):
    extension = _build_extension(config_settings or {})
    files = {"ndcontour/" + p.name: p.read_bytes() for p in sorted(PACKAGE.iterdir())
             if p.is_file() and p.suffix in (".py", ".pyi", ".typed")}
    files["ndcontour/" + extension.name] = extension.read_bytes()
    return _write_wheel(wheel_directory, files)
