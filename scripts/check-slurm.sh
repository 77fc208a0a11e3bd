#!/bin/bash
# check-slurm.sh: test scripts/slurm/ against a real single-node Slurm
# (`make check-slurm`; docs/batch.md).
#
# As root on Debian 12: installs slurm-wlm and munge if missing (apt-get),
# starts munged, slurmctld and slurmd on 127.0.0.1 with a private
# configuration, state and sockets under a temporary directory (nothing in
# /etc is changed), submits a three-fabric batch of a tiny hang scene
# (5 cm spacing, 0.05 s) with scripts/slurm/submit.sh, checks the merged
# results.csv against a local `drape batch` of the same fabrics, and stops
# the daemons it started.  Exit status 0 if the check passed.
#
# Facts (STYLE.md): slurm-wlm 22.05 with munge starts as root with
# ProctrackType=proctrack/linuxproc and TaskPlugin=task/none (no cgroups
# needed); `sbatch --wait` returns the highest exit status of an array.
set -u
cd "$(dirname "$0")/.."
repo=$PWD
DRAPE=${DRAPE:-$repo/drape}
export DRAPE
t0=$(date +%s)
say() { echo "check-slurm: $*" >&2; }
fail() { say "FAILED: $*"; exit 1; }

[ -x "$DRAPE" ] || fail "no drape binary at $DRAPE (run make first)"
if [ "$(id -u)" != 0 ]; then
    say "skipped: needs root (to install and start slurm and munge)"
    exit 77
fi

# ---- install ---------------------------------------------------------------
pkgs="slurm-wlm munge"
missing=
for p in $pkgs; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'ok installed' || missing="$missing $p"
done
if [ -n "$missing" ]; then
    say "installing:$missing"
    # the packages' postinst scripts would start services where systemd runs
    export DEBIAN_FRONTEND=noninteractive
    { apt-get update -q && apt-get install -y -q --no-install-recommends $missing; } >&2 ||
        fail "apt-get install$missing"
fi
t_inst=$(date +%s)

# ---- configure and start ----------------------------------------------------
w=$(mktemp -d /tmp/drape-slurm.XXXXXX)
chmod 755 "$w"
mkdir -p "$w/munge" "$w/state" "$w/spool"
pids=()
cleanup() {
    for f in "$w/slurmd.pid" "$w/slurmctld.pid" "$w/munge/munged.pid"; do
        [ -f "$f" ] && kill "$(cat "$f")" 2>/dev/null
    done
    sleep 1
    for f in "$w/slurmd.pid" "$w/slurmctld.pid" "$w/munge/munged.pid"; do
        [ -f "$f" ] && kill -9 "$(cat "$f")" 2>/dev/null
    done
    if [ "${KEEP:-0}" = 1 ]; then say "kept $w"; else rm -rf "$w"; fi
}
trap cleanup EXIT

# munge: a private key and socket
dd if=/dev/urandom of="$w/munge/munge.key" bs=1024 count=1 status=none
chmod 400 "$w/munge/munge.key"
chmod 700 "$w/munge"
munged --force --key-file="$w/munge/munge.key" --socket="$w/munge/munge.socket" \
    --pid-file="$w/munge/munged.pid" --log-file="$w/munge/munged.log" \
    --seed-file="$w/munge/munged.seed" || fail "munged did not start (see $w/munge/munged.log)"
chmod 755 "$w/munge"

cpus=$(nproc)
cat >"$w/slurm.conf" <<CONF
ClusterName=drapecheck
SlurmctldHost=localhost(127.0.0.1)
SlurmUser=root
SlurmdUser=root
SlurmctldPort=16817
SlurmdPort=16818
AuthType=auth/munge
AuthInfo=socket=$w/munge/munge.socket
CredType=cred/munge
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
SchedulerType=sched/backfill
MpiDefault=none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
ReturnToService=2
StateSaveLocation=$w/state
SlurmdSpoolDir=$w/spool
SlurmctldPidFile=$w/slurmctld.pid
SlurmdPidFile=$w/slurmd.pid
SlurmctldLogFile=$w/slurmctld.log
SlurmdLogFile=$w/slurmd.log
SlurmctldDebug=info
SlurmdDebug=info
NodeName=localhost NodeAddr=127.0.0.1 CPUs=$cpus RealMemory=500 State=UNKNOWN
PartitionName=check Nodes=localhost Default=YES MaxTime=INFINITE State=UP
CONF
export SLURM_CONF=$w/slurm.conf
slurmctld -f "$SLURM_CONF" -i || fail "slurmctld did not start (see $w/slurmctld.log)"
slurmd -f "$SLURM_CONF" -N localhost || fail "slurmd did not start (see $w/slurmd.log)"
for i in $(seq 1 60); do
    state=$(sinfo -h -N -o '%T' 2>/dev/null | head -n 1)
    case $state in idle*) break ;; esac
    sleep 1
done
case $state in idle*) ;; *)
    tail -n 20 "$w/slurmctld.log" "$w/slurmd.log" >&2
    fail "the node is not idle after 60 s (state: ${state:-none})" ;;
esac
t_up=$(date +%s)
say "slurm up: node localhost idle, $cpus CPUs ($((t_up - t_inst)) s to start)"

# ---- a batch through the array ------------------------------------------------
bad=$w/bad-fabric.yaml
printf 'fabric: bad\nwieght: 1\n' >"$bad"
fabrics=("$repo/fabrics/cotton-breen.yaml" "$bad" "$repo/fabrics/denim-wang.yaml")
run=(--spacing 5cm --t-max 0.05s)
scripts/slurm/submit.sh --out "$w/out" scenes/hang.yaml "${fabrics[@]}" -- "${run[@]}"
rc=$?
t_run=$(date +%s)
[ "$rc" = 6 ] || fail "submit.sh exit status $rc, expected 6 (one invalid fabric)"
[ -f "$w/out/results.csv" ] || fail "no merged results.csv"

# the same batch locally: the same rows, but for the timing columns wall_s, cpu_s
"$DRAPE" batch -q scenes/hang.yaml "${fabrics[@]}" "${run[@]}" --out "$w/local"
lrc=$?
[ "$lrc" = 6 ] || fail "local drape batch exit status $lrc, expected 6"
strip() { # blank the timing columns wall_s and cpu_s (no field before them holds a comma)
    awk -F, -v OFS=, 'NR == 1 { for (i = 1; i <= NF; i++) { if ($i == "wall_s") c = i; if ($i == "cpu_s") d = i }
                               if (!c || !d) { print "check-slurm: no wall_s or cpu_s column" > "/dev/stderr"; exit 1 } }
                      { $c = ""; $d = ""; print }' "$1"
}
if ! diff <(strip "$w/local/results.csv") <(strip "$w/out/results.csv") >&2; then
    fail "merged rows differ from a local batch"
fi
[ "$(wc -l <"$w/out/results.csv")" = 4 ] || fail "expected a header and 3 rows"
grep -q ',t_max,' <(sed -n 2p "$w/out/results.csv") || fail "row 1 is not t_max"
grep -q 'wieght: unknown key' <(sed -n 3p "$w/out/results.csv") || fail "row 2 has no error"

# a re-submission with --resume skips the done fabrics (cheap)
scripts/slurm/submit.sh --resume --out "$w/out" scenes/hang.yaml "${fabrics[@]}" -- "${run[@]}"
rc=$?
[ "$rc" = 6 ] || fail "resume: exit status $rc, expected 6"
t_end=$(date +%s)
say "passed: install $((t_inst - t0)) s, start $((t_up - t_inst)) s, array of 3 $((t_run - t_up)) s, total $((t_end - t0)) s"
