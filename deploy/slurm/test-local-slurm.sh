#!/bin/bash
# A real Slurm test of deploy/slurm/drape-array.sbatch on a one-node cluster on localhost:
# starts munged, slurmctld and slurmd with a minimal slurm.conf (all state in a temporary folder,
# nothing under /etc touched), submits the job array over a manifest of small garments in 4
# tasks, cancels task 1 once it has finished some but not all of its items, resubmits that
# task alone, waits, and checks that the report holds every item exactly once with no
# half-written folder.
#
#   apt-get install -y slurm-wlm munge        # Debian/Ubuntu
#   cargo build --release
#   sudo deploy/slurm/test-local-slurm.sh     # [DRAPEKIT_BINARY] [ITEMS]
#
# Needs root (slurmd starts jobs as their user). Exit 0 when every check passes.
set -euo pipefail

REPO=$(cd "$(dirname "$0")/../.." && pwd)
DRAPEKIT=$(realpath "${1:-$REPO/target/release/drapekit}")
ITEMS=${2:-12}
TASKS=4
[ -x "$DRAPEKIT" ] || { echo "no drapekit binary at $DRAPEKIT: cargo build --release" >&2; exit 1; }
for tool in munged slurmctld slurmd sbatch squeue scancel scontrol; do
    command -v "$tool" >/dev/null || { echo "$tool missing: apt-get install -y slurm-wlm munge" >&2; exit 1; }
done

STATE=$(mktemp -d /tmp/drape-slurm.XXXXXX)
chmod 755 "$STATE"
mkdir -p "$STATE"/{munge,spool/ctld,spool/d,log,work}
chmod 700 "$STATE/munge"
export SLURM_CONF=$STATE/slurm.conf
SOCKET=$STATE/munge/munge.socket
say() { printf '[%s] %s\n' "$(date +%T)" "$*"; }
fail() { say "FAIL: $*"; exit 1; }

cleanup() {
    set +e
    scancel --quiet --user="$(id -un)" 2>/dev/null
    scontrol shutdown >/dev/null 2>&1
    sleep 1
    munged --stop --socket="$SOCKET" >/dev/null 2>&1
    say "state, logs and outputs kept in $STATE"
}
trap cleanup EXIT

# --- munge: a private key and socket --------------------------------------------------------
dd if=/dev/urandom of="$STATE/munge/munge.key" bs=1024 count=1 status=none
chmod 600 "$STATE/munge/munge.key"
munged --force --key-file="$STATE/munge/munge.key" --socket="$SOCKET" \
    --pid-file="$STATE/munge/munged.pid" --log-file="$STATE/munge/munged.log" \
    --seed-file="$STATE/munge/munged.seed"
munge --socket="$SOCKET" -n | unmunge --socket="$SOCKET" >/dev/null || fail "munge does not work"

# --- slurm: one node, this machine ----------------------------------------------------------
HOST=$(hostname -s)
cat > "$SLURM_CONF" <<EOF
ClusterName=drapetest
SlurmctldHost=$HOST
SlurmctldPort=16817
SlurmdPort=16818
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$SOCKET
CredType=cred/munge
StateSaveLocation=$STATE/spool/ctld
SlurmdSpoolDir=$STATE/spool/d
SlurmctldPidFile=$STATE/slurmctld.pid
SlurmdPidFile=$STATE/slurmd.pid
SlurmctldLogFile=$STATE/log/slurmctld.log
SlurmdLogFile=$STATE/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
MpiDefault=none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
SchedulerType=sched/backfill
ReturnToService=2
NodeName=$HOST NodeAddr=127.0.0.1 CPUs=$(nproc) RealMemory=$(free -m | awk '/^Mem:/ {print int($2 * 0.9)}') State=UNKNOWN
PartitionName=debug Nodes=ALL Default=YES MaxTime=INFINITE State=UP
EOF
slurmctld -f "$SLURM_CONF"
slurmd -f "$SLURM_CONF"
for _ in $(seq 60); do
    sinfo -h -o %T 2>/dev/null | grep -q idle && break
    sleep 1
done
sinfo -h -o %T | grep -q idle || fail "the node never became idle (see $STATE/log)"
say "slurm $(sinfo -V | awk '{print $2}') up: $(sinfo -h -o '%P %D node(s) %c CPUs %T')"

# --- the manifest: the first ITEMS garments of skirts_small, scene paths made absolute --------
MANIFEST=$STATE/work/garments.jsonl
OUT=$STATE/work/out
head -n "$ITEMS" "$REPO/fixtures/datasets/skirts_small.jsonl" |
    sed "s|\"scene\": \"\\.\\./scenes/|\"scene\": \"$REPO/fixtures/scenes/|" > "$MANIFEST"
mapfile -t IDS < <(sed 's/.*"id": "\([^"]*\)".*/\1/' "$MANIFEST")
[ "${#IDS[@]}" -ge 8 ] || fail "the manifest has ${#IDS[@]} items, the test wants at least 8"
say "manifest: ${#IDS[@]} items in $TASKS tasks"

submit() {  # extra sbatch options...
    sbatch --parsable --cpus-per-task=1 --output="$STATE/log/drape-%A_%a.log" \
        --export=ALL,MANIFEST="$MANIFEST",OUT="$OUT",DRAPEKIT="$DRAPEKIT",XDG_CACHE_HOME="$STATE/cache" \
        "$@" "$REPO/deploy/slurm/drape-array.sbatch"
}
JOB=$(submit --array=0-$((TASKS - 1)))
say "submitted array job $JOB (tasks 0-$((TASKS - 1)))"

# Task 1's items are those at positions 1, 5, 9, ... (k mod 4 = 1).
MINE=()
for ((k = 1; k < ${#IDS[@]}; k += TASKS)); do MINE+=("${IDS[k]}"); done
done_count() { local n=0; for id in "${MINE[@]}"; do [ -f "$OUT/$id/done" ] && n=$((n + 1)); done; echo $n; }
for _ in $(seq 1200); do
    [ "$(done_count)" -ge 1 ] && break
    sleep 0.5
done
[ "$(done_count)" -ge 1 ] || fail "task 1 never finished an item"
scancel "${JOB}_1"
FINISHED=$(done_count)
say "cancelled task ${JOB}_1 with $FINISHED of its ${#MINE[@]} items done"
[ "$FINISHED" -lt "${#MINE[@]}" ] || fail "task 1 finished before it was cancelled: raise ITEMS"
sleep 1
for dir in "$OUT"/*/; do
    [ -f "$dir/done" ] || fail "$dir is visible without a done marker"
done
say "after the cancel: $(ls "$OUT" | wc -l) item folders, all with a marker; hidden (in flight or abandoned): $(ls -A "$OUT" | grep '^\.' | tr '\n' ' ' || true)"

# Resubmit shard 1 alone: an array of one task whose id is the shard index.
JOB2=$(submit --array=1 --export=ALL,MANIFEST="$MANIFEST",OUT="$OUT",DRAPEKIT="$DRAPEKIT",XDG_CACHE_HOME="$STATE/cache",SHARDS=$TASKS)
say "resubmitted task 1 as job $JOB2"
for _ in $(seq 3600); do
    [ -z "$(squeue -h -j "$JOB,$JOB2" 2>/dev/null)" ] && break
    sleep 1
done
[ -z "$(squeue -h -j "$JOB,$JOB2" 2>/dev/null)" ] || fail "jobs still queued after an hour"
say "all tasks finished"

# --- checks -----------------------------------------------------------------------------------
"$DRAPEKIT" batch report "$OUT"
CSV=$OUT/batch.csv
got=$(tail -n +2 "$CSV" | cut -d, -f1 | sort)
want=$(printf '%s\n' "${IDS[@]}" | sort)
[ "$got" = "$want" ] || fail "the report's ids differ from the manifest's:\n$(diff <(echo "$want") <(echo "$got"))"
[ "$(tail -n +2 "$CSV" | cut -d, -f1 | sort | uniq -d)" = "" ] || fail "an item appears twice"
bad=$(tail -n +2 "$CSV" | awk -F, '$2 != "ok" {print $1 " " $2}')
[ -z "$bad" ] || fail "items not ok: $bad"
for dir in "$OUT"/*/; do
    [ -f "$dir/done" ] && [ -f "$dir/summary.json" ] || fail "$dir is half-written"
done
hidden=$(ls -A "$OUT" | grep '^\.partial~\|^\.replaced~' || true)
[ -z "$hidden" ] || fail "leftover temporary folders: $hidden"
skipped=$(grep -c 'done before, skipped' "$STATE/log/drape-${JOB2}_1.log" || true)
[ "$skipped" -eq "$FINISHED" ] || fail "the resubmitted task skipped $skipped items, expected $FINISHED"
say "resubmitted task log:"
sed 's/^/    /' "$STATE/log/drape-${JOB2}_1.log"
say "report:"
sed 's/^/    /' "$OUT/batch.md"
say "PASS: ${#IDS[@]} items, each exactly once and ok; task 1 cancelled after $FINISHED item(s), resumed by job $JOB2 which skipped them"
