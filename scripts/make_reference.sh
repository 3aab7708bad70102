#!/usr/bin/env bash
# scripts/make_reference.sh SCENE_DIR MINUTES_PER_HALF
#
# Renders a scene's reference with bdpt: two independent halves (seeds 1
# and 2, MINUTES_PER_HALF each, all threads), averaged into
# SCENE_DIR/reference.exr. Prints:
#   - relmse(A, B): for independent renders of equal effort, E[relmse(A,B)]
#     ~ relmse(A) + relmse(B), so the reference's own relative MSE is about
#     relmse(A, B) / 4;
#   - the relmse of a 60-second bdpt render (seed 3) against the reference,
#     and the ratio of the two (the margin the issue asks to be >= 20).
# Needs build/lmc (bash scripts/setup.sh demo builds it).
set -euo pipefail
cd "$(dirname "$0")/.."
dir=${1:?usage: make_reference.sh SCENE_DIR MINUTES_PER_HALF}
minutes=${2:?usage: make_reference.sh SCENE_DIR MINUTES_PER_HALF}
secs=$((minutes * 60))
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
lmc=build/lmc

for seed in 1 2; do
  $lmc render "$dir/scene.xml" --integrator bdpt --time "$secs" --seed "$seed" -q -o "$tmp/half$seed.exr"
done
$lmc merge "$tmp/half1.exr" "$tmp/half2.exr" -o "$dir/reference.exr"
halves=$($lmc compare "$tmp/half1.exr" "$tmp/half2.exr" | sed -n 's/^relmse: //p')
$lmc render "$dir/scene.xml" --integrator bdpt --time 60 --seed 3 -q -o "$tmp/short.exr"
short=$($lmc compare "$tmp/short.exr" "$dir/reference.exr" | sed -n 's/^relmse: //p')
awk -v halves="$halves" -v short="$short" -v d="$dir" -v m="$minutes" 'BEGIN {
  ref = halves / 4.0
  printf "%s: bdpt, 2 x %s min; relmse(halves) %.6g; reference relmse ~ %.6g; 60 s bdpt relmse %.6g; margin %.1fx\n",
         d, m, halves, ref, short, short / ref
}'
