#!/bin/sh
# make bench-ensemble: the drape test as
# a lab runs it, accurate against fast, measured and written down.
#
# For each case (scene, fabric, spacing):
#   accurate  drape run CASE --specimens N_REF --method dynamic --integrator auto
#   fall      drape run CASE --specimens N_FAST            (the default method)
#   compare   drape compare ACCURATE FALL: exact test of the node histograms
#             (p_nodes), Welch's test of the mean DCs, the difference of the
#             means, and the ratio of CPU seconds per specimen.
# The fall ensemble is judged by: (a) p_nodes >= 0.05, (b) |dc_diff| <=
# 0.01 and inside the accurate 95 % interval, (c) cpu_ratio >= 50.
# Also: a second accurate setting on the default scene (the scene's own
# arkode-imex against auto) and the fall ensemble's mean DC against
# the lattice spacing.
#
# Results: docs/performance/ensemble/CASE-{accurate,fall,compare}.json, each
# with a .meta file (command, drape commit, date, CPU and wall seconds), and
# the tables between the markers "ensemble-bench" in docs/performance.md.
#
# Environment:
#   BENCH_CASES   cases to run (default: all; see case_args; " ": none, e.g.
#                 for the spacing study alone)
#   BENCH_REF_SPECIMENS, BENCH_FAST_SPECIMENS   (16, 128: a fall specimen
#                 costs about a second, and with 32 its own interval was as
#                 wide as the reference's)
#   BENCH_JOBS    specimens at a time (2)
#   BENCH_REUSE_ACCURATE=1  keep an accurate JSON that exists (the slow part:
#                 about 50 s of CPU per specimen at 1 cm); its .meta says
#                 which commit made it
#   BENCH_SPACINGS  spacings of the study to run (2cm 1cm 0.75cm 0.5cm; "" =
#                 none); the table shows these and every default spacing
#                 whose ensemble is there
#   BENCH_SPACING_SPECIMENS  specimens per spacing (16; at 0.5 cm a specimen
#                 takes 10-80 s of CPU)
#   BENCH_TABLES_ONLY=1  only rebuild the tables from the JSON files there
#                 (in every mode the tables are stamped with the commits in
#                 the fall ensembles' .meta files, whatever this run made)
#   BENCH_DAMPING_SHEAR  a shear damping for every run (`--damping-shear`,
#                 e.g. 0ms; default none: the fabric's own, docs/model.md 3.6). Its
#                 ensembles go to docs/performance/ensemble/damping-shear-VALUE/
#                 and its tables between the markers "ensemble-bench-damped
#                 VALUE" in docs/performance.md
#   BENCH_CALIBRATE  accurate specimens rerun now for each case (2; 0 = none):
#                 the first seeds of its reference, at -j BENCH_JOBS like the
#                 fall.  A reference made on another day was timed on a
#                 machine of another speed (these machines are shared: the
#                 same accurate specimens took 1.5 times longer on
#                 2026-11-26 than on 2026-11-24), so the CPU ratio (c) is
#                 taken in one run: the reference's CPU per specimen times
#                 the speed factor (these seeds' CPU now / in the
#                 reference), over the fall's CPU now.  Its DCs must be
#                 the reference's (the accurate path is deterministic).
#                 The same for the scene's own integrator where its
#                 ensemble exists (CASE-imex-calib).
#   DRAPE_BIN     the drape binary (./drape)
# The accurate ensembles take 1-2 hours of CPU in all for the first six
# cases and about 80 minutes more for the eight library cases (16 seeds:
# 10-75 s per specimen) and 2.6 hours for the 1 cm table; the fall
# ensembles about 50 minutes in all (20 of them the 1 cm table).
set -eu
cd "$(dirname "$0")/.."
DRAPE=${DRAPE_BIN:-./drape}
OUT=docs/performance/ensemble
N_REF=${BENCH_REF_SPECIMENS:-16}
N_FAST=${BENCH_FAST_SPECIMENS:-128}
JOBS=${BENCH_JOBS:-2}
# the library's other five fabrics at 1 cm: the
# shipped scene as `drape batch` runs it (the bias term where the fabric
# has a bias curve), so that every fabric of fabrics/ is measured; and
# the three older *-wang cases in that model too (*-bias-1cm)
LIBRARY_CASES="denim-1cm blanket-1cm interlock-1cm ponte-1cm cotton-kes-1cm cotton-poly-bias-1cm jacket-bias-1cm tablecloth-bias-1cm"
# the table at 1 cm, the shipped scene: its accurate ensemble costs about 2.6 CPU hours
# (16 specimens, 592 s each), its 128 fall specimens about 20 CPU minutes
ALL_CASES="cotton-1cm cotton-poly-1cm jacket-1cm tablecloth-1cm cotton-2cm table-2cm table-1cm $LIBRARY_CASES"
CASES=${BENCH_CASES:-$ALL_CASES}
SPACINGS=${BENCH_SPACINGS-"2cm 1cm 0.75cm 0.5cm"}
SPACINGS_TABLE=$(for h in 2cm 1cm 0.75cm 0.5cm $SPACINGS; do echo "$h"; done | awk '!seen[$0]++' | tr '\n' ' ')
REUSE=${BENCH_REUSE_ACCURATE:-0}
N_SPACING=${BENCH_SPACING_SPECIMENS:-16}
N_CAL=${BENCH_CALIBRATE:-2}
DAMP=${BENCH_DAMPING_SHEAR:-}
DARGS=""
MARK=ensemble-bench
if [ -n "$DAMP" ]; then
    OUT=docs/performance/ensemble/damping-shear-$DAMP
    DARGS="--damping-shear $DAMP"
    MARK="ensemble-bench-damped $DAMP"
fi
COMMIT=$(git rev-parse --short HEAD 2>/dev/null || echo unknown)
[ -z "$(git status --porcelain -- src include 2>/dev/null)" ] || COMMIT="$COMMIT+changes"
mkdir -p "$OUT"

# The first cases are the seed's model: the *-wang fabrics have bias
# curves, which the shipped Cusick scene uses; these cases measure the
# fall without the bias term, so both runs leave it out.
SEED_TERMS="--terms stretch,bend,shear,gravity"
case_args() { # (an unknown case stops the bench: exit 2 in the $() alone would not)
    m=$(case_args_model "$1") || exit 2
    printf '%s ' "$m" "$DARGS"
}
case_args_model() {
    case "$1" in
    cotton-1cm) echo "scenes/cusick.yaml" ;;
    cotton-poly-1cm) echo "scenes/cusick.yaml --fabric fabrics/cotton-poly-wang.yaml $SEED_TERMS" ;;
    jacket-1cm) echo "scenes/cusick.yaml --fabric fabrics/polyester-jacket-wang.yaml $SEED_TERMS" ;;
    tablecloth-1cm) echo "scenes/cusick.yaml --fabric fabrics/polyester-tablecloth-wang.yaml $SEED_TERMS" ;;
    cotton-2cm) echo "scenes/cusick.yaml --spacing 2cm" ;;
    table-2cm) echo "scenes/table.yaml --spacing 2cm" ;;
    table-1cm) echo "scenes/table.yaml" ;;
    denim-1cm) echo "scenes/cusick.yaml --fabric fabrics/denim-wang.yaml" ;;
    blanket-1cm) echo "scenes/cusick.yaml --fabric fabrics/polyester-blanket-wang.yaml" ;;
    interlock-1cm) echo "scenes/cusick.yaml --fabric fabrics/interlock-knit-wang.yaml" ;;
    ponte-1cm) echo "scenes/cusick.yaml --fabric fabrics/ponte-roma-knit-wang.yaml" ;;
    cotton-kes-1cm) echo "scenes/cusick.yaml --fabric fabrics/cotton-breen-kes.yaml" ;;
    cotton-poly-bias-1cm) echo "scenes/cusick.yaml --fabric fabrics/cotton-poly-wang.yaml" ;;
    jacket-bias-1cm) echo "scenes/cusick.yaml --fabric fabrics/polyester-jacket-wang.yaml" ;;
    tablecloth-bias-1cm) echo "scenes/cusick.yaml --fabric fabrics/polyester-tablecloth-wang.yaml" ;;
    spacing-*) echo "scenes/cusick.yaml --spacing ${1#spacing-}" ;;
    *) echo "bench-ensemble: unknown case $1" >&2; exit 2 ;;
    esac
}

# run NAME ARGS...: drape run ARGS > OUT/NAME.json, with its .meta.  A run
# with a result (exit 0, or 4: every specimen failed, its specimens say
# why) replaces the last one; an interrupted or broken run (no result)
# leaves OUT/NAME.json and .meta as they were (a stored accurate ensemble
# costs hours) and stops the script.
run() {
    name=$1
    shift
    echo "bench-ensemble: $name: drape run $*" >&2
    t=$(mktemp)
    st=0
    /usr/bin/time -f "%U %S %e" -o "$t" "$DRAPE" run -q "$@" > "$OUT/$name.json.tmp" || st=$?
    if [ "$st" -ne 0 ] && { [ "$st" -ne 4 ] || [ ! -s "$OUT/$name.json.tmp" ]; }; then
        mv "$OUT/$name.json.tmp" "$OUT/$name.json.failed"
        rm -f "$t"
        echo "bench-ensemble: $name: exit status $st, no result: $OUT/$name.json left as it was (output in $name.json.failed)" >&2
        exit 1
    fi
    [ "$st" -eq 0 ] || echo "bench-ensemble: $name: exit status $st (kept: its specimens say why)" >&2
    mv "$OUT/$name.json.tmp" "$OUT/$name.json"
    # GNU time writes "Command exited with non-zero status N" before the
    # times when the command fails: the times are its last line
    read -r u s e <<EOT
$(tail -n 1 "$t")
EOT
    rm -f "$t"
    printf 'command: drape run -q %s\ncommit: %s\ndate: %s\ncpu_s: %s\nwall_s: %s\n' \
        "$*" "$COMMIT" "$(date -u +%FT%TZ)" "$(echo "$u $s" | awk '{print $1 + $2}')" "$e" \
        > "$OUT/$name.meta"
}

# compare A B OUT: drape compare A B > OUT, replaced only when complete
compare() {
    "$DRAPE" compare "$1" "$2" > "$3.tmp" || {
        echo "bench-ensemble: drape compare $1 $2 failed; $3 left as it was" >&2
        rm -f "$3.tmp"
        exit 1
    }
    mv "$3.tmp" "$3"
}

# calibrate NAME REFERENCE ARGS...: the first N_CAL seeds of REFERENCE (a
# result JSON) run again now with ARGS, into OUT/NAME.json (BENCH_CALIBRATE)
calibrate() {
    name=$1 ref=$2
    shift 2
    s0=$(python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["specimens"][0]["seed"])' "$ref")
    run "$name" "$@" --specimens "$N_CAL" --seed "$s0" -j "$JOBS"
}

[ "${BENCH_TABLES_ONLY:-0}" = 1 ] && CASES="" && SPACINGS_RUN="" || SPACINGS_RUN=$SPACINGS
for c in $CASES; do
    a=$(case_args "$c")
    # shellcheck disable=SC2086
    if [ "$REUSE" = 1 ] && [ -s "$OUT/$c-accurate.json" ]; then
        echo "bench-ensemble: $c: keeping $OUT/$c-accurate.json ($(grep commit "$OUT/$c-accurate.meta" 2>/dev/null))" >&2
    else
        run "$c-accurate" $a --specimens "$N_REF" -j "$JOBS" --method dynamic --integrator auto
    fi
    # shellcheck disable=SC2086
    run "$c-fall" $a --specimens "$N_FAST" -j "$JOBS"
    # shellcheck disable=SC2086
    [ "$N_CAL" -le 0 ] ||
        calibrate "$c-calib" "$OUT/$c-accurate.json" $a --method dynamic --integrator auto
    compare "$OUT/$c-accurate.json" "$OUT/$c-fall.json" "$OUT/$c-compare.json"
    # the scene's own integrator (arkode-imex), where its ensemble was made
    # (cotton here; cotton-poly and tablecloth by hand, their .meta says how)
    if [ -s "$OUT/$c-imex.json" ]; then
        # its CPU in this run too (the scene's integrator)
        # shellcheck disable=SC2086
        [ "$N_CAL" -le 0 ] || calibrate "$c-imex-calib" "$OUT/$c-imex.json" $a --method dynamic
        compare "$OUT/$c-imex.json" "$OUT/$c-fall.json" "$OUT/$c-imex-fall-compare.json"
        compare "$OUT/$c-accurate.json" "$OUT/$c-imex.json" "$OUT/$c-imex-compare.json"
    fi
done
# a second accurate setting, the scene's own integrator (arkode-imex)
case " $CASES " in
*" cotton-1cm "*)
    if [ "$REUSE" = 1 ] && [ -s "$OUT/cotton-1cm-imex.json" ]; then
        echo "bench-ensemble: keeping $OUT/cotton-1cm-imex.json" >&2
    else
        # shellcheck disable=SC2086
        run cotton-1cm-imex scenes/cusick.yaml $DARGS --specimens "$N_REF" -j "$JOBS" --method dynamic
    fi
    compare "$OUT/cotton-1cm-accurate.json" "$OUT/cotton-1cm-imex.json" "$OUT/cotton-1cm-imex-compare.json"
    compare "$OUT/cotton-1cm-imex.json" "$OUT/cotton-1cm-fall.json" "$OUT/cotton-1cm-imex-fall-compare.json" ;;
esac
# the comparisons, again for every case whose ensembles exist (cheap; so
# that BENCH_TABLES_ONLY=1 picks up what a newer `drape compare` reports)
for c in $ALL_CASES; do
    [ -s "$OUT/$c-accurate.json" ] && [ -s "$OUT/$c-fall.json" ] || continue
    compare "$OUT/$c-accurate.json" "$OUT/$c-fall.json" "$OUT/$c-compare.json"
    if [ -s "$OUT/$c-imex.json" ]; then
        compare "$OUT/$c-imex.json" "$OUT/$c-fall.json" "$OUT/$c-imex-fall-compare.json"
        compare "$OUT/$c-accurate.json" "$OUT/$c-imex.json" "$OUT/$c-imex-compare.json"
    fi
done
# the fall ensemble against the spacing
for h in $SPACINGS_RUN; do
    # shellcheck disable=SC2046
    run "spacing-$h-fall" $(case_args "spacing-$h") --specimens "$N_SPACING" -j "$JOBS"
done

# the tables' stamp names the commits that ran the fall ensembles in them
# (their .meta files), not only this checkout: a run of some cases or only
# the spacings (BENCH_CASES, BENCH_SPACINGS) or none (BENCH_TABLES_ONLY)
# rewrites tables whose other rows came from earlier commits
RUNS=$(sed -n 's/^commit: //p' "$OUT"/*-fall.meta 2>/dev/null | sort -u | paste -sd, -)
[ "$RUNS" = "$COMMIT" ] || COMMIT="${RUNS:-unknown}; tables written with $COMMIT"

python3 - "$OUT" "$COMMIT" "$N_REF" "$N_FAST" "$SPACINGS_TABLE" "$MARK" "$DAMP" "$ALL_CASES" "$LIBRARY_CASES" <<'EOF'
import json, math, os, re, sys
out, commit, n_ref, n_fast, spacings, mark, damp, all_cases, library_cases = sys.argv[1:10]
def load(name):
    p = os.path.join(out, name)
    return json.load(open(p)) if os.path.exists(p) else None
def meta(name):
    p = os.path.join(out, name + ".meta")
    d = {}
    if os.path.exists(p):
        for l in open(p):
            k, _, v = l.partition(": ")
            d[k] = v.strip()
    return d
def hist(h):
    return ", ".join("%s: %d" % (k, h[k]) for k in sorted(h, key=int))
def fmt(d):
    return "%.4f +- %.4f" % (d["dc"], d["dc_ci95"]) if d.get("dc_ci95") is not None else "%.4f" % d["dc"]
rows = []
cases = all_cases.split()
def calibration(c, ref_name="accurate", cal_name="calib"):
    """Speed factor of this run's machine against the reference's: the
    accurate specimens rerun now (c-calib.json) over the same seeds' CPU in
    the reference (c-accurate.json), and whether their DCs are the
    reference's; (None, None) without a calibration."""
    cal, ref = load(c + "-" + cal_name + ".json"), load(c + "-" + ref_name + ".json")
    if not cal or not ref:
        return None, None
    by_seed = {s["seed"]: s for s in ref["specimens"]}
    now = then = 0.0
    same = True
    for s in cal["specimens"]:
        r = by_seed.get(s["seed"])
        if r is None or s.get("cpu_s") is None or r.get("cpu_s") is None:
            return None, None
        now += s["cpu_s"]
        then += r["cpu_s"]
        same = same and s["dc"] is not None and r["dc"] is not None and abs(s["dc"] - r["dc"]) < 1e-6
    return (now / then if then > 0 else None), same
def one_run(c, ref, other, recorded, ref_name, cal_name, notes):
    """(c)'s ratio measured in one run where CASE-cal_name exists (else the
    recorded one), the "; now" CPU cell, the "; ratio" cell; appends the
    speed factor to notes."""
    k, same = calibration(c, ref_name, cal_name)
    if k is None:
        return recorded, "", ""
    now = ref["cpu_per_specimen_s"] * k
    notes.append("%s %.2f (%d seeds%s)" % (
        c, k, len(load(c + "-" + cal_name + ".json")["specimens"]),
        "" if same else ", DCs NOT the reference's"))
    ratio = now / other["cpu_per_specimen_s"]
    return ratio, "; %.1f" % now, "; %.0f" % ratio
lines = ["| case | accurate: n, DC +- 95 %, nodes | CPU s / specimen: as recorded; now | fall: n, DC +- 95 %, nodes | CPU s / specimen | p_nodes (a) | DC diff (b) | p_dc_dist | CPU ratio (c): as recorded; one run | a b c |",
         "|---|---|---|---|---|---|---|---|---|---|"]
notes = []
for c in cases:
    cmp = load(c + "-compare.json")
    if not cmp:
        continue
    r, o = cmp["reference"], cmp["other"]
    a_ok = cmp["p_nodes"] >= 0.05
    b_ok = abs(cmp["dc_diff"]) <= 0.01 and (cmp["dc_in_ci95"] == 1 or r["dc_ci95"] is None
                                            or abs(cmp["dc_diff"]) <= r["dc_ci95"])
    ratio, now_ref, ratio_cell = one_run(c, r, o, cmp["cpu_ratio"], "accurate", "calib", notes)
    c_ok = ratio is not None and ratio >= 50
    lines.append("| %s | %d, %s, {%s} | %.1f%s | %d, %s, {%s} | %.2f | %.3f | %+.4f%s%s | %s | %.0f%s | %s |" % (
        c, r["n"], fmt(r), hist(r["nodes_hist"]), r["cpu_per_specimen_s"], now_ref,
        o["n"], fmt(o), hist(o["nodes_hist"]), o["cpu_per_specimen_s"], cmp["p_nodes"],
        cmp["dc_diff"], " +- %.4f" % cmp["dc_diff_ci95"] if cmp.get("dc_diff_ci95") is not None else "",
        "" if cmp["dc_in_ci95"] else " (outside)",
        "%.4f" % cmp["p_dc_dist"] if cmp.get("p_dc_dist") is not None else "", cmp["cpu_ratio"],
        ratio_cell,
        " ".join("yes" if x else "NO" for x in (a_ok, b_ok, c_ok))))
lib = [c for c in library_cases.split() if load(c + "-compare.json")]
if lib:
    lines += ["", "Models: cotton-poly, the jacket and the tablecloth in the seed's model (`--terms "
              "stretch,bend,shear,gravity`: their references predate the bias term); " +
              ", ".join(lib) + " as the shipped scene runs them (`drape batch`): the bias term "
              "where the fabric has a bias curve (the `*-wang` fabrics; cotton-breen-kes has none)."]
if notes:
    lines += ["", "CPU in one run: the accurate specimens of each case's first seeds were run again "
              "with this fall ensemble (`CASE-calib`, at the same `-j`); the speed factor is their "
              "CPU now over theirs in the reference, and the reference's CPU per specimen times it "
              "is the \"now\" figure that (c) uses. Speed factors: " + "; ".join(notes) + "."]
prov = []
for c in cases:
    for k in ("accurate", "fall", "calib", "imex-calib"):
        m = meta("%s-%s" % (c, k))
        if m:
            prov.append("- `%s-%s`: `%s` (drape %s, %s; %s CPU s, %s s wall)" % (
                c, k, m.get("command", "?"), m.get("commit", "?"), m.get("date", "?"),
                m.get("cpu_s", "?"), m.get("wall_s", "?")))
for h in spacings.split():
    m = meta("spacing-%s-fall" % h)
    if m:
        prov.append("- `spacing-%s-fall`: `%s` (drape %s, %s; %s CPU s, %s s wall)" % (
            h, m.get("command", "?"), m.get("commit", "?"), m.get("date", "?"),
            m.get("cpu_s", "?"), m.get("wall_s", "?")))
imex = load("cotton-1cm-imex-compare.json")
second = []
if imex:
    r, o = imex["reference"], imex["other"]
    second = ["| setting | n | DC +- 95 % | sd | nodes | CPU s / specimen |", "|---|---|---|---|---|---|",
              "| auto, rtol 1e-4 | %d | %s | %.4f | {%s} | %.1f |" % (r["n"], fmt(r), r["dc_sd"], hist(r["nodes_hist"]), r["cpu_per_specimen_s"]),
              "| arkode-imex, rtol 1e-4 (the scene's) | %d | %s | %.4f | {%s} | %.1f |" % (o["n"], fmt(o), o["dc_sd"], hist(o["nodes_hist"]), o["cpu_per_specimen_s"]),
              "", "Exact test of the node histograms p = %.3f, Welch's test of the means p = %.3f, difference %+.4f." % (imex["p_nodes"], imex["p_mean"], imex["dc_diff"])]
    m = meta("cotton-1cm-imex")
    if m:
        prov.append("- `cotton-1cm-imex`: `%s` (drape %s, %s)" % (m.get("command", "?"), m.get("commit", "?"), m.get("date", "?")))
# the fall against the scene's own integrator (arkode-imex, rtol 1e-4: what
# `--method dynamic` runs), where that ensemble exists
own = ["| case | imex: n, DC +- 95 %, nodes | CPU s / specimen: as recorded; now | imex vs auto: p_nodes, p_mean | fall vs imex: p_nodes (a) | DC diff (b) | p_dc_dist | CPU ratio (c): as recorded; one run | a b c |",
       "|---|---|---|---|---|---|---|---|---|"]
own_notes = []
for c in cases:
    fc, ac = load(c + "-imex-fall-compare.json"), load(c + "-imex-compare.json")
    if not fc:
        continue
    r = fc["reference"]
    a_ok = fc["p_nodes"] >= 0.05
    b_ok = abs(fc["dc_diff"]) <= 0.01 and (fc["dc_in_ci95"] == 1 or abs(fc["dc_diff"]) <= (r["dc_ci95"] or 0))
    ratio, now_ref, ratio_cell = one_run(c, r, fc["other"], fc["cpu_ratio"], "imex", "imex-calib",
                                         own_notes)
    c_ok = ratio is not None and ratio >= 50
    own.append("| %s | %d, %s, {%s} | %.1f%s | %s | %.3f | %+.4f%s | %s | %.0f%s | %s |" % (
        c, r["n"], fmt(r), hist(r["nodes_hist"]), r["cpu_per_specimen_s"], now_ref,
        "%.3f, %.3f" % (ac["p_nodes"], ac["p_mean"]) if ac else "",
        fc["p_nodes"], fc["dc_diff"], "" if fc["dc_in_ci95"] else " (outside)",
        "%.4f" % fc["p_dc_dist"] if fc.get("p_dc_dist") is not None else "", fc["cpu_ratio"],
        ratio_cell,
        " ".join("yes" if x else "NO" for x in (a_ok, b_ok, c_ok))))
    m = meta(c + "-imex")
    if m and c != "cotton-1cm":
        prov.append("- `%s-imex`: `%s` (drape %s, %s; %s CPU s, %s s wall)" % (
            c, m.get("command", "?"), m.get("commit", "?"), m.get("date", "?"),
            m.get("cpu_s", "?"), m.get("wall_s", "?")))
if own_notes:
    own += ["", "Speed factors of the scene's integrator in this run (its specimens of the first "
            "seeds timed again, `CASE-imex-calib`): " + "; ".join(own_notes) + "."]
sp = ["| spacing | particles | n | DC +- 95 % | sd | nodes | dc_mode | CPU s / specimen |", "|---|---|---|---|---|---|---|---|"]
pts = []
for h in spacings.split():
    d = load("spacing-%s-fall.json" % h)
    if not d:
        continue
    n = len([s for s in d["specimens"] if s["dc"] is not None])
    sp.append("| %s | %d | %d | %s | %.4f | {%s} | %.4f | %.2f |" % (
        h, d["particles"], n, fmt(d), d["dc_sd"] or 0, hist(d["nodes_hist"]), d["dc_mode"],
        d["cpu_s"] / max(1, len(d["specimens"]))))
    pts.append((float(h[:-2]), d["dc"], d["dc_ci95"]))
fit = ""
if len(pts) >= 2:
    f = sorted(pts, reverse=True)
    fit = ("Mean DC from the coarsest to the finest spacing: " +
           ", ".join("%.4f (%s cm)" % (d, ("%g" % h)) for h, d, _ in f) +
           "; differences between neighbours: " +
           ", ".join("%+.4f" % (f[i + 1][1] - f[i][1]) for i in range(len(f) - 1)) + ".")
text = ["<!-- %s begin: written by scripts/bench-ensemble.sh; do not edit -->" % mark,
        "", "Regenerated by `make bench-ensemble%s` (drape %s). %sAccurate: `--method dynamic "
        "--integrator auto` (rtol 1e-4) to equilibrium, %s specimens (or more where a reference was extended: n); fall: the default "
        "method, %s specimens. (a) exact test of the node histograms p >= 0.05; (b) mean DC "
        "within 0.01 and inside the accurate 95 %% interval (the DC diff column adds the 95 %% "
        "half-width of the difference itself, Welch: the uncertainty of both means); (c) at "
        "least 50 times less CPU per specimen, judged on the ratio measured in one run where "
        "there is one (the accurate specimens of the first seeds timed again with the fall)." % (
            " BENCH_DAMPING_SHEAR=" + damp if damp else "", commit,
            ("Every run with `--damping-shear %s` in place of the fabric's own shear damping. " % damp) if damp else "",
            n_ref, n_fast), ""] + lines + ["", "Second accurate setting, default scene:", ""] + second + \
       ["", "The same fall ensembles against the scene's own integrator, arkode-imex at rtol 1e-4 (`--method dynamic`), where its 16-specimen ensemble exists; its agreement with auto is the second accurate setting of those fabrics:", ""] + own + \
       (["", "The fall method's ensemble against the lattice spacing, default scene:", ""] + sp + ["", fit] if len(sp) > 2 else []) + ["", "Provenance:", ""] + prov + ["", "<!-- %s end -->" % mark]
open(os.path.join(out, "table.md"), "w").write("\n".join(text) + "\n")
p = "docs/performance.md"
doc = open(p).read()
block = "\n".join(text)
begin, end = "<!-- %s begin" % mark, "<!-- %s end -->" % mark
if begin in doc:
    doc = re.sub(re.escape(begin) + r".*?" + re.escape(end), lambda m: block, doc, flags=re.S)
elif damp:
    doc = doc.rstrip("\n") + ("\n\n## The drape test with shear damping %s (not the model's (docs/model.md) model)\n\n" % damp) + block + "\n"
else:
    doc = doc.rstrip("\n") + "\n\n## The drape test: accurate against fast ensembles\n\n" + block + "\n"
open(p + ".tmp", "w").write(doc)
os.replace(p + ".tmp", p)
print("\n".join(lines))
EOF
echo "bench-ensemble: tables in $OUT/table.md and docs/performance.md"
