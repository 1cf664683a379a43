#!/usr/bin/env bash
# The studio in headless Chromium: `experiments studio` on a free port, then
# crates/server/tests/browser/studio_browser.py (first mesh, canvas not blank, clustering changes
# the triangle counter, 64^3 update time and bytes per mesh, .glb export loaded back, compare in
# blind mode, one sculpt stroke with latency and chunk readouts, undo; LOD mode: levels, a
# flight, colour by level, a stroke, and clustering integrated lowering the triangle count).
# Screenshots go to OUT, and the README's docs/studio.png is regenerated from the radius-ratio
# view.
#
#   scripts/studio-browser.sh OUT
#
# Needs target/release/experiments, and chromium, chromium-driver and python3-selenium from
# Debian (.ci/run installs them).
set -euo pipefail
cd "$(dirname "$0")/.."
out=$1
mkdir -p "$out"
bin=target/release/experiments
"$bin" studio --addr 127.0.0.1:0 --threads 2 > "$out/studio.log" 2>&1 &
server=$!
trap 'kill "$server" 2>/dev/null || true' EXIT
url=""
for _ in $(seq 1 100); do
  url=$(sed -n 's#^Studio: \(http://[^ ]*\) .*#\1#p' "$out/studio.log")
  [ -n "$url" ] && break
  kill -0 "$server" 2>/dev/null || { cat "$out/studio.log"; exit 1; }
  sleep 0.1
done
[ -n "$url" ] || { echo "studio did not start"; cat "$out/studio.log"; exit 1; }
echo "-- $url"
/usr/bin/python3 crates/server/tests/browser/studio_browser.py --url "$url" --out "$out" \
  --readme-shot docs/studio.png | tee "$out/measurements.json"
ls "$out"/*.png
