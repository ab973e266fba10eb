#!/usr/bin/env bash
# Measurements of `illume view` for BENCHMARKS.md: presentation overhead per redraw,
# input-to-photon latency of photon_stream, viewer fps against `animate --realtime`.
# Needs an X display (DISPLAY) and the viewer's dependencies
# (scripts/ci/install-viewer-deps.sh). Usage: scripts/bench-viewer.sh [ILLUME_BINARY]
set -euo pipefail
bin=${1:-target/release/illume}
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
echo "# $(date -u +%FT%TZ) $(uname -m) $(nproc) cores; load: $(uptime | sed 's/.*load/load/')"
echo "## presentation overhead (reference at 1 spp: the renderer idles; 300 redraws)"
for size in "800 600" "1280 1024"; do
    set -- $size
    "$bin" view builtin:cornell-spot --technique reference --spp 1 --width "$1" --height "$2" \
        --exit-after-frames 300 --log-input 2>&1 | grep summary | sed "s/^/$1x$2: /"
    echo "   load: $(uptime | sed 's/.*load/load/')"
done
echo "## viewer fps vs animate --realtime (photon_stream, 800x600, animation move, ping-pong)"
"$bin" animate builtin:cornell-spot --technique photon_stream --realtime --animation move \
    --ping-pong --duration 10 --width 800 --height 600 -o "$out/anim" 2>&1 | grep "frames per second"
echo "   load: $(uptime | sed 's/.*load/load/')"
"$bin" view builtin:cornell-spot --technique photon_stream --play --animation move \
    --width 800 --height 600 --duration 10 2>&1 | grep summary
echo "   load: $(uptime | sed 's/.*load/load/')"
echo "## input-to-photon latency (photon_stream, 800x600): click the sphere, then → five times"
log="$out/latency.log"
"$bin" view builtin:cornell-spot --technique photon_stream --width 800 --height 600 --log-input \
    2>"$log" &
pid=$!
sleep 8
id=$(xdotool search --pid "$pid" --name "illume view" | head -1)
xdotool windowfocus --sync "$id"
xdotool mousemove --window "$id" 250 420 click 1
sleep 1
for _ in 1 2 3 4 5; do
    xdotool key Right
    sleep 1.5
done
kill "$pid"
wait "$pid" 2>/dev/null || true
# For each → : the first frame whose commands include it (frames and ms later).
awk '
/input key ArrowRight/ { for (i = 1; i <= NF; i++) { if ($i ~ /^handled_unix_ms=/) { split($i, a, "="); t = a[2] } if ($i ~ /^sent=/) { split($i, b, "="); s = b[2] } } pending = 1; n = 0; next }
/ frame / && pending { n++; for (i = 1; i <= NF; i++) { if ($i ~ /^commands=/) { split($i, c, "="); k = c[2] } if ($i ~ /^shown_unix_ms=/) { split($i, d, "="); u = d[2] } }
  if (k + 0 >= s + 0) { printf "edit shown after %d frames, %.1f ms\n", n, u - t; pending = 0 } }
' "$log"
echo "   load: $(uptime | sed 's/.*load/load/')"
