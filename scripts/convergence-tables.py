#!/usr/bin/env python3
"""The tables of docs/convergence.md from the results of
scripts/bench-convergence.sh.

usage: convergence-tables.py OUT TAG DOC "FABRIC ..."

Reads OUT/F-H-{fall,accurate}TAG.json (drape run ensembles), their .meta
files and the drape compare results the script made, and replaces the text
between the markers <!-- convergence-bench start --> and
<!-- convergence-bench end --> of DOC (the markers are added at the end
when missing).  Nothing but the standard library.
"""
import json
import os
import re
import subprocess
import sys

SPACINGS = ["1cm", "0.7cm", "0.5cm", "0.35cm", "0.25cm"]
HALF = {"1cm": "0.5cm", "0.7cm": "0.35cm", "0.5cm": "0.25cm"}


def load(path):
    try:
        with open(path) as f:
            return json.load(f)
    except (OSError, ValueError):
        return None


def meta(path):
    m = {}
    try:
        with open(path) as f:
            for line in f:
                k, _, v = line.partition(": ")
                m[k.strip()] = v.strip()
    except OSError:
        pass
    return m


def hist(h):
    if not h:
        return "{}"
    return "{" + ", ".join("%s: %d" % (k, v) for k, v in sorted(h.items(), key=lambda kv: int(kv[0]))) + "}"


def cpu_per(r):
    sp = r.get("specimens") or []
    c = [s.get("cpu_s") for s in sp if isinstance(s.get("cpu_s"), (int, float))]
    return sum(c) / len(c) if c else float("nan")


def ens(r):
    n = len(r.get("specimens") or [])
    ci = r.get("dc_ci95")
    return "%d, %.4f +- %s, %s" % (n, r["dc"], "%.4f" % ci if isinstance(ci, (int, float)) else "-",
                                   hist(r.get("nodes_hist")))


def fabric_props(name):
    """bending lengths (warp, weft) and shear rigidity from drape check"""
    drape = os.environ.get("DRAPE_BIN", "./drape")
    try:
        out = subprocess.run([drape, "check", "fabrics/%s.yaml" % name], capture_output=True,
                             text=True, check=False).stdout
    except OSError:
        return None
    c = dict(re.findall(r"^  (warp|weft): .*bending_length_m \(B/Wg\)\^\(1/3\) ([0-9.e+-]+)", out, re.M))
    g = re.search(r"shear_rigidity_N_m_rad ([0-9.e+-]+)", out)
    w = re.search(r"weight_kg_m2\s+([0-9.e+-]+)", out)
    if "warp" not in c or "weft" not in c:
        return None
    return {"c_warp": float(c["warp"]), "c_weft": float(c["weft"]),
            "G": float(g.group(1)) if g else float("nan"), "W": float(w.group(1)) if w else float("nan")}


def main():
    out, tag, doc, fabrics = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4].split()
    lines = []
    for f in fabrics:
        p = fabric_props(f)
        lines.append("### %s%s" % (f, " (%s)" % tag.lstrip("-") if tag else ""))
        lines.append("")
        if p:
            lines.append("Bending length c = (B / (W g))^(1/3): warp %.1f mm, weft %.1f mm; "
                         "shear rigidity %.3g N/m; weight %.0f g/m^2." %
                         (1e3 * p["c_warp"], 1e3 * p["c_weft"], p["G"], 1e3 * p["W"]))
            lines.append("")
        lines.append("| spacing | particles | fall: n, DC +- 95 %, nodes | fall CPU s / specimen "
                     "| accurate: n, DC +- 95 %, nodes | accurate CPU s / specimen "
                     "| fall - accurate +- 95 % | p_nodes | p_dc_dist | commit |")
        lines.append("|---|---|---|---|---|---|---|---|---|---|")
        any_row = False
        for h in SPACINGS:
            fa = load(os.path.join(out, "%s-%s-fall%s.json" % (f, h, tag)))
            ac = load(os.path.join(out, "%s-%s-accurate%s.json" % (f, h, tag)))
            if not fa and not ac:
                continue
            any_row = True
            cm = load(os.path.join(out, "%s-%s-fall-accurate%s-compare.json" % (f, h, tag)))
            commits = sorted({meta(os.path.join(out, "%s-%s-%s%s.meta" % (f, h, m, tag))).get("commit", "")
                              for m, r in (("fall", fa), ("accurate", ac)) if r} - {""})
            row = [h.replace("cm", " cm"), str((fa or ac).get("particles", "")),
                   ens(fa) if fa else "not run", "%.1f" % cpu_per(fa) if fa else "",
                   ens(ac) if ac else "not run", "%.1f" % cpu_per(ac) if ac else ""]
            if cm:
                row += ["%+.4f +- %.4f" % (cm["dc_diff"], cm["dc_diff_ci95"]),
                        "%.3f" % cm["p_nodes"], "%.3f" % cm["p_dc_dist"]]
            else:
                row += ["", "", ""]
            row.append(", ".join(commits))
            lines.append("| " + " | ".join(row) + " |")
        if not any_row:
            lines.append("| (no results yet) | | | | | | | | | |")
        lines.append("")
        lines.append("Halving the spacing (MODEL.md 6: the mean moves by less than 0.01 and "
                     "the node histograms are not distinguished at 5 %):")
        lines.append("")
        lines.append("| method | spacing -> half | mean change +- 95 % | p_nodes | converged |")
        lines.append("|---|---|---|---|---|")
        hstar = {}
        for m in ("accurate", "fall"):
            for h, h2 in HALF.items():
                cm = load(os.path.join(out, "%s-%s-%s-%s%s-compare.json" % (f, h, h2, m, tag)))
                if not cm:
                    continue
                ok = abs(cm["dc_diff"]) < 0.01 and cm["p_nodes"] >= 0.05
                if ok and m not in hstar:
                    hstar[m] = h
                lines.append("| %s | %s -> %s | %+.4f +- %.4f | %.3f | %s |" %
                             (m, h.replace("cm", " cm"), h2.replace("cm", " cm"), cm["dc_diff"],
                              cm["dc_diff_ci95"], cm["p_nodes"], "yes" if ok else "no"))
        lines.append("")
        for m in ("accurate", "fall"):
            lines.append("- h* (%s): %s" % (m, hstar[m].replace("cm", " cm") if m in hstar
                                              else "not reached among the spacings run"))
        lines.append("")
    text = "\n".join(lines)
    start, end = "<!-- convergence-bench start -->", "<!-- convergence-bench end -->"
    try:
        with open(doc) as fh:
            d = fh.read()
    except OSError:
        d = ""
    if start in d and end in d:
        d = d[:d.index(start) + len(start)] + "\n" + text + "\n" + d[d.index(end):]
    else:
        d = d + "\n" + start + "\n" + text + "\n" + end + "\n"
    tmp = doc + ".tmp"
    with open(tmp, "w") as fh:
        fh.write(d)
    os.replace(tmp, doc)


if __name__ == "__main__":
    main()
