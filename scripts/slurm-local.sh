#!/usr/bin/env bash
# A one-node SLURM on this machine (Debian's slurm-wlm and munge), a small co-design sweep
# submitted to it as a job array plus its collect job with sbatch, and the collected report
# checked against the in-process `adam codesign sweep`: the same files, byte for byte.
#
#   sudo bash scripts/slurm-local.sh            # as root: installs the packages if missing
#   GRID=3 ADAM=target/release/adam bash scripts/slurm-local.sh
#
# It starts munged, slurmctld and slurmd with a private configuration under a temporary
# folder, and stops every daemon it started on exit (success, failure or Ctrl-C). Debian 12
# (slurm-wlm 22.05); needs root (apt-get, munge's key, the daemons). Not run by CI.
set -euo pipefail
cd "$(dirname "$0")/.."
repo=$(pwd)
start_s=$(date +%s)
GRID=${GRID:-2}
ADAM=${ADAM:-$repo/target/release/adam}
TIMEOUT_S=${TIMEOUT_S:-900}

say() { printf '== %s\n' "$*"; }

if [ "$(id -u)" -ne 0 ]; then
    echo "slurm-local.sh: run as root (it installs packages and starts munged, slurmctld, slurmd)" >&2
    exit 2
fi

if ! command -v slurmctld >/dev/null || ! command -v munged >/dev/null; then
    say "installing slurm-wlm and munge (apt-get)"
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -qq
    apt-get install -y -qq --no-install-recommends slurm-wlm munge >/dev/null
fi
say "$(slurmctld -V), munge $(dpkg-query -W -f='${Version}' munge)"

if [ ! -x "$ADAM" ]; then
    say "building adam (cargo build --release)"
    cargo build --release --quiet
fi
ADAM=$(readlink -f "$ADAM")

work=$(mktemp -d /tmp/adam-slurm.XXXXXX)
chmod 755 "$work"
started=()
cleanup() {
    status=$?
    for pidfile in "${started[@]}"; do
        if [ -s "$pidfile" ]; then
            pid=$(cat "$pidfile")
            kill "$pid" 2>/dev/null || true
            for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
            kill -9 "$pid" 2>/dev/null || true
        fi
    done
    if [ "$status" -ne 0 ]; then
        echo "slurm-local.sh failed (exit $status); logs in $work" >&2
        for f in "$work"/slurmctld.log "$work"/slurmd.log "$work"/sweep/logs/*.out; do
            [ -f "$f" ] && { echo "--- $f" >&2; tail -20 "$f" >&2; }
        done
    else
        rm -rf "$work"
    fi
    say "daemons stopped; $(( $(date +%s) - start_s )) s wall in all"
    exit "$status"
}
trap cleanup EXIT INT TERM

# munge: Debian's postinst made the key; start our own munged unless one answers already.
if ! munge -n </dev/null >/dev/null 2>&1; then
    [ -s /etc/munge/munge.key ] || mungekey --create --keyfile=/etc/munge/munge.key
    install -d -o munge -g munge -m 0755 /run/munge
    chown munge:munge /etc/munge/munge.key
    # Its pid file in a folder it may write (munged runs as the munge user).
    install -d -o munge -g munge -m 0755 "$work/munge"
    runuser -u munge -- /usr/sbin/munged --pid-file="$work/munge/munged.pid"
    started+=("$work/munge/munged.pid")
    for _ in $(seq 50); do munge -n </dev/null >/dev/null 2>&1 && break; sleep 0.1; done
    munge -n </dev/null | unmunge >/dev/null
fi
say "munge answers"

# A one-node cluster: this machine, its cores and most of its memory, one partition.
node=$(hostname -s)
cpus=$(nproc)
mem_mb=$(( $(awk '/MemTotal/ {print int($2/1024)}' /proc/meminfo) * 8 / 10 ))
mkdir -p "$work/state" "$work/spool"
cat >"$work/slurm.conf" <<EOF
ClusterName=adamlocal
SlurmctldHost=$node(127.0.0.1)
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
StateSaveLocation=$work/state
SlurmdSpoolDir=$work/spool
SlurmctldPidFile=$work/slurmctld.pid
SlurmdPidFile=$work/slurmd.pid
SlurmctldLogFile=$work/slurmctld.log
SlurmdLogFile=$work/slurmd.log
SlurmctldPort=6817
SlurmdPort=6818
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core_Memory
ReturnToService=2
MpiDefault=none
JobCompType=jobcomp/none
AccountingStorageType=accounting_storage/none
SlurmctldTimeout=30
SlurmdTimeout=30
NodeName=$node NodeAddr=127.0.0.1 CPUs=$cpus RealMemory=$mem_mb State=UNKNOWN
PartitionName=local Nodes=$node Default=YES MaxTime=INFINITE State=UP
EOF
export SLURM_CONF=$work/slurm.conf
slurmctld -f "$SLURM_CONF"
started+=("$work/slurmctld.pid")
slurmd -f "$SLURM_CONF"
started+=("$work/slurmd.pid")
for _ in $(seq 100); do
    state=$(sinfo -h -N -o '%T' 2>/dev/null | head -1 || true)
    case "$state" in idle*|mixed*|allocated*) break ;; esac
    sleep 0.2
done
say "one-node SLURM up: $(sinfo -h -N -o '%N %T %c CPUs %m MB')"

# The sweep on the cluster: plan, scripts, array + collect submitted with sbatch.
say "adam sweep plan --study codesign --grid $GRID"
"$ADAM" sweep plan --study codesign --grid "$GRID" --out-dir "$work/sweep" \
    --out "$work/plan.toml" --time-per-task-min 10 --mem-per-task-mb 1024
submitted=$("$ADAM" sweep slurm --plan "$work/plan.toml" --submit)
echo "$submitted"
array_id=$(sed -n 's/.*array job \([0-9]*\),.*/\1/p' <<<"$submitted")
collect_id=$(sed -n 's/.*collect job \([0-9]*\) .*/\1/p' <<<"$submitted")
[ -n "$array_id" ] && [ -n "$collect_id" ] || { echo "no job ids in: $submitted" >&2; exit 1; }
t0=$(date +%s)
while squeue -h -j "$array_id,$collect_id" 2>/dev/null | grep -q .; do
    if (( $(date +%s) - t0 > TIMEOUT_S )); then
        echo "jobs still queued after $TIMEOUT_S s:" >&2
        squeue >&2
        exit 1
    fi
    sleep 1
done
say "array job $array_id and collect job $collect_id done in $(( $(date +%s) - t0 )) s; the collect job's log:"
cat "$work/sweep/logs/collect.out"
grep -q "tasks have results (0 failed, 0 missing)" "$work/sweep/logs/collect.out" \
    || { echo "the collect job did not find every result" >&2; exit 1; }
ls "$work/sweep/logs"

# The same study in one process, and the two reports compared.
say "adam codesign sweep --grid $GRID (in-process)"
"$ADAM" codesign sweep --grid "$GRID" --out-dir "$work/inproc" >"$work/inproc.log"
tail -3 "$work/inproc.log"
for f in table.md sweep.csv sweep.json convergence.svg convergence.png; do
    cmp "$work/inproc/$f" "$work/sweep/$f"
    say "identical: $f"
done
say "the SLURM sweep's report equals the in-process one"
