#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# `bvhlab sweep --slurm` against a real Slurm cluster that this test starts on localhost
# (Debian's slurm-wlm and munge: munged, slurmctld and slurmd with their own key, ports and
# state under a temporary folder): the grid is submitted as a job array and a merge job, every
# cell runs once, the merge leaves one results file, and --status reports it done.
# Exits 77 (skipped) with a reason when Slurm or munge is not installed.
# Usage: slurm_sweep.sh BVHLAB
set -u
bin=$(readlink -f "$1")
for p in munged slurmctld slurmd sbatch squeue scontrol; do
    if ! command -v "$p" >/dev/null && [ ! -x "/usr/sbin/$p" ]; then
        echo "slurm_sweep.sh: skipped: '$p' is not installed (tools/install_deps.sh installs slurm-wlm and munge)"
        exit 77
    fi
done
export PATH=$PATH:/usr/sbin
tmp=$(mktemp -d)
chmod 755 "$tmp"  # munged wants its socket's folders open to everyone (execute), the key private
export SLURM_CONF=$tmp/slurm.conf BVHLAB_CACHE_DIR=$tmp/cache
cleanup() {
    [ -s "$tmp/slurmctld.pid" ] && timeout 10 scontrol shutdown >/dev/null 2>&1 && sleep 1
    for f in "$tmp"/slurmctld.pid "$tmp"/slurmd.pid "$tmp"/munge/pid; do [ -s "$f" ] && kill "$(cat "$f")" 2>/dev/null; done
    rm -rf "$tmp"
}
trap cleanup EXIT
. "$(dirname "$0")/check_lib.sh"
die() {
    echo "slurm_sweep.sh: $*"
    for f in "$tmp"/log/* "$tmp"/*.log; do [ -f "$f" ] && { echo "--- $f"; tail -20 "$f"; }; done
    exit 1
}

# The daemons: as root they always start; a user without root may not be allowed to run slurmd
# here, and that is a skip with its reason, not a failure.
startup_failed() {
    if [ "$(id -u)" -ne 0 ]; then
        echo "slurm_sweep.sh: skipped: $* as user $(id -un) (the test starts Slurm as root in CI)"
        for f in "$tmp"/log/*; do [ -f "$f" ] && tail -3 "$f"; done
        exit 77
    fi
    die "$@"
}

# munge: its own key and socket.
mkdir -p "$tmp/munge" "$tmp/state" "$tmp/spool" "$tmp/log"
chmod 755 "$tmp/munge"
head -c 1024 /dev/urandom >"$tmp/munge/munge.key"
chmod 600 "$tmp/munge/munge.key"
munged --key-file="$tmp/munge/munge.key" --socket="$tmp/munge/sock" --pid-file="$tmp/munge/pid" \
    --log-file="$tmp/munge/log" --seed-file="$tmp/munge/seed" || startup_failed "munged did not start"

# Slurm: one node (this host as localhost), ports chosen from the process id.
user=$(id -un)
port=$((20000 + ($$ % 20000)))
cat >"$SLURM_CONF" <<EOF
ClusterName=bvhlabtest
SlurmctldHost=localhost
SlurmUser=$user
SlurmdUser=$user
AuthType=auth/munge
AuthInfo=socket=$tmp/munge/sock
CredType=cred/munge
SlurmctldPort=$port
SlurmdPort=$((port + 1))
StateSaveLocation=$tmp/state
SlurmdSpoolDir=$tmp/spool
SlurmctldPidFile=$tmp/slurmctld.pid
SlurmdPidFile=$tmp/slurmd.pid
SlurmctldLogFile=$tmp/log/slurmctld.log
SlurmdLogFile=$tmp/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
MpiDefault=none
SchedulerType=sched/builtin
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
ReturnToService=2
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
NodeName=localhost CPUs=$(nproc) State=UNKNOWN
PartitionName=debug Nodes=localhost Default=YES MaxTime=INFINITE State=UP
EOF
slurmctld -i >/dev/null 2>&1 || startup_failed "slurmctld did not start"
slurmd -N localhost >/dev/null 2>&1 || startup_failed "slurmd did not start"
for _ in $(seq 1 60); do
    sinfo -h -o %t 2>/dev/null | grep -q idle && break
    sleep 0.5
done
sinfo -h -o %t | grep -q idle || startup_failed "the node did not come up"

cat >"$tmp/grid.json" <<'EOF'
{"name": "slurm-grid", "command": "bench", "scenes": ["gen:soup:2000:1", "gen:soup:2000:2"],
 "grid": {"--builder": ["binned", "sbvh"], "--max-leaf": [2, 4, 8]},
 "args": ["--device", "cpu", "--width", "16", "--height", "16", "--types", "primary", "--runs", "1"]}
EOF
cd "$tmp" || exit 1
"$bin" sweep grid.json --slurm --tasks 3 --json >submit.json 2>submit.err || die "submission failed: $(cat submit.err)"
check "the submission names the array and merge jobs" python3 -c "
import json; j = json.load(open('submit.json'))
assert j['record'] == 'sweep_submit' and j['cells'] == 12 and j['tasks'] == 3 and j['array_job'] and j['merge_job'], j"
check "the job script asks for a 3-task array" grep -q "^#SBATCH --array=0-2$" grid.results.jsonl.slurm.sh
for _ in $(seq 1 600); do
    [ -z "$(squeue -h 2>/dev/null)" ] && break
    sleep 0.5
done
[ -z "$(squeue -h)" ] || die "the jobs did not finish in 5 minutes: $(squeue)"
check "the merge left no part files" [ -z "$(ls grid.results.jsonl.part-* 2>/dev/null)" ]
check "every cell ran once, on the cluster" python3 -c "
import collections, json
n = collections.Counter(json.loads(l)['sweep']['key'] for l in open('grid.results.jsonl') if l.strip())
assert len(n) == 12 and set(n.values()) == {1}, n"
check "each of the 3 tasks ran its cells" [ "$(ls grid.results.jsonl.slurm-*_[0-9].log | wc -l)" -eq 3 ]
"$bin" sweep grid.json --status >status.txt
check "--status: 12 of 12 done" grep -q "12 of 12 cells done" status.txt
"$bin" sweep grid.json --slurm >again.txt
check "a second submission finds nothing to run" grep -q "every cell is done; nothing to submit" again.txt

if [ "$fail" -ne 0 ]; then
    for f in "$tmp"/*.log; do echo "--- $f"; tail -5 "$f"; done
fi
finish "slurm_sweep.sh"
