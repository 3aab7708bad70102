#!/usr/bin/env bash
# bench/vs_reference.sh: lmc against the LMC paper's own implementation
# (Luan et al. 2020, a fork of Li et al.'s dpt) on its own scenes, at equal
# wall time, side by side in one run.
#
# usage: bench/vs_reference.sh [-s torus|veachdoor] [-t SECONDS] [-n RUNS]
#                              [-i "OURS ..."] [-m "MODES ..."] [-j THREADS]
#                              [-b BUILD_DIR] [-o OUT_DIR]
#
# For every seed 1 .. RUNS (default 3) it renders the scene with each
# reference mode in MODES (default "pssmlt lmc": the paper's PSSMLT-style
# mode, its h2mc.xml with h2mc and mala off, and its LMC mode, lmc.xml),
# as shipped and in the exact variant (chain resets compiled out), each
# for SECONDS (default 30) of wall time including loading and the direct
# pass (the reference takes a sample count: two calibration runs per mode
# set it, and each render's wall time corrects it for the next), then
# each of our integrators in OURS (default "mmlt pssmlt lmc"; an entry
# NAME:FLAG=VALUE:... adds --FLAG VALUE to the render) with --time
# SECONDS. It prints one table (written to
# OUT_DIR/table.md): wall time, relative MSE against each renderer's own
# converged image (mean over the runs, its standard error and each run's;
# trimmed: without the worst 0.1% of pixels),
# the mean ratio against it, mutations per second of the chains, the
# acceptance per kernel and b with its standard error where the renderer
# reports them; and writes OUT_DIR/grid.png, every render of the first
# seed side by side at one exposure, labelled.
#
# The scenes are ../shared/scenes/<scene>/ at the paper's benchmark sizes:
# the torus at 256x192, the Veach door at 320x180.
#
# Environment (the script skips cleanly without them):
#   LMC_REF_DPT        the reference's dpt as shipped: the wrapper bin/dpt-ref
#                      of ../shared/tools/build_reference_impl.sh
#   LMC_REF_DPT_EXACT  its exact variant (bin/dpt-ref-exact)
#   LMC_REF_RUNS       the reference's scene copies (default: the runs/ folder
#                      beside bin/, which the build script fills)
#   LMC_CONVERGED      our converged image of the scene (EXR at that size;
#                      default scenes/<scene>/reference.exr, see its README)
#   LMC_REF_CONVERGED  the reference's own converged image
#   LMC_GRID_EXPOSURE  the grid's exposure in stops (default 0, lmc convert --exposure)
# Without a converged image the relmse column of that renderer reads "-".
# Needs ImageMagick's montage for the grid (apt-get install imagemagick).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"

scene=torus secs=30 runs=3 ours="mmlt pssmlt lmc" modes="pssmlt lmc" threads=2
build=build out=bench-out/vs-reference
while getopts "s:t:n:i:m:j:b:o:h" opt; do
  case $opt in
    s) scene=$OPTARG ;;
    t) secs=$OPTARG ;;
    n) runs=$OPTARG ;;
    i) ours=$OPTARG ;;
    m) modes=$OPTARG ;;
    j) threads=$OPTARG ;;
    b) build=$OPTARG ;;
    o) out=$OPTARG ;;
    *) sed -n '2,42p' "$0"; exit 2 ;;
  esac
done
lmc=$root/$build/lmc
[ -x "$lmc" ] || { echo "vs_reference: $lmc not found (build first)" >&2; exit 2; }
sdir=$root/../shared/scenes/$scene
[ -d "$sdir" ] || { echo "vs_reference: $sdir not found; skipped" >&2; exit 0; }
case $scene in
  torus) res=256x192 ref_suffix=256 ;;
  veachdoor) res=320x180 ref_suffix=320 ;;
  *) echo "vs_reference: unknown scene $scene (torus or veachdoor)" >&2; exit 2 ;;
esac
have_ref=1
for v in LMC_REF_DPT LMC_REF_DPT_EXACT; do
  if [ -z "${!v:-}" ] || [ ! -x "${!v}" ]; then
    echo "vs_reference: $v is not set to the reference's dpt; its columns are skipped" >&2
    have_ref=0
  fi
done
runs_dir=${LMC_REF_RUNS:-}
if [ "$have_ref" = 1 ] && [ -z "$runs_dir" ]; then runs_dir=$(dirname "$LMC_REF_DPT")/../runs; fi
if [ "$have_ref" = 1 ] && [ ! -d "$runs_dir/$scene" ]; then
  echo "vs_reference: $runs_dir/$scene not found (the reference's scene copies); its columns are skipped" >&2
  have_ref=0
fi
mkdir -p "$out"
out=$(cd "$out" && pwd)
LMC_CONVERGED=${LMC_CONVERGED:-$root/scenes/$scene/reference.exr}
font=/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf

# The reference's scene copy of a mode with a sample count and a seed; its
# output lands beside it as <name>_timeuse_<t>s.exr (dpt works there).
ref_xml() { # mode spp seed name -> path of the XML
  local mode=$1 spp=$2 name=$4 src
  case $mode in
    pssmlt) src=$runs_dir/$scene/pssmlt_$ref_suffix.xml ;;
    lmc) src=$runs_dir/$scene/lmc_$ref_suffix.xml ;;
    h2mc) src=$runs_dir/$scene/h2mc_$ref_suffix.xml ;;
  esac
  [ -f "$src" ] || { echo "vs_reference: $src not found" >&2; return 1; }
  local dst=$runs_dir/$scene/bench_$name.xml
  sed -e "s|name=\"spp\" *value=\"[0-9]*\"|name=\"spp\" value=\"$spp\"|" \
      -e "/<film /,/<\/film>/s|<string name=\"filename\" value=\"[^\"]*\"/>|<string name=\"filename\" value=\"bench_$name\"/>|" \
      "$src" >"$dst"
  echo "$dst"
}

# Runs the reference: ref_run BIN mode spp seed name -> wall seconds; the
# image goes to $out/name.exr, the log to $out/name.log.
ref_run() {
  local bin=$1 mode=$2 spp=$3 seed=$4 name=$5 xml t0 t1
  xml=$(ref_xml "$mode" "$spp" "$seed" "$name") || return 1
  rm -f "$runs_dir/$scene"/bench_"$name"_timeuse_*.exr
  t0=$(date +%s.%N)
  # (dpt takes its seed from the command line: --seedoffset overrides the XML's)
  DPT_NUM_THREADS=$threads "$bin" --seedoffset $((seed * 1000)) "$xml" >"$out/$name.log" 2>&1 || return 1
  t1=$(date +%s.%N)
  mv "$runs_dir/$scene"/bench_"$name"_timeuse_*.exr "$out/$name.exr"
  rm -f "$xml"
  awk -v a="$t0" -v b="$t1" 'BEGIN { printf "%.2f", b - a }'
}

# Figures from a reference log: mcmc seconds, mutations, acceptance.
ref_figures() { # log -> "mutations/s|acceptance|b"
  local log=$1
  tr '\r' '\n' <"$log" | awk '
    /^Elapsed time:/ { e[++n] = substr($0, 14) }
    /^Mutations:/ { m = $2 }
    /^Acceptance:/ { acc = sprintf("large %.1f%%, small %.1f%%", 100 * $5, 100 * $7) }
    /^Average brightness:/ { b = substr($0, 20) }
    END { printf "%.3g|%s|%s", (n >= 3 && e[3] > 0) ? m / e[3] : 0, acc, b }'
}

# Calibration: the sample count that makes a mode's wall time secs. Two
# runs (4 spp, then the count predicted for half the time) fit wall time
# as a line in spp; after every render the count of that mode and variant
# is corrected by the wall time it took (the machine's speed drifts).
declare -A spp_of fixed_of
if [ "$have_ref" = 1 ]; then
  for mode in $modes; do
    w1=$(ref_run "$LMC_REF_DPT" "$mode" 4 0 "calib-$mode") || { echo "vs_reference: the reference failed (see $out/calib-$mode.log)" >&2; exit 1; }
    mc=$(tr '\r' '\n' <"$out/calib-$mode.log" | awk '/^Elapsed time:/ { e = substr($0, 14) } END { print e }')
    s2=$(awk -v w="$w1" -v m="$mc" -v t="$secs" 'BEGIN {
      s = 4 * (t / 2 - (w - m)) / m; if (s < 8) s = 8; printf "%d", s + 0.5 }')
    w2=$(ref_run "$LMC_REF_DPT" "$mode" "$s2" 0 "calib2-$mode") || { echo "vs_reference: the reference failed (see $out/calib2-$mode.log)" >&2; exit 1; }
    read -r spp fixed < <(awk -v w1="$w1" -v w2="$w2" -v s2="$s2" -v t="$secs" 'BEGIN {
      slope = (w2 - w1) / (s2 - 4); if (slope <= 0) slope = w2 / s2
      fixed = w1 - 4 * slope; s = (t - fixed) / slope; if (s < 1) s = 1
      printf "%d %.3f\n", s + 0.5, fixed }')
    for variant in shipped exact; do spp_of[$mode-$variant]=$spp; done
    fixed_of[$mode]=$fixed
    echo "vs_reference: $mode: calibration ${w1} s at 4 spp, ${w2} s at $s2 spp: $spp spp for ${secs} s" >&2
  done
fi
# The next count of a mode and variant after a render of spp that took w s.
recalibrate() { # mode variant spp w
  spp_of[$1-$2]=$(awk -v s="$3" -v w="$4" -v f="${fixed_of[$1]}" -v t="$secs" 'BEGIN {
    if (w - f > 0 && t - f > 0) s = s * (t - f) / (w - f); if (s < 1) s = 1; printf "%d", s + 0.5 }')
}

# The renders.
declare -A rel trim walls rate acc bval ratio
rows=()
# Records lmc compare's figures of one render of row key against a converged image.
add_cmp() { # key image converged
  local cmp
  cmp=$("$lmc" compare "$2" "$3")
  rel[$1]="${rel[$1]:-}${rel[$1]:+ }$(sed -n 's/^relmse: //p' <<<"$cmp")"
  trim[$1]="${trim[$1]:-}${trim[$1]:+ }$(sed -n 's/^relmse_trimmed: //p' <<<"$cmp")"
  ratio[$1]="${ratio[$1]:-}${ratio[$1]:+ }$(sed -n 's/^mean_ratio: //p' <<<"$cmp")"
}
for seed in $(seq 1 "$runs"); do
  if [ "$have_ref" = 1 ]; then
    for mode in $modes; do
      for variant in shipped exact; do
        bin=$LMC_REF_DPT
        [ $variant = exact ] && bin=$LMC_REF_DPT_EXACT
        key="reference $mode ($variant)"
        name="ref-$mode-$variant-s$seed"
        echo "  $key, seed $seed ..." >&2
        spp=${spp_of[$mode-$variant]}
        w=$(ref_run "$bin" "$mode" "$spp" "$seed" "$name") || { echo "vs_reference: $key failed (see $out/$name.log)" >&2; continue; }
        recalibrate "$mode" "$variant" "$spp" "$w"
        walls[$key]="${walls[$key]:-}${walls[$key]:+ }$w"
        IFS='|' read -r r a b <<<"$(ref_figures "$out/$name.log")"
        rate[$key]="${rate[$key]:-}${rate[$key]:+ }$r"
        acc[$key]=$a
        bval[$key]="$b"
        if [ -n "${LMC_REF_CONVERGED:-}" ] && [ -f "$LMC_REF_CONVERGED" ]; then
          add_cmp "$key" "$out/$name.exr" "$LMC_REF_CONVERGED"
        fi
        [[ " ${rows[*]} " == *" $key "* ]] || rows+=("$key")
      done
    done
  fi
  for entry in $ours; do
    name=${entry%%:*}
    flags=(--integrator "$name")
    rest=${entry#"$name"}
    IFS=':' read -r -a opts <<<"${rest#:}"
    for o in "${opts[@]}"; do
      [ -n "$o" ] && flags+=("--${o%%=*}" "${o#*=}")
    done
    key="lmc $entry"
    stem="lmc-${entry//[:=]/-}-s$seed"
    echo "  $key, seed $seed ..." >&2
    t0=$(date +%s.%N)
    "$lmc" render "$sdir/lmc.xml" "${flags[@]}" --resolution "$res" --time "$secs" \
      --threads "$threads" --seed "$seed" -o "$out/$stem.exr" >"$out/$stem.log" 2>&1 || {
      echo "vs_reference: $key failed (see $out/$stem.log)" >&2
      continue
    }
    t1=$(date +%s.%N)
    walls[$key]="${walls[$key]:-}${walls[$key]:+ }$(awk -v a="$t0" -v b="$t1" 'BEGIN { printf "%.2f", b - a }')"
    rate[$key]="${rate[$key]:-}${rate[$key]:+ }$(sed -n 's/.* \([0-9.e+]*\) mutations\/s.*/\1/p' "$out/$stem.log" | tail -1)"
    acc[$key]=$(sed -n 's/^lmc: \([a-z-]*\) *proposed [0-9]*, accepted [0-9]* (\([0-9.]*%\)).*/\1 \2/p' \
      "$out/$stem.log" | paste -sd, - | sed 's/,/, /g')
    bval[$key]=$(sed -n 's/.*; b = \([0-9.e+]*\) +- \([0-9.e+-]*\) (\([0-9.]*%\).*/\1 +- \3/p' "$out/$stem.log" | tail -1)
    if [ -n "${LMC_CONVERGED:-}" ] && [ -f "$LMC_CONVERGED" ]; then
      add_cmp "$key" "$out/$stem.exr" "$LMC_CONVERGED"
    fi
    [[ " ${rows[*]} " == *" $key "* ]] || rows+=("$key")
  done
done

# The table: means over the runs.
mean() { tr ' ' '\n' | awk 'NF { s += $1; n++ } END { if (n) printf "%.3g", s / n; else printf "-" }'; }
mean_se() { tr ' ' '\n' | awk 'NF { s += $1; s2 += $1 * $1; v[++n] = $1 }
  END { if (!n) { printf "-"; exit } m = s / n; line = sprintf("%.4g", m)
        if (n > 1) { se = sqrt((s2 - n * m * m) / (n - 1) / n); line = line sprintf(" +- %.2g (", se)
                     for (i = 1; i <= n; i++) line = line sprintf(i > 1 ? ", %.3g" : "%.3g", v[i]); line = line ")" }
        printf "%s", line }'; }
table=$out/table.md
{
  echo "$scene at $res, ${secs} s, $threads threads, $runs run(s); $(nproc) cores, load $(cut -d' ' -f1-3 /proc/loadavg); $(date -u +%Y-%m-%d)"
  echo
  echo "| renderer and mode | wall s | relmse (runs) | trimmed | mean ratio | mutations/s | acceptance | b |"
  echo "| --- | --- | --- | --- | --- | --- | --- | --- |"
  for k in "${rows[@]}"; do
    echo "| $k | $(mean <<<"${walls[$k]:-}") | $(mean_se <<<"${rel[$k]:-}") | $(mean <<<"${trim[$k]:-}") | $(mean <<<"${ratio[$k]:-}") | $(mean <<<"${rate[$k]:-}") | ${acc[$k]:--} | ${bval[$k]:--} |"
  done
  echo
  echo "relmse: each render against its own renderer's converged image; trimmed:"
  echo "the same without the worst 0.1% of pixels (lmc compare's relmse_trimmed)"
  echo "(lmc: ${LMC_CONVERGED:-none}; reference: ${LMC_REF_CONVERGED:-none})."
} >"$table"
cat "$table"

# The grid: the first seed's renders and the converged image, all at one
# exposure (LMC_GRID_EXPOSURE stops, default 0), labelled.
if command -v montage >/dev/null; then
  exposure=${LMC_GRID_EXPOSURE:-0}
  if [ -n "${LMC_CONVERGED:-}" ] && [ -f "$LMC_CONVERGED" ]; then
    "$lmc" convert "$LMC_CONVERGED" "$out/converged.png" --exposure "$exposure" >/dev/null
  fi
  tiles=()
  for f in "$out"/*-s1.exr; do
    [ -f "$f" ] || continue
    png=${f%.exr}.png
    "$lmc" convert "$f" "$png" --exposure "$exposure" >/dev/null
    label=$(basename "${f%-s1.exr}")
    tiles+=(-label "$label" "$png")
  done
  [ -f "$out/converged.png" ] && tiles+=(-label converged "$out/converged.png")
  fopt=()
  [ -f "$font" ] && fopt=(-font "$font")
  if [ ${#tiles[@]} -gt 0 ]; then
    montage "${fopt[@]}" -pointsize 11 "${tiles[@]}" -tile 4x -geometry +3+3 "$out/grid.png"
    echo "vs_reference: wrote $out/grid.png" >&2
  fi
else
  echo "vs_reference: montage not found; no grid (apt-get install imagemagick)" >&2
fi
