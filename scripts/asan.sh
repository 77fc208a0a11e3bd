#!/bin/sh
# asan.sh: build drape and every Check suite with AddressSanitizer +
# UndefinedBehaviorSanitizer out of tree, run the whole suite (the CLI
# tests run the instrumented drape binary too) and one small `drape run`;
# fail on any sanitizer report.  docs/reliability.md explains the choices.
#
#   scripts/asan.sh                 (make asan)
#   O=DIR CC=clang scripts/asan.sh  other build directory or compiler
#
# Check runs each test in a forked child (CK_FORK is left alone): LeakSanitizer
# checks each child when it exits, so a leak fails the test that made it
# (exit 23), and a crash or UB report fails only that test.  Every report is
# also written to $O/logs/ (log_path), including those of the drape
# processes that the CLI tests start: a bad input that makes drape crash
# would otherwise still pass a test that expects a non-zero status.
set -eu
cd "$(dirname "$0")/.."
ROOT=$(pwd)
O=${O:-build/asan}
case $O in /*) ;; *) O=$ROOT/$O ;; esac
CC=${CC:-cc}
SAN="-fsanitize=address,undefined,float-cast-overflow -fno-omit-frame-pointer -fno-sanitize-recover=all"
LOGS=$O/logs
mkdir -p "$O"
rm -rf "$LOGS" "$O/run"
mkdir -p "$LOGS"

# $(O)/drape: the Makefile's private binary for out-of-tree builds
make O="$O" CC="$CC" CFLAGS="-O1 -g $SAN" LDFLAGS="$SAN" "$O/drape" "$O/tests/check_drape"

ASAN_OPTIONS="log_path=$LOGS/asan:detect_leaks=1:detect_stack_use_after_return=1:check_initialization_order=1:strict_init_order=1:detect_invalid_pointer_pairs=0"
UBSAN_OPTIONS="log_path=$LOGS/ubsan:print_stacktrace=1:halt_on_error=1"
LSAN_OPTIONS="suppressions=$ROOT/scripts/lsan.supp:print_suppressions=0"
# Instrumented code is 2-3x slower: stretch Check's per-test timeouts.
CK_TIMEOUT_MULTIPLIER=${CK_TIMEOUT_MULTIPLIER:-4}
# CHOLMOD's supernodal kernels in one thread, as drape runs them (src/main.c)
OMP_THREAD_LIMIT=1
# the instrumented drape's resident memory is not a run's: the memory
# estimate's test against ru_maxrss is skipped (tests/check_scene.c)
DRAPE_TEST_SKIP_RSS=1
export ASAN_OPTIONS UBSAN_OPTIONS LSAN_OPTIONS CK_TIMEOUT_MULTIPLIER OMP_THREAD_LIMIT DRAPE_TEST_SKIP_RSS

status=0
t0=$(date +%s)
(cd tests && DRAPE_BIN="$O/drape" "$O/tests/check_drape") || status=1
t1=$(date +%s)
echo "asan: Check suite $((t1 - t0)) s"

# One small run through the whole pipeline, frames included.
mkdir -p "$O/run"
if ! "$O/drape" run scenes/hang.yaml --spacing 5cm --t-max 0.05s --out "$O/run" -q \
        > "$O/run/result.json"; then
    echo "asan: drape run failed" >&2
    status=1
fi
echo "asan: drape run $(( $(date +%s) - t1 )) s"

if ls "$LOGS"/* >/dev/null 2>&1; then
    echo "asan: sanitizer reports:" >&2
    for f in "$LOGS"/*; do echo "==== $f" >&2; cat "$f" >&2; done
    status=1
fi
[ $status -eq 0 ] && echo "asan: clean"
exit $status
