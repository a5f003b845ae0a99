#!/usr/bin/env bash
# A sharded sweep on a real Slurm: starts slurmctld + slurmd on this machine with a configuration
# written into a temporary folder (no munge: auth/none, cred/none; processes tracked without
# cgroups), submits bench/slurm/sweep.sbatch as a 2-task job array on a tiny sweep (built-in
# Cornell box, 32x32, 3 configurations), waits for it, merges the shards with `gi sweep --merge`
# and checks that every configuration finished ok exactly once and the report was written.
# Exit 77 (ctest: skipped) with the reason only when Slurm cannot be started here.
#   usage: slurm_sweep_test.sh GI_BINARY SOURCE_DIR
set -euo pipefail
gi=$(realpath "$1")
src=$(realpath "$2")

skip() {
  echo "SKIPPED: $*" >&2
  exit 77
}
for tool in slurmctld slurmd sbatch squeue sinfo python3; do
  command -v "$tool" > /dev/null || skip "'$tool' is not installed (setup.sh test installs slurmctld slurmd slurm-client)"
done

work=$(mktemp -d /tmp/gi_slurm_test.XXXXXX)
pids=()
cleanup() {
  for pid in "${pids[@]}"; do kill "$pid" 2> /dev/null || true; done
  for pid in "${pids[@]}"; do
    for _ in $(seq 50); do kill -0 "$pid" 2> /dev/null || break; sleep 0.1; done
  done
  if [ "${keep_work:-0}" = 1 ]; then echo "kept $work" >&2; else rm -rf "$work"; fi
}
trap cleanup EXIT

# Two free TCP ports on localhost.
read -r ctld_port slurmd_port < <(python3 -c '
import socket
s = [socket.socket() for _ in range(2)]
for x in s: x.bind(("127.0.0.1", 0))
print(*[x.getsockname()[1] for x in s])')
host=$(hostname -s)
user=$(id -un)
cpus=$(nproc)
mkdir -p "$work/state" "$work/spool" "$work/log"
export SLURM_CONF="$work/slurm.conf"
cat > "$SLURM_CONF" << EOF
ClusterName=gitest
SlurmctldHost=$host(127.0.0.1)
SlurmUser=$user
SlurmdUser=$user
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
AuthType=auth/none
CredType=cred/none
StateSaveLocation=$work/state
SlurmdSpoolDir=$work/spool
SlurmctldPidFile=$work/slurmctld.pid
SlurmdPidFile=$work/slurmd.pid
SlurmctldLogFile=$work/log/slurmctld.log
SlurmdLogFile=$work/log/slurmd.log
SlurmctldDebug=info
SlurmdDebug=info
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
MpiDefault=none
SchedulerType=sched/builtin
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
ReturnToService=2
SlurmdTimeout=30
InactiveLimit=0
KillWait=5
NodeName=$host NodeAddr=127.0.0.1 CPUs=$cpus State=UNKNOWN
PartitionName=gitest Nodes=$host Default=YES MaxTime=INFINITE State=UP OverSubscribe=YES
EOF

slurmctld -D -i -f "$SLURM_CONF" > "$work/log/slurmctld.out" 2>&1 &
pids+=($!)
slurmd -D -f "$SLURM_CONF" -N "$host" > "$work/log/slurmd.out" 2>&1 &
pids+=($!)

# The node must come up idle; otherwise Slurm cannot run here.
up=0
for _ in $(seq 60); do
  state=$(sinfo -h -N -o '%T' 2> /dev/null | head -1 || true)
  case "$state" in idle*|mixed*|allocated*) up=1; break ;; esac
  sleep 0.5
done
if [ $up != 1 ]; then
  echo "--- slurmctld" >&2; tail -n 20 "$work/log/slurmctld.log" "$work/log/slurmctld.out" >&2 || true
  echo "--- slurmd" >&2; tail -n 20 "$work/log/slurmd.log" "$work/log/slurmd.out" >&2 || true
  skip "single-node Slurm did not come up on this machine (node state '${state:-none}'; logs above)"
fi
echo "slurm up: node $host, ports $ctld_port/$slurmd_port"

cd "$work"
cat > spec.json << 'EOF'
{"name": "slurm test", "resolutions": ["32x32"], "frames": 2, "warmup": 1,
    "set": {"shadow.resolution": 256, "shadow.cube_resolution": 64, "rsm.resolution": 64},
 "techniques": ["direct", {"name": "vpl", "grid": {"vpl.count": [8, 16]}}]}
EOF
# --wait returns when every task of the array has ended; its status is the worst of theirs.
if ! timeout 600 sbatch --wait --array=0-1 --export=ALL,GI_DEVICE=cpu -o "$work/task-%a.out" \
    "$src/bench/slurm/sweep.sbatch" spec.json results "$gi"; then
  for f in "$work"/task-*.out; do echo "--- $f" >&2; cat "$f" >&2; done
  echo "FAILED: the job array did not succeed" >&2
  exit 1
fi
for k in 0 1; do
  grep -q "task $k of 2" "$work/task-$k.out" || { cat "$work/task-$k.out" >&2; echo "FAILED: task $k did not run shard $k/2" >&2; exit 1; }
done

"$gi" sweep --merge results/shard-0 results/shard-1 --out results/merged
python3 - "$work/results" << 'EOF'
import json, os, sys
root = sys.argv[1]
shard_ids = [set(r["id"] for r in json.load(open(f"{root}/shard-{k}/results.json"))["rows"]) for k in (0, 1)]
merged = json.load(open(f"{root}/merged/results.json"))
ids = [r["id"] for r in merged["rows"]]
assert not (shard_ids[0] & shard_ids[1]), "shards overlap"
assert len(shard_ids[0]) == 2 and len(shard_ids[1]) == 1, [len(s) for s in shard_ids]
assert merged["total"] == 3 and len(ids) == 3 and set(ids) == shard_ids[0] | shard_ids[1], merged
for r in merged["rows"]:
    assert r["status"] == "ok", r
    assert os.path.getsize(os.path.join(root, "merged", r["image"])) > 0, r
assert os.path.getsize(f"{root}/merged/report.html") > 1000
print("merged", len(ids), "configurations from 2 Slurm array tasks: ok")
EOF
