#!/usr/bin/env bash
# One-command set-up for a fresh Debian 12 machine (see README.md):
#   ./setup.sh run    install what is missing, build, render the built-in Cornell box to
#                     out/cornell.png and print per-pass milliseconds
#   ./setup.sh test   install what is missing, build, run the whole test suite (ctest)
#   ./setup.sh build  install what is missing and build only
# Environment: BUILD_DIR (default build), JOBS (default: number of cores).
set -euo pipefail
cd "$(dirname "$0")"
mode="${1:-run}"
build_dir="${BUILD_DIR:-build}"
jobs="${JOBS:-$(nproc)}"

# Debian packages the engine, its tests and its benchmarks need.
packages=(
  build-essential cmake pkg-config
  pocl-opencl-icd ocl-icd-opencl-dev opencl-headers clinfo
  libglm-dev libtinygltf-dev libstb-dev nlohmann-json3-dev libcli11-dev
  libopenimageio-dev
  libgtest-dev libbenchmark-dev
  python3 python3-pip python3-numpy
)
# Only the tests need these: chromium renders the sweep report (tests/sweep_report_test.cpp), and a
# single-node Slurm runs a sharded sweep as a job array (tests/slurm_sweep_test.sh).
if [ "$mode" = test ]; then
  packages+=(chromium slurmctld slurmd slurm-client)
fi
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "setup: installing ${missing[*]}"
  sudo_cmd=()
  [ "$(id -u)" -ne 0 ] && sudo_cmd=(sudo)
  "${sudo_cmd[@]}" apt-get update -qq
  DEBIAN_FRONTEND=noninteractive "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

cmake -S . -B "$build_dir" -DCMAKE_BUILD_TYPE=Release > "$build_dir.configure.log" 2>&1 || { cat "$build_dir.configure.log"; exit 1; }
cmake --build "$build_dir" -j "$jobs"

case "$mode" in
  run)
    mkdir -p out
    "$build_dir/gi" render --out out/cornell.png --timings
    ;;
  test)
    cd "$build_dir"
    ctest --output-on-failure -j "$jobs" --timeout 900
    ;;
  build) ;;
  *) echo "usage: $0 run|test|build" >&2; exit 2 ;;
esac
