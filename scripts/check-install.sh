#!/bin/sh
# make check-install (docs/install.md): install drape into a
# temporary DESTDIR, use the staged binary from another directory as a user
# would after `make install` (DRAPE_DATA points it at the staged data, as
# the compiled-in /usr/local/share/drape is not there yet), render its
# manual page, uninstall, and check that nothing is left.  Then the same
# with another PREFIX, whose data directory the binary must have compiled
# in.  Prints one line per check and a summary; exit 1 on any failure.
set -eu
cd "$(dirname "$0")/.."
ROOT=$(pwd)
MAKE=${MAKE:-make}
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
pass=0
fail=0
ok() { pass=$((pass + 1)); echo "check-install: ok   $*"; }
bad() { fail=$((fail + 1)); echo "check-install: FAIL $*"; }

# ---- the default PREFIX (/usr/local), staged
STAGE=$TMP/stage
$MAKE -s install DESTDIR="$STAGE" >/dev/null
BIN=$STAGE/usr/local/bin/drape
DATA=$STAGE/usr/local/share/drape
MAN=$STAGE/usr/local/share/man/man1/drape.1
DOC=$STAGE/usr/local/share/doc/drape
for f in "$BIN" "$MAN" "$DATA/scenes/cusick.yaml" "$DATA/fabrics/cotton-breen.yaml" \
         "$DOC/README.md" "$DOC/docs/ensemble.md"; do
    if [ -f "$f" ]; then ok "installed ${f#"$STAGE"}"; else bad "missing ${f#"$STAGE"}"; fi
done
n_inst=$(find "$STAGE" -type f | wc -l)
n_want=$((2 + $(ls fabrics/*.yaml scenes/*.yaml | wc -l) + 1 + $(find docs -type f | wc -l)))
if [ "$n_inst" -eq "$n_want" ]; then ok "$n_inst files installed"; else bad "$n_inst files installed, expected $n_want"; fi

WORK=$TMP/elsewhere
mkdir -p "$WORK"
cd "$WORK"
# the compiled-in data directory of the staged binary is /usr/local/share/drape
if "$BIN" --version | grep -q "/usr/local/share/drape (compiled in)"; then
    ok "--version names the compiled-in data directory"
else bad "--version: $("$BIN" --version)"; fi
export DRAPE_DATA="$DATA"
if "$BIN" --version | grep -q "$DATA (DRAPE_DATA)"; then ok "--version names DRAPE_DATA"
else bad "--version with DRAPE_DATA: $("$BIN" --version)"; fi
# drape run with no arguments: the default scene's ensemble
if "$BIN" run > run.json 2> run.err &&
   python3 -c 'import json,sys; r=json.load(open("run.json")); sys.exit(not (r["scene"]=="cusick" and r["specimens_failed"]==0 and 0<r["dc"]<1))'; then
    ok "drape run (no arguments) from $WORK: $(python3 -c 'import json; r=json.load(open("run.json")); print("DC %.4f +- %.4f, nodes %s" % (r["dc"], r["dc_ci95"], r["nodes_hist"]))')"
else bad "drape run from $WORK: $(tail -n 3 run.err)"; fi
if "$BIN" check fabrics/cotton-breen.yaml > check.out 2>&1 &&
   grep -q "^$DATA/fabrics/cotton-breen.yaml: valid fabric" check.out; then
    ok "drape check fabrics/cotton-breen.yaml (the installed fabric)"
else bad "drape check on an installed fabric: $(head -n 3 check.out)"; fi
if "$BIN" check "$DATA"/fabrics/*.yaml "$DATA"/scenes/*.yaml > /dev/null 2>&1; then
    ok "drape check on every installed fabric and scene"
else bad "drape check on the installed files"; fi
set +e
DRAPE_DATA=$TMP/nothing "$BIN" run > /dev/null 2> miss.err
st=$?
set -e
if [ "$st" -eq 3 ] && grep -q "looked in the current directory, $TMP/nothing (DRAPE_DATA)" miss.err; then
    ok "without data: exit 3 naming where it looked"
else bad "without data: status $st, $(cat miss.err)"; fi
unset DRAPE_DATA

# the manual page: renders, has its sections, and every option of every
# command's --help appears in it
if MANWIDTH=100 man -l "$MAN" > man.txt 2> man.err && [ ! -s man.err ]; then ok "man -l renders drape.1"
else bad "man -l: $(head -n 3 man.err)"; fi
for sec in NAME SYNOPSIS DESCRIPTION OPTIONS "EXIT STATUS" COMMANDS ENVIRONMENT FILES EXAMPLES "SEE ALSO"; do
    if grep -q "^$sec\$" man.txt; then :; else bad "drape.1 has no section $sec"; fi
done
missing=""
for c in "" check run batch import compare bench; do
    for o in $("$BIN" $c --help | grep -o -- '--[a-z][a-z-]*' | sort -u); do
        grep -q -- "$o" man.txt || missing="$missing $c:$o"
    done
done
if [ -z "$missing" ]; then ok "every option of every --help is in drape.1"; else bad "not in drape.1:$missing"; fi
if grep -q 'fB\|fR\|fI' man.txt; then bad "stray font escapes in drape.1"; else ok "no stray font escapes"; fi

cd "$ROOT"
$MAKE -s uninstall DESTDIR="$STAGE" >/dev/null
left=$(find "$STAGE" -type f | wc -l)
if [ "$left" -eq 0 ] && [ ! -d "$STAGE/usr/local/share/drape" ] && [ ! -d "$DOC" ]; then
    ok "make uninstall removed all $n_inst files"
else bad "make uninstall left $left files: $(find "$STAGE" -type f | head -n 5)"; fi

# ---- another PREFIX: the binary compiles that data directory in (O keeps
# the checkout's own build untouched)
STAGE2=$TMP/stage2
$MAKE -s install O="$TMP/build-opt" PREFIX=/opt/drape DESTDIR="$STAGE2" >/dev/null
if "$STAGE2/opt/drape/bin/drape" --version | grep -q "/opt/drape/share/drape (compiled in)" &&
   [ -f "$STAGE2/opt/drape/share/drape/scenes/cusick.yaml" ] &&
   [ -f "$STAGE2/opt/drape/share/man/man1/drape.1" ]; then
    ok "PREFIX=/opt/drape: compiled-in data directory and files under it"
else bad "PREFIX=/opt/drape: $("$STAGE2/opt/drape/bin/drape" --version)"; fi
$MAKE -s uninstall O="$TMP/build-opt" PREFIX=/opt/drape DESTDIR="$STAGE2" >/dev/null
left=$(find "$STAGE2" -type f | wc -l)
if [ "$left" -eq 0 ]; then ok "PREFIX=/opt/drape: uninstalled"; else bad "PREFIX=/opt/drape: $left files left"; fi

echo "check-install: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
