#!/usr/bin/env bash
# bench/error_coverage.sh: how often --error's estimated standard error
# covers the true error, against a scene's converged image.
#
# usage: bench/error_coverage.sh [-s "SCENE ..."] [-i "INTEGRATOR ..."] [-p "SPP ..."]
#                                [-n SEEDS] [-j THREADS] [-b BUILD_DIR]
#
# For each scene of scenes/ (default "ring-caustics ring-caustics-glass",
# each with its reference.exr), integrator (default "pt bdpt pssmlt mmlt
# lmc mlt h2mc") and budget (default "16 128" samples or mutations per
# pixel; h2mc a quarter of it), renders SEEDS seeds (default 2) with
# --error on and prints `lmc compare`'s relmse and coverage (the share of
# values within one and two estimated standard errors of the reference;
# 0.68 and 0.95 for normal errors), then their means per setting.
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
scenes="ring-caustics ring-caustics-glass"
integrators="pt bdpt pssmlt mmlt lmc mlt h2mc"
budgets="16 128"
seeds=2
threads=2
build=$here/build
while getopts "s:i:p:n:j:b:" opt; do
  case $opt in
    s) scenes=$OPTARG ;;
    i) integrators=$OPTARG ;;
    p) budgets=$OPTARG ;;
    n) seeds=$OPTARG ;;
    j) threads=$OPTARG ;;
    b) build=$OPTARG ;;
    *) sed -n '2,15p' "$0"; exit 2 ;;
  esac
done
lmc=$build/lmc
[ -x "$lmc" ] || { echo "no $lmc (build first, or -b BUILD_DIR)" >&2; exit 2; }
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

printf "%-20s %-7s %5s %5s %10s %8s %8s\n" scene integrator spp seed relmse "1 se" "2 se"
for scene in $scenes; do
  ref=$here/scenes/$scene/reference.exr
  [ -f "$ref" ] || { echo "no $ref" >&2; exit 2; }
  for integ in $integrators; do
    for spp in $budgets; do
      [ "$integ" = h2mc ] && spp=$(( spp / 4 > 0 ? spp / 4 : 1 ))
      sums="0 0 0"
      for seed in $(seq "$seeds"); do
        "$lmc" render "$here/scenes/$scene/scene.xml" --integrator "$integ" --spp "$spp" \
          --seed "$seed" --threads "$threads" --error on -q -o "$tmp/out.exr" >/dev/null 2>&1
        line=$("$lmc" compare "$tmp/out.exr" "$ref" | awk '
          /^relmse:/ { r = $2 } /^coverage_1se:/ { c1 = $2 } /^coverage_2se:/ { c2 = $2 }
          END { print r, c1, c2 }')
        # shellcheck disable=SC2086
        printf "%-20s %-7s %5s %5s %10.4g %8.4f %8.4f\n" "$scene" "$integ" "$spp" "$seed" $line
        sums=$(echo "$sums $line" | awk '{ print $1 + $4, $2 + $5, $3 + $6 }')
      done
      echo "$sums" | awk -v s="$scene" -v i="$integ" -v p="$spp" -v n="$seeds" '{
        printf "%-20s %-7s %5s %5s %10.4g %8.4f %8.4f\n", s, i, p, "mean", $1 / n, $2 / n, $3 / n }'
    done
  done
done
