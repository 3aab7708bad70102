#!/usr/bin/env bash
# bench/tev_overhead.sh: what --display-server costs a render.
#
# usage: bench/tev_overhead.sh [-s SCENE.xml] [-i "INTEGRATOR ..."] [-t SECONDS]
#                              [-n RUNS] [-d INTERVAL] [-j THREADS] [-b BUILD_DIR]
#                              [-f "FLAGS"] [-w "FLAGS"]
#
# Renders the scene (default scenes/cornell-box/scene.xml) at 320x240 with
# each integrator (default "pt pssmlt") for SECONDS (default 10) each,
# RUNS times (default 3) without and with a viewer, alternating, and
# prints the samples (pt, bdpt) or mutations (MCMC) per second of each and
# the relative cost: 1 - rate with / rate without; the same per second of
# the process's CPU time (user + system, the sender thread's included),
# which the other loads of a shared machine disturb less than the wall
# clock. The viewer is a sink that reads and drops every byte (python3), as
# fast as tev would take them; --display-interval is INTERVAL (default 1,
# lmc's default). -f adds FLAGS to every render (-f "--error on": the
# viewer gets the error channels too); -w compares renders with FLAGS
# against renders without them, no viewer (-w "--error on": what the
# error itself costs).
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
scene=$here/scenes/cornell-box/scene.xml
integrators="pt pssmlt"
seconds=10
runs=3
interval=1
threads=2
build=$here/../build-tev
flags=""
with_flags=""
while getopts "s:i:t:n:d:j:b:f:w:" opt; do
  case $opt in
    s) scene=$OPTARG ;;
    i) integrators=$OPTARG ;;
    t) seconds=$OPTARG ;;
    n) runs=$OPTARG ;;
    d) interval=$OPTARG ;;
    j) threads=$OPTARG ;;
    b) build=$OPTARG ;;
    f) flags=$OPTARG ;;
    w) with_flags=$OPTARG ;;
    *) sed -n '2,21p' "$0"; exit 2 ;;
  esac
done
lmc=$build/lmc
[ -x "$lmc" ] || { echo "no $lmc (build first, or -b BUILD_DIR)" >&2; exit 2; }
tmp=$(mktemp -d)
sink_pid=
cleanup() { [ -n "$sink_pid" ] && kill "$sink_pid" 2>/dev/null; rm -rf "$tmp"; }
trap cleanup EXIT

# The sink: accepts any number of connections and reads them to the end;
# its port goes to $tmp/port.
python3 -c '
import socket, sys, threading
s = socket.socket()
s.bind(("127.0.0.1", 0))
s.listen(8)
open(sys.argv[1], "w").write(str(s.getsockname()[1]))
def drain(c):
    while c.recv(1 << 20):
        pass
    c.close()
while True:
    c, _ = s.accept()
    threading.Thread(target=drain, args=(c,), daemon=True).start()
' "$tmp/port" &
sink_pid=$!
for _ in $(seq 50); do [ -s "$tmp/port" ] && break; sleep 0.1; done
port=$(cat "$tmp/port")

# The rates of one render: samples (or mutations) over its seconds and
# over its CPU seconds, from its summary line and /usr/bin/time.
rate() {
  /usr/bin/time -f "cpu %U %S" -o "$tmp/cpu" "$lmc" render "$scene" --integrator "$1" \
    --time "$seconds" --threads "$threads" --resolution 320x240 -q -o "$tmp/out.exr" "${@:2}" \
    2>"$tmp/err" >/dev/null
  n=$(sed -n 's/.*spp (\([0-9]*\) samples) in \([0-9.]*\) s.*/\1 \2/p' "$tmp/err")
  c=$(sed -n 's/^cpu //p' "$tmp/cpu")
  echo "$n $c" | awk '{ printf "%.6g %.6g\n", $1 / $2, $1 / ($3 + $4) }'
}

printf "%-10s %12s %12s %8s %14s %14s %8s\n" integrator "per s" "with" cost "per CPU s" with cost
for integ in $integrators; do
  sums="0 0 0 0"
  for r in $(seq "$runs"); do
    # (FLAGS split into words on purpose)
    # shellcheck disable=SC2086
    a=$(rate "$integ" --seed "$r" $flags)
    if [ -n "$with_flags" ]; then
      # shellcheck disable=SC2086
      b=$(rate "$integ" --seed "$r" $flags $with_flags)
    else
      # shellcheck disable=SC2086
      b=$(rate "$integ" --seed "$r" $flags --display-server "127.0.0.1:$port" \
        --display-interval "$interval")
    fi
    sums=$(echo "$sums $a $b" | awk '{ print $1 + $5, $2 + $6, $3 + $7, $4 + $8 }')
  done
  echo "$sums" | awk -v i="$integ" -v n="$runs" '{
    printf "%-10s %12.4g %12.4g %7.2f%% %14.4g %14.4g %7.2f%%\n",
           i, $1 / n, $3 / n, 100 * (1 - $3 / $1), $2 / n, $4 / n, 100 * (1 - $4 / $2) }'
done
if [ -n "$with_flags" ]; then
  echo "(320x240, $seconds s a render, the mean of $runs run(s) each; with: $with_flags${flags:+; all: $flags})"
else
  echo "(320x240, $seconds s a render, the mean of $runs run(s) each, --display-interval $interval${flags:+; all: $flags})"
fi
