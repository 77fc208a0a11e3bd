#!/bin/sh
# make check-default : the default scene the way a user
# meets it, and the way it once was run.
#  1. `drape run` with no arguments: the default Cusick test, 12 specimens
#     with the fall method (a few seconds); every specimen must reach a
#     certified equilibrium and the 95 % half-width of the mean DC must
#     stay below 0.02 (docs/ensemble.md measures about 0.012).
#  2. One specimen in time with the scene's integrator (arkode-imex, 1 cm):
#     status `equilibrium` (about 100 s of CPU).
# Kept out of `make check` for its time; CI runs it.
set -eu
cd "$(dirname "$0")/.."
DRAPE=${DRAPE_BIN:-./drape}
out=$("$DRAPE" run -q)
echo "$out"
echo "$out" | python3 -c '
import json, sys
d = json.load(sys.stdin)
sp = d["specimens"]
bad = [s for s in sp if s["status"] != "equilibrium"]
assert d["method"] == "fall", d["method"]
assert len(sp) == 12 and not bad, "specimens not at equilibrium: %r" % bad
assert d["certified"] == "minimum", d["certified"]
assert d["dc_ci95"] < 0.02, d["dc_ci95"]
print("check-default: drape run: %d specimens, DC %.4f +- %.4f, nodes %s, %.1f CPU s"
      % (len(sp), d["dc"], d["dc_ci95"], d["nodes_hist"], d["cpu_s"]))
' || { echo "check-default: FAILED: the default drape test" >&2; exit 1; }
out=$("$DRAPE" run -q scenes/cusick.yaml --method dynamic --specimens 1)
echo "$out"
case "$out" in
*'"status": "equilibrium"'*) echo "check-default: the default Cusick scene, in time, reached equilibrium" ;;
*) echo "check-default: FAILED: the default Cusick scene did not reach equilibrium" >&2; exit 1 ;;
esac
