#!/usr/bin/env bash
# The render farm's recipe on a real Slurm, on this machine: installs Slurm and munge from
# Debian's packages when they are missing (slurmctld, slurmd, slurm-client, munge; as root or
# with passwordless sudo), starts a one-node cluster with a generated slurm.conf (its own ports,
# state and munge socket under a temporary folder, nothing of /etc touched), submits the
# guide's two job scripts (tools/farm/photons.sh, then the tile array tools/farm/render.sh with
# --dependency=afterok), waits, stitches the tiles and checks the image byte-identical to a
# one-process render. It stops the daemons and leaves nothing running, whatever happens.
#   bash tools/slurm.sh [SCENE] [TILES]     (default scenes/cornell_glass.lua at a quarter, 4)
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
scene=$root/${1:-scenes/cornell_glass.lua}
tiles=${2:-4}
flags="--scale 0.25"
say() { echo "slurm: $*" >&2; }

as_root() {
  if [ "$(id -u)" = 0 ]; then "$@"; elif sudo -n true 2>/dev/null; then sudo -n "$@"; else return 1; fi
}
if ! command -v slurmctld >/dev/null || ! command -v slurmd >/dev/null ||
  ! command -v sbatch >/dev/null || ! command -v munged >/dev/null; then
  say "installing slurmctld, slurmd, slurm-client and munge from Debian's packages"
  as_root env DEBIAN_FRONTEND=noninteractive apt-get update -qq
  as_root env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq slurmctld slurmd \
    slurm-client munge >/dev/null
fi
if [ "$(id -u)" != 0 ]; then
  say "the daemons run as root here (SlurmUser=root): run this as root"
  exit 1
fi

cargo build --release --locked -q
bin=$root/target/release/caustic
work=$(mktemp -d /tmp/caustic-slurm.XXXXXX)
node=$(hostname -s)

# The daemons run in the foreground as this script's children, so that it stops and reaps
# them (a daemon that forks away would be left a zombie where nothing reaps orphans).
daemons=()
stop() {
  local status=$?
  set +e
  [ -n "${SLURM_CONF:-}" ] && scancel --quiet --user=root 2>/dev/null
  for ((k = ${#daemons[@]} - 1; k >= 0; k--)); do
    local pid=${daemons[k]}
    kill "$pid" 2>/dev/null
    for _ in $(seq 100); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
    kill -9 "$pid" 2>/dev/null
    wait "$pid" 2>/dev/null
  done
  if [ "$status" = 0 ]; then rm -rf "$work"; else say "logs kept in $work"; fi
  local left
  left=$(for d in slurmctld slurmd munged; do pgrep -x "$d"; done || true)
  [ -z "$left" ] && say "the daemons are stopped" || say "still running: $left"
  exit "$status"
}
trap stop EXIT

# munge, on its own key and socket.
mkdir -p "$work/munge" "$work/state" "$work/spool" "$work/jobs"
chmod 711 "$work/munge"
dd if=/dev/urandom of="$work/munge/munge.key" bs=1024 count=1 status=none
chmod 600 "$work/munge/munge.key"
munged --foreground --force --key-file="$work/munge/munge.key" \
  --socket="$work/munge/munge.socket" --pid-file="$work/munge/munged.pid" \
  --log-file="$work/munge/munged.log" --seed-file="$work/munge/munge.seed" \
  >"$work/munged.out" 2>&1 &
daemons+=($!)
for _ in $(seq 50); do [ -S "$work/munge/munge.socket" ] && break; sleep 0.1; done

cpus=$(nproc)
memory=$(($(awk '/MemTotal/ {print $2}' /proc/meminfo) / 1024 / 2))
cat >"$work/slurm.conf" <<CONF
ClusterName=caustic
SlurmctldHost=$node(127.0.0.1)
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$work/munge/munge.socket
CryptoType=crypto/munge
SlurmctldPort=16817
SlurmdPort=16818
StateSaveLocation=$work/state
SlurmdSpoolDir=$work/spool
SlurmctldPidFile=$work/slurmctld.pid
SlurmdPidFile=$work/slurmd.pid
SlurmctldLogFile=$work/slurmctld.log
SlurmdLogFile=$work/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
MpiDefault=none
ReturnToService=2
MinJobAge=600
NodeName=$node NodeAddr=127.0.0.1 CPUs=$cpus RealMemory=$memory State=UNKNOWN
PartitionName=render Nodes=$node Default=YES MaxTime=INFINITE State=UP
CONF
export SLURM_CONF=$work/slurm.conf
slurmctld -D -f "$SLURM_CONF" >"$work/slurmctld.out" 2>&1 &
daemons+=($!)
slurmd -D -f "$SLURM_CONF" -N "$node" >"$work/slurmd.out" 2>&1 &
daemons+=($!)
for _ in $(seq 100); do
  sinfo -h -o %T 2>/dev/null | grep -q idle && break
  sleep 0.2
done
sinfo -h -o "%P %D %T %c" | sed 's/^/slurm: partition /' >&2

# The one-process render the tiles must equal, and its size.
cd "$work/jobs"
wrote=$("$bin" render "$scene" $flags -o whole.png 2>&1)
size=$(echo "$wrote" | sed -n 's/.*(\([0-9]*\)x\([0-9]*\)).*/\1 \2/p' | head -1)
read -r width height <<<"$size"
say "one process: $width x $height"

vars="ALL,CAUSTIC=$bin,SCENE=$scene,FLAGS=$flags,WIDTH=$width,HEIGHT=$height,TILES=$tiles"
start=$SECONDS
jid=$(sbatch --parsable --export="$vars" -o photons.out "$root/tools/farm/photons.sh")
aid=$(sbatch --parsable --export="$vars" -o tile-%a.out --dependency=afterok:"$jid" \
  --array=0-$((tiles - 1)) "$root/tools/farm/render.sh")
say "submitted the photon pass ($jid) and $tiles tiles ($aid, after it)"
for _ in $(seq 1200); do
  [ -z "$(squeue -h -j "$jid,$aid" 2>/dev/null)" ] && break
  sleep 0.5
done
# Every job's state (an array's tasks each have theirs).
states=$(for j in "$jid" "$aid"; do scontrol -o show job "$j" 2>/dev/null || true; done |
  sed -n 's/.*JobState=\([A-Z_]*\).*/\1/p' | sort | uniq -c | tr -s ' ')
say "jobs done in $((SECONDS - start)) s:$states"
if [ -z "$states" ] || echo "$states" | grep -qv COMPLETED; then
  say "a job did not complete:"; cat ./*.out >&2; exit 1
fi
"$bin" stitch tile*.png -o stitched.png 2>/dev/null
if cmp -s stitched.png whole.png; then
  say "the stitched image is byte-identical to the one-process render"
else
  say "the stitched image differs from the one-process render"; exit 1
fi
