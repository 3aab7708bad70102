#!/usr/bin/env bash
# scripts/add_reference_parts.sh SCENE_DIR SPP SEED SEED [SEED ...]
#
# Makes a scene's reference better by merging more bdpt renders ("parts")
# into it, weighted by inverse variance, and prints what that did:
#
#   1. renders one part per seed (bdpt, SPP samples per pixel, one thread
#      each, LMC_REF_JOBS of them side by side, default 2, at nice 15) into
#      LMC_REF_DIR (default build/refparts/SCENE), skipping parts that are
#      already there, so an interrupted run resumes;
#   2. a part's own relmse e_part: half the relmse between the parts of each
#      consecutive pair of seeds (independent renders of equal effort:
#      E[relmse(A, B)] ~ relmse(A) + relmse(B)), averaged over the pairs;
#   3. the reference's own relmse e_ref: the mean relmse of the parts against
#      it, less e_part (or LMC_REF_ERROR when set: the figure the last merge
#      printed, steadier than a measurement from a few parts; the measured
#      one is printed either way);
#   4. merges the reference (weight 1/e_ref) and the parts (1/e_part each)
#      with `lmc merge --weight` into SCENE_DIR/reference.exr (the previous
#      one is kept in LMC_REF_DIR), whose own relmse is then
#      1 / (1/e_ref + n/e_part); the relmse between the previous reference
#      and the new one should be e_ref - e_new.
#
# Needs an even number of seeds (pairs) that were never used for this
# scene's reference before, and build/lmc. Uses bash, awk and lmc only.
set -euo pipefail
cd "$(dirname "$0")/.."
usage="usage: add_reference_parts.sh SCENE_DIR SPP SEED SEED [SEED ...] (an even number of seeds)"
dir=${1:?$usage}
spp=${2:?$usage}
shift 2
seeds=("$@")
if [ ${#seeds[@]} -lt 2 ] || [ $((${#seeds[@]} % 2)) -ne 0 ]; then
  echo "$usage" >&2
  exit 2
fi
[ -f "$dir/scene.xml" ] || { echo "add_reference_parts: no $dir/scene.xml" >&2; exit 2; }
[ -f "$dir/reference.exr" ] || { echo "add_reference_parts: no $dir/reference.exr" >&2; exit 2; }
lmc=build/lmc
[ -x "$lmc" ] || { echo "add_reference_parts: build/lmc is missing (bash scripts/setup.sh demo)" >&2; exit 2; }
name=$(basename "$dir")
work=${LMC_REF_DIR:-build/refparts/$name}
jobs=${LMC_REF_JOBS:-2}
mkdir -p "$work"
# The parts are rendered by a copy of the binary, so a rebuild cannot change it mid-run.
cp "$lmc" "$work/lmc"

# 1. The parts, LMC_REF_JOBS at a time.
render_part() {
  local seed=$1
  [ -f "$work/part$seed.exr" ] && return 0
  local t0=$SECONDS
  nice -n 15 "$work/lmc" render "$dir/scene.xml" --integrator bdpt --spp "$spp" --seed "$seed" \
    --threads 1 -q -o "$work/tmp$seed.exr" > "$work/part$seed.log" 2>&1
  mv "$work/tmp$seed.exr" "$work/part$seed.exr"
  rm -f "$work/tmp$seed.png"
  echo "part $seed: $spp spp in $((SECONDS - t0)) s"
}
running=0
for s in "${seeds[@]}"; do
  render_part "$s" &
  running=$((running + 1))
  if [ "$running" -ge "$jobs" ]; then
    wait -n
    running=$((running - 1))
  fi
done
wait

relmse() { "$lmc" compare "$1" "$2" | sed -n 's/^relmse: //p'; }

# 2. A part's own error, from the pairs.
pairs=""
for ((i = 0; i < ${#seeds[@]}; i += 2)); do
  a=${seeds[i]} b=${seeds[i + 1]}
  pairs="$pairs $(relmse "$work/part$a.exr" "$work/part$b.exr")"
done
# 3. The reference's own error, from the parts against it.
against=""
for s in "${seeds[@]}"; do against="$against $(relmse "$work/part$s.exr" "$dir/reference.exr")"; done

read -r e_part e_ref <<< "$(awk -v p="$pairs" -v r="$against" 'BEGIN {
  np = split(p, P, " "); nr = split(r, R, " ");
  for (i = 1; i <= np; i++) sp += P[i]; for (i = 1; i <= nr; i++) sr += R[i];
  ep = sp / np / 2; printf "%.6g %.6g\n", ep, sr / nr - ep }')"
e_measured=$e_ref
e_ref=${LMC_REF_ERROR:-$e_ref}
if awk -v e="$e_ref" 'BEGIN { exit !(e <= 0) }'; then
  echo "add_reference_parts: the parts read no worse against the reference than against" >&2
  echo "each other (e_ref = $e_ref): too few parts to measure the reference; add more seeds" >&2
  exit 1
fi

# 4. The inverse-variance merge.
# The weights, the new reference's error, the reference's weight in parts
# and how far the reference should move (e_ref - e_new).
n=${#seeds[@]}
read -r w_ref w_part e_new worth expected <<< "$(awk -v er="$e_ref" -v ep="$e_part" -v n="$n" 'BEGIN {
  en = 1 / (1 / er + n / ep); printf "%.6g %.6g %.6g %.3g %.3g\n", 1 / er, 1 / ep, en, ep / er, er - en }')"
prev="$work/reference-before-${seeds[0]}.exr"
cp "$dir/reference.exr" "$prev"
args=(--weight "$w_ref" "$prev")
for s in "${seeds[@]}"; do args+=(--weight "$w_part" "$work/part$s.exr"); done
"$lmc" merge "${args[@]}" -o "$work/merged.exr" > /dev/null
cp "$work/merged.exr" "$dir/reference.exr"
moved=$(relmse "$prev" "$dir/reference.exr")

echo "$name: $n parts of $spp spp (seeds ${seeds[*]})"
echo "  relmse between the parts of each pair:${pairs}"
echo "  each part against the previous reference:${against}"
echo "  a part's own relmse e_part = $e_part"
echo "  the previous reference's own relmse, measured: $e_measured${LMC_REF_ERROR:+ (used: LMC_REF_ERROR = $LMC_REF_ERROR)}"
echo "  e_ref = $e_ref (weight 1/e_ref = $w_ref parts' worth: $worth)"
echo "  the new reference's own relmse = $e_new"
echo "  relmse between the previous reference and the new one: $moved ($expected expected)"
echo "  wrote $dir/reference.exr (the previous one: $prev)"
