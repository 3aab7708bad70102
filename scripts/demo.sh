#!/usr/bin/env bash
# scripts/demo.sh: the demo of `bash scripts/setup.sh demo`.
#
# usage: scripts/demo.sh [BUILD_DIR [OUT_DIR]]      (defaults: build, out)
#
# Renders scenes/ring-caustics with lmc's headline method, Langevin Monte
# Carlo (--integrator lmc, its default --adapt cache, which ties pssmlt as
# the best integrator on this scene at equal time; docs/benchmarks.md), for
# a fixed budget of LMC_DEMO_SPP mutations per pixel (default 340: about a
# minute on 2 cores), then path tracing for the same wall time, and writes
#   OUT_DIR/ring-caustics-lmc.exr, .png   the LMC render
#   OUT_DIR/ring-caustics-pt.exr, .png    path tracing, same wall time
#   OUT_DIR/ring-caustics-{lmc,pt}.log    their statistics
#   OUT_DIR/ring-caustics-side-by-side.png  both, labelled with integrator,
#                                         wall time and relative MSE against
#                                         the scene's reference
# Previews at exposure 0 (radiance as it is, clamped, sRGB): the scene is lit
# to show that way. Needs ImageMagick's montage for the side-by-side picture
# (setup.sh installs it). LMC_DEMO_SPP=8 makes a quick run (CI does that).
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
out=${2:-out}
lmc=$build/lmc
scene=scenes/ring-caustics
spp=${LMC_DEMO_SPP:-340}
[ -x "$lmc" ] || { echo "demo: $lmc not found (build first)" >&2; exit 2; }
command -v montage >/dev/null || { echo "demo: ImageMagick's montage is missing (apt-get install imagemagick)" >&2; exit 2; }
mkdir -p "$out"

# Wall time of a render in seconds (two decimals); its messages go to LOG.
timed() { # LOG command...
  local log=$1 t0 t1
  shift
  t0=$(date +%s.%N)
  "$@" >/dev/null 2>"$log" || { cat "$log" >&2; echo "demo: the render failed (log: $log)" >&2; exit 1; }
  t1=$(date +%s.%N)
  awk -v a="$t0" -v b="$t1" 'BEGIN { printf "%.2f", b - a }'
}
relmse() { "$lmc" compare "$1" "$scene/reference.exr" | sed -n 's/^relmse: //p'; }

echo "demo: Langevin Monte Carlo, $spp mutations per pixel ..."
t_lmc=$(timed "$out/ring-caustics-lmc.log" "$lmc" render "$scene/scene.xml" --integrator lmc \
  --spp "$spp" -o "$out/ring-caustics-lmc.exr")
echo "demo: path tracing for the same $t_lmc s ..."
t_pt=$(timed "$out/ring-caustics-pt.log" "$lmc" render "$scene/scene.xml" --integrator pt \
  --time "$t_lmc" -o "$out/ring-caustics-pt.exr")
r_lmc=$(relmse "$out/ring-caustics-lmc.exr")
r_pt=$(relmse "$out/ring-caustics-pt.exr")

font=()
dejavu=/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf
[ -f "$dejavu" ] && font=(-font "$dejavu")
montage "${font[@]}" -pointsize 14 -background white -geometry +4+4 \
  -label "path tracing (pt), ${t_pt} s, relmse $(printf '%.3g' "$r_pt")" "$out/ring-caustics-pt.png" \
  -label "Langevin MC (lmc), ${t_lmc} s, relmse $(printf '%.3g' "$r_lmc")" "$out/ring-caustics-lmc.png" \
  -tile 2x1 "$out/ring-caustics-side-by-side.png"

printf 'demo: ring-caustics, equal time, relative MSE against %s (previews at exposure 0):\n' "$scene/reference.exr"
printf '  pt   %6.2f s  relmse %s\n  lmc  %6.2f s  relmse %s\n' "$t_pt" "$r_pt" "$t_lmc" "$r_lmc"
echo "demo: wrote $out/ring-caustics-lmc.exr and .png (the LMC render)"
echo "demo: wrote $out/ring-caustics-pt.exr and .png (path tracing, same wall time)"
echo "demo: wrote $out/ring-caustics-side-by-side.png (both, labelled)"
