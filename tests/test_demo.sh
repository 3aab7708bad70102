#!/usr/bin/env bash
# tests/test_demo.sh BUILD_DIR: the demo of `bash scripts/setup.sh demo`,
# shortened (LMC_DEMO_SPP=8): it must write the LMC render, the path-traced
# render and the labelled side-by-side picture, and print both figures.
# Exit 77 (skipped) without ImageMagick's montage, which setup.sh installs.
set -euo pipefail
build=$1
command -v montage >/dev/null || { echo "test_demo: montage missing; skipped"; exit 77; }
command -v identify >/dev/null || { echo "test_demo: identify missing; skipped"; exit 77; }
out=$(mktemp -d /tmp/lmc_test_demo.XXXXXX)
trap 'rm -rf "$out"' EXIT
LMC_DEMO_SPP=8 bash "$(dirname "$0")/../scripts/demo.sh" "$build" "$out" >"$out/log.txt" 2>&1 || {
  cat "$out/log.txt"; echo "test_demo: the demo failed"; exit 1; }
checked=0
for f in ring-caustics-lmc.exr ring-caustics-lmc.png ring-caustics-pt.exr ring-caustics-pt.png \
         ring-caustics-side-by-side.png; do
  [ -s "$out/$f" ] || { echo "test_demo: $f not written"; exit 1; }
  grep -q "wrote $out/${f%%.*}" "$out/log.txt" || { echo "test_demo: the demo does not name $f"; exit 1; }
  checked=$((checked + 1))
done
# The renders are 320x240; the side-by-side picture holds both and labels.
read -r w h < <(identify -format '%w %h\n' "$out/ring-caustics-lmc.png")
[ "$w" = 320 ] && [ "$h" = 240 ] || { echo "test_demo: lmc preview is ${w}x$h"; exit 1; }
read -r w h < <(identify -format '%w %h\n' "$out/ring-caustics-side-by-side.png")
[ "$w" -ge 640 ] && [ "$h" -gt 240 ] || { echo "test_demo: side-by-side is ${w}x$h"; exit 1; }
# Both figures printed, as numbers.
for i in pt lmc; do
  grep -Eq "^  $i +[0-9.]+ s  relmse [0-9.e+-]+$" "$out/log.txt" || {
    cat "$out/log.txt"; echo "test_demo: no figure for $i"; exit 1; }
  checked=$((checked + 1))
done
[ "$checked" = 7 ] || { echo "test_demo: checked $checked of 7"; exit 1; }
echo "test_demo: 5 files and 2 figures checked"
