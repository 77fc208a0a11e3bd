#!/bin/bash
# submit.sh: run `drape batch` on a Slurm cluster, one array task per fabric
# (docs/batch.md, "On a Slurm cluster").
#
#   scripts/slurm/submit.sh [--out DIR] [--resume] [--max-parallel N]
#                           SCENE.yaml FABRIC.yaml... [-- RUN OPTIONS...]
#
# Writes DIR/fabrics.txt (one fabric per line, absolute paths), submits
# scripts/slurm/drape-array.sbatch as an array of one task per fabric, waits
# for the whole array (`sbatch --wait`), and merges the tasks' rows
# (DIR/tasks/I/results.csv) into DIR/results.csv, in the order of the
# fabrics, with the columns of `drape batch`.  A task that left no row
# (cancelled, out of time, node failure) gets a row with status `error`.
# The merged file is written to a temporary file and renamed.
#
# RUN OPTIONS are passed to every run (--spacing, --t-max, --integrator,
# --rtol, --atol, --energy-form, --max-steps, --frames).  Slurm options
# (partition, time limit, account, ...) are given the Slurm way, through
# its input environment variables: SBATCH_PARTITION, SBATCH_TIMELIMIT,
# SBATCH_ACCOUNT, ... (man sbatch, "INPUT ENVIRONMENT VARIABLES").
# The drape binary is $DRAPE, else `drape` on PATH, else ./drape of the
# repository this script is in; it must be reachable from the nodes.
#
# Without --resume the array's earlier rows in DIR are removed first; with
# it, the fabric list, the scene and the run options must be the same
# (DIR/fabrics.txt, DIR/submit.args) and done fabrics are skipped.
#
# Exit status: 0 every fabric reached equilibrium or t_max; 6 at least one
# failed or has no row; 2 bad command line, or a task refused its own
# (a scene file changed since the first submission); 3 DIR cannot be
# written or sbatch failed to submit.
set -u

usage() {
    sed -n '3,5p' "$0" | sed 's/^# \{0,1\}//' >&2
    exit 2
}

out=batch-out
resume=0
throttle=
while [ $# -gt 0 ]; do
    case $1 in
    --out) [ $# -ge 2 ] || usage; out=$2; shift 2 ;;
    --out=*) out=${1#--out=}; shift ;;
    --resume) resume=1; shift ;;
    --max-parallel) [ $# -ge 2 ] || usage; throttle=$2; shift 2 ;;
    -h|--help) sed -n '2,/^[^#]/p' "$0" | sed -e '$d' -e 's/^# \{0,1\}//'; exit 0 ;;
    -*) echo "submit.sh: unknown option $1" >&2; usage ;;
    *) break ;;
    esac
done
[ $# -ge 2 ] || usage
here=$(cd "$(dirname "$0")" && pwd)
abs() { case $1 in /*) printf '%s\n' "$1" ;; *) printf '%s\n' "$PWD/$1" ;; esac; }
scene=$(abs "$1"); shift
fabrics=()
while [ $# -gt 0 ] && [ "$1" != "--" ]; do
    case $1 in *$'\n'*) echo "submit.sh: a fabric path with a line break" >&2; exit 2 ;; esac
    fabrics+=("$(abs "$1")"); shift
done
[ $# -gt 0 ] && shift # --
run_opts=("$@")
n=${#fabrics[@]}
[ "$n" -ge 1 ] || usage
if [ -n "$throttle" ] && ! [ "$throttle" -ge 1 ] 2>/dev/null; then
    echo "submit.sh: --max-parallel: expected a positive integer" >&2; exit 2
fi

if [ -z "${DRAPE:-}" ]; then
    if command -v drape >/dev/null 2>&1; then DRAPE=$(command -v drape)
    else DRAPE=$here/../../drape; fi
fi
DRAPE=$(abs "$DRAPE")
[ -x "$DRAPE" ] || { echo "submit.sh: no drape binary at $DRAPE (set DRAPE)" >&2; exit 2; }
export DRAPE

mkdir -p "$out" || exit 3
out=$(cd "$out" && pwd)
list=$(printf '%s\n' "${fabrics[@]}")
# the scene and run options, one per line: every task's `drape batch
# --resume` would refuse others (exit 2) after the whole array had run
args=$(printf '%s\n' "$scene" ${run_opts[@]+"${run_opts[@]}"})
if [ "$resume" = 1 ] && [ -f "$out/fabrics.txt" ]; then
    if [ "$list" != "$(cat "$out/fabrics.txt")" ]; then
        echo "submit.sh: --resume: $out/fabrics.txt lists other fabrics; use the same ones or another --out" >&2
        exit 2
    fi
    if [ -f "$out/submit.args" ] && [ "$args" != "$(cat "$out/submit.args")" ]; then
        echo "submit.sh: --resume: $out/submit.args shows another scene or other run options; use the same ones or another --out" >&2
        exit 2
    fi
elif [ "$resume" = 0 ]; then
    rm -rf "$out/tasks" "$out/slurm"
fi
printf '%s\n' "$list" > "$out/fabrics.txt.tmp" && mv "$out/fabrics.txt.tmp" "$out/fabrics.txt" || exit 3
printf '%s\n' "$args" > "$out/submit.args.tmp" && mv "$out/submit.args.tmp" "$out/submit.args" || exit 3
mkdir -p "$out/tasks" "$out/slurm" || exit 3

array="0-$((n - 1))${throttle:+%$throttle}"
echo "submit.sh: $n fabric(s), array $array, output in $out" >&2
jobid=$(sbatch --parsable --wait --array="$array" \
    --output="$out/slurm/%a.out" --error="$out/slurm/%a.out" \
    "$here/drape-array.sbatch" "$out" "$scene" "${run_opts[@]}")
rc=$?
if [ -z "$jobid" ]; then
    echo "submit.sh: sbatch failed (exit status $rc)" >&2
    exit 3
fi
echo "submit.sh: job $jobid finished, highest task exit status $rc" >&2

# ---- merge ---------------------------------------------------------------
csv_quote() { # RFC 4180 field
    case $1 in
    *[,\"]*|" "*|*" ") printf '"%s"' "${1//\"/\"\"}" ;;
    *) printf '%s' "$1" ;;
    esac
}
header=
for ((i = 0; i < n; i++)); do
    f=$out/tasks/$i/results.csv
    if [ -f "$f" ]; then header=$(head -n 1 "$f"); break; fi
done
if [ -z "$header" ]; then
    echo "submit.sh: no task wrote a results file; see $out/slurm/*.out" >&2
    exit 6
fi
IFS=, read -r -a cols <<<"$header"
ncol=${#cols[@]}
missing=0
{
    printf '%s\n' "$header"
    for ((i = 0; i < n; i++)); do
        f=$out/tasks/$i/results.csv
        # rows of drape batch are one line each (it keeps line breaks out)
        if [ -f "$f" ] && [ "$(head -n 1 "$f")" = "$header" ] && [ "$(wc -l <"$f")" -ge 2 ]; then
            tail -n +2 "$f"
            continue
        fi
        missing=$((missing + 1))
        row=$(csv_quote "${fabrics[$i]}")
        for ((c = 1; c < ncol; c++)); do
            case ${cols[$c]} in
            status) row+=",error" ;;
            error) row+=","$(csv_quote "Slurm array task $jobid"_"$i left no row (cancelled, out of time or failed to start); see $out/slurm/$i.out") ;;
            *) row+="," ;;
            esac
        done
        printf '%s\n' "$row"
    done
} >"$out/results.csv.tmp" || exit 3
mv "$out/results.csv.tmp" "$out/results.csv" || exit 3
echo "submit.sh: $out/results.csv ($n rows, $missing without a task row)" >&2
if [ "$rc" -eq 0 ] && [ "$missing" -eq 0 ]; then exit 0; fi
if [ "$rc" -eq 2 ]; then # a task refused its command line (a changed scene file)
    echo "submit.sh: a task refused its command line (exit status 2); see $out/slurm/*.out" >&2
    exit 2
fi
exit 6
