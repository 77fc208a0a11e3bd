#!/bin/sh
# The manual page drape.1, generated from the program's own help so that
# the two cannot drift (docs/install.md):
#   - help2man turns `drape --help` and `drape --version` into NAME,
#     SYNOPSIS, DESCRIPTION (the commands), OPTIONS and EXIT STATUS;
#   - a section per command holds `drape COMMAND --help` verbatim, and the
#     SYNOPSIS lists every command's usage lines;
#   - EXAMPLES are the README's "## Commands" block; ENVIRONMENT, FILES
#     and SEE ALSO are written here (they describe the installation).
# Usage: scripts/man.sh DRAPE_BINARY README.md DATADIR DOCDIR > drape.1
set -eu
DRAPE=$1
README=$2
DATADIR=$3
DOCDIR=$4
COMMANDS="check run batch import compare bench"

# print one line as it is (dash's echo would expand \f)
p() { printf '%s\n' "$*"; }

command -v help2man >/dev/null 2>&1 || {
    p "man.sh: help2man is missing (make deps installs it)" >&2
    exit 1
}
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT

# roff-escape verbatim text: backslashes, leading dots and quotes, hyphens
roff() {
    sed -e 's/\\/\\e/g' -e 's/^\([.'"'"']\)/\\\&\1/' -e 's/-/\\-/g'
}

# each command's help once, into a file: a command whose --help fails
# stops the page (inside a pipeline below its status would be lost)
for c in $COMMANDS; do
    "$DRAPE" "$c" --help > "$TMP/$c.help" || {
        p "man.sh: \`$DRAPE $c --help' failed" >&2
        exit 1
    }
    [ -s "$TMP/$c.help" ] || { p "man.sh: \`$DRAPE $c --help' printed nothing" >&2; exit 1; }
done

{
    p "[NAME]"
    p "drape \\- simulate the drape of woven fabrics from Kawabata (KES\\-F) data"
    p ""
    p "[SYNOPSIS]"
    for c in $COMMANDS; do
        awk '
            /^Usage: / { sub(/^Usage: /, ""); print; on = 1; next }
            on && /^       drape / { sub(/^ +/, ""); print; next }
            { on = 0 }' "$TMP/$c.help" |
        roff | sed -e 's/^drape \([a-z]*\)\(.*\)$/\\fBdrape \1\\fR\2\n.br/'
    done
    p "\\fBdrape\\fR \\-\\-help | \\-\\-version"
    p ""
    p "[COMMANDS]"
    p "Each command's options, as \\fBdrape\\fR \\fICOMMAND\\fR \\fB\\-\\-help\\fR prints them."
    for c in $COMMANDS; do
        p ".SS \"drape $c\""
        p ".nf"
        roff < "$TMP/$c.help"
        p ".fi"
    done
    p ""
    p "[ENVIRONMENT]"
    p ".TP"
    p ".B DRAPE_DATA"
    p "The directory of drape's shipped data (scenes/, fabrics/). Relative"
    p "paths that name no file in the current directory (the default scene"
    p "scenes/cusick.yaml among them) are looked up there instead of in the"
    p "checkout the binary was built in or the compiled\\-in directory"
    p "$DATADIR. \\fBdrape \\-\\-version\\fR prints the search order."
    p ".TP"
    p ".B OMP_THREAD_LIMIT"
    p "drape is single\\-threaded (ensembles and batches run processes in"
    p "parallel). When it is not set, drape sets it to 1 and executes itself"
    p "again, so that CHOLMOD's OpenMP loops run in one thread; set it to"
    p "allow more."
    p ".TP"
    p ".B TMPDIR"
    p "Not used: outputs are written to a temporary name next to their"
    p "destination and renamed when complete."
    p ""
    p "[FILES]"
    p ".TP"
    p ".I $DATADIR/scenes/"
    p "the shipped scenes: cusick.yaml (the default drape test), table.yaml,"
    p "hang.yaml, cantilever.yaml, cantilever\-bias.yaml"
    p ".TP"
    p ".I $DATADIR/fabrics/"
    p "the shipped fabric library (Kawabata and ARCSim\\-converted fabrics)"
    p ".TP"
    p ".I $DOCDIR/"
    p "README.md and docs/: the model, its validation, the drape test as an"
    p "ensemble, performance, batch and Slurm use"
    p ".TP"
    p ".I DIR/"
    p "with \\fB\\-\\-out\\fR \\fIDIR\\fR: OBJ frames, drape.h5 and drape.xmf (ParaView),"
    p "shadow.svg (Cusick and table scenes), specimen\\-NNN/ (ensembles),"
    p "results.csv and logs/ (\\fBdrape batch\\fR)"
    p ""
    p "[EXAMPLES]"
    p ".nf"
    sed -n '/^## Commands/,/^```$/p' "$README" | sed -e '1,/^```sh$/d' -e '/^```$/d' | roff
    p ".fi"
    p ""
    p "[SEE ALSO]"
    p "The documentation in"
    p ".IR $DOCDIR/README.md"
    p "and"
    p ".IR $DOCDIR/docs/ ."
    p "The method: Chen & Xu (2000), after Breen, House & Wozny (1994)."
} > "$TMP/drape.h2m"

help2man --no-info --no-discard-stderr --include "$TMP/drape.h2m" \
    --version-string "$("$DRAPE" --version | head -n 1 | sed 's/^drape //')" \
    "$DRAPE" > "$TMP/drape.1"
# help2man makes `Exit status:` of the main help a subsection of OPTIONS;
# it is the last paragraph there, so it becomes its own section
sed -e 's/^\.SS "Exit status:"$/.SH "EXIT STATUS"/' "$TMP/drape.1"
