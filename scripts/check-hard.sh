#!/bin/sh
# check-hard.sh: the hard-case suite (tests/hard/, docs/stability.md).
#
#   scripts/check-hard.sh [--update-doc] [--timeout S] [CASE...]
#   scripts/check-hard.sh --self-test
#
# Runs every scene of tests/hard/ (or the CASEs named, e.g. `folded`)
# through `drape run` twice, with the scene's energy form (consistent) and
# with --energy-form seed, each under `timeout`, and checks the contract:
#
#   either  exit 0, status t_max or equilibrium, every energy finite,
#           max_strain < 0.01 (the key, and over every HDF5 frame), the
#           energy bounded (below), no NaN/inf in the JSON, in drape.h5 or
#           in the OBJ frames;
#   or      exit 4, status `failed`, and a message on stderr naming the time
#           (`... at t = T s ...`, T finite) and the reason, with no NaN/inf
#           in the JSON, the message, or a drape.h5 / OBJ frames left behind.
#
# Anything else (a timeout, a signal, another exit status, a NaN anywhere, a
# strain of 1 % or more, an energy out of bounds) breaks the contract.
#
# Energy bound, over the HDF5 frames (every 0.002-0.05 s). The pinned
# particles do not move, so gravity is the only external force and it is
# part of E_pot; damping only removes energy. So E = E_kin + E_pot can only
# fall:
#   E(t_k) <= min over j <= k of E(t_j) + 0.01 M g L    (so E <= E(0) + ...),
#   E_grav(t_k) >= E_grav(0) - 1.01 M g D,
# with M the mass, L the largest extent of the rest lattice, D the largest
# rest distance of a particle from its nearest pin (a particle cannot hang
# lower than that, stretched by less than 1 %). Together they bound E_kin,
# which is at most E(0) + 0.01 M g L - E_grav.
#
# Environment: DRAPE_BIN (default ./drape), CHECK_HARD_TIMEOUT (seconds per
# run, default 300), CHECK_HARD_INTEGRATORS (default `auto animate`: the
# scenes' own and the fixed-step animate method; e.g. "auto
# arkode-imex" runs every case with each, and the table gets one row per
# integrator), CHECK_HARD_UPDATE_DOC=1 (same as --update-doc, which
# rewrites the table between the GENERATED markers of docs/stability.md).
# Exit status 0 if every run kept the contract, 1 if not, 2 on a usage or
# set-up error. --self-test checks the checker: a fake drape (the real one
# plus one defect: a hang, a crash, NaN in the JSON or an OBJ, a strain of
# 2 %, no drape.h5, a silent or mislabelled failure) must be flagged.
set -eu
cd "$(dirname "$0")/.."
# The checker is a python3 script: install the interpreter on a fresh
# Debian machine (root), as scripts/asan.sh does for clang.
if ! command -v python3 >/dev/null 2>&1; then
    echo "check-hard: installing python3" >&2
    apt-get update && DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends python3
fi
root=$(pwd)
bin=${DRAPE_BIN:-./drape}
case $bin in /*) ;; *) bin="$root/$bin" ;; esac
if [ ! -x "$bin" ]; then
    echo "check-hard: no drape binary at $bin (make, or set DRAPE_BIN)" >&2
    exit 2
fi
tmp=$(mktemp -d "${TMPDIR:-/tmp}/drape-hard.XXXXXX")
trap 'rm -rf "$tmp"' EXIT
trap 'exit 130' INT
trap 'exit 143' TERM
# h5scan reads drape.h5 independently of drape (tests/hard/h5scan.c).
if ! cc -std=c99 -D_POSIX_C_SOURCE=200809L -O2 $(pkg-config --cflags hdf5-serial) \
        -o "$tmp/h5scan" tests/hard/h5scan.c $(pkg-config --libs hdf5-serial) -lm; then
    echo "check-hard: cannot build tests/hard/h5scan.c" >&2
    exit 2
fi
# --self-test: feed the checker a drape that misbehaves in each way the
# contract forbids (on the base case) and make sure every one is flagged,
# and that the unmodified drape is not.
if [ "${1:-}" = --self-test ]; then
    cat > "$tmp/fake-drape" <<'EOF'
#!/bin/sh
# A fake drape for check-hard.sh --self-test: the real one plus one defect.
real=$FAKE_REAL
[ "$1" = run ] || exec "$real" "$@"
out=""; prev=""
for a in "$@"; do [ "$prev" = --out ] && out=$a; prev=$a; done
case ${FAKE_MODE:-none} in
    none) exec "$real" "$@" ;;
    hang) exec sleep 600 ;;
    crash) kill -SEGV $$ ;;
    nan-json) "$real" "$@" | sed 's/"max_strain": [^,]*/"max_strain": nan/'; exit 0 ;;
    strain) "$real" "$@" | sed 's/"max_strain": [^,]*/"max_strain": 0.02/'; exit 0 ;;
    obj-nan) "$real" "$@"; rc=$?; sed -i '0,/^v /s/^v .*/v nan 0 0/' "$out/frame_000003.obj"; exit $rc ;;
    no-h5) "$real" "$@"; rc=$?; rm -f "$out/drape.h5"; exit $rc ;;
    silent-fail) "$real" "$@" --max-steps 50 2>/dev/null ;;
    exit0-failed) "$real" "$@" --max-steps 50; exit 0 ;;
esac
EOF
    chmod +x "$tmp/fake-drape"
    bad=0
    for m in none:- hang:"timeout after" crash:"killed by signal 11" \
             nan-json:"not one JSON object" strain:"max_strain 0.02 >= 0.01" \
             obj-nan:"non-finite value" no-h5:"no drape.h5 written" \
             silent-fail:"without a message" exit0-failed:"status failed but exit 0"; do
        mode=${m%%:*} want=${m#*:}
        rc=0
        out=$(DRAPE_BIN="$tmp/fake-drape" FAKE_MODE=$mode FAKE_REAL="$bin" \
              CHECK_HARD_INTEGRATORS=auto CHECK_HARD_UPDATE_DOC= \
              "$root/scripts/check-hard.sh" --timeout 5 base 2>&1) || rc=$?
        if [ "$mode" = none ]; then
            if [ $rc -eq 0 ]; then echo "self-test $mode: not flagged (right)"
            else echo "self-test $mode: FLAGGED a good run:"; echo "$out"; bad=1; fi
        elif [ $rc -eq 1 ] && printf '%s\n' "$out" | grep -qF -- "$want"; then
            echo "self-test $mode: flagged ($want)"
        else
            echo "self-test $mode: NOT FLAGGED as \"$want\" (exit $rc):"; echo "$out"; bad=1
        fi
    done
    exit $bad
fi
# One line, parsed with its here-document before it runs: the shell reads
# nothing of this file after it (so editing the script during a run is safe).
rc=0; python3 - "$bin" "$tmp" "$@" <<'PY' || rc=$?; exit $rc
import json, math, os, re, subprocess, sys, time

bin_, tmp = sys.argv[1], sys.argv[2]
args = sys.argv[3:]
update_doc = os.environ.get("CHECK_HARD_UPDATE_DOC", "") == "1"
timeout_s = float(os.environ.get("CHECK_HARD_TIMEOUT", "300"))
only = []
i = 0
while i < len(args):
    a = args[i]
    if a == "--update-doc":
        update_doc = True
    elif a == "--timeout" and i + 1 < len(args):
        timeout_s = float(args[i + 1]); i += 1
    elif a.startswith("-"):
        print("usage: scripts/check-hard.sh [--update-doc] [--timeout S] [CASE...]", file=sys.stderr)
        sys.exit(2)
    else:
        only.append(a)
    i += 1

G = 9.80665
STRAIN_MAX = 0.01
E_TOL = 0.01       # energy excess allowed, in units of M g L
FORMS = ["consistent", "seed"]
INTEGRATORS = os.environ.get("CHECK_HARD_INTEGRATORS", "auto animate").split()

# (case, scene file, what makes it hard[, extra options, expected status]).
# Order = table order.
CASES = [
    ("base", "base.yaml",
     "reference (not hard): cotton-breen 20 cm square, 11 x 11 at 2 cm, 2 corner pins, air 0.5/s, 0.5 s"),
    ("stiff-k1e6", "stiff-k1e6.yaml",
     "tensile stiffness 1e6 N/m (100 x): stretch/bend stiffness ratio ~1e6"),
    ("lattice-150", "lattice-150.yaml",
     "150 x 150 lattice, 22 500 particles, 134 988 unknowns (first 0.02 s only)"),
    ("limp-silk", "limp-silk.yaml",
     "very light limp silk: 3 mg/cm^2, bending length ~1.5 cm (one spacing)"),
    ("heavy-denim", "heavy-denim.yaml",
     "heavy stiff denim: 50 mg/cm^2, k 5e4 N/m, B 3 gf.cm^2/cm, G 8 gf/cm/deg"),
    ("folded", "folded.yaml",
     "strip pinned across its middle: halves fold face to face, psi -> pi (approximates a folded start)"),
    ("corner-pin", "corner-pin.yaml",
     "one corner pin: falls, swings and turns 45 deg in plane (large rotation), 1 s"),
    ("undamped", "undamped.yaml",
     "no damping at all: energy must be conserved, stretch vibrations never decay"),
    ("rtol-1e-2", "rtol-1e-2.yaml",
     "rtol 1e-2, atol 1e-5 m: large steps over stiff modes"),
    # The failure path itself: the base case with too few steps allowed must
    # end with exit 4, status failed and a diagnosis naming the time.
    ("step-limit", "base.yaml",
     "the failure path: base with --max-steps 50 (per output interval) must fail cleanly",
     ["--max-steps", "50"], "failed"),
]
CASES = [c if len(c) == 5 else c + ([], None) for c in CASES]
if only:
    unknown = [c for c in only if c not in [k[0] for k in CASES]]
    if unknown:
        print("check-hard: unknown case(s): %s (known: %s)"
              % (" ".join(unknown), " ".join(k[0] for k in CASES)), file=sys.stderr)
        sys.exit(2)
    CASES = [k for k in CASES if k[0] in only]

NUM = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?")
BAD_TOKEN = re.compile(r"(?i)\b(?:-?nan|-?inf(?:inity)?)\b")

def reject_constant(name):
    raise ValueError("non-finite JSON constant " + name)

def drape_check(scene):
    """Particles and the stiffness bounds printed by `drape check`."""
    p = subprocess.run(["timeout", "-k", "5", "60", bin_, "check", scene],
                       capture_output=True, text=True)
    info = {"rc": p.returncode}
    m = re.search(r"particles\s+(\d+) \(free (\d+)", p.stdout)
    if m:
        info["particles"], info["free"] = int(m.group(1)), int(m.group(2))
    for term in ("stretch", "shear", "bend"):
        m = re.search(r"^\s+%s\s+(\S+)\s+\(explicit RK4 step limit ~ (\S+) s\)" % term,
                      p.stdout, re.M)
        if m:
            info["w_" + term] = float(m.group(1))
            info["h_" + term] = float(m.group(2))
    return info

def h5scan(path):
    p = subprocess.run([os.path.join(tmp, "h5scan"), path], capture_output=True, text=True)
    r = {"rc": p.returncode, "err": p.stderr.strip(), "data": [], "attr": [],
         "frames": [], "final": None}
    for line in p.stdout.splitlines():
        f = line.split()
        if not f:
            continue
        if f[0] == "nonfinite_data":
            r["data"].append("%s (%s values)" % (f[1], f[2]))
        elif f[0] == "nonfinite_attr":
            r["attr"].append((f[1], f[2]))
        elif f[0] == "frame":
            r["frames"].append([float(v) for v in f[2:]])   # t, 5 energies, strain, psi
        elif f[0] == "final":
            r["final"] = (float(f[1]), float(f[2]))
        elif f[0] == "geometry":
            r["L"], r["D"] = float(f[1]), float(f[2])
    return r

def scan_h5_finite(h5, d, bad):
    """h5scan the file; NaN/inf anywhere is a problem, except a /stats
    attribute whose JSON key is null (a quantity the scene does not have)."""
    s = h5scan(h5)
    if s["rc"] != 0:
        bad.append("drape.h5 unreadable: " + s["err"])
        return None
    for x in s["data"]:
        bad.append("NaN/inf in drape.h5 dataset " + x)
    def json_null(key):          # "energy_J.kinetic" -> d["energy_J"]["kinetic"]
        v = d
        for part in key.split("."):
            if not isinstance(v, dict) or part not in v:
                return False
            v = v[part]
        return v is None
    for path, name in s["attr"]:
        if not (path == "/stats" and json_null(name)):
            bad.append("NaN/inf in drape.h5 attribute %s:%s" % (path, name))
    return s

def obj_check(outdir, particles):
    """Every OBJ frame: only finite numbers, one `v` per particle."""
    problems, n = [], 0
    for name in sorted(os.listdir(outdir)):
        if not name.endswith(".obj"):
            continue
        n += 1
        nv = 0
        with open(os.path.join(outdir, name)) as fh:
            for line in fh:
                if line.startswith("#"):
                    continue
                if BAD_TOKEN.search(line):
                    problems.append("%s: non-finite value: %s" % (name, line.strip()[:60]))
                    break
                if line.startswith("v "):
                    nv += 1
                    vals = line.split()[1:]
                    if len(vals) != 3 or not all(NUM.fullmatch(v) for v in vals):
                        problems.append("%s: bad vertex line: %s" % (name, line.strip()[:60]))
                        break
        if nv != particles:
            problems.append("%s: %d vertices, expected %d" % (name, nv, particles))
    return n, problems

def fmt(x, spec="%.3g"):
    return "-" if x is None else spec % x

def run_case(case, scene, form, integ, extra, expect):
    outdir = os.path.join(tmp, "%s-%s-%s" % (case, form, integ))
    os.makedirs(outdir)
    cmd = ["timeout", "-k", "10", "%g" % timeout_s, bin_, "run", scene, "-q",
           "--energy-form", form, "--out", outdir]
    if integ != "auto":
        cmd += ["--integrator", integ]
    cmd += extra
    if integ == "animate" and expect == "failed":
        # one step per frame: the step limit needs more steps per frame
        cmd += ["--substeps", "100"]
    c0, t0 = os.times(), time.monotonic()
    p = subprocess.run(cmd, capture_output=True, text=True)
    wall = time.monotonic() - t0
    c1 = os.times()
    cpu = (c1.children_user - c0.children_user) + (c1.children_system - c0.children_system)
    r = {"case": case, "form": form, "rc": p.returncode, "wall": wall, "cpu": cpu,
         "problems": [], "notes": [], "cmd": " ".join(cmd[5:])}
    bad = r["problems"]
    err = p.stderr.strip()
    r["stderr"] = err
    if p.returncode in (124, 137):
        bad.append("timeout after %g s (a hang is a failure of the suite)" % timeout_s)
        return r
    if p.returncode < 0:
        bad.append("killed by signal %d (a crash)%s"
                   % (-p.returncode, ": " + err.splitlines()[-1] if err else ""))
    elif p.returncode not in (0, 4):
        bad.append("exit status %d (expected 0, or 4 with status failed)%s"
                   % (p.returncode, ": " + err.splitlines()[-1] if err else ""))
    if BAD_TOKEN.search(p.stdout):
        bad.append("NaN/inf in the JSON: " + BAD_TOKEN.search(p.stdout).group(0))
    try:
        d = json.loads(p.stdout, parse_constant=reject_constant)
        if not isinstance(d, dict):
            raise ValueError("not an object")
    except ValueError as e:
        bad.append("stdout is not one JSON object (%s): %s" % (e, p.stdout[:80]))
        return r
    r["json"] = d
    for k in ("status", "integrator", "t_end_s", "steps", "max_strain", "mass_kg",
              "particles", "linear_solver"):
        r[k] = d.get(k)
    en = d.get("energy_J") or {}
    if expect and d.get("status") != expect:
        bad.append("status %r, expected %r" % (d.get("status"), expect))
    if p.returncode == 4 or d.get("status") == "failed":
        if d.get("status") != "failed":
            bad.append("exit 4 but status %r" % d.get("status"))
        if p.returncode != 4:
            bad.append("status failed but exit %d" % p.returncode)
        # The message must name the time: `... at t = T s ...` (the
        # integrators say `NAME failed at t = T s: FLAG (...); hint: ...`).
        m = re.search(r"\bt = ([^\s,;:]+) s\b", err)
        if not err:
            bad.append("status failed without a message on stderr")
        elif not m:
            bad.append("failure message does not name the time: " + err.splitlines()[0][:120])
        else:
            try:
                tf = float(m.group(1))
                if not math.isfinite(tf):
                    raise ValueError
            except ValueError:
                bad.append("failure time is not a finite number: " + m.group(1))
            r["reason"] = re.sub(r"^drape: ", "", err.splitlines()[0])
            # for the table: up to the solver's own message or the hint
            r["reason_short"] = re.split(r" \(|; hint", r["reason"])[0]
        if BAD_TOKEN.search(err):
            bad.append("NaN/inf in the failure message: " + err[:120])
        # A numerical failure keeps drape.h5 with the frames before the
        # fault and /stats/error (docs/outputs.md): it must hold no NaN/inf.
        h5 = os.path.join(outdir, "drape.h5")
        if os.path.exists(h5):
            r["notes"].append("failed run kept drape.h5")
            scan_h5_finite(h5, d, bad)
        n, probs = obj_check(outdir, d.get("particles") or 0)
        bad.extend(probs)
        return r
    # Success: the full contract.
    if d.get("status") not in ("t_max", "equilibrium"):
        bad.append("exit 0 with status %r" % d.get("status"))
    for k in ("kinetic", "stretch", "bend", "shear", "gravity"):
        v = en.get(k)
        if not isinstance(v, (int, float)):
            bad.append("energy_J.%s is %r" % (k, v))
    ms = d.get("max_strain")
    if not isinstance(ms, (int, float)):
        bad.append("max_strain is %r" % ms)
    elif ms >= STRAIN_MAX:
        bad.append("max_strain %.4g >= %g" % (ms, STRAIN_MAX))
    if err:
        r["notes"].append("stderr: " + err.splitlines()[0][:100])
    h5 = os.path.join(outdir, "drape.h5")
    if not os.path.exists(h5):
        bad.append("no drape.h5 written")
        return r
    s = scan_h5_finite(h5, d, bad)
    if s is None:
        return r
    fr = s["frames"]
    if not fr:
        bad.append("drape.h5 has no frames")
        return r
    M = d.get("mass_kg") or 0.0
    L, D = s.get("L", 0.0), s.get("D", 0.0)
    eg0 = fr[0][5]
    excess, lowest = 0.0, math.inf
    for f in fr:
        e = sum(f[1:6])
        lowest = min(lowest, e)
        excess = max(excess, e - lowest)
    drop = min(f[5] for f in fr) - eg0
    smax = max(f[6] for f in fr)
    psimax = max(f[7] for f in fr)
    r.update(excess=excess / (M * G * L), drop=drop / (M * G * D) if D > 0 else None,
             strain_frames=smax, psi=psimax, frames=len(fr))
    if not excess <= E_TOL * M * G * L:
        bad.append("energy rose by %.3g J = %.3g M g L above an earlier value (bound %g M g L)"
                   % (excess, excess / (M * G * L), E_TOL))
    if not drop >= -1.01 * M * G * D:
        bad.append("E_grav fell by %.3g J, more than 1.01 M g D = %.3g J"
                   % (-drop, 1.01 * M * G * D))
    if not smax < STRAIN_MAX:
        bad.append("strain %.4g >= %g in a frame" % (smax, STRAIN_MAX))
    if s["final"] and isinstance(ms, (int, float)):
        fs = s["final"][0]
        if abs(fs - ms) > 1e-6 * max(abs(ms), 1e-12) + 1e-12:
            bad.append("max_strain key %.9g disagrees with the strain of /final/positions %.9g"
                       % (ms, fs))
    n, probs = obj_check(outdir, d.get("particles") or 0)
    r["obj"] = n
    bad.extend(probs)
    return r

def line_for(r):
    ok = "PASS" if not r["problems"] else "FAIL"
    if r.get("status") == "failed" and not r["problems"]:
        ok = "PASS (failed cleanly)"
    parts = ["%-22s %-12s %-10s" % (ok, r["case"], r["form"])]
    if "json" in r:
        parts.append("%s %s t=%s steps=%s strain=%s" % (
            r.get("integrator"), r.get("status"), fmt(r.get("t_end_s"), "%.4g"),
            r.get("steps"), fmt(r.get("max_strain"), "%.2e")))
        if "excess" in r:
            parts.append("dE+=%s MgL psi=%s" % (fmt(r["excess"], "%.1e"), fmt(r["psi"], "%.3f")))
        if r.get("obj"):
            parts.append("obj=%d" % r["obj"])
    parts.append("cpu=%.1fs wall=%.1fs" % (r["cpu"], r["wall"]))
    s = "  ".join(parts)
    for pr in r["problems"]:
        s += "\n    - " + pr
    if r.get("reason"):
        s += "\n    reason: " + r["reason"][:200]
    return s

t_start = time.monotonic()
load0 = os.getloadavg()[0]
results, checks = [], {}
for case, fname, hard, extra, expect in CASES:
    scene = os.path.join("tests/hard", fname)
    checks[case] = drape_check(scene)
    if checks[case]["rc"] != 0:
        print("FAIL %s: drape check %s exits %d" % (case, scene, checks[case]["rc"]))
    for form, integ in [(f, i) for i in INTEGRATORS for f in FORMS]:
        r = run_case(case, scene, form, integ, extra, expect)
        r["hard"] = hard
        results.append(r)
        print(line_for(r), flush=True)
total_wall = time.monotonic() - t_start
load1 = os.getloadavg()[0]
nfail = sum(1 for r in results if r["problems"]) + \
        sum(1 for c in checks.values() if c["rc"] != 0)
cpu = sum(r["cpu"] for r in results)
print("check-hard: %d runs, %d kept the contract, %d broke it; CPU %.0f s, wall %.0f s "
      "(load average %.1f at start, %.1f at end)"
      % (len(results), len(results) - sum(1 for r in results if r["problems"]),
         sum(1 for r in results if r["problems"]), cpu, total_wall, load0, load1))

def cell(s):
    return str(s).replace("|", "\\|")

def table():
    out = []
    out.append("Generated by `scripts/check-hard.sh --update-doc` on %s, drape `%s`; "
               "load average %.1f-%.1f on 2 cores; suite CPU %.0f s, wall %.0f s."
               % (time.strftime("%Y-%m-%d"), os.path.relpath(bin_) if bin_.startswith(os.getcwd()) else bin_,
                  load0, load1, cpu, total_wall))
    out.append("")
    out.append("Stiffness bounds: `drape check` on the scene (Gershgorin bound on "
               "omega of M^-1 K at the flat start, consistent form; h = explicit RK4 step limit).")
    out.append("")
    out.append("| case | what makes it hard | particles (free) | omega stretch / shear / bend, rad/s | h stretch, s |")
    out.append("|---|---|---|---|---|")
    for case, fname, hard, extra, expect in CASES:
        c = checks[case]
        out.append("| `%s` | %s | %s (%s) | %s / %s / %s | %s |" % (
            case, cell(hard), c.get("particles", "?"), c.get("free", "?"),
            fmt(c.get("w_stretch")), fmt(c.get("w_shear")), fmt(c.get("w_bend")),
            fmt(c.get("h_stretch"))))
    out.append("")
    out.append("Runs: `drape run tests/hard/CASE.yaml -q --energy-form FORM --out DIR`. "
               "dE+ = largest rise of E_kin + E_pot above its lowest earlier value over the "
               "frames, in M g L (bound 0.01; 0: never rose); strain = max_strain key / largest over the frames; "
               "psi = largest hinge turning angle over the frames (pi = folded flat).")
    out.append("")
    out.append("| case | form | contract | integrator | status | t_end s | steps | strain (key / frames) | dE+ / M g L | psi max | CPU s | wall s |")
    out.append("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for r in results:
        if r["problems"]:
            verdict = "**broken**: " + "; ".join(r["problems"])
        elif r.get("status") == "failed":
            verdict = "kept (failed cleanly: %s)" % (r.get("reason_short") or "")[:120]
        else:
            verdict = "kept"
        out.append("| `%s` | %s | %s | %s | %s | %s | %s | %s / %s | %s | %s | %.1f | %.1f |" % (
            r["case"], r["form"], cell(verdict), r.get("integrator", "-"), r.get("status", "-"),
            fmt(r.get("t_end_s"), "%.4g"), r.get("steps", "-"),
            fmt(r.get("max_strain"), "%.2e"), fmt(r.get("strain_frames"), "%.2e"),
            fmt(r.get("excess"), "%.1e"), fmt(r.get("psi"), "%.3f"), r["cpu"], r["wall"]))
    return "\n".join(out) + "\n"

if update_doc:
    doc = "docs/stability.md"
    begin, end = "<!-- BEGIN GENERATED by scripts/check-hard.sh -->", "<!-- END GENERATED -->"
    if only:
        print("check-hard: --update-doc needs the whole suite; not updating %s" % doc,
              file=sys.stderr)
    else:
        text = open(doc).read()
        a, b = text.find(begin), text.find(end)
        if a < 0 or b < a:
            print("check-hard: %s has no GENERATED markers" % doc, file=sys.stderr)
            sys.exit(1)
        new = text[:a + len(begin)] + "\n" + table() + text[b:]
        with open(doc + ".tmp", "w") as fh:
            fh.write(new)
        os.replace(doc + ".tmp", doc)
        print("check-hard: table written to %s" % doc)
sys.exit(1 if nfail else 0)
PY
