#!/bin/sh
# fuzz.sh: build the libFuzzer harnesses of the fabric and scene loaders
# (tests/fuzz/) with clang -fsanitize=fuzzer,address,undefined, replay the
# regression inputs, then fuzz each harness for a fixed time from a seed
# corpus (fabrics/, scenes/, tests/bad/, tests/fuzz/regressions/).  Both
# harnesses run at once, one per core.  Exit status 1 if anything was found;
# the crashing input is kept in $O/artifacts/ (docs/reliability.md says how
# to turn it into a regression file).
#
#   scripts/fuzz.sh                  (make fuzz) 30 s per harness
#   FUZZ_TIME=300 scripts/fuzz.sh    longer
#   O=DIR scripts/fuzz.sh            build directory (default build/fuzz)
#
# The corpus grown by a run is kept in $O/corpus-NAME and reused by the
# next run on the same machine; a fresh clone starts from the seeds.
set -eu
cd "$(dirname "$0")/.."
ROOT=$(pwd)
O=${O:-build/fuzz}
case $O in /*) ;; *) O=$ROOT/$O ;; esac
FUZZ_TIME=${FUZZ_TIME:-30}
CC=${FUZZ_CC:-clang}

# clang and its fuzzer runtime are not on a new machine (Debian: clang,
# libclang-rt-14-dev); install them only when missing.
probe() {
    printf '#include <stdint.h>\n#include <stddef.h>\nint LLVMFuzzerTestOneInput(const uint8_t *d, size_t n);\nint LLVMFuzzerTestOneInput(const uint8_t *d, size_t n) { (void)d; (void)n; return 0; }\n' \
        > "$O/probe.c"
    "$CC" -fsanitize=fuzzer,address,undefined -o "$O/probe" "$O/probe.c" >/dev/null 2>&1
}
mkdir -p "$O"
if ! command -v "$CC" >/dev/null 2>&1 || ! probe; then
    echo "fuzz: installing clang and libclang-rt-14-dev"
    apt-get update -q && DEBIAN_FRONTEND=noninteractive \
        apt-get install -y -q --no-install-recommends clang libclang-rt-14-dev
    probe || { echo "fuzz: clang cannot build a libFuzzer program" >&2; exit 1; }
fi

# Only what the harnesses need: the loaders, their helpers and the lattice.
LIB="src/alloc.c src/error.c src/units.c src/yamldoc.c src/fit.c src/fabric.c src/scene.c src/scene_check.c src/yread.c src/perturbation.c src/lattice.c src/lattice_check.c"
SAN="-fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer"
cat > "$O/extra.mk" <<'MK'
$(O)/fuzz_%: tests/fuzz/fuzz_%.c tests/fuzz/fuzz_common.h $(O)/libdrape.a
	$(CC) $(ALL_CFLAGS) -DDRAPE_FUZZ_ROOT='"$(CURDIR)"' -fsanitize=fuzzer $(LDFLAGS) -o $@ $< $(O)/libdrape.a $(DRAPE_LIBS)
MK
make -s -f Makefile -f "$O/extra.mk" O="$O" CC="$CC" LIB_SRC="$LIB" \
    CFLAGS="-O1 -g -fsanitize=fuzzer-no-link $SAN" LDFLAGS="$SAN" \
    "$O/fuzz_fabric" "$O/fuzz_scene"

# Seeds per harness (YAML-level bad inputs go to both), with the corpora
# minimized from earlier long runs (tests/fuzz/corpus/NAME).
seed() { # NAME FILES...
    name=$1; shift
    mkdir -p "$O/corpus-$name"
    for f in "$@"; do [ -f "$f" ] && cp "$f" "$O/corpus-$name/seed-$(basename "$f")"; done
    return 0
}
seed fabric fabrics/*.yaml tests/bad/fabric-*.yaml tests/bad/yaml-*.yaml \
    tests/fuzz/regressions/fabric-*.yaml tests/fuzz/corpus/fabric/*
seed scene scenes/*.yaml tests/bad/scene-*.yaml tests/bad/combo-*.yaml \
    tests/bad/yaml-*.yaml tests/fuzz/regressions/scene-*.yaml tests/fuzz/corpus/scene/*

rm -rf "$O/artifacts"
mkdir -p "$O/artifacts"
# Reports of the sanitizers go to the fuzzer's log; leaks are checked.
export ASAN_OPTIONS="detect_leaks=1:allocator_may_return_null=1"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
OPTS="-timeout=10 -rss_limit_mb=2048 -max_len=16384 -dict=tests/fuzz/drape.dict -print_final_stats=1"
status=0

# 1. Regressions: every kept input once (rejected or accepted, never a crash).
for name in fabric scene; do
    set -- tests/bad/*.yaml tests/fuzz/regressions/*.yaml
    files=""
    for f in "$@"; do [ -f "$f" ] && files="$files $f"; done
    # shellcheck disable=SC2086
    if ! "$O/fuzz_$name" -runs=1 $files > "$O/regress-$name.log" 2>&1; then
        echo "fuzz: $name: a regression input fails; see $O/regress-$name.log" >&2
        tail -40 "$O/regress-$name.log" >&2
        status=1
    fi
done

# 2. Fuzz both harnesses at once for FUZZ_TIME seconds each.
t0=$(date +%s)
pids=""
for name in fabric scene; do
    # shellcheck disable=SC2086
    "$O/fuzz_$name" $OPTS -max_total_time="$FUZZ_TIME" \
        -artifact_prefix="$O/artifacts/$name-" "$O/corpus-$name" \
        > "$O/fuzz-$name.log" 2>&1 &
    pids="$pids $!"
done
i=0
for pid in $pids; do
    i=$((i + 1))
    name=$( [ $i -eq 1 ] && echo fabric || echo scene )
    if ! wait "$pid"; then
        echo "fuzz: $name: found a problem; see $O/fuzz-$name.log" >&2
        grep -A30 -m1 'ERROR\|==ERROR\|runtime error\|abort\|deadly signal' "$O/fuzz-$name.log" >&2 || tail -40 "$O/fuzz-$name.log" >&2
        status=1
    fi
    runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$O/fuzz-$name.log")
    cov=$(grep -o 'cov: [0-9]*' "$O/fuzz-$name.log" | tail -1)
    echo "fuzz: $name: ${runs:-?} inputs, $cov, corpus $(find "$O/corpus-$name" -type f | wc -l) files"
done
echo "fuzz: $(( $(date +%s) - t0 )) s of fuzzing"
if ls "$O"/artifacts/* >/dev/null 2>&1; then
    echo "fuzz: inputs kept:" >&2
    ls -l "$O"/artifacts/ >&2
    status=1
fi
[ $status -eq 0 ] && echo "fuzz: clean"
exit $status
