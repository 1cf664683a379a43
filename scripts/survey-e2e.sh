#!/usr/bin/env bash
# The survey end to end with real parts: a rendered run, `experiments survey serve`, one
# participant's whole session in headless Chromium (crates/server/tests/browser/survey_browser.py),
# `experiments survey export`, then `experiments analyse` on the export.
#
#   scripts/survey-e2e.sh CI_RUN OUT
#
# CI_RUN is a run folder of experiments/manifests/ci.toml (configurations.csv and meshes/); the
# script takes its 18 paper configurations (marching tetrahedra; sphere, asteroid and bunny; both
# lattices; three clustering modes), renders them small, and leaves everything in OUT, including
# OUT/question.png (a question screen). Then it serves the same run again with
# `--per-participant N` (6; SURVEY_PER_PARTICIPANT) into its own database, has the browser
# answer one participant's subset, and checks through the export that exactly those N answers
# (and the 2 controls) arrived, each with the sides the screen showed and the side clicked.
# Needs target/release/experiments, and chromium, chromium-driver and python3-selenium from
# Debian (.ci/run installs them).
set -euo pipefail
cd "$(dirname "$0")/.."
ci_run=$1
out=$2
# Real questions of the balanced subset one participant answers in the second session.
per=${SURVEY_PER_PARTICIPANT:-6}
bin=target/release/experiments
run="$out/run"
rm -rf "$run"
mkdir -p "$run/meshes"

# The paper design out of the CI run: id and the three study variables.
/usr/bin/python3 - "$ci_run" "$run" <<'PY'
import csv, os, sys
src, dst = sys.argv[1], sys.argv[2]
with open(os.path.join(src, "configurations.csv"), newline="") as f:
    rows = [r for r in csv.DictReader(f)
            if r["method"] == "mt" and r["object"] in ("sphere", "asteroid", "bunny")
            and r["clustering"] in ("none", "integrated", "postprocessed")]
assert len(rows) == 18, f"expected the 18 paper configurations, found {len(rows)}"
with open(os.path.join(dst, "configurations.csv"), "w", newline="") as f:
    w = csv.writer(f, lineterminator="\n")
    w.writerow(["id", "object", "lattice", "clustering"])
    for r in rows:
        w.writerow([r["id"], r["object"], r["lattice"], r["clustering"]])
        os.symlink(os.path.abspath(os.path.join(src, "meshes", r["id"] + ".ply")),
                   os.path.join(dst, "meshes", r["id"] + ".ply"))
PY

echo "-- render (18 small turntables)"
"$bin" render "$run" --width 120 --height 90 --frames 12 --supersampling 2 --seed 7 > "$out/render.log" 2>&1

echo "-- serve"
: > "$out/serve.log"  # exists before the server opens it, for the sed below
"$bin" survey serve "$run" --addr 127.0.0.1:0 --controls 2 > "$out/serve.log" 2>&1 &
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

echo "-- browser: one participant's whole session in headless Chromium"
/usr/bin/python3 crates/server/tests/browser/survey_browser.py --url "$url" --run "$run" \
  --screenshot "$out/question.png" | tee "$out/browser.json"
test -s "$out/question.png"

kill -INT "$server"
wait "$server" || true
trap - EXIT

echo "-- export and analyse"
"$bin" survey export "$run/survey.sqlite" --out "$out/export"
test "$(wc -l < "$out/export/responses.csv")" -eq 28 || { echo "expected 27 answers"; cat "$out/export/responses.csv"; exit 1; }
test "$(wc -l < "$out/export/controls.csv")" -eq 3 || { echo "expected 2 control answers"; exit 1; }
grep -q ',29,29,1,' "$out/export/participants.csv" || { echo "participant not completed"; cat "$out/export/participants.csv"; exit 1; }
"$bin" analyse --responses "$out/export/responses.csv" --questions "$out/export/questions.csv" \
  --configurations "$out/export/configurations.csv" --controls "$out/export/controls.csv" \
  --out "$out/analysis" --resamples 0 > "$out/analyse.log"
for f in summary.csv preference_factors.csv questions.csv position_effect.csv order_effect.csv power.csv; do
  test -s "$out/analysis/$f" || { echo "analysis: missing $f"; ls "$out/analysis"; exit 1; }
done
grep -q '^participants,1$' "$out/analysis/summary.csv" || { echo "analysis is not of one participant"; cat "$out/analysis/summary.csv"; exit 1; }
echo "-- serve a balanced subset: --per-participant $per (own database)"
rm -f "$out/subset.sqlite"*
: > "$out/subset-serve.log"
"$bin" survey serve "$run" --addr 127.0.0.1:0 --controls 2 --per-participant "$per" \
  --db "$out/subset.sqlite" > "$out/subset-serve.log" 2>&1 &
server=$!
trap 'kill "$server" 2>/dev/null || true' EXIT
url=""
for _ in $(seq 1 100); do
  url=$(sed -n 's#^Participants: \(http://[^ ]*\)$#\1#p' "$out/subset-serve.log")
  [ -n "$url" ] && break
  kill -0 "$server" 2>/dev/null || { cat "$out/subset-serve.log"; exit 1; }
  sleep 0.1
done
[ -n "$url" ] || { echo "server did not start"; cat "$out/subset-serve.log"; exit 1; }
echo "   $url"

echo "-- browser: one participant's subset in headless Chromium, every screen recorded"
/usr/bin/python3 crates/server/tests/browser/survey_browser.py --url "$url" --run "$run" \
  --screenshot "$out/subset-question.png" --record "$out/subset-screens.json" \
  | tee "$out/subset-browser.json"

kill -INT "$server"
wait "$server" || true
trap - EXIT

echo "-- export: exactly that participant's $per answers, with the sides the screen showed"
"$bin" survey export "$out/subset.sqlite" --out "$out/subset-export"
/usr/bin/python3 crates/server/tests/browser/check_subset.py "$run" "$out/subset-export" \
  "$out/subset-screens.json" "$per" 2
echo "survey end to end: ok ($out)"
