#!/usr/bin/env bash
# bench/equal_time.sh: the equal-time benchmark (issue 4).
#
# usage: bench/equal_time.sh [-s "SCENE_DIR ..."] [-i "INTEGRATOR ..."] [-t SECONDS]
#                            [-n RUNS] [-j THREADS] [-b BUILD_DIR] [-o OUT_DIR]
#
# Renders every scene with every integrator RUNS times (seeds 101 ..
# 100 + RUNS, default 1 run) for SECONDS (default 60) each with the same thread count
# (default: all cores), writing a snapshot every SECONDS/6 (--snapshot),
# compares each snapshot and the final image with the scene's
# reference.exr (lmc compare), and writes
#   OUT_DIR/table.md                 scene x integrator: relmse (mean over
#                                    the runs, with its standard error when
#                                    RUNS > 1, and each run's), relmse
#                                    without the worst 0.1% of pixels (mean),
#                                    mean ratio, samples or mutations per
#                                    second, acceptance (of the first run)
#                                    and, under it, each reference's own
#                                    estimated relmse (a floor under every
#                                    figure: relmse(I, R) ~ relmse(I) +
#                                    relmse(R) for independent I and R)
#   OUT_DIR/<scene>-convergence.png  log-log mean relmse against time (gnuplot)
#   OUT_DIR/<scene>/<integrator>-sN.* the renders, their logs and curves
# References are bdpt renders with seeds 1 and 2; the runs start at seed
# 101 so that no bdpt run replays the first samples of its own reference
# (with seed 1, a 60 s bdpt run is a prefix of the reference's first half
# and looks far better than it is).
# A short render's relmse is heavy-tailed (one firefly can outweigh the rest
# of the image), so compare integrators over several runs.
# Defaults: scenes/ring-caustics, scenes/ring-caustics-glass and, when
# ../shared/scenes/torus exists, the torus (it has no reference there: one
# is made with scripts/make_reference.sh's recipe into OUT_DIR/torus-ref
# when TORUS_REF_MINUTES is set and reused by later runs into the same
# OUT_DIR, else the torus is skipped with a message);
# integrators pt bdpt pssmlt mmlt, plus "lmc:none lmc:diminish lmc:cache"
# when the build accepts --integrator lmc. An entry NAME:ADAPT means
# --integrator NAME --adapt ADAPT.
# Extra render flags for every render (references included) come from the
# environment: LMC_BENCH_FLAGS="--resolution 256x192" renders the torus at
# the LMC paper's benchmark size.
# Needs BUILD_DIR/lmc (default build/) and gnuplot (gnuplot-nox).
set -euo pipefail
read -r -a extra <<<"${LMC_BENCH_FLAGS:-}"
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"

scenes="" integrators="" secs=60 runs=1 threads="" build=build out=bench-out
while getopts "s:i:t:n:j:b:o:h" opt; do
  case $opt in
    s) scenes=$OPTARG ;;
    i) integrators=$OPTARG ;;
    t) secs=$OPTARG ;;
    n) runs=$OPTARG ;;
    j) threads=$OPTARG ;;
    b) build=$OPTARG ;;
    o) out=$OPTARG ;;
    *) sed -n '2,31p' "$0"; exit 2 ;;
  esac
done
lmc=$build/lmc
[ -x "$lmc" ] || { echo "equal_time.sh: $lmc not found (build first)" >&2; exit 2; }
[ -n "$threads" ] || threads=$(nproc)
mkdir -p "$out"

if [ -z "$scenes" ]; then
  scenes="scenes/ring-caustics scenes/ring-caustics-glass"
  [ -d ../shared/scenes/torus ] && scenes="$scenes ../shared/scenes/torus"
fi
if [ -z "$integrators" ]; then
  integrators="pt bdpt pssmlt mmlt"
  if "$lmc" render scenes/ring-caustics/scene.xml --integrator lmc --spp 1 --resolution 16x12 \
       -q -o "$out/.probe.exr" >/dev/null 2>&1; then
    integrators="$integrators lmc:none lmc:diminish lmc:cache"
  fi
  rm -f "$out/.probe.exr" "$out/.probe.png"
fi
snap=$(awk -v t="$secs" 'BEGIN { s = t / 6; if (s < 1) s = 1; print s }')

echo "equal_time: T=${secs}s, $runs run(s) each, threads=$threads, snapshots every ${snap}s; load: $(cut -d' ' -f1-3 /proc/loadavg)"
table="$out/table.md"
{
  echo "| scene | integrator | relmse (runs) | relmse without worst 0.1% | mean ratio | samples or mutations / s | acceptance |"
  echo "| --- | --- | --- | --- | --- | --- | --- |"
} >"$table"

notes=()
for sdir in $scenes; do
  sname=$(basename "$sdir")
  ref="$sdir/reference.exr"
  if [ ! -f "$ref" ]; then
    if [ "$sname" = torus ] && [ -f "$out/torus-ref/reference.exr" ]; then
      ref="$out/torus-ref/reference.exr" # made by an earlier run into this OUT_DIR
    elif [ "$sname" = torus ] && [ -n "${TORUS_REF_MINUTES:-}" ]; then
      mkdir -p "$out/torus-ref"
      for seed in 1 2; do
        "$lmc" render "$sdir/lmc.xml" --integrator bdpt --time $((TORUS_REF_MINUTES * 60)) \
          --seed $seed "${extra[@]}" -q -o "$out/torus-ref/half$seed.exr" >/dev/null
      done
      "$lmc" merge "$out/torus-ref/half1.exr" "$out/torus-ref/half2.exr" -o "$out/torus-ref/reference.exr"
      ref="$out/torus-ref/reference.exr"
    else
      echo "equal_time: $sdir has no reference.exr; skipped (set TORUS_REF_MINUTES to make one for the torus)" >&2
      continue
    fi
  fi
  # The reference's own error: from its two halves when they are at hand
  # (relmse(half1, half2) / 4), else as its scene README records it.
  rdir=$(dirname "$ref")
  if [ -f "$rdir/half1.exr" ] && [ -f "$rdir/half2.exr" ]; then
    floor=$("$lmc" compare "$rdir/half1.exr" "$rdir/half2.exr" | sed -n 's/^relmse: //p' |
      awk '{ printf "%.3g", $1 / 4 }')
  else
    # (the last such row: a scene README adds one each time its reference grows)
    floor=$(sed -n 's/^| estimated relmse of the reference[^|]*| *\([0-9.e+-]*\) *|.*/\1/p' \
      "$sdir/README.md" 2>/dev/null | tail -n 1)
  fi
  notes+=("$sname: the reference's own relmse is about ${floor:-unknown} (every relmse above includes it)")
  # A scene folder holds scene.xml; the torus of the LMC reference
  # implementation holds lmc.xml instead.
  sfile="$sdir/scene.xml"
  [ -f "$sfile" ] || sfile="$sdir/lmc.xml"
  mkdir -p "$out/$sname"
  plot_lines=()
  for entry in $integrators; do
    name=${entry%%:*}
    label=${entry/:/-}
    flags=(--integrator "$name")
    [ "$entry" != "$name" ] && flags+=(--adapt "${entry#*:}")
    rels=() trims=() ratios=() dats=() rate="" acc=""
    for seed in $(seq 101 $((100 + runs))); do
      stem="$out/$sname/$label-s$seed"
      rm -f "$stem"-*s.exr
      echo "  $sname / $label / seed $seed ..." >&2
      "$lmc" render "$sfile" "${flags[@]}" "${extra[@]}" --time "$secs" --threads "$threads" \
        --seed "$seed" --snapshot "$snap" -o "$stem.exr" >"$stem.log" 2>&1 || {
        echo "equal_time: $label failed on $sname (see $stem.log)" >&2
        continue
      }
      # The convergence curve: seconds, relmse (snapshots, then the final image).
      : >"$stem.dat"
      for f in "$stem"-*s.exr; do
        [ -f "$f" ] || continue
        t=${f##*-}
        t=${t%s.exr}
        echo "$t $("$lmc" compare "$f" "$ref" | sed -n 's/^relmse: //p')" >>"$stem.dat"
      done
      cmp=$("$lmc" compare "$stem.exr" "$ref")
      rels+=("$(sed -n 's/^relmse: //p' <<<"$cmp")")
      trims+=("$(sed -n 's/^relmse_trimmed: //p' <<<"$cmp")")
      ratios+=("$(sed -n 's/^mean_ratio: //p' <<<"$cmp")")
      secs_used=$(sed -n 's/.* in \([0-9.]*\) s (load.*/\1/p' "$stem.log" | tail -1)
      echo "$secs_used ${rels[-1]}" >>"$stem.dat"
      sort -g -o "$stem.dat" "$stem.dat"
      dats+=("$stem.dat")
      [ -n "$rate" ] && continue
      # Throughput: mutations per second (MCMC) or camera samples per second.
      rate=$(sed -n 's/.* \([0-9.e+]*\) mutations\/s.*/\1 mutations/p' "$stem.log" | tail -1)
      if [ -z "$rate" ]; then
        rate=$(sed -n 's/.*spp (\([0-9]*\) samples) in \([0-9.]*\) s.*/\1 \2/p' "$stem.log" |
          awk '{ printf "%.3g samples", $1 / $2 }')
      fi
      acc=$(sed -n 's/^lmc: \([a-z-]*\) *proposed [0-9]*, accepted [0-9]* (\([0-9.]*%\)).*/\1 \2/p' \
        "$stem.log" | paste -sd, - | sed 's/,/, /g')
    done
    [ ${#rels[@]} -gt 0 ] || continue
    # Means over the runs (the relmse with its standard error and each run's).
    rel=$(printf '%s\n' "${rels[@]}" | awk '{ s += $1; s2 += $1 * $1; v[NR] = $1 }
      END { m = s / NR; line = sprintf("%.4g", m)
            if (NR > 1) { se = sqrt((s2 - NR * m * m) / (NR - 1) / NR); line = line sprintf(" +- %.2g (", se)
                          for (i = 1; i <= NR; i++) line = line sprintf(i > 1 ? ", %.3g" : "%.3g", v[i]); line = line ")" }
            print line }')
    trim=$(printf '%s\n' "${trims[@]}" | awk '{ s += $1 } END { printf "%.4g", s / NR }')
    ratio=$(printf '%s\n' "${ratios[@]}" | awk '{ s += $1 } END { printf "%.4f", s / NR }')
    echo "| $sname | $label | $rel | $trim | $ratio | $rate | ${acc:--} |" >>"$table"
    # The mean curve over the runs (the snapshots fall at the same seconds;
    # the final image's time differs by run, its mean is used).
    paste -d' ' "${dats[@]}" | awk '{ t = 0; r = 0; n = NF / 2
      for (i = 1; i <= NF; i += 2) { t += $i; r += $(i + 1) } print t / n, r / n }' >"$out/$sname/$label.dat"
    stem="$out/$sname/$label"
    plot_lines+=("'$stem.dat' using 1:2 with linespoints title '$label'")
  done
  if command -v gnuplot >/dev/null && [ ${#plot_lines[@]} -gt 0 ]; then
    joined=$(printf '%s, ' "${plot_lines[@]}")
    gnuplot <<EOF
set terminal pngcairo size 800,560 noenhanced
set output '$out/$sname-convergence.png'
set logscale xy
set xlabel 'seconds'
set ylabel 'relative MSE'
set title '$sname: relative MSE against time (${threads} threads)'
set key outside right
set grid
plot ${joined%, }
EOF
  elif ! command -v gnuplot >/dev/null; then
    echo "equal_time: gnuplot not found; no plot (apt-get install gnuplot-nox)" >&2
  fi
done
if [ ${#notes[@]} -gt 0 ]; then
  echo >>"$table"
  printf -- '- %s\n' "${notes[@]}" >>"$table"
fi
cat "$table"
