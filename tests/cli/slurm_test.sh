#!/usr/bin/env bash
# tombuild on a real Slurm cluster: starts munged, slurmctld and slurmd (Debian's slurm-wlm and
# munge) on this machine with a generated key and configuration in a temporary folder, then
#  1. submits scripts/slurm/submit.sh's 4-task array and merge job over sample folders and checks
#     the outputs byte-identical to a one-machine run, the merged manifest and summary complete;
#  2. converts again into a fresh folder, cancels the task holding the largest input while it
#     converts, checks that no truncated or temporary file is left and that the merge names the
#     missing shard, resubmits the array and checks that only that shard's inputs are converted.
# Stops the daemons at the end, whatever happens.
set -u
tools="$1"; data="$2"; src="$(cd "$(dirname "$0")/../.." && pwd)"
for d in munged slurmctld slurmd sbatch; do
  command -v "$d" >/dev/null || { echo "$d is not installed: run scripts/install-deps.sh"; exit 1; }
done
[ -s "$data/meshes/bunny00.off" ] || { echo "samples missing: run scripts/fetch-samples.sh"; exit 1; }
work="$(mktemp -d /tmp/tom-slurm.XXXXXX)"; chmod 755 "$work"
export SLURM_CONF="$work/slurm.conf"
stop_cluster() {
  scontrol shutdown >/dev/null 2>&1
  for _ in $(seq 50); do pgrep -f "$work/slurm.conf" >/dev/null || pgrep -x slurmctld >/dev/null || break; sleep 0.2; done
  [ -f "$work/slurmd.pid" ] && kill "$(cat "$work/slurmd.pid")" 2>/dev/null
  [ -f "$work/slurmctld.pid" ] && kill "$(cat "$work/slurmctld.pid")" 2>/dev/null
  munged -s --socket="$work/munge/socket" >/dev/null 2>&1
  sleep 0.5
}
trap 'stop_cluster; rm -rf "$work"' EXIT
. "$(dirname "$0")/check.sh"
show_logs() { tail -n 20 "$work"/log/*.log "$work"/out*/slurm-logs/* 2>/dev/null; }

# --- the cluster ------------------------------------------------------------------------------
mkdir -p "$work/munge" "$work/state" "$work/spool" "$work/log"
chmod 700 "$work/munge"
mungekey --create --keyfile="$work/munge/munge.key" || exit 1
munged --force --key-file="$work/munge/munge.key" --socket="$work/munge/socket" --pid-file="$work/munge/munged.pid" \
  --log-file="$work/munge/munged.log" --seed-file="$work/munge/seed" || { echo "munged did not start"; exit 1; }
node="$(hostname -s)"
port=$((20000 + ($$ % 20000) * 2))  # private ports, two per test run
cat > "$SLURM_CONF" <<EOF
ClusterName=tomtest
SlurmctldHost=$node(127.0.0.1)
SlurmctldPort=$port
SlurmdPort=$((port + 1))
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$work/munge/socket
CredType=cred/munge
StateSaveLocation=$work/state
SlurmdSpoolDir=$work/spool
SlurmctldPidFile=$work/slurmctld.pid
SlurmdPidFile=$work/slurmd.pid
SlurmctldLogFile=$work/log/slurmctld.log
SlurmdLogFile=$work/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
MpiDefault=none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
ReturnToService=2
KillWait=5
MinJobAge=600
NodeName=$node NodeAddr=127.0.0.1 CPUs=$(nproc) State=UNKNOWN
PartitionName=tom Nodes=$node Default=YES MaxTime=INFINITE State=UP
EOF
slurmctld || { echo "slurmctld did not start"; show_logs; exit 1; }
slurmd || { echo "slurmd did not start"; show_logs; exit 1; }
for _ in $(seq 100); do sinfo -h -o %T 2>/dev/null | grep -q idle && break; sleep 0.2; done
check "the one-node cluster is up" bash -c "sinfo -h -o %T | grep -q idle"

# wait_done JOBID...: until none of the jobs is pending or running (at most 5 minutes)
wait_done() {
  for _ in $(seq 1500); do
    [ -z "$(squeue -h -j "$(IFS=,; echo "$*")" 2>/dev/null)" ] && return 0
    sleep 0.2
  done
  echo "jobs $* did not finish"; squeue; show_logs; return 1
}

# --- the batch: the sample meshes, an OBJ with its .mtl and a glTF with its .bin --------------
mkdir -p "$work/in/obj" "$work/in/gltf"
cp "$data"/meshes/*.off "$work/in/"
cp "$data/assimp/OBJ/spider.obj" "$data/assimp/OBJ/spider.mtl" "$work/in/obj/"
cp "$data/assimp/glTF2/BoxTextured-glTF/BoxTextured.gltf" "$data/assimp/glTF2/BoxTextured-glTF/BoxTextured0.bin" "$work/in/gltf/"
inputs=$(find "$work/in" -name '*.off' -o -name '*.obj' -o -name '*.gltf' | wc -l)

"$tools/tombuild" "$work/in" -o "$work/single" --report-json "$work/single-reports" -q || { echo "the one-machine run failed"; exit 1; }

export TOMBUILD="$tools/tombuild"
read -r array merge < <(bash "$src/scripts/slurm/submit.sh" 4 "$work/out" "$work/in" --report-json "$work/out-reports" -q)
check "submit.sh printed the array's and the merge's job ids" test -n "$array" -a -n "$merge"
wait_done "$array" "$merge" || exit 1
check "the 4 tasks each wrote their manifest part" test "$(ls "$work"/out/manifest.shard-*-of-4.jsonl | wc -l)" -eq 4
check "the merge job succeeded" grep -q "merged 4 of 4 shards" "$work"/out/slurm-logs/merge-"$merge".out
same_outputs() {  # same_outputs DIR: every .tom of the one-machine run, byte-identical in DIR, and no other
  local a b
  a=$(cd "$work/single" && find . -name '*.tom' | sort); b=$(cd "$1" && find . -name '*.tom' | sort)
  [ "$a" = "$b" ] || { echo "outputs differ: $a vs $b"; return 1; }
  for f in $a; do cmp -s "$work/single/$f" "$1/$f" || { echo "$f differs"; return 1; }; done
}
check "the array's outputs are byte-identical to the one-machine run's" same_outputs "$work/out"
check "the merged manifest has one record per input" test "$(wc -l < "$work/out/manifest.jsonl")" -eq "$inputs"
# the same records in the same order, seconds aside
strip_seconds() { sed -e 's/,"seconds":[^}]*}/}/' -e "s#$1#DIR#g" "$2"; }
check "the merged manifest is the one-machine manifest (but for the seconds)" \
  diff <(strip_seconds "$work/single" "$work/single/manifest.jsonl" | sed "s#$work/single-reports#R#") \
       <(strip_seconds "$work/out" "$work/out/manifest.jsonl" | sed "s#$work/out-reports#R#")
cut_times() { cut -d, -f1-4,7- "$1"; }  # summary.csv without build_seconds and report_seconds
check "the merged summary.csv is the one-machine summary (but for the timings)" diff <(cut_times "$work/single-reports/summary.csv") <(cut_times "$work/out-reports/summary.csv")
check "no temporary file is left" test -z "$(find "$work/out" -name '*.tmp.*')"

# --- a task cancelled mid-run, then the array resubmitted --------------------------------------
# shard 0 holds the largest input (bunny00.off); with many samples per face it converts for
# several seconds, long enough to be cancelled while it writes
slow=(--samples-per-face 60)
read -r array merge < <(bash "$src/scripts/slurm/submit.sh" 4 "$work/out2" "$work/in" --report-json "$work/out2-reports" "${slow[@]}" -q)
for _ in $(seq 300); do
  [ "$(squeue -h -j "${array}_0" -o %T 2>/dev/null)" = RUNNING ] && break
  sleep 0.1
done
sleep 1
scancel "${array}_0"
wait_done "$array" "$merge" || exit 1
check "the cancelled task left no manifest part (it was stopped mid-run)" test ! -e "$work/out2/manifest.shard-0-of-4.jsonl"
check "the merge names the missing shard" grep -q "shard 0/4 is missing" "$work"/out2/slurm-logs/merge-"$merge".out
check "no temporary file is left after the cancel" test -z "$(find "$work/out2" "$work/out2-reports" -name '*.tmp.*')"
check "every .tom left is complete" bash -c "for f in \$(find '$work/out2' -name '*.tom'); do '$tools/tominfo' \"\$f\" >/dev/null || exit 1; done"
before=$(find "$work/out2" -name '*.tom' | wc -l)
read -r array merge < <(bash "$src/scripts/slurm/submit.sh" 4 "$work/out2" "$work/in" --report-json "$work/out2-reports" "${slow[@]}" -q)
wait_done "$array" "$merge" || exit 1
check "the resubmitted array's merge succeeds" grep -q "merged 4 of 4 shards" "$work"/out2/slurm-logs/merge-"$merge".out
converted=$(grep -c '"status":"converted"' "$work/out2/manifest.jsonl")
fresh=$(grep -c '"status":"up to date"' "$work/out2/manifest.jsonl")
check "only the cancelled shard's inputs are converted again ($converted converted, $fresh up to date, $before outputs before)" \
  test "$converted" -eq $((inputs - before)) -a "$fresh" -eq "$before" -a "$converted" -ge 1
check "the shard converted again is the cancelled one" bash -c "grep '\"status\":\"converted\"' '$work/out2/manifest.jsonl' | grep -q bunny00"
check "every input has its output" test "$(find "$work/out2" -name '*.tom' | wc -l)" -eq "$inputs"

echo "slurm_test: $passed checks passed, $fail failed"
[ "$fail" -eq 0 ]
