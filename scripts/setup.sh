#!/usr/bin/env bash
# scripts/setup.sh: the README's two commands.
#
#   bash scripts/setup.sh demo   install what is missing, build (Release), render
#                                scenes/ring-caustics with Langevin Monte Carlo and with
#                                path tracing at the same wall time (scripts/demo.sh),
#                                and print where the images are
#   bash scripts/setup.sh test   install what is missing, build, run the whole test
#                                suite (ctest), then the unit tests again under
#                                AddressSanitizer + UndefinedBehaviorSanitizer,
#                                then every libFuzzer target of tests/fuzz briefly
#                                on its corpus (clang build in build-fuzz/)
#
# Works on a fresh Debian 12 machine as root (or with sudo). Environment:
#   LMC_JOBS      parallel build jobs (default: the number of cores)
#   LMC_DEMO_SPP  mutations per pixel of the demo's LMC render (default 340, about a
#                 minute on 2 cores; the test suite's test_demo runs it with 8)
#   LMC_FUZZ_SECONDS  seconds per fuzz target in `test` (default 10; 0 skips fuzzing)
set -euo pipefail
cd "$(dirname "$0")/.."

mode=${1:-demo}
jobs=${LMC_JOBS:-$(nproc)}
packages=(build-essential cmake pkg-config libembree-dev libopenexr-dev libpng-dev
          libjpeg-dev zlib1g-dev libexpat1-dev libcmocka-dev liblapack-dev
          clang libclang-rt-dev libomp-dev   # libFuzzer (-fsanitize=fuzzer) and OpenMP for clang
          openmpi-bin libopenmpi-dev         # mpirun: one image over many processes or machines
          gnuplot-nox                        # plots of bench/equal_time.sh
          python3-dev python3-numpy python3-pytest  # the Python module lmc (src/python) and its tests
          imagemagick fonts-dejavu-core)     # the demo's side-by-side picture, benchmark grids

# Install the Debian packages that are missing.
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "setup: installing ${missing[*]}"
  sudo=""
  [ "$(id -u)" -eq 0 ] || sudo="sudo"
  $sudo apt-get update -q
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -q --no-install-recommends "${missing[@]}"
fi

# Build (Release, warnings are errors).
build() { # dir, extra cmake args...
  local dir=$1
  shift
  cmake -S . -B "$dir" -DCMAKE_BUILD_TYPE=Release -DLMC_WERROR=ON "$@" >/dev/null
  cmake --build "$dir" -j "$jobs"
}

case "$mode" in
  demo)
    build build
    bash scripts/demo.sh build out
    ;;
  test)
    build build
    ctest --test-dir build --output-on-failure -j "$jobs"
    build build-sanitize -DLMC_SANITIZE=ON
    ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 \
      ctest --test-dir build-sanitize --output-on-failure -j "$jobs" -L fast
    if [ "${LMC_FUZZ_SECONDS:-10}" -gt 0 ]; then
      # Only the fuzz targets: clang's warnings elsewhere are gcc's business.
      cmake -S . -B build-fuzz -DCMAKE_BUILD_TYPE=Release -DLMC_WERROR=ON \
        -DCMAKE_C_COMPILER=clang -DLMC_FUZZ=ON -DLMC_MPI=OFF -DBUILD_TESTING=OFF >/dev/null
      cmake --build build-fuzz -j "$jobs" --target fuzz_xml fuzz_obj fuzz_ply fuzz_serialized \
        fuzz_png fuzz_jpeg fuzz_exr
      bash scripts/fuzz.sh build-fuzz "${LMC_FUZZ_SECONDS:-10}"
    fi
    ;;
  *)
    echo "usage: bash scripts/setup.sh demo|test" >&2
    exit 2
    ;;
esac
