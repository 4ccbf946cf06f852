#!/usr/bin/env bash
# A live check of `kick slurm` on a single-node SLURM cluster brought up on
# this machine: Debian's slurm-wlm and munge, daemons started by hand with a
# minimal slurm.conf (no systemd). It runs studies/slurm_check.toml (4 cases
# of about a minute each) as a 2-shard array job with the finishing job
# after it, kills and requeues one task mid-run, then checks that
#   - the requeued task resumed without redoing its finished case,
#   - the merged summary.csv has every case once,
#   - every case's final state hash equals a local `kick matrix` run's,
#   - the report rendered.
# Needs root with apt-get; says "skipped" and exits 0 where it cannot run.
# Tears the cluster down afterwards (the packages stay installed).
# Usage: scripts/slurm/check.sh [KICK_BINARY]   (make slurm-check builds it)
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
KICK=${1:-$ROOT/target/release/kick}
STUDY=$ROOT/studies/slurm_check.toml
START=$(date +%s)
say() { echo "slurm-check [$(( $(date +%s) - START )) s]: $*"; }
fail() { say "FAIL: $*"; exit 1; }

if [ "$(id -u)" != 0 ] || ! command -v apt-get >/dev/null 2>&1; then
  echo "slurm-check: skipped: needs root with apt-get to install slurm-wlm and munge"
  exit 0
fi
[ -x "$KICK" ] || fail "no kick binary at $KICK (run: cargo build --release -p kick-study)"
if ! command -v slurmctld >/dev/null 2>&1 || ! command -v munged >/dev/null 2>&1; then
  say "installing slurm-wlm and munge"
  if ! { DEBIAN_FRONTEND=noninteractive apt-get update -qq &&
         DEBIAN_FRONTEND=noninteractive apt-get install -y -qq slurm-wlm munge >/dev/null; }; then
    echo "slurm-check: skipped: slurm-wlm and munge could not be installed"
    exit 0
  fi
fi
for daemon in slurmctld slurmd munged sbatch squeue scontrol; do
  command -v "$daemon" >/dev/null 2>&1 || fail "$daemon not found after installing slurm-wlm and munge"
done

WORK=$(mktemp -d -t kick-slurm-check.XXXXXX)
PIDS=()
ARRAY=""
FINISH=""
teardown() {
  # Only this check's jobs, on this check's controller.
  # Wait for them to stop: killing slurmd leaves its job processes running.
  if [ -n "${ARRAY:-}" ] && [ -n "${SLURM_CONF:-}" ]; then
    scancel --quiet "$ARRAY" ${FINISH:+"$FINISH"} >/dev/null 2>&1 || true
    for _ in $(seq 30); do
      [ -z "$(squeue -h -j "$ARRAY${FINISH:+,$FINISH}" 2>/dev/null)" ] && break
      sleep 1
    done
  fi
  for pid in "${PIDS[@]}"; do kill "$pid" 2>/dev/null || true; done
  [ -f "$WORK/munged.pid" ] && kill "$(cat "$WORK/munged.pid")" 2>/dev/null || true
  sleep 1
  if [ "${KEEP:-0}" = 1 ]; then say "kept $WORK"; else rm -rf "$WORK"; fi
}
trap teardown EXIT

# --- munge: a fresh key, the daemon on its own socket -----------------------
mkdir -p "$WORK/munge"
dd if=/dev/urandom of="$WORK/munge/munge.key" bs=1024 count=1 status=none
chmod 400 "$WORK/munge/munge.key"
munged --force --key-file="$WORK/munge/munge.key" --socket="$WORK/munge/munge.socket" \
       --pid-file="$WORK/munged.pid" --log-file="$WORK/munge/munged.log" \
       --seed-file="$WORK/munge/munged.seed"
sleep 1

# --- slurm: one node with this machine's CPUs, no accounting, no cgroups ----
NODE=$(hostname -s)
CPUS=$(nproc)
mkdir -p "$WORK/state" "$WORK/spool"
export SLURM_CONF=$WORK/slurm.conf
cat > "$SLURM_CONF" <<CONF
ClusterName=kickcheck
SlurmctldHost=$NODE(127.0.0.1)
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$WORK/munge/munge.socket
CredType=cred/munge
StateSaveLocation=$WORK/state
SlurmdSpoolDir=$WORK/spool
SlurmctldPidFile=$WORK/slurmctld.pid
SlurmdPidFile=$WORK/slurmd.pid
SlurmctldLogFile=$WORK/slurmctld.log
SlurmdLogFile=$WORK/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
MpiDefault=none
ReturnToService=2
JobRequeue=1
MinJobAge=3600
NodeName=$NODE NodeAddr=127.0.0.1 CPUs=$CPUS State=UNKNOWN
PartitionName=check Nodes=$NODE Default=YES MaxTime=INFINITE State=UP
CONF
slurmctld -D -f "$SLURM_CONF" > "$WORK/slurmctld.out" 2>&1 & PIDS+=($!)
sleep 2
slurmd -D -f "$SLURM_CONF" > "$WORK/slurmd.out" 2>&1 & PIDS+=($!)
for _ in $(seq 60); do
  state=$(sinfo -h -o %T 2>/dev/null || true)
  [ "$state" = idle ] && break
  sleep 1
done
[ "$state" = idle ] || { tail -5 "$WORK/slurmctld.log" "$WORK/slurmd.log" 2>/dev/null; fail "the node is '$state', not idle"; }
say "cluster up: node $NODE, $CPUS CPUs, $(sinfo -V)"

# --- the array job and its finishing job ------------------------------------
OUT=$WORK/out
submitted=0
"$KICK" slurm "$STUDY" --out "$OUT" --shards 2 --cpus-per-task 1 --time 00:30:00 > "$WORK/submit.txt" 2>&1 || submitted=$?
cat "$WORK/submit.txt"
ARRAY=$(sed -n 's/.*array job \([0-9][0-9]*\).*/\1/p' "$WORK/submit.txt" | head -1)
FINISH=$(sed -n 's/.*finishing job \([0-9]*\) after it.*/\1/p' "$WORK/submit.txt")
[ "$submitted" = 0 ] && [ -n "$ARRAY" ] && [ -n "$FINISH" ] || fail "kick slurm failed (exit $submitted) or printed no job ids"

# Shard 1's cases, as kick matrix --shard 1/2 takes them (positions 1, 3, ...).
mapfile -t SHARD1 < <("$KICK" list "$STUDY" | cut -f1 | awk 'NR % 2 == 0')
finished_of_shard1() { for c in "${SHARD1[@]}"; do [ -f "$OUT/$c/summary.json" ] && echo "$c"; done; return 0; }
say "waiting for task 1 to finish its first case (${SHARD1[*]})"
for _ in $(seq 900); do
  [ "$(finished_of_shard1 | wc -l)" -ge 1 ] && break
  sleep 1
done
DONE=$(finished_of_shard1)
[ "$(echo "$DONE" | grep -c .)" = 1 ] || fail "task 1 finished '$DONE' (expected one case)"
sleep 15
BEFORE=$(sha256sum "$OUT/$DONE/summary.json")
say "task 1 finished $DONE; killing and requeueing it mid-run of its next case"
scontrol requeue "${ARRAY}_1"

say "waiting for the finishing job $FINISH"
for _ in $(seq 1800); do
  [ -z "$(squeue -h -j "$FINISH" 2>/dev/null)" ] && break
  sleep 2
done
[ -z "$(squeue -h -j "$FINISH" 2>/dev/null)" ] || fail "the finishing job did not end in an hour"
grep -q "JobState=COMPLETED" <<< "$(scontrol show job "$FINISH")" ||
  { cat "$OUT/slurm/finish.log"; fail "the finishing job did not complete"; }

# --- the checks -------------------------------------------------------------
grep -q "start 1:" "$OUT/slurm/shard-1.log" || { cat "$OUT/slurm/shard-1.log"; fail "task 1 was not restarted"; }
grep -q "ran 1 cases (1 already done)" "$OUT/slurm/shard-1.log" ||
  { cat "$OUT/slurm/shard-1.log"; fail "the requeued task did not skip its finished case"; }
[ "$(sha256sum "$OUT/$DONE/summary.json")" = "$BEFORE" ] || fail "$DONE was run again after the requeue"
say "requeued task resumed: skipped $DONE, ran the rest"
say "local run of the same study for the hashes"
"$KICK" matrix "$STUDY" --out "$WORK/local" --jobs 2 --threads 1 > "$WORK/local.txt" 2>&1 ||
  { cat "$WORK/local.txt"; fail "the local matrix failed"; }
python3 - "$OUT" "$WORK/local" "$STUDY" "$KICK" <<'PY' || fail "the merged results differ from the local run"
import csv, json, subprocess, sys
out, local, study, kick = sys.argv[1:5]
names = [l.split("\t")[0] for l in subprocess.run([kick, "list", study], capture_output=True, text=True, check=True).stdout.splitlines()]
rows = list(csv.DictReader(open(f"{out}/summary.csv")))
cases = [r["case"] for r in rows]
assert sorted(cases) == sorted(names), f"merged cases {cases} != study cases {names}"
for r in rows:
    merged = json.load(open(f"{out}/{r['case_dir']}/summary.json"))
    alone = json.load(open(f"{local}/{r['case']}/summary.json"))
    assert merged["status"] == "completed", (r["case"], merged["status"])
    assert merged["final_state_hash"] == alone["final_state_hash"], (r["case"], merged["final_state_hash"], alone["final_state_hash"])
    print(f"  {r['case']:<20} {merged['final_state_hash']} = local")
print(f"  {len(rows)} cases, each once, hashes equal to the local run")
PY
for f in index.html; do [ -s "$OUT/report/$f" ] || fail "the report has no $f"; done
grep -q "$DONE" "$OUT/report/index.html" || fail "the report does not name $DONE"
say "report rendered: $OUT/report/index.html"
say "PASS (whole check $(( $(date +%s) - START )) s)"
