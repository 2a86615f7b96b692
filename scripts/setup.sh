#!/usr/bin/env bash
# Installs the Debian packages ndcontour needs, and nothing when they are all present; then the
# npm packages of the viewer page (experiments/view/web: three.js, pinned in its package-lock.json)
# with `npm ci`, skipped when node_modules already holds exactly the locked versions. ParaView
# (paraview, python3-paraview: pvpython) is for the test that opens mesh.vtu in ParaView.
# Usage: scripts/setup.sh [--tex] [--bench] [--slurm]
#   --tex    also installs TeX for the `paper` target
#   --bench  also installs CGAL, GUDHI, numpy and scipy for the peer benchmark in bench/ (bench/run.sh)
#   --slurm  also installs Slurm and MUNGE for `ndcontour experiment --executor slurm` and its test
#            (a single-node cluster on localhost: scripts/slurm-cluster.sh)
set -euo pipefail

packages=(
  build-essential cmake pkg-config
  libeigen3-dev libboost-dev libmpfr-dev libmpfi-dev libgmp-dev libtbb-dev
  catch2 doxygen gnuplot-nox libtomlplusplus-dev libcli11-dev libbenchmark-dev
  clang libclang-rt-14-dev
  python3 python3-dev pybind11-dev python3-numpy python3-pytest python3-meshio python3-scipy python3-skimage python3-venv
  zlib1g-dev
  chromium
  paraview python3-paraview
)
# node and npm for `npm ci` below, from Debian only where the machine has no npm.
if ! command -v npm >/dev/null 2>&1; then
  packages+=(nodejs npm)
fi
for arg in "$@"; do
  case "$arg" in
    --tex) packages+=(texlive-latex-base texlive-latex-recommended texlive-latex-extra) ;;
    --bench) packages+=(libcgal-dev libgudhi-dev libtbb-dev python3 python3-numpy python3-scipy) ;;
    --slurm) packages+=(slurm-wlm munge) ;;
    *)
      echo "setup: unknown option '$arg' (usage: scripts/setup.sh [--tex] [--bench] [--slurm])" >&2
      exit 2
      ;;
  esac
done

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

install_debian() {
  echo "setup: installing ${missing[*]}" >&2
  sudo_cmd=()
  if [[ $(id -u) -ne 0 ]]; then
    if command -v sudo >/dev/null 2>&1; then
      sudo_cmd=(sudo)
    else
      echo "setup: need root or sudo to install: ${missing[*]}" >&2
      exit 1
    fi
  fi
  export DEBIAN_FRONTEND=noninteractive
  "${sudo_cmd[@]}" apt-get update -qq
  "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
}
if [[ ${#missing[@]} -gt 0 ]]; then
  install_debian
fi

# The viewer's npm packages: `npm ci` only when node_modules lacks a locked version (so that a
# machine without network that has them already needs nothing).
web="$(cd "$(dirname "$0")/.." && pwd)/experiments/view/web"
locked_installed() {
  node -e '
    const fs = require("fs"), path = require("path"), dir = process.argv[1];
    const lock = JSON.parse(fs.readFileSync(path.join(dir, "package-lock.json"), "utf8"));
    for (const [where, p] of Object.entries(lock.packages || {})) {
      if (!where) continue;
      const file = path.join(dir, where, "package.json");
      if (!fs.existsSync(file) || JSON.parse(fs.readFileSync(file, "utf8")).version !== p.version)
        process.exit(1);
    }' "$web"
}
if ! locked_installed; then
  echo "setup: npm ci in experiments/view/web" >&2
  (cd "$web" && npm ci --no-audit --no-fund --loglevel=error)
fi
