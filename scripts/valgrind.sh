#!/bin/sh
# valgrind.sh: memcheck on `drape check` of every shipped and every bad
# input file, on one small `drape run` with frames, one with the shadow
# picture (SVG and PNG), and on the test suites
# of the loaders, the lattice and the allocation-failure walks
# (tests/check_alloc.c), which is where "no leak" is checked.  Any memcheck error or definite/indirect/possible leak fails.
# docs/reliability.md explains the choices.
#
#   scripts/valgrind.sh          (make valgrind) uses ./drape and
#                                build/tests/check_drape (made if missing)
#   O=DIR DRAPE=BIN scripts/valgrind.sh   other test build and drape binary
#                                (both must exist)
#
# Memcheck reports with exit status 99 (--error-exitcode), apart from
# drape's own statuses (1 invalid input, 3 I/O, ...).  The suites run with
# CK_FORK=no: one process, so a leak anywhere in a suite shows in its log
# (Check's per-test timeouts do not apply then).
set -eu
cd "$(dirname "$0")/.."
ROOT=$(pwd)
O=${O:-build}
case $O in /*) ;; *) O=$ROOT/$O ;; esac
DRAPE=${DRAPE:-$ROOT/drape}
SUITES=${VALGRIND_SUITES:-"yamldoc units fit fabric scene lattice alloc"}
LOGS=$O/valgrind
# drape executes itself again to set OMP_THREAD_LIMIT when it is not set
# (src/main.c); under valgrind that second program would run natively
export OMP_THREAD_LIMIT=1
# memcheck with its options (a function: the checkout's path may hold spaces)
vg_run() {
    valgrind --tool=memcheck --leak-check=full --show-leak-kinds=definite,indirect,possible \
        --errors-for-leak-kinds=definite,indirect,possible --track-origins=yes \
        --error-exitcode=99 --suppressions="$ROOT/scripts/valgrind.supp" "$@"
}

command -v valgrind >/dev/null 2>&1 || {
    echo "valgrind: installing valgrind"
    apt-get update -q && DEBIAN_FRONTEND=noninteractive \
        apt-get install -y -q --no-install-recommends valgrind
}
if [ "$DRAPE" = "$ROOT/drape" ]; then make -s O="$O" drape "$O/tests/check_drape"; fi
rm -rf "$LOGS"
mkdir -p "$LOGS/run"
status=0

# vg DIR NAME WANT CMD...: run CMD in DIR under memcheck; WANT is "zero"
# (exit 0) or "nonzero" (a rejection: any status but 0 and 99).
vg() {
    dir=$1 name=$2 want=$3
    shift 3
    t0=$(date +%s)
    st=0
    (cd "$dir" && vg_run --log-file="$LOGS/$name.log" "$@") > "$LOGS/$name.out" 2>&1 || st=$?
    ok=1
    if [ "$st" -eq 99 ] || grep -q 'ERROR SUMMARY: [1-9]' "$LOGS/$name.log"; then ok=0; fi
    case $want in
    zero) [ "$st" -eq 0 ] || ok=0 ;;
    nonzero) [ "$st" -ne 0 ] || ok=0 ;;
    esac
    if [ $ok -eq 1 ]; then
        echo "valgrind: $name: clean ($(( $(date +%s) - t0 )) s)"
    else
        echo "valgrind: $name: FAILED (status $st); $LOGS/$name.log:" >&2
        tail -60 "$LOGS/$name.log" >&2
        tail -20 "$LOGS/$name.out" >&2
        status=1
    fi
}

vg . check-good zero "$DRAPE" check fabrics/*.yaml scenes/*.yaml
# every bad input once (drape check goes on after a bad file)
vg . check-bad nonzero "$DRAPE" check tests/bad/*.yaml
vg . run zero "$DRAPE" run scenes/hang.yaml --spacing 5cm --t-max 0.05s \
    --out "$LOGS/run" -q
# the shadow picture, SVG and PNG (librsvg, cairo, pango: scripts/valgrind.supp)
vg . run-shadow zero "$DRAPE" run scenes/cusick.yaml --spacing 3cm --method static \
    --specimens 1 --out "$LOGS/run-shadow" -q
export CK_FORK=no
# a child forked under memcheck keeps memcheck's resident memory in its
# ru_maxrss through the exec: the memory estimate's test is skipped
export DRAPE_TEST_SKIP_RSS=1
for s in $SUITES; do
    export CK_RUN_SUITE="$s"
    vg tests "suite-$s" zero "$O/tests/check_drape"
done
[ $status -eq 0 ] && echo "valgrind: clean"
exit $status
