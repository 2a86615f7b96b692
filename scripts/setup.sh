#!/usr/bin/env bash
# Installs the Debian packages ndcontour needs, and nothing when they are all present.
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
  python3 python3-dev pybind11-dev python3-numpy python3-pytest python3-meshio
)
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
if [[ ${#missing[@]} -eq 0 ]]; then
  exit 0
fi

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
