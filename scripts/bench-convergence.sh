#!/bin/sh
# make bench-convergence: the drape test against the lattice spacing
# (docs/model.md 6, "Converged in the spacing"; docs/convergence.md).
#
# For each fabric F and spacing h, on the shipped Cusick scene:
#   fall      drape run scenes/cusick.yaml --fabric F --spacing h
#             --specimens N_FALL            (the default method)
#   accurate  the same with --method dynamic --integrator auto, N_ACC
#             specimens (N_ACC_FINE at the spacings FINE_ACC, where a
#             specimen costs more than 10 CPU minutes)
# each an ensemble with --out WORK/F-h-METHOD, so that an interrupted run
# is taken up again (drape run --resume) by the next call, and each
# result with a .meta (command, commit, date, CPU and wall seconds) in
# OUT.  Then drape compare: each spacing against the one half as fine
# (the convergence test of docs/model.md 6: the mean moves by less than 0.01
# and the node histograms are not distinguished at 5 %), and the fall
# against the accurate ensemble at the same spacing; and the tables
# between the markers "convergence-bench" in docs/convergence.md.
#
# The scene's own outputs (frames, drape.h5) are left out: the study runs
# WORK/cusickTAG.yaml, scenes/cusick.yaml without its `output` line.
#
# Environment:
#   BENCH_FABRICS   fabric names in fabrics/ or, for the study fabrics
#                   (isotropic-soft, isotropic-plate), in OUT (cotton-breen
#                   ponte-roma-knit-wang cotton-poly-wang: the default
#                   cotton, a limp knit, a stiff woven)
#   BENCH_SPACINGS  (1cm 0.7cm 0.5cm 0.35cm 0.25cm)
#   BENCH_METHODS   (fall accurate)
#   BENCH_FALL_SPECIMENS (16), BENCH_ACCURATE_SPECIMENS (16),
#   BENCH_ACCURATE_FINE_SPECIMENS (8), BENCH_ACCURATE_FINE (0.25cm)
#   BENCH_JOBS      specimens at a time (1: CPU seconds are then measured
#                   one specimen at a time)
#   BENCH_SCENE_ARGS  more `drape run` options for every run
#   BENCH_PERTURBATION  the scene's perturbation instead of the shipped one,
#                   e.g. "{amplitude: 0.2 mm, seed: 1}" (with a BENCH_TAG)
#   BENCH_TAG       a suffix for the names of the results (default none)
#   BENCH_TABLES_ONLY=1  only remake the tables from the results in OUT
#   DRAPE_BIN       the drape binary (./drape)
#   BENCH_COMMIT    the commit DRAPE_BIN was built from (a copy of an older
#                   build, so that hours of runs use one binary)
set -eu
cd "$(dirname "$0")/.."
DRAPE=${DRAPE_BIN:-./drape}
OUT=${BENCH_OUT:-docs/performance/convergence}
WORK=${BENCH_WORK:-build/convergence}
FABRICS=${BENCH_FABRICS:-"cotton-breen ponte-roma-knit-wang cotton-poly-wang"}
SPACINGS=${BENCH_SPACINGS:-"1cm 0.7cm 0.5cm 0.35cm 0.25cm"}
METHODS=${BENCH_METHODS:-"fall accurate"}
N_FALL=${BENCH_FALL_SPECIMENS:-16}
N_ACC=${BENCH_ACCURATE_SPECIMENS:-16}
N_ACC_FINE=${BENCH_ACCURATE_FINE_SPECIMENS:-8}
FINE_ACC=${BENCH_ACCURATE_FINE:-"0.25cm"}
JOBS=${BENCH_JOBS:-1}
EXTRA=${BENCH_SCENE_ARGS:-}
TAG=${BENCH_TAG:-}
# the commit DRAPE_BIN was built from (BENCH_COMMIT; default this
# checkout's, marked +changes when its tracked files differ from it)
COMMIT=${BENCH_COMMIT:-$(git rev-parse --short HEAD 2>/dev/null || echo unknown)}
if [ -z "${BENCH_COMMIT:-}" ] && [ -n "$(git status --porcelain --untracked-files=no 2>/dev/null)" ]; then
    COMMIT="$COMMIT+changes"
fi
mkdir -p "$OUT" "$WORK"

# the shipped scene without its outputs (its fabric given by --fabric),
# with BENCH_PERTURBATION's perturbation when set
SCENE=$WORK/cusick$TAG.yaml
sed -e '/^output:/d' -e 's|^fabric: .*|fabric: ../../fabrics/cotton-breen.yaml|' \
    scenes/cusick.yaml > "$SCENE.tmp"
if [ -n "${BENCH_PERTURBATION:-}" ]; then
    sed -i "s|^perturbation: .*|perturbation: $BENCH_PERTURBATION|" "$SCENE.tmp"
fi
if cmp -s "$SCENE.tmp" "$SCENE"; then rm -f "$SCENE.tmp"; else mv "$SCENE.tmp" "$SCENE"; fi

# run NAME ARGS...: an ensemble into WORK/NAME (resumed when interrupted),
# its result in OUT/NAME.json with OUT/NAME.meta.  An ensemble already in
# OUT whose .meta has this commit and these arguments is kept.
run() {
    name=$1
    shift
    if [ -s "$OUT/$name.json" ] && grep -qxF "command: drape run -q $*" "$OUT/$name.meta" 2>/dev/null &&
        grep -qxF "commit: $COMMIT" "$OUT/$name.meta"; then
        echo "bench-convergence: $name: kept ($OUT/$name.json)" >&2
        return 0
    fi
    dir=$WORK/$name
    t=$(mktemp)
    st=0
    if [ -f "$dir/ensemble.json" ] && [ -f "$dir/.args" ] && [ "$(cat "$dir/.args")" = "$* @ $COMMIT" ] &&
        grep -q '"status": *"\(running\|interrupted\)"' "$dir/ensemble.json"; then
        echo "bench-convergence: $name: drape run --resume $dir" >&2
        /usr/bin/time -f "%U %S %e" -o "$t" "$DRAPE" run -q --resume "$dir" -j "$JOBS" \
            > "$OUT/$name.json.tmp" || st=$?
    else
        rm -rf "$dir"
        mkdir -p "$dir"
        echo "$* @ $COMMIT" > "$dir/.args"
        echo "bench-convergence: $name: drape run $*" >&2
        /usr/bin/time -f "%U %S %e" -o "$t" "$DRAPE" run -q "$@" -j "$JOBS" --out "$dir" \
            > "$OUT/$name.json.tmp" || st=$?
    fi
    if [ "$st" -ne 0 ] && { [ "$st" -ne 4 ] || [ ! -s "$OUT/$name.json.tmp" ]; }; then
        rm -f "$OUT/$name.json.tmp" "$t"
        echo "bench-convergence: $name: exit status $st, no result (run again to resume $dir)" >&2
        exit 1
    fi
    mv "$OUT/$name.json.tmp" "$OUT/$name.json"
    read -r u s e <<EOT
$(tail -n 1 "$t")
EOT
    rm -f "$t"
    # an ensemble's cpu_s (its specimens' CPU, summed) is in the result;
    # the time here is that of this call (a resumed run: its last part)
    printf 'command: drape run -q %s\ncommit: %s\ndate: %s\ncpu_s: %s\nwall_s: %s\n' \
        "$*" "$COMMIT" "$(date -u +%FT%TZ)" "$(echo "$u $s" | awk '{print $1 + $2}')" "$e" \
        > "$OUT/$name.meta"
}

compare() {
    [ -s "$1" ] && [ -s "$2" ] || return 0
    "$DRAPE" compare "$1" "$2" > "$3.tmp" 2>/dev/null && mv "$3.tmp" "$3" || rm -f "$3.tmp"
}

# fabric_file F: the library's fabric F, or the study fabric F kept in OUT
fabric_file() {
    if [ -f "fabrics/$1.yaml" ]; then echo "fabrics/$1.yaml"; else echo "$OUT/$1.yaml"; fi
}

if [ "${BENCH_TABLES_ONLY:-0}" != 1 ]; then
    for f in $FABRICS; do
        for h in $SPACINGS; do
            for m in $METHODS; do
                case $m in
                fall) run "$f-$h-fall$TAG" "$SCENE" --fabric "$(fabric_file "$f")" \
                    --spacing "$h" --specimens "$N_FALL" --seed 1 $EXTRA ;;
                accurate)
                    n=$N_ACC
                    for g in $FINE_ACC; do [ "$g" = "$h" ] && n=$N_ACC_FINE; done
                    run "$f-$h-accurate$TAG" "$SCENE" --fabric "$(fabric_file "$f")" \
                        --spacing "$h" --specimens "$n" --seed 1 --method dynamic \
                        --integrator auto $EXTRA ;;
                *) echo "bench-convergence: unknown method $m" >&2; exit 2 ;;
                esac
            done
        done
    done
fi

# comparisons: spacing h against h/2, fall against accurate
for f in $FABRICS; do
    for m in fall accurate; do
        compare "$OUT/$f-1cm-$m$TAG.json" "$OUT/$f-0.5cm-$m$TAG.json" "$OUT/$f-1cm-0.5cm-$m$TAG-compare.json"
        compare "$OUT/$f-0.7cm-$m$TAG.json" "$OUT/$f-0.35cm-$m$TAG.json" "$OUT/$f-0.7cm-0.35cm-$m$TAG-compare.json"
        compare "$OUT/$f-0.5cm-$m$TAG.json" "$OUT/$f-0.25cm-$m$TAG.json" "$OUT/$f-0.5cm-0.25cm-$m$TAG-compare.json"
        compare "$OUT/$f-0.35cm-$m$TAG.json" "$OUT/$f-0.175cm-$m$TAG.json" "$OUT/$f-0.35cm-0.175cm-$m$TAG-compare.json"
    done
    for h in 1cm 0.7cm 0.5cm 0.35cm 0.25cm 0.175cm; do
        compare "$OUT/$f-$h-accurate$TAG.json" "$OUT/$f-$h-fall$TAG.json" "$OUT/$f-$h-fall-accurate$TAG-compare.json"
    done
done

python3 scripts/convergence-tables.py "$OUT" "$TAG" docs/convergence.md "$FABRICS" "$WORK"
echo "bench-convergence: tables in docs/convergence.md (results in $OUT)" >&2
