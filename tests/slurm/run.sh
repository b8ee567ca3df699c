#!/usr/bin/env bash
# nimbus on a real Slurm, started the way a user would on one machine (issue 15):
#
#   bash tests/slurm/run.sh
#
# Installs Debian's slurm-wlm and munge if missing, writes a one-node slurm.conf for this host
# into a scratch folder, starts munged, slurmctld and slurmd (as root: a throwaway test
# cluster), then, through `nimbus cluster --submit`:
#   1. a render in 4 tiles, merged and compared bit for bit with the same render done locally;
#   2. a 4-frame camera orbit from one radiance graph (a precompute job the frames depend on),
#      each frame compared bit for bit with a local render from the same graph;
#   3. 3 seed batches, one part deleted, `--resume --submit` re-running only it, then merged.
# Stops the daemons it started and removes the scratch folder. About a minute once Slurm is
# installed (the install itself takes about a minute more).
set -euo pipefail

ROOT=$(cd "$(dirname "$0")/../.." && pwd)
NIMBUS=${NIMBUS:-$ROOT/target/release/nimbus}
WORK=$(mktemp -d /tmp/nimbus-slurm.XXXXXX)
HOST=$(hostname -s)
NCPU=$(nproc)
PIDS=()

say() { echo "slurm test: $*"; }
fail() { echo "slurm test: FAILED: $*" >&2; exit 1; }

cleanup() {
    for f in "$WORK"/slurmd.pid "$WORK"/slurmctld.pid "$WORK"/munge/munged.pid; do
        [ -f "$f" ] && kill "$(cat "$f")" 2>/dev/null || true
    done
    sleep 1
    rm -rf "$WORK"
}
trap cleanup EXIT

if ! command -v slurmctld >/dev/null || ! command -v munged >/dev/null; then
    say "installing slurm-wlm and munge"
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -q >/dev/null
    apt-get install -y -q slurm-wlm munge >/dev/null
fi
[ -x "$NIMBUS" ] || cargo build --release --manifest-path "$ROOT/Cargo.toml"

# munge: a key of our own, its socket in the scratch folder.
mkdir -p "$WORK"/munge "$WORK"/state "$WORK"/spool
chmod 700 "$WORK"/munge
dd if=/dev/urandom of="$WORK"/munge/munge.key bs=1024 count=1 status=none
chmod 400 "$WORK"/munge/munge.key
SOCKET="$WORK"/munge/munge.socket
munged --force --key-file="$WORK"/munge/munge.key --socket="$SOCKET" \
    --pid-file="$WORK"/munge/munged.pid --log-file="$WORK"/munge/munged.log \
    --seed-file="$WORK"/munge/munged.seed

export SLURM_CONF="$WORK"/slurm.conf
cat >"$SLURM_CONF" <<EOF
ClusterName=nimbus-test
SlurmctldHost=$HOST(127.0.0.1)
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$SOCKET
CredType=cred/munge
StateSaveLocation=$WORK/state
SlurmdSpoolDir=$WORK/spool
SlurmctldPidFile=$WORK/slurmctld.pid
SlurmdPidFile=$WORK/slurmd.pid
SlurmctldLogFile=$WORK/slurmctld.log
SlurmdLogFile=$WORK/slurmd.log
SlurmctldPort=16817
SlurmdPort=16818
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
SchedulerType=sched/backfill
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
MpiDefault=none
ReturnToService=2
NodeName=$HOST NodeAddr=127.0.0.1 CPUs=$NCPU State=UNKNOWN
PartitionName=test Nodes=ALL Default=YES MaxTime=INFINITE State=UP
EOF
slurmctld
slurmd
for _ in $(seq 60); do
    [[ $(sinfo -h -o %T 2>/dev/null) == *idle* ]] && break
    sleep 1
done
[[ $(sinfo -h -o %T) == *idle* ]] || fail "the node did not come up: $(cat "$WORK"/slurmd.log | tail -5)"
say "Slurm is up ($HOST, $NCPU CPUs)"

# Waits for the jobs whose ids `nimbus cluster --submit` printed (in file $1).
wait_jobs() {
    local ids
    ids=$(awk '/job [0-9]+/ {print $3}' "$1" | paste -sd, -)
    [ -n "$ids" ] || fail "no job ids in $1: $(cat "$1")"
    for _ in $(seq 300); do
        [ -z "$(squeue -h -j "$ids" 2>/dev/null)" ] && return 0
        sleep 1
    done
    fail "jobs $ids still queued after 300 s"
}

# The same pixels: nimbus diff's MSE of exactly 0. Its output is read whole first: piped into
# `grep -q`, which stops at the first line, nimbus could die of SIGPIPE writing the rest, and
# under pipefail that read as a difference (it did once, with MSE 0).
same_pixels() {
    local out
    out=$("$NIMBUS" diff "$1" "$2")
    grep -q '^MSE *0.000000e0$' <<<"$out" || fail "$1 and $2 differ: $(head -3 <<<"$out")"
}

cd "$WORK"
cat >scene.pbrt <<'EOF'
LookAt 0 1 4  0 0.3 0  0 1 0
Camera "perspective" "float fov" 40
Sampler "zsobol" "integer pixelsamples" 8
Film "rgb" "integer xresolution" 48 "integer yresolution" 32
MakeNamedMedium "m" "string type" "homogeneous" "rgb sigma_a" [0.1 0.1 0.1] "rgb sigma_s" [2 2 2]
WorldBegin
LightSource "distant" "point3 from" [1 3 2] "rgb L" [3 3 3]
AttributeBegin
  MediumInterface "m" ""
  Material "interface"
  Shape "sphere" "float radius" 0.8
AttributeEnd
EOF
echo '{"graphBuilder": {"radiusModifier": 40, "dimensionSteps": 60, "iterationsPerStep": 4}, "lightingCalculator": {"bounces": [9]}}' >scene.json

say "1. four tiles"
"$NIMBUS" cluster scene.pbrt --tiles 4 --seed 3 --out tiles --submit | tee tiles.jobs
wait_jobs tiles.jobs
"$NIMBUS" merge tiles -o tiles.exr
"$NIMBUS" render scene.pbrt --seed 3 --quiet --outfile local.exr
same_pixels tiles.exr local.exr
say "   merged tiles = the local render, bit for bit"

say "2. a four-frame radiance-graph orbit"
cat >orbit.txt <<'EOF'
LookAt 0 1 4   0 0.3 0  0 1 0
LookAt 4 1 0   0 0.3 0  0 1 0
LookAt 0 1 -4  0 0.3 0  0 1 0
LookAt -4 1 0  0 0.3 0  0 1 0
EOF
"$NIMBUS" cluster scene.pbrt --cameras orbit.txt --integrator graph --out orbit --submit | tee orbit.jobs
grep -q "precompute job" orbit.jobs || fail "no precompute job for the radiance graph"
wait_jobs orbit.jobs
[ -f orbit/graph/scene_d10.txt ] || fail "the precompute job wrote no graph: $(cat orbit/logs/precompute.log)"
i=0
while read -r _ ex ey ez lx ly lz ux uy uz; do
    f=$(printf "orbit/frame-%03d.exr" $i)
    [ -f "$f" ] || fail "$f missing: $(cat orbit/logs/render-$i.log 2>/dev/null)"
    "$NIMBUS" render scene.pbrt --integrator graph --graph-data orbit/graph/scene_d10.txt --seed 0 --quiet \
        --lookat "$ex" "$ey" "$ez" "$lx" "$ly" "$lz" "$ux" "$uy" "$uz" --outfile local-frame.exr
    same_pixels "$f" local-frame.exr
    i=$((i + 1))
done <orbit.txt
say "   4 frames from one graph = local renders from it, bit for bit"

say "3. seed batches, one lost and resubmitted"
"$NIMBUS" cluster scene.pbrt --seeds 3 --out seeds --submit | tee seeds.jobs
wait_jobs seeds.jobs
rm seeds/seed-001.exr
"$NIMBUS" merge seeds -o seeds.exr 2>merge.err && fail "merge accepted a missing part"
grep -q "seed-001.exr" merge.err || fail "merge did not name the missing part: $(cat merge.err)"
"$NIMBUS" cluster --resume seeds --submit | tee resume.jobs
grep -q "1 of 3 parts missing: seed-001.exr" resume.jobs || fail "resume: $(cat resume.jobs)"
wait_jobs resume.jobs
"$NIMBUS" merge seeds -o seeds.exr
say "   the resubmitted part completed the merge"

say "passed"
