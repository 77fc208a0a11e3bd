#!/bin/sh
# bench-quick.sh: wall time, steps and drape coefficient of the default
# Cusick and hang scenes for every integrator on this machine.
# Writes docs/bench-quick.csv and the table between the
# GENERATED markers of docs/integrators.md.  Never run by the tests.
#
#   scripts/bench-quick.sh                    (or `make bench-quick`)
#   BENCH_TIMEOUT=120 scripts/bench-quick.sh  (seconds allowed per run)
#   BENCH_JOBS=2 scripts/bench-quick.sh       (the two scenes side by side)
#   BENCH_INTEGRATORS="arkode-imex" scripts/bench-quick.sh
#                      (rerun only these rows, e.g. after a change to one
#                      integrator, and replace them in docs/bench-quick.csv;
#                      `static` names the static method)
#
# Each run is one process, single-threaded (drape sets its BLAS and OpenMP
# thread counts to 1).  A run that exceeds BENCH_TIMEOUT gets SIGTERM,
# which makes drape stop within one model evaluation and print its result
# so far (status interrupted): it is recorded as `timeout` with the
# simulated time it reached and its counters.  BENCH_JOBS=2 runs the Cusick
# and the hang list at the same time, one process each (use it only on a
# machine with two idle cores).  The machine is shared and noisy: compare
# ratios within one run of this script, not across runs.
set -eu
cd "$(dirname "$0")/.."
T=${BENCH_TIMEOUT:-300}
DOC=docs/integrators.md
CSV=docs/bench-quick.csv
BEGIN='<!-- BEGIN GENERATED: scripts/bench-quick.sh -->'
END='<!-- END GENERATED -->'
[ -x ./drape ] || make drape
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

HEADER="scene,method,integrator,status,t_end_s,wall_s,cpu_s,steps,rhs_evals,jac_evals,lin_setups,dc,nodes,max_strain"
JOBS=${BENCH_JOBS:-1}
load0=$(cut -d" " -f1-3 /proc/loadavg)
run() { # scene method integrator csv-file
    scene=$1 method=$2 integ=$3 csv=$4
    args="run -q scenes/$scene.yaml --method $method --format csv"
    [ "$method" = dynamic ] && args="$args --integrator $integ"
    echo "bench: $scene $method $integ (limit $T s)" >&2
    set +e
    # CPU time (user + system) of the run: less disturbed by other jobs
    # on a shared machine than the wall time
    /usr/bin/time -f "%U %S" -o "$tmp/time.$scene" timeout "$T" ./drape $args > "$tmp/out.$scene" 2> "$tmp/err.$scene"
    st=$?
    set -e
    cpu=$(awk 'END { if (NF >= 2) printf "%.3f", $1 + $2 }' "$tmp/time.$scene" 2>/dev/null || true)
    python3 - "$scene" "$method" "$integ" "$tmp/out.$scene" "$cpu" "$st" "$T" >> "$csv" <<'PY'
import csv, sys
scene, method, integ, path, cpu, st, limit = sys.argv[1:8]
rows = list(csv.DictReader(open(path)))
if not rows:
    status = "timeout" if st == "124" else "error"
    wall = limit if st == "124" else ""
    print(f"{scene},{method},{integ},{status},,{wall},{cpu},,,,,,,")
    sys.exit(0)
r = rows[0]
if st == "124":   # stopped by the time limit: keep what it reached
    r["status"] = "timeout"
keys = ["status", "t_end_s", "wall_s"]
keys2 = ["steps", "rhs_evals", "jac_evals", "lin_setups", "dc", "nodes", "max_strain"]
print(",".join([scene, method, integ] + [r.get(k, "") for k in keys] + [cpu] + [r.get(k, "") for k in keys2]))
PY
}

INTEGS=${BENCH_INTEGRATORS:-"static auto cvode-bdf arkode-imex arkode-dirk arkode-erk gsl-rk8pd gsl-msbdf"}
scene_list() { # scene csv-file
    for integ in $INTEGS; do
        if [ "$integ" = static ]; then run "$1" static static "$2"
        else run "$1" dynamic "$integ" "$2"; fi
    done
}

: > "$tmp/csv.cusick"; : > "$tmp/csv.hang"
if [ "$JOBS" -ge 2 ]; then
    scene_list cusick "$tmp/csv.cusick" &
    pid=$!
    scene_list hang "$tmp/csv.hang"
    wait $pid
else
    scene_list cusick "$tmp/csv.cusick"
    scene_list hang "$tmp/csv.hang"
fi
{ echo "$HEADER"; cat "$tmp/csv.cusick" "$tmp/csv.hang"; } > "$tmp/csv"
PARTIAL=""
if [ -n "${BENCH_INTEGRATORS:-}" ] && [ -f "$CSV" ]; then
    # replace the rerun rows in the previous record, keep the others
    python3 - "$CSV" "$tmp/csv" > "$tmp/merged" <<'PY'
import csv, sys
old = list(csv.DictReader(open(sys.argv[1])))
new = list(csv.DictReader(open(sys.argv[2])))
fields = open(sys.argv[2]).readline().strip().split(",")
key = lambda r: (r["scene"], r["integrator"])
fresh = {key(r): r for r in new}
rows = [fresh.pop(key(r), r) for r in old] + list(fresh.values())
w = csv.DictWriter(sys.stdout, fieldnames=fields, lineterminator="\n")
w.writeheader()
for r in rows: w.writerow({k: r.get(k, "") for k in fields})
PY
    mv "$tmp/merged" "$tmp/csv"
    PARTIAL="$BENCH_INTEGRATORS"
fi
cp "$tmp/csv" "$CSV"
load1=$(cut -d" " -f1-3 /proc/loadavg)

COMMIT=$(git rev-parse --short HEAD 2>/dev/null || echo unknown)
git diff --quiet HEAD 2>/dev/null || COMMIT="$COMMIT (with uncommitted changes)"
python3 - "$CSV" "$DOC" "$BEGIN" "$END" "$T" "$load0" "$load1" "$JOBS" "$PARTIAL" "$COMMIT" <<'PY'
import csv, sys, platform, os, datetime
path, doc, begin, end, limit, load0, load1, jobs, partial, commit = sys.argv[1:11]
rows = list(csv.DictReader(open(path)))
def f(v, fmt):
    try: return fmt % float(v)
    except ValueError: return v or "-"
cpu = "unknown"
try:
    for line in open("/proc/cpuinfo"):
        if line.startswith("model name"):
            cpu = line.split(":", 1)[1].strip(); break
except OSError: pass
text = open(doc).read()
head = (f"`scripts/bench-quick.sh` (`make bench-quick`) at drape {commit} on "
        f"{datetime.date.today().isoformat()}, {cpu}, {os.cpu_count()} cores, "
        f"{jobs} process(es) at a time, time limit {limit} s per run (wall; a run "
        f"stopped by it shows the simulated time it reached); load average {load0} "
        f"at the start and {load1} at the end")
if partial and begin in text:
    # keep the provenance of the rows that were not rerun
    prev = text[text.index(begin):text.index(end)].splitlines()
    runs = [("- other rows: " + l[len("Generated by "):]) if l.startswith("Generated by ")
            else l for l in prev if l.startswith("Generated by ") or l.startswith("- ")]
    lines = ["Generated in parts:", ""] + runs + [f"- rows {partial}: {head}", ""]
else:
    lines = [f"Generated by {head}.", ""]
out = [begin, ""] + lines + [
       "The machine is shared: CPU s is the steadier figure.  Raw data: "
       "`docs/bench-quick.csv`.", "",
       "| scene | method | integrator | status | t_end (s) | wall (s) | CPU (s) | steps | RHS | Jac | lin. setups | DC | nodes |",
       "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
for r in rows:
    out.append("| " + " | ".join([r["scene"], r["method"], r["integrator"], r["status"],
        f(r["t_end_s"], "%.3g"), f(r["wall_s"], "%.3g"), f(r["cpu_s"], "%.3g"), r["steps"] or "-", r["rhs_evals"] or "-",
        r["jac_evals"] or "-", r["lin_setups"] or "-", f(r["dc"], "%.4f"), r["nodes"] or "-"]) + " |")
out += ["", end]
text = open(doc).read()
if begin in text and end in text:
    a = text.index(begin); b = text.index(end) + len(end)
    text = text[:a] + "\n".join(out) + text[b:]
else:
    text = text.rstrip("\n") + "\n\n" + "\n".join(out) + "\n"
open(doc + ".tmp", "w").write(text)
os.replace(doc + ".tmp", doc)
PY
echo "bench-quick: wrote $CSV and the table in $DOC" >&2
