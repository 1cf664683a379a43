#!/usr/bin/env bash
# End-to-end test of `experiments slurm` against a real one-node Slurm (scripts/slurm-local.sh):
#  1. `experiments slurm experiments/manifests/ci.toml --shards 4 --submit` runs to the merged
#     folder; its counts (every non-time column of raw.csv and summary.csv) and meshes equal a
#     local `experiments run` of the same manifest, and `experiments report` accepts it;
#  2. with a job holding the node, one array task is cancelled (scancel): the merge job is
#     cancelled too (DependencyNeverSatisfied); `experiments slurm --resume` resubmits that shard
#     only and the run is merged;
#  3. the daemons are stopped by PID (slurm-local.sh down), also on failure.
# Needs root, slurm-wlm and munge installed, and the release binary (EXPERIMENTS to override).
set -euo pipefail
cd "$(dirname "$0")/.."
BIN=${EXPERIMENTS:-$PWD/target/release/experiments}
MANIFEST=experiments/manifests/ci.toml
[ -x "$BIN" ] || { echo "slurm-e2e: $BIN not built (cargo build --release -p experiments)"; exit 1; }
command -v sbatch >/dev/null || { echo "slurm-e2e: Slurm is not installed (apt-get install slurm-wlm munge)"; exit 1; }

work=$(mktemp -d)
started=0
cleanup() {
  local rc=$?
  if [ "$started" = 1 ]; then
    # Cancel whatever this test left queued, then stop the daemons by PID.
    [ -n "${jobs_to_cancel:-}" ] && scancel $jobs_to_cancel 2>/dev/null || true
    scripts/slurm-local.sh down
  fi
  rm -rf "$work"
  exit $rc
}
trap cleanup EXIT
scripts/slurm-local.sh up
started=1

fail() { echo "slurm-e2e: FAIL: $*" >&2; exit 1; }

# Waits until none of the jobs is queued (pending or running); at most $2 seconds.
wait_jobs() {
  local ids=$1 limit=${2:-300} t=0
  while [ -n "$(squeue -h -j "$ids" -o %i 2>/dev/null)" ]; do
    sleep 1; t=$((t + 1))
    [ "$t" -lt "$limit" ] || { squeue; fail "jobs $ids still queued after ${limit}s"; }
  done
}
job_state() { scontrol show job "$1" | sed -n 's/.*JobState=\([A-Z_]*\).*/\1/p' | head -1; }
job_reason() { scontrol show job "$1" | sed -n 's/.*Reason=\([A-Za-z_]*\).*/\1/p' | head -1; }

# Non-time columns of a CSV (drops run_id, t_*, share_*), for comparing counts.
counts() {
  awk -F, 'NR == 1 { for (i = 1; i <= NF; i++) keep[i] = ($i != "run_id" && $i !~ /^t_/ && $i !~ /^share_/) }
           { line = ""; for (i = 1; i <= NF; i++) if (keep[i]) line = line $i ","; print line }' "$1"
}
same_counts() {
  local a=$1 b=$2
  for f in raw.csv summary.csv configurations.csv; do
    grep -q '"' "$a/$f" && fail "$a/$f has quoted fields; the column filter cannot compare it"
    diff <(counts "$a/$f") <(counts "$b/$f") >/dev/null || { diff <(counts "$a/$f") <(counts "$b/$f") | head; fail "$f differs between $a and $b"; }
  done
  diff -r "$a/meshes" "$b/meshes" >/dev/null || fail "meshes differ between $a and $b"
}

echo "== slurm-e2e: local run of $MANIFEST"
"$BIN" run "$MANIFEST" --out "$work/local" --quiet

echo "== slurm-e2e: 4 shards on Slurm"
t0=$(date +%s%N)
"$BIN" slurm "$MANIFEST" --shards 4 --submit --out "$work/merged" | tee "$work/submit.txt"
array=$(sed -n 's/^array job \([0-9]*\).*/\1/p' "$work/submit.txt")
merge=$(sed -n 's/^merge job \([0-9]*\).*/\1/p' "$work/submit.txt")
[ -n "$array" ] && [ -n "$merge" ] || fail "no job ids printed"
jobs_to_cancel="$array $merge"
wait_jobs "$array,$merge"
t1=$(date +%s%N)
[ "$(job_state "$merge")" = COMPLETED ] || { cat "$work"/merged.slurm/logs/* || true; fail "merge job $merge: $(job_state "$merge")"; }
test -s "$work/merged/run.json" || fail "no merged run.json"
grep -q '"merged_from"' "$work/merged/run.json" || fail "run.json does not list the shards"
same_counts "$work/local" "$work/merged"
echo "slurm-e2e: merged run equals the local run (counts, meshes); submit to merged in $(( (t1 - t0) / 1000000 )) ms"
"$BIN" report --run "$work/merged" --out "$work/report" --no-scaling --resamples 1000 >/dev/null
"$BIN" report --check --run "$work/report/data" --out "$work/report" --no-scaling --resamples 1000 >/dev/null
echo "slurm-e2e: experiments report accepts the merged run"

echo "== slurm-e2e: cancel one shard, the merge is cancelled, --resume finishes"
# A job holding every CPU keeps the shards pending, so the cancel cannot race them.
blocker=$(sbatch --parsable --exclusive --output=/dev/null --wrap "sleep 600")
jobs_to_cancel="$blocker"
"$BIN" slurm "$MANIFEST" --shards 4 --submit --out "$work/again" | tee "$work/submit2.txt"
array=$(sed -n 's/^array job \([0-9]*\).*/\1/p' "$work/submit2.txt")
merge=$(sed -n 's/^merge job \([0-9]*\).*/\1/p' "$work/submit2.txt")
jobs_to_cancel="$blocker $array $merge"
scancel "${array}_2"
scancel "$blocker"
wait_jobs "$array,$merge"
[ "$(job_state "$merge")" = CANCELLED ] || fail "merge job $merge is $(job_state "$merge"), expected CANCELLED"
echo "slurm-e2e: merge job $merge cancelled ($(job_reason "$merge"))"
[ ! -e "$work/again/run.json" ] || fail "a merged run appeared although a shard was cancelled"
"$BIN" slurm --resume "$work/again" | tee "$work/resume.txt"
grep -q '^resubmitted shards 2 ' "$work/resume.txt" || fail "--resume did not resubmit exactly shard 2"
array=$(sed -n 's/.* as array job \([0-9]*\).*/\1/p' "$work/resume.txt")
merge=$(sed -n 's/^merge job \([0-9]*\).*/\1/p' "$work/resume.txt")
jobs_to_cancel="$array $merge"
wait_jobs "$array,$merge"
[ "$(job_state "$merge")" = COMPLETED ] || { cat "$work"/again.slurm/logs/* || true; fail "resumed merge job $merge: $(job_state "$merge")"; }
same_counts "$work/local" "$work/again"
"$BIN" slurm --resume "$work/again" | grep -q '^already merged' || fail "--resume of a merged run should say so"
echo "slurm-e2e: all steps passed"
