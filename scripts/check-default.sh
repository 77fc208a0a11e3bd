#!/bin/sh
# make check-default: the default Cusick scene, run the way it asks (in time,
# arkode-imex, 1 cm), must end with status `equilibrium` (issue 3).  Takes
# about 150 s of CPU on this project's machines, so it is kept out of
# `make check` (which runs the same scene at 2 cm); CI runs it.
set -eu
cd "$(dirname "$0")/.."
DRAPE=${DRAPE_BIN:-./drape}
out=$("$DRAPE" run -q scenes/cusick.yaml)
echo "$out"
case "$out" in
*'"status": "equilibrium"'*) echo "check-default: the default Cusick scene reached equilibrium" ;;
*) echo "check-default: FAILED: the default Cusick scene did not reach equilibrium" >&2; exit 1 ;;
esac
