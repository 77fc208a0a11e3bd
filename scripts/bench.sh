#!/bin/sh
# bench.sh: the work-precision report docs/performance.md (`make bench`).
# Runs `drape bench` on the default Cusick scene, the hang scene at 1 cm and
# 100 x 100 and 200 x 200 hang lattices (scripts/bench/hang-*.yaml), and
# `drape bench --kernels`, plus the Cusick scene at 2 cm (cusick2cm), where
# the dense gsl-msbdf (the paper's Gear method) finishes in time; writes docs/performance/NAME.csv, the plots
# NAME-{pos,final,dc}.png/.svg and kernels.png/.svg (gnuplot, installed with
# apt-get when missing), and regenerates the tables between the GENERATED
# markers of docs/performance.md (scripts/bench/report.py).  Never run by
# the tests.  One benchmark process at a time; each run single-threaded.
#
#   scripts/bench.sh                          everything (hours)
#   BENCH_SCENES="kernels cusick" scripts/bench.sh   a subset; the other
#                                             CSVs and blocks are kept
#
# Environment (defaults in brackets):
#   DRAPE              binary [./drape, built with `make drape`]
#   BENCH_SCENES       names to run [kernels cusick cusick2cm hang hang100 hang200];
#                      `none`: only redraw the plots and tables from the CSVs
#   BENCH_MAX_WALL     wall-time limit per run, s [300]
#   BENCH_REF_MAX_WALL limit per reference run, s [0 = none]
#   BENCH_REF          reference pair A,B [arkode-erk,gsl-rk8pd]
#   BENCH_REF_RTOL     their tolerances X[,Y] [1e-10]
#   BENCH_REPEAT       repeats of runs shorter than 2 s [3]
#   BENCH_SAMPLES      sample times for err_pos_rel [10]
#   BENCH_RTOLS        tolerance sweep [1e-3:1e-8:2: 11 values, half decades]
#   BENCH_INTEGRATORS  comma list [all six]
#   BENCH_RTOLS_<name>, BENCH_INTEGRATORS_<name>, BENCH_REF_RTOL_<name>
#                      per-scene overrides
#   BENCH_T_CUSICK [0.1s]  BENCH_T_HANG [0.3s]  BENCH_T_LARGE [2ms]
#                      horizons (cusick; hang at 1 cm; hang100 and hang200)
#   BENCH_SIZES        lattice sides for --kernels [10,20,50,100,200]
#   BENCH_TIME         time column of plots and tables: cpu_s or wall_s [cpu_s]
#   BENCH_OUT, BENCH_DOC   [docs/performance, docs/performance.md]
set -eu
cd "$(dirname "$0")/.."
ROOT=$(pwd)
OUT=${BENCH_OUT:-docs/performance}
DOC=${BENCH_DOC:-docs/performance.md}
SCENES=${BENCH_SCENES:-kernels cusick cusick2cm hang hang100 hang200}
MAX_WALL=${BENCH_MAX_WALL:-300}
REF_MAX_WALL=${BENCH_REF_MAX_WALL:-0}
REF=${BENCH_REF:-arkode-erk,gsl-rk8pd}
REF_RTOL=${BENCH_REF_RTOL:-1e-10}
REPEAT=${BENCH_REPEAT:-3}
SAMPLES=${BENCH_SAMPLES:-10}
RTOLS=${BENCH_RTOLS:-1e-3:1e-8:2}
INTEGRATORS=${BENCH_INTEGRATORS:-}
T_CUSICK=${BENCH_T_CUSICK:-0.1s}
T_HANG=${BENCH_T_HANG:-0.3s}
T_LARGE=${BENCH_T_LARGE:-2ms}
SIZES=${BENCH_SIZES:-10,20,50,100,200}
TIME=${BENCH_TIME:-cpu_s}
if [ -z "${DRAPE:-}" ] && [ "$SCENES" != none ]; then make -s drape; DRAPE=$ROOT/drape; fi

command -v gnuplot >/dev/null 2>&1 || {
    echo "bench: installing gnuplot-nox" >&2
    apt-get update -q && DEBIAN_FRONTEND=noninteractive \
        apt-get install -y -q --no-install-recommends gnuplot-nox
}
mkdir -p "$OUT"

load1() { cut -d' ' -f1 /proc/loadavg; }

# record NAME ARGS ELAPSED LOAD_BEFORE LOAD_AFTER: one row of runs.csv per
# name (replaced when the name runs again), with the drape commit, CFLAGS
# and date of that run (a partial run leaves the other rows' as they were)
record() {
    python3 - "$OUT/runs.csv" "$@" "$COMMIT" "$CFLAGS_USED" "$(date -u +%F)" <<'PY'
import csv, os, sys
path, name, args, el, lb, la, commit, cflags, date = sys.argv[1:10]
cols = ["name", "args", "elapsed_s", "load_before", "load_after", "commit", "cflags", "date"]
rows = list(csv.DictReader(open(path), restval="")) if os.path.exists(path) else []
new = {"name": name, "args": args, "elapsed_s": el, "load_before": lb, "load_after": la,
       "commit": commit, "cflags": cflags, "date": date}
rows = [new if r["name"] == name else r for r in rows]
if not any(r["name"] == name for r in rows):
    rows.append(new)
with open(path + ".tmp", "w", newline="") as f:
    w = csv.DictWriter(f, cols)
    w.writeheader()
    w.writerows(rows)
os.replace(path + ".tmp", path)
PY
}

# bench NAME ARGS...: run drape bench, time it, record it
bench() {
    name=$1; shift
    eval "rt=\${BENCH_RTOLS_$name:-$RTOLS}"
    eval "it=\${BENCH_INTEGRATORS_$name:-$INTEGRATORS}"
    eval "rr=\${BENCH_REF_RTOL_$name:-$REF_RTOL}"
    set -- "$@" --rtols "$rt" --repeat "$REPEAT" --samples "$SAMPLES" \
        --max-wall "$MAX_WALL" --ref "$REF" --ref-rtol "$rr" --ref-max-wall "$REF_MAX_WALL"
    [ -n "$it" ] && set -- "$@" --integrators "$it"
    echo "bench: $name: drape bench $*" >&2
    lb=$(load1); t0=$(date +%s)
    # into a directory of its own, moved into place only when the run is
    # complete: drape bench rewrites its CSV after every point, and a run
    # that stops half-way must not replace the last complete one (whose
    # command and commit runs.csv keeps)
    part=$(mktemp -d "$OUT/.partial-$name.XXXXXX")
    "$DRAPE" bench "$@" --out "$part" --name "$name" || {
        st=$?
        echo "bench: $name: drape bench failed (exit $st); $OUT/$name.csv left as it was, partial CSV in $part" >&2
        exit "$st"
    }
    mv "$part/$name.csv" "$OUT/$name.csv"
    rmdir "$part"
    record "$name" "$*" "$(( $(date +%s) - t0 ))" "$lb" "$(load1)"
}

COMMIT=$(git rev-parse --short HEAD 2>/dev/null || echo unknown)
[ -n "$(git status --porcelain -- src include 2>/dev/null)" ] && COMMIT="$COMMIT + uncommitted changes"
CFLAGS_USED=${CFLAGS:--O3 -g}

machine() {
    cpu=$(sed -n 's/^model name[^:]*: //p' /proc/cpuinfo | head -1)
    mem=$(awk '/MemTotal/ {printf "%.0f GiB", $2 / 1048576}' /proc/meminfo)
    os=$(. /etc/os-release 2>/dev/null && echo "$PRETTY_NAME")
    {
        echo "cpu=$cpu"; echo "cores=$(nproc)"; echo "mem=$mem"; echo "os=$os"
        echo "commit=$COMMIT"; echo "cflags=$CFLAGS_USED"; echo "date=$(date -u +%F)"
    } > "$OUT/machine.txt"
}

[ "$SCENES" = none ] || machine
for name in $SCENES; do
    case $name in
    none) ;;
    kernels)
        lb=$(load1); t0=$(date +%s)
        echo "bench: kernels: drape bench --kernels --sizes $SIZES" >&2
        # (drape bench --kernels replaces its CSV atomically at the end)
        "$DRAPE" bench --kernels scenes/hang.yaml --sizes "$SIZES" --out "$OUT" --name kernels
        record kernels "--kernels scenes/hang.yaml --sizes $SIZES" "$(( $(date +%s) - t0 ))" "$lb" "$(load1)"
        ;;
    cusick) bench cusick scenes/cusick.yaml --t-end "$T_CUSICK" ;;
    cusick2cm) bench cusick2cm scenes/cusick.yaml --spacing 2cm --t-end "$T_CUSICK" ;;
    hang) bench hang scenes/hang.yaml --t-end "$T_HANG" ;;
    hang100) bench hang100 scripts/bench/hang-100.yaml --t-end "$T_LARGE" ;;
    hang200) bench hang200 scripts/bench/hang-200.yaml --t-end "$T_LARGE" ;;
    *) echo "bench: unknown name $name (kernels cusick cusick2cm hang hang100 hang200)" >&2; exit 2 ;;
    esac
done

# plots of every CSV present (they need no drape run)
mach="$(sed -n 's/^cpu=//p' "$OUT/machine.txt"), 1 thread, shared machine"
if [ -f "$OUT/kernels.csv" ]; then
    gnuplot -e "csv='$OUT/kernels.csv'; out='$OUT/kernels'; machine='$mach'" scripts/bench/kernels.gp
fi
for name in cusick cusick2cm hang hang100 hang200; do
    csv=$OUT/$name.csv
    [ -f "$csv" ] || continue
    integs=$(awk -F, 'NR > 1 && $1 == "sweep" && !seen[$9]++ { printf "%s ", $9 }' "$csv")
    nopts=$(awk -F, 'NR > 1 && $1 == "sweep" { all[$9] = 1; if ($14 == "ok") ok[$9] = 1 }
        END { for (i in all) if (!(i in ok)) printf "%s ", i }' "$csv")
    default=$(awk -F, 'NR > 1 && $10 == "1" { print $9; exit }' "$csv")
    t_end=$(awk -F, 'NR == 2 { print $7 }' "$csv")
    parts=$(awk -F, 'NR == 2 { print $4 }' "$csv")
    title="$name: $parts particles, t in [0, $t_end s]"
    for m in pos final dc; do
        case $m in
        pos) col=err_pos_rel; xl="max position error at the sample times / specimen size" ;;
        final) col=err_final_rel; xl="max position error at t_end / specimen size" ;;
        dc) col=err_dc; xl="|DC - DC_ref| at t_end"
            awk -F, 'NR > 1 && $32 != "" { f = 1 } END { exit !f }' "$csv" || continue ;;
        esac
        gnuplot -e "csv='$csv'; out='$OUT/$name-$m'; err='$col'; time='$TIME'; integrators='$integs'; title='$title'; xlabel='$xl'; default='$default'; machine='$mach'; nopoints='$nopts'" scripts/bench/wp.gp
    done
done
python3 scripts/bench/report.py "$OUT" "$DOC" "$TIME"
echo "bench: wrote $OUT/ and the tables in $DOC" >&2
