#!/usr/bin/env bash
# bench/builds.sh: two builds of lmc on the same render, side by side.
#
# usage: bench/builds.sh -a LMC_A -b LMC_B [-n RUNS] [-t SECONDS] [-j THREADS]
#                        [-r REFERENCE.exr] [-o OUT_DIR] -- RENDER_ARGS ...
#
# For seeds 1 .. RUNS (default 3) it renders `lmc render RENDER_ARGS --time
# SECONDS --threads THREADS --seed S` (default 30 s, 2 threads) with build A,
# then with build B, so that the machine's load falls on both alike, and
# prints per run and per build (means over the runs): the chains' mutations
# per second (MCMC integrators; camera samples per second of the render's
# whole time for pt and bdpt), the peak resident memory (/usr/bin/time)
# and, with -r, the relative MSE and its trimmed form against REFERENCE
# (lmc compare, with build B). Each build's statistics lines of the last
# run are kept in OUT_DIR (default bench-out/builds) beside the images.
#
# Example (what H2MC's shared arenas changed on the Veach door):
#   bash bench/builds.sh -a /tmp/lmc-before -b build/lmc -t 10 -- \
#     ../shared/scenes/veachdoor/h2mc.xml --integrator h2mc --resolution 320x180
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
a="" b="" runs=3 secs=30 threads=2 ref="" out=$root/bench-out/builds
while getopts "a:b:n:t:j:r:o:h" opt; do
  case $opt in
    a) a=$OPTARG ;;
    b) b=$OPTARG ;;
    n) runs=$OPTARG ;;
    t) secs=$OPTARG ;;
    j) threads=$OPTARG ;;
    r) ref=$OPTARG ;;
    o) out=$OPTARG ;;
    *) sed -n '2,19p' "$0"; exit 2 ;;
  esac
done
shift $((OPTIND - 1))
if [ -z "$a" ] || [ -z "$b" ] || [ $# -eq 0 ]; then
  echo "builds: -a LMC_A, -b LMC_B and the render's arguments after -- are required" >&2
  exit 2
fi
for bin in "$a" "$b"; do
  [ -x "$bin" ] || { echo "builds: $bin is not an executable" >&2; exit 2; }
done
[ -z "$ref" ] || [ -f "$ref" ] || { echo "builds: -r $ref: no such file" >&2; exit 2; }
command -v /usr/bin/time >/dev/null || { echo "builds: needs /usr/bin/time (apt-get install time)" >&2; exit 2; }
mkdir -p "$out"

rows=$out/rows.txt
: > "$rows"
for ((s = 1; s <= runs; s++)); do
  for side in A B; do
    bin=$a
    [ $side = B ] && bin=$b
    img=$out/$side-s$s.exr log=$out/$side.log
    /usr/bin/time -f "peak %M" "$bin" render "$@" --time "$secs" --threads "$threads" \
      --seed "$s" -o "$img" > "$log" 2>&1 || { echo "builds: build $side failed, see $log" >&2; exit 1; }
    rate=$(grep -o '[0-9.e+]* mutations/s' "$log" | head -1 | cut -d' ' -f1 || true)
    if [ -z "$rate" ]; then
      # pt, bdpt: samples over the render's seconds.
      rate=$(sed -n 's/.*(\([0-9]*\) samples) in \([0-9.]*\) s.*/\1 \2/p' "$log" |
        awk '{ if ($2 > 0) printf "%.4g", $1 / $2 }')
    fi
    peak=$(grep -o 'peak [0-9]*' "$log" | cut -d' ' -f2 || true)
    rel=- trim=-
    if [ -n "$ref" ]; then
      cmp=$("$b" compare "$img" "$ref")
      rel=$(echo "$cmp" | awk '$1 == "relmse:" {print $2}')
      trim=$(echo "$cmp" | awk '$1 == "relmse_trimmed:" {print $2}')
    fi
    echo "$side $s ${rate:--} $peak $rel $trim" >> "$rows"
    printf '%s seed %d: %s per second, peak %s MB, relmse %s (trimmed %s)\n' \
      "$side" "$s" "${rate:--}" "$((peak / 1024))" "$rel" "$trim"
  done
done

echo
echo "| build | runs | rate /s | peak MB | relmse | trimmed |"
echo "| --- | --- | --- | --- | --- | --- |"
for side in A B; do
  bin=$a
  [ $side = B ] && bin=$b
  awk -v side=$side -v name="$bin" '
    $1 == side { n++; r += $3; p += $4; if ($5 != "-") { e += $5; t += $6; ne++ } }
    END {
      printf "| %s (%s) | %d | %.4g | %.0f | %s | %s |\n", side, name, n, r / n, p / n / 1024,
             ne ? sprintf("%.4g", e / ne) : "-", ne ? sprintf("%.4g", t / ne) : "-"
    }' "$rows"
done
awk '$1 == "A" { ra += $3; na++ } $1 == "B" { rb += $3; nb++ }
     END { if (ra > 0) printf "\nrate B / A: %.3f\n", (rb / nb) / (ra / na) }' "$rows"
