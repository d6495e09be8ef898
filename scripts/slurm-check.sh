#!/bin/bash
# The shard workflow on a real Slurm: a single-node cluster (Debian's slurmctld, slurmd and munge
# as local processes), the job array of scripts/slurm-sweep.sh on a slice of the brute force,
# the merge, and the merge compared byte for byte with the unsharded sweep. Run by .ci/run;
# needs root (apt-get, munged, slurmd). Exits non-zero on any difference or failure.
#
#   bash scripts/slurm-check.sh [BIN]     # BIN: the built validate-design
set -euo pipefail

BIN=$(realpath "${1:-target/release/validate-design}")
REPO=$(cd "$(dirname "$0")/.." && pwd)
WORK=$(mktemp -d /tmp/pg-slurm.XXXXXX)
SHARDS=3
# A slice of the brute force: catalog robots on one cluttered task (ids as sweeps print them).
DESIGNS="modular6/D-D-D-D-D-D modular6/Ll-Is-Ll-Il-D-Ls modular6/D-Ls-Il-D-Is-Ll modular6/Is-Is-Is-Is-Is-Is modular6/Ll-Ll-Ll-Ll-Ll-Ll modular6/D-Il-Ls-D-Ll-Is modular6/Ls-D-Ls-D-Ls-D modular6/Il-D-Il-D-Il-D"
SCENARIOS="$REPO/scenarios/cluttered/task-00.json"

if ! command -v slurmctld >/dev/null || ! command -v munged >/dev/null; then
    apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends slurmctld slurmd slurm-client munge >/dev/null
fi

HOST=$(hostname -s)
mkdir -p "$WORK"/{state,spool,log,munge}
cat >"$WORK/slurm.conf" <<EOF
ClusterName=pg
SlurmctldHost=$HOST
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
MpiDefault=none
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
ReturnToService=2
StateSaveLocation=$WORK/state
SlurmdSpoolDir=$WORK/spool
SlurmctldPidFile=$WORK/slurmctld.pid
SlurmdPidFile=$WORK/slurmd.pid
SlurmctldLogFile=$WORK/log/slurmctld.log
SlurmdLogFile=$WORK/log/slurmd.log
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
NodeName=$HOST CPUs=$(nproc) State=UNKNOWN
PartitionName=check Nodes=$HOST Default=YES MaxTime=INFINITE State=UP
EOF
export SLURM_CONF="$WORK/slurm.conf"

cleanup() {
    for pid in "$WORK/slurmd.pid" "$WORK/slurmctld.pid" "$WORK/munged.pid"; do
        [ -f "$pid" ] && kill "$(cat "$pid")" 2>/dev/null || true
    done
}
trap cleanup EXIT

# munge's own key when the package made one, else one for this check.
KEY=/etc/munge/munge.key
if [ ! -f "$KEY" ]; then
    KEY="$WORK/munge/munge.key"
    head -c 1024 /dev/urandom >"$KEY"
    chmod 400 "$KEY"
fi
mkdir -p /run/munge
munged --force --key-file="$KEY" --pid-file="$WORK/munged.pid" --socket=/run/munge/munge.socket.2 --log-file="$WORK/log/munged.log" --seed-file="$WORK/munge/seed"
slurmctld -f "$SLURM_CONF"
slurmd -f "$SLURM_CONF"

for _ in $(seq 60); do
    sinfo -h -o %t 2>/dev/null | grep -Eq '^(idle|mix|alloc)' && break
    sleep 1
done
sinfo -h -o '%P %t %c' || { cat "$WORK"/log/*.log; exit 1; }

cd "$WORK"
# The shipped job script, as a user runs it: the array writes sweep-shards/K.
job=$(BIN="$BIN" DESIGNS="$DESIGNS" SCENARIOS="$SCENARIOS" \
    sbatch --parsable --array=1-$SHARDS --cpus-per-task=1 --export=ALL "$REPO/scripts/slurm-sweep.sh")
echo "submitted job array $job ($SHARDS shards)"
for _ in $(seq 600); do
    [ -z "$(squeue -h -j "$job" 2>/dev/null)" ] && break
    sleep 1
done
if [ -n "$(squeue -h -j "$job" 2>/dev/null)" ]; then
    echo "slurm check: the job array did not finish in 10 minutes"; squeue; exit 1
fi
for k in $(seq $SHARDS); do
    [ -f "sweep-shards/$k/results.jsonl" ] || { echo "slurm check: shard $k wrote no results"; cat pg-sweep-*.out || true; exit 1; }
done

# shellcheck disable=SC2086
"$BIN" merge sweep-shards/1 sweep-shards/2 sweep-shards/3 --out merged --quiet
# shellcheck disable=SC2086
"$BIN" sweep $DESIGNS --scenarios "$SCENARIOS" --out whole --quiet
for file in results.jsonl results.csv table.txt sweep.json; do
    cmp "merged/$file" "whole/$file" || { echo "slurm check: merged $file differs from the unsharded sweep"; exit 1; }
done
pairs=$(wc -l <whole/results.jsonl)
echo "slurm check: $SHARDS shards of a Slurm job array merged into the unsharded sweep byte for byte ($pairs pairs)"
