#!/usr/bin/env bash
# bench/mpi_scaling.sh: strong scaling over MPI ranks on one machine (issue
# 21), processes standing in for machines.
#
# usage: bench/mpi_scaling.sh [-s SCENE.xml] [-i "INTEGRATOR ..."] [-t SECONDS]
#                             [-n RUNS] [-b BUILD_DIR] [-o OUT_DIR]
#
# For every integrator (default: pt pssmlt mmlt lmc mlt) and run, three
# renders of SECONDS (default 20) each, one after the other so that the
# machine's noise falls on all three alike:
#   1x2  one process, 2 threads (no mpirun)
#   2x1  mpirun, 2 ranks of 1 thread
#   1x1  one process, 1 thread (the base)
# each with a snapshot every SECONDS/5. Prints per configuration the
# throughput (mutations per second of the chains for MCMC, camera samples
# per second for pt and bdpt; the mean over the runs), the ratio 2x1 / 1x2
# (the target: within 10% of 1) and 2x1 / 1x1, and the time each snapshot
# took to gather b, the counters and the splats of every rank (MCMC).
# The table goes to OUT_DIR/scaling.md too. Build with OpenMPI
# (BUILD_DIR/CMakeCache.txt with MPI found); default BUILD_DIR build.
set -euo pipefail
cd "$(dirname "$0")/.."
scene=scenes/ring-caustics/scene.xml
integrators="pt pssmlt mmlt lmc mlt"
seconds=20
runs=1
build=build
out=bench-out/mpi
while getopts "s:i:t:n:b:o:" opt; do
  case $opt in
    s) scene=$OPTARG ;;
    i) integrators=$OPTARG ;;
    t) seconds=$OPTARG ;;
    n) runs=$OPTARG ;;
    b) build=$OPTARG ;;
    o) out=$OPTARG ;;
    *) echo "usage: see the header of $0" >&2; exit 2 ;;
  esac
done
lmc=$build/lmc
[ -x "$lmc" ] || { echo "mpi_scaling: no $lmc (build first, or -b BUILD_DIR)" >&2; exit 2; }
mpirun=$(command -v mpirun || true)
[ -n "$mpirun" ] || { echo "mpi_scaling: no mpirun (apt-get install openmpi-bin libopenmpi-dev)" >&2; exit 2; }
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
export OMPI_MCA_btl_vader_single_copy_mechanism=none OMPI_MCA_rmaps_base_oversubscribe=1
mkdir -p "$out"
snap=$(awk -v t="$seconds" 'BEGIN { print t / 5 }')

# The throughput of a render's log: the chains' mutations/s, else samples/s.
rate() {
  local r
  r=$(sed -n 's/.* chains, \([0-9.e+]*\) mutations\/s.*/\1/p' "$1" | head -1)
  if [ -z "$r" ]; then
    r=$(sed -n 's/.*(\([0-9]*\) samples) in \([0-9.]*\) s.*/\1 \2/p' "$1" | head -1 |
      awk '{ if ($2 > 0) printf "%.6g", $1 / $2 }')
  fi
  echo "${r:-0}"
}
# Milliseconds per snapshot to gather (MCMC), or -.
snapms() {
  local m
  m=$(sed -n 's/.* snapshots, \([0-9.e+]*\) ms each.*/\1/p' "$1" | head -1)
  echo "${m:--}"
}

table="$out/scaling.md"
{
  echo "Strong scaling, $(basename "$(dirname "$scene")"), ${seconds} s per render, $runs run(s)"
  echo
  echo "| integrator | 1x2 /s | 2x1 /s | 1x1 /s | 2x1 / 1x2 | 2x1 / 1x1 | snapshot gather 1x2 ms | 2x1 ms |"
  echo "| --- | --- | --- | --- | --- | --- | --- | --- |"
} > "$table"
for i in $integrators; do
  a=0 b=0 c=0 sa=- sb=-
  for r in $(seq 1 "$runs"); do
    base="$out/$i-r$r"
    flags=(render "$scene" --integrator "$i" --time "$seconds" --snapshot "$snap" --seed "$((100 + r))")
    timeout -k 10 $((seconds * 3 + 60)) "$lmc" "${flags[@]}" --threads 2 -o "$base-1x2.exr" \
      > /dev/null 2> "$base-1x2.log"
    timeout -k 10 $((seconds * 3 + 60)) "$mpirun" --bind-to none -n 2 "$lmc" "${flags[@]}" \
      --threads 1 -o "$base-2x1.exr" > /dev/null 2> "$base-2x1.log"
    timeout -k 10 $((seconds * 3 + 60)) "$lmc" "${flags[@]}" --threads 1 -o "$base-1x1.exr" \
      > /dev/null 2> "$base-1x1.log"
    a=$(awk -v s="$a" -v v="$(rate "$base-1x2.log")" -v n="$runs" 'BEGIN { print s + v / n }')
    b=$(awk -v s="$b" -v v="$(rate "$base-2x1.log")" -v n="$runs" 'BEGIN { print s + v / n }')
    c=$(awk -v s="$c" -v v="$(rate "$base-1x1.log")" -v n="$runs" 'BEGIN { print s + v / n }')
    sa=$(snapms "$base-1x2.log") sb=$(snapms "$base-2x1.log")
    rm -f "$out"/*-[0-9]*.[0-9]s.exr
  done
  awk -v i="$i" -v a="$a" -v b="$b" -v c="$c" -v sa="$sa" -v sb="$sb" 'BEGIN {
    ra = 0; rc = 0
    if (a > 0) ra = b / a
    if (c > 0) rc = b / c
    printf "| %s | %.4g | %.4g | %.4g | %.3f | %.3f | %s | %s |\n", i, a, b, c, ra, rc, sa, sb
  }' >> "$table"
done
cat "$table"
