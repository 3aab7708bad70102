#!/usr/bin/env bash
# scripts/fuzz.sh: runs every libFuzzer target of tests/fuzz on its corpus.
#
#   bash scripts/fuzz.sh BUILD_DIR [SECONDS [TARGET...]]
#
# BUILD_DIR is a build configured with -DCMAKE_C_COMPILER=clang -DLMC_FUZZ=ON
# (scripts/setup.sh test makes build-fuzz/). Each target runs SECONDS
# (default 15) on a scratch copy of tests/fuzz/corpus/<target>, so the
# committed corpus is never changed; a crash, leak, timeout (10 s per input)
# or out-of-memory (2 GB) fails the script and leaves the input in
# fuzz-artifacts/<target>/. Add such an input to tests/fuzz/corpus/<target>/
# once it is fixed: it then replays in every ctest run.
set -euo pipefail
cd "$(dirname "$0")/.."

build=${1:?usage: bash scripts/fuzz.sh BUILD_DIR [SECONDS [TARGET...]]}
seconds=${2:-15}
shift $(( $# >= 2 ? 2 : 1 ))
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(xml obj ply serialized png jpeg exr)

scratch=$(mktemp -d)
trap 'rm -rf "$scratch"' EXIT
failed=()
for t in "${targets[@]}"; do
  bin="$build/tests/fuzz/fuzz_$t"
  [ -x "$bin" ] || { echo "fuzz: $bin is missing (configure with -DLMC_FUZZ=ON)" >&2; exit 2; }
  mkdir -p "$scratch/$t" "fuzz-artifacts/$t"
  cp tests/fuzz/corpus/"$t"/* "$scratch/$t/"
  echo "fuzz: $t for ${seconds}s"
  if "$bin" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 \
       -artifact_prefix="fuzz-artifacts/$t/" "$scratch/$t" >"$scratch/$t.log" 2>&1; then
    grep -E "^stat::number_of_executed_units|^stat::average_exec_per_sec" "$scratch/$t.log" |
      tr '\n' ' '
    echo
  else
    tail -n 60 "$scratch/$t.log"
    failed+=("$t")
  fi
done
if [ ${#failed[@]} -gt 0 ]; then
  echo "fuzz: FAILED: ${failed[*]} (inputs in fuzz-artifacts/)" >&2
  exit 1
fi
echo "fuzz: all ${#targets[@]} targets ran ${seconds}s without a finding"
