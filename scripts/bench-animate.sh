#!/bin/sh
# make bench-animate: the animate method against
# backward Euler under error control, in one run on one core, and where
# animate's time goes.
#
# Cases: the hang scene (two corner pins, cotton-breen, 1 cm) to t = 3 s at
#   hang30    scenes/hang.yaml             31 x 31 particles
#   hang100   scripts/bench/hang-100.yaml  100 x 100
#   hang200   scripts/bench/hang-200.yaml  200 x 200
# Methods:
#   animate   drape run CASE --method animate (one step per 1/30 s frame)
#   be        drape run CASE --method dynamic --integrator cvode-bdf
#             --max-order 1 --rtol 1e-2 --atol 1e-5 (backward Euler, error
#             controlled: the cheapest error-controlled way through the hang)
# Each run alone (-j 1 in effect: one process at a time); CPU seconds from
# the result's cpu_s.  Then `drape bench --kernels` at the same sizes: the
# cost of one force evaluation, one K and D, one factorisation and one
# solve, from which the table splits animate's CPU by kernel.
#
# Results: docs/performance/animate/CASE-METHOD.json (+ .meta: command,
# commit, date), docs/performance/animate/kernels.csv, and the tables
# between the markers "animate-bench" in docs/performance.md.
#
# Environment:
#   BENCH_CASES       cases (default: hang30 hang100 hang200)
#   BENCH_BE_CASES    cases that also run backward Euler (default: hang30
#                     hang100; at 200 x 200 it would take hours)
#   BENCH_TABLES_ONLY=1  rebuild the tables from the files there
#   DRAPE_BIN         the drape binary (./drape)
set -eu
cd "$(dirname "$0")/.."
DRAPE=${DRAPE_BIN:-./drape}
OUT=docs/performance/animate
CASES=${BENCH_CASES:-"hang30 hang100 hang200"}
BE_CASES=${BENCH_BE_CASES-"hang30 hang100"}
COMMIT=$(git rev-parse --short HEAD 2>/dev/null || echo unknown)
[ -z "$(git status --porcelain -- src include 2>/dev/null)" ] || COMMIT="$COMMIT+changes"
mkdir -p "$OUT"

scene_of() {
    case "$1" in
    hang30) echo "scenes/hang.yaml" ;;
    hang100) echo "scripts/bench/hang-100.yaml" ;;
    hang200) echo "scripts/bench/hang-200.yaml" ;;
    *) echo "bench-animate: unknown case $1" >&2; exit 2 ;;
    esac
}

run_one() { # case method args...
    c=$1 m=$2
    shift 2
    f="$OUT/$c-$m.json"
    echo "bench-animate: $c $m: drape run -q $*" >&2
    start=$(date +%s)
    if "$DRAPE" run -q "$@" > "$f.tmp"; then mv "$f.tmp" "$f"; else
        st=$?
        # a failed or interrupted run must not replace the last complete
        # one, nor reach the tables
        mv "$f.tmp" "$f.failed"
        echo "bench-animate: $c $m failed (exit $st; output in $f.failed); $f and the tables left as they were" >&2
        exit 1
    fi
    end=$(date +%s)
    {
        echo "command: drape run -q $*"
        echo "commit: $COMMIT"
        echo "date: $(date -u +%Y-%m-%d)"
        echo "elapsed_s: $((end - start))"
        echo "load_before_after: $(cut -d' ' -f1 /proc/loadavg)"
    } > "$f.meta"
}

if [ "${BENCH_TABLES_ONLY:-0}" != 1 ]; then
    for c in $CASES; do
        sc=$(scene_of "$c")
        run_one "$c" animate "$sc" --method animate
        case " $BE_CASES " in
        *" $c "*) run_one "$c" be "$sc" --method dynamic --integrator cvode-bdf \
                      --max-order 1 --rtol 1e-2 --atol 1e-5 ;;
        esac
    done
    echo "bench-animate: kernels" >&2
    "$DRAPE" bench --kernels scenes/hang.yaml --sizes 31,100,200 -q > "$OUT/kernels.csv.tmp"
    mv "$OUT/kernels.csv.tmp" "$OUT/kernels.csv"
    { echo "command: drape bench --kernels scenes/hang.yaml --sizes 31,100,200"
      echo "commit: $COMMIT"; echo "date: $(date -u +%Y-%m-%d)"; } > "$OUT/kernels.csv.meta"
fi

python3 - "$OUT" <<'PY'
import csv, json, os, re, sys
out = sys.argv[1]
def load(name):
    p = os.path.join(out, name)
    if not os.path.exists(p):
        return None, {}
    try:
        d = json.load(open(p))
    except ValueError:
        d = None
    meta = {}
    if os.path.exists(p + ".meta"):
        for line in open(p + ".meta"):
            k, _, v = line.partition(": ")
            meta[k] = v.strip()
    return d, meta
def g(x, f="%.3g"):
    return "-" if x is None else f % x
side = {"hang30": 31, "hang100": 100, "hang200": 200}
kern = {}
kp = os.path.join(out, "kernels.csv")
if os.path.exists(kp):
    for r in csv.DictReader(open(kp)):
        kern[int(r["side"])] = r
L = []
L.append("| lattice | particles | method | status | steps | CPU s | CPU per step | "
         "energy: start -> end, J | largest rise between output points, J | largest strain | "
         "BE / animate CPU | commit |")
L.append("|---|---|---|---|---|---|---|---|---|---|---|---|")
rows = {}
for c in ["hang30", "hang100", "hang200"]:
    for m in ["animate", "be"]:
        d, meta = load("%s-%s.json" % (c, m))
        if d is None:
            continue
        rows[(c, m)] = d
for c in ["hang30", "hang100", "hang200"]:
    for m in ["animate", "be"]:
        d = rows.get((c, m))
        if d is None:
            continue
        n = side[c]
        ratio = ""
        if m == "be" and (c, "animate") in rows:
            ratio = "%.0f" % (d["cpu_s"] / rows[(c, "animate")]["cpu_s"])
        meta = load("%s-%s.json" % (c, m))[1]
        L.append("| %d x %d | %d | %s | %s | %d | %.2f | %s | %s -> %s | %s | %s | %s | %s |" % (
            n, n, d["particles"], "animate (1/30 s)" if m == "animate" else "backward Euler, rtol 1e-2",
            d["status"], d["steps"], d["cpu_s"], g(d["cpu_s"] / max(d["steps"], 1) * 1e3, "%.1f ms"),
            g(d.get("energy_total_start_J"), "%.4f"), g(d.get("energy_total_end_J"), "%.4f"),
            g(d.get("energy_max_rise_J"), "%.2g"), g(d.get("max_strain_peak"), "%.4f"), ratio,
            meta.get("commit", "?")))
T = []
T.append("| lattice | factorisations (+ refused) | Newton iterations | line-search halvings | factorise, ms | "
         "solve, ms | force, ms | K and D, ms | modelled CPU s: factorise / solve / force + energy / K, D | measured CPU s |")
T.append("|---|---|---|---|---|---|---|---|---|---|")
for c in ["hang30", "hang100", "hang200"]:
    d = rows.get((c, "animate"))
    k = kern.get(side[c])
    if d is None or k is None:
        continue
    fac, tried, it, ls = d["lin_factors"], d["lin_setups"], d["nonlin_iters"], d["err_test_fails"]
    f_ms, s_ms, r_ms, j_ms = (float(k["schur_factor_ms"]), float(k["schur_solve_ms"]),
                              float(k["rhs_ms"]), float(k["jac_ms"]))
    # K and D: jac_evals (each refactorisation; D once for air drag alone);
    # per iteration one force evaluation, one solve; every energy evaluation
    # (one per line-search trial, the predictor's two, the energy check) is
    # counted as a force evaluation (it measures the same segments)
    n_energy = it + ls + 3 * d["steps"]
    parts = (fac * f_ms / 1e3, it * s_ms / 1e3, (it + n_energy) * r_ms / 1e3, d["jac_evals"] * j_ms / 1e3)
    T.append("| %d x %d | %d (+%d) | %d | %d | %.2f | %.2f | %.2f | %.2f | %.2f / %.2f / %.2f / %.2f (sum %.2f) | %.2f |" % (
        side[c], side[c], fac, tried - fac, it, ls, f_ms, s_ms, r_ms, j_ms, *parts, sum(parts), d["cpu_s"]))
text = ("Hang scene to t = 3 s, one process on one core (`make bench-animate`, "
        "scripts/bench-animate.sh; JSON and commands in docs/performance/animate/):\n\n"
        + "\n".join(L) + "\n\nThe 100 x 100 and 200 x 200 scenes write no frames: their "
        "energy balance has two output points, the start and the end (the 30 x 30 one has "
        "a frame every 1/30 s).\n\nWhere animate's time goes: the counters of each run times "
        "the cost of one kernel from `drape bench --kernels` at that size "
        "(docs/performance/animate/kernels.csv; refused factorisations, an indefinite S "
        "shifted and factored again, stop early and are not counted in the model):\n\n"
        + "\n".join(T) + "\n")
doc = "docs/performance.md"
s = open(doc).read()
b, e = "<!-- animate-bench begin: written by scripts/bench-animate.sh; do not edit -->", "<!-- animate-bench end -->"
if b in s and e in s:
    s = s[:s.index(b) + len(b)] + "\n" + text + s[s.index(e):]
else:
    s += "\n## Animate: frames at graphics speed\n\n" + b + "\n" + text + e + "\n"
open(doc + ".tmp", "w").write(s)
os.replace(doc + ".tmp", doc)
open(os.path.join(out, "table.md.tmp"), "w").write(text)
os.replace(os.path.join(out, "table.md.tmp"), os.path.join(out, "table.md"))
print(text)
PY
