#!/usr/bin/env bash
# The second perception study (issue 42) from its design to a browser: `experiments study run
# experiments/studies/peers.toml` at the design's full size, every turntable it rendered checked
# against the 2 MB a browser should load, the survey started exactly as `study run` printed it,
# one participant's whole balanced subset answered in headless Chromium
# (crates/server/tests/browser/survey_browser.py --record), then `experiments survey export`
# checked against the screens (crates/server/tests/browser/check_subset.py): exactly the
# subset's questions and the controls arrived, each with the sides the screen showed and the
# side clicked.
#
#   scripts/study-e2e.sh OUT
#
# Everything stays in OUT: the run folder OUT/study (meshes, turntables, survey.sqlite), the
# logs, a question screenshot, the recorded screens and the export. Needs
# target/release/experiments, and chromium, chromium-driver and python3-selenium from Debian
# (.ci/run installs them).
set -euo pipefail
cd "$(dirname "$0")/.."
out=$1
bin=target/release/experiments
design=experiments/studies/peers.toml
# The bound `study run` reports against (study::MAX_GIF_BYTES): 2 MB = 2,000,000 bytes.
max_gif=2000000
mkdir -p "$out"
rm -rf "$out/study" "$out/export"

echo "-- study run $design (full size)"
start=$(date +%s)
"$bin" study run "$design" --out "$out/study" > "$out/study-run.log" 2> "$out/study-run.err" \
  || { cat "$out/study-run.err" "$out/study-run.log"; exit 1; }
echo "   $(( $(date +%s) - start )) s"
cat "$out/study-run.log"

echo "-- turntables: every GIF at most $max_gif bytes"
# The run folder's configurations, one turntable each, all in render/.
run=$(sed -n 's#^serve it: *experiments survey serve \([^ ]*\) .*$#\1#p' "$out/study-run.log")
[ "$run" = "$out/study" ] || { echo "study run printed no serve command for $out/study"; exit 1; }
configs=$(( $(wc -l < "$run/configurations.csv") - 1 ))
gifs=$(find "$run/render" -name '*.gif' | wc -l)
[ "$gifs" -eq "$configs" ] && [ "$gifs" -gt 0 ] \
  || { echo "$gifs turntables for $configs configurations"; exit 1; }
find "$run/render" -name '*.gif' -printf '%s %f\n' | sort -n > "$out/gif-sizes.txt"
awk -v max="$max_gif" '{ n++; t += $1; if ($1 > max) { bad = bad " " $2 "=" $1 } }
  END { printf "   %d turntables, %.2f MB in all, smallest %.2f MB, largest %.2f MB\n", n, t / 1e6, min / 1e6, $1 / 1e6
        if (bad) { print "over " max " bytes:" bad; exit 1 } }
  NR == 1 { min = $1 }' "$out/gif-sizes.txt"

echo "-- serve, as study run printed it"
# The printed arguments, word for word, plus a free port of the loopback interface.
serve_args=$(sed -n 's#^serve it: *experiments survey serve ##p' "$out/study-run.log")
read -r -a args <<<"$serve_args"
per=$(sed -n 's#^.* --per-participant \([0-9][0-9]*\)\( .*\)*$#\1#p' <<<"$serve_args")
controls=$(sed -n 's#^.* --controls \([0-9][0-9]*\)\( .*\)*$#\1#p' <<<"$serve_args")
design_per=$(sed -n 's#^questions *= *\([0-9][0-9]*\).*$#\1#p' "$design")
design_controls=$(sed -n 's#^controls *= *\([0-9][0-9]*\).*$#\1#p' "$design")
[ -n "$per" ] && [ "$per" = "$design_per" ] && [ "$controls" = "$design_controls" ] \
  || { echo "served with $per questions and $controls controls, the design asks $design_per and $design_controls"; exit 1; }
: > "$out/serve.log"  # exists before the server opens it, for the sed below
"$bin" survey serve "${args[@]}" --addr 127.0.0.1:0 > "$out/serve.log" 2>&1 &
server=$!
trap 'kill "$server" 2>/dev/null || true' EXIT
url=""
for _ in $(seq 1 100); do
  url=$(sed -n 's#^Participants: \(http://[^ ]*\)$#\1#p' "$out/serve.log")
  [ -n "$url" ] && break
  kill -0 "$server" 2>/dev/null || { cat "$out/serve.log"; exit 1; }
  sleep 0.1
done
[ -n "$url" ] || { echo "server did not start"; cat "$out/serve.log"; exit 1; }
echo "   $url"

echo "-- browser: one participant's $per questions and $controls controls in headless Chromium, every screen recorded"
# Blinding: no response body may name a configuration id or a value of the study's variables.
start=$(date +%s)
/usr/bin/python3 crates/server/tests/browser/survey_browser.py --url "$url" --run "$run" \
  --secret-columns object,method,lattice,clustering,simplify,shading \
  --screenshot "$out/question.png" --record "$out/screens.json" | tee "$out/browser.json"
echo "   $(( $(date +%s) - start )) s"
test -s "$out/question.png"

kill -INT "$server"
wait "$server" || true
trap - EXIT

echo "-- export: exactly that participant's $per answers, with the sides the screen showed"
"$bin" survey export "$run/survey.sqlite" --out "$out/export"
/usr/bin/python3 crates/server/tests/browser/check_subset.py "$run" "$out/export" \
  "$out/screens.json" "$per" "$controls"
echo "study end to end: ok ($out)"
