#!/usr/bin/env bash
# bench/fused.sh: equal-time figures of the fused chain (mmlt with
# --path-mutations) against its parts, mmlt and path-space mlt.
#
# usage: bench/fused.sh [-t SECONDS] [-n RUNS] [-b BUILD_DIR] [-o OUT_DIR]
#                       [-c "NAME=FLAGS;NAME=FLAGS..."]
#
# Renders the Veach door (../shared/scenes/veachdoor/h2mc.xml at 320x180,
# skipped when absent) and scenes/ring-caustics-glass with every
# configuration RUNS times (seeds 1 .. RUNS, default 2) for SECONDS
# (default 60), the configurations alternating within each seed, and
# compares each image with the scene's reference.exr (lmc compare).
# Prints, per scene and configuration, the mean relmse over the runs with
# each run's, the mean trimmed relmse (the worst 0.1% of pixels dropped)
# and mutations per second; the images (EXR and PNG) and logs stay in
# OUT_DIR (default a fresh temporary directory). Default configurations:
#   mmlt=--integrator mmlt
#   fused=--integrator mmlt --path-mutations 0.5
#   mlt=--integrator mlt
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
secs=60 runs=2 build="$root/build" out="" confs=""
while getopts "t:n:b:o:c:" o; do
  case $o in
    t) secs=$OPTARG ;;
    n) runs=$OPTARG ;;
    b) build=$OPTARG ;;
    o) out=$OPTARG ;;
    c) confs=$OPTARG ;;
    *) sed -n 2,20p "$0" >&2; exit 2 ;;
  esac
done
[ -n "$confs" ] || confs="mmlt=--integrator mmlt;fused=--integrator mmlt --path-mutations 0.5;mlt=--integrator mlt"
[ -n "$out" ] || out=$(mktemp -d /tmp/lmc-fused.XXXXXX)
mkdir -p "$out"
lmc="$build/lmc"
[ -x "$lmc" ] || { echo "bench/fused.sh: no lmc binary in $build (-b)" >&2; exit 2; }
scenes=()
door="$root/../shared/scenes/veachdoor/h2mc.xml"
[ -f "$door" ] && scenes+=("door|$door|$root/scenes/veachdoor/reference.exr|--resolution 320x180")
[ -f "$door" ] || echo "bench/fused.sh: $door absent: the door is skipped" >&2
scenes+=("ring-glass|$root/scenes/ring-caustics-glass/scene.xml|$root/scenes/ring-caustics-glass/reference.exr|")
IFS=';' read -r -a conf <<<"$confs"
for sc in "${scenes[@]}"; do
  IFS='|' read -r name xml ref sflags <<<"$sc"
  for s in $(seq 1 "$runs"); do
    for c in "${conf[@]}"; do
      cn=${c%%=*} flags=${c#*=}
      base="$out/$name-$cn-s$s"
      # shellcheck disable=SC2086
      timeout $((secs * 3 + 120)) nice "$lmc" render "$xml" $sflags $flags --time "$secs" --seed "$s" \
        -o "$base.exr" >"$base.log" 2>&1 || echo "bench/fused.sh: $base failed" >&2
      "$lmc" compare "$base.exr" "$ref" >"$base.cmp" 2>&1 || true
    done
  done
done
printf '| scene | configuration | relmse (runs) | trimmed | mutations/s |\n| --- | --- | --- | --- | --- |\n'
for sc in "${scenes[@]}"; do
  IFS='|' read -r name xml ref <<<"$sc"
  for c in "${conf[@]}"; do
    cn=${c%%=*}
    python3 - "$out" "$name" "$cn" "$runs" <<'PY'
import re, sys
out, name, cn, runs = sys.argv[1], sys.argv[2], sys.argv[3], int(sys.argv[4])
rel, trim, rate = [], [], []
for s in range(1, runs + 1):
    b = f"{out}/{name}-{cn}-s{s}"
    try:
        t = open(b + ".cmp").read()
        rel.append(float(re.search(r"\brelmse[ =:]+([0-9.eE+-]+)", t).group(1)))
        m = re.search(r"trimmed[^0-9]*([0-9.eE+-]+)", t)
        if m: trim.append(float(m.group(1)))
        m = re.findall(r"([0-9.]+e[+-]?[0-9]+|[0-9.]+) mutations/s", open(b + ".log").read())
        if m: rate.append(float(m[-1]))
    except (OSError, AttributeError):
        pass
mean = lambda v: sum(v) / len(v) if v else float("nan")
print(f"| {name} | {cn} | {mean(rel):.4f} ({', '.join(f'{r:.4f}' for r in rel)}) | "
      f"{mean(trim):.4f} | {mean(rate):.3g} |")
PY
  done
done
echo "images and logs: $out" >&2
