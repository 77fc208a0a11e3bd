#!/usr/bin/env python3
"""The tables of docs/convergence.md from the results of
scripts/bench-convergence.sh.

usage: convergence-tables.py OUT TAG DOC "FABRIC ..." [WORK]

Reads OUT/F-H-{fall,accurate}TAG.json (drape run ensembles), their .meta
files and the drape compare results the script made, and replaces the text
between the markers <!-- convergence-bench start --> and
<!-- convergence-bench end --> of DOC (the markers are added at the end
when missing).  With WORK (the ensembles' directories), also the node
positions, read from each specimen's outline (the @shadow line of its
result.txt).  Nothing but the standard library.
"""
import json
import os
import re
import subprocess
import sys

SPACINGS = ["1cm", "0.7cm", "0.5cm", "0.35cm", "0.25cm", "0.175cm"]
HALF = {"1cm": "0.5cm", "0.7cm": "0.35cm", "0.5cm": "0.25cm", "0.35cm": "0.175cm"}


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


def fabric_props(name, out_dir):
    """bending lengths (warp, weft) and shear rigidity from drape check (a
    study fabric that is not in fabrics/ is read from out_dir)"""
    drape = os.environ.get("DRAPE_BIN", "./drape")
    path = "fabrics/%s.yaml" % name
    if not os.path.exists(path):
        path = os.path.join(out_dir, "%s.yaml" % name)
    try:
        out = subprocess.run([drape, "check", path], capture_output=True,
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


def peaks(r, thr):
    """sample indices of the nodes of circular samples r: maxima whose
    prominence exceeds thr (drape_nodes_find's rule, src/drape.c)"""
    n = len(r)
    m0 = min(range(n), key=lambda k: r[k])
    a = lambda k: r[(m0 + k) % n]
    out, k = [], 1
    while k < n:
        e = k
        while e + 1 < n and a(e + 1) == a(k):
            e += 1
        h = a(k)
        if a(k - 1) < h and a((e + 1) % n) < h:
            lo_l = lo_r = h
            found, ln = False, e - k + 1
            for st in range(1, n - ln + 1):
                j = (k - st) % n
                if a(j) > h or (a(j) == h and j > k):
                    found = True
                    break
                lo_l = min(lo_l, a(j))
            if found:
                for st in range(1, n - ln + 1):
                    j = (e + st) % n
                    if a(j) > h or (a(j) == h and j > k):
                        break
                    lo_r = min(lo_r, a(j))
            prom = h - max(lo_l, lo_r) if found else h - min(r)
            if prom > thr:
                out.append((m0 + (k + e) // 2) % n)
        k = e + 1
    return out


def node_angles(work, name):
    """angles (deg, 0-45) of every node of the ensemble WORK/name from the
    nearest lattice axis; None without its specimens"""
    d = os.path.join(work, name)
    if not os.path.isdir(d):
        return None
    ang = []
    for sp in sorted(os.listdir(d)):
        try:
            with open(os.path.join(d, sp, "result.txt")) as f:
                for line in f:
                    if line.startswith("@shadow"):
                        p = line.split()
                        thr, r = float(p[4]), [float(x) for x in p[5:]]
                        for k in peaks(r, thr):
                            t = (360.0 * k / len(r)) % 90.0
                            ang.append(min(t, 90.0 - t))
        except OSError:
            continue
    return ang


def extra_tables(out, work, fabrics):
    lines = []
    if work:
        lines.append("### Where the nodes sit")
        lines.append("")
        lines.append("Each node's angle from the nearest lattice axis (the warp or the weft), "
                     "read from the specimens' outlines; a fabric without a preferred direction "
                     "would put a third of its nodes in each column.")
        lines.append("")
        lines.append("| fabric | method | spacing | nodes | 0-15 deg | 15-30 deg | 30-45 deg |")
        lines.append("|---|---|---|---|---|---|---|")
        for f in fabrics + [x for x in ("isotropic-soft", "isotropic-plate") if x not in fabrics]:
            for m in ("fall", "accurate"):
                for h in SPACINGS:
                    a = node_angles(work, "%s-%s-%s" % (f, h, m))
                    if not a:
                        continue
                    b = [sum(1 for x in a if lo <= x < lo + 15 or (lo == 30 and x == 45))
                         for lo in (0, 15, 30)]
                    lines.append("| %s | %s | %s | %d | %.0f %% | %.0f %% | %.0f %% |" %
                                 (f, m, h.replace("cm", " cm"), len(a),
                                  *[100.0 * x / len(a) for x in b]))
        lines.append("")
    variants = [("", "0.1 mm, 2 cm to 30 cm (the shipped scene)"), ("-a0.05mm", "amplitude 0.05 mm"),
                ("-a0.2mm", "amplitude 0.2 mm"), ("-a0.5mm", "amplitude 0.5 mm"),
                ("-a1mm", "amplitude 1 mm"), ("-lmin1cm", "lambda_min 1 cm"),
                ("-lmin4cm", "lambda_min 4 cm")]
    rows = []
    for h in SPACINGS:
        for t, what in variants:
            r = load(os.path.join(out, "cotton-breen-%s-fall%s.json" % (h, t)))
            if r and (t or load(os.path.join(out, "cotton-breen-%s-fall-a1mm.json" % h))):
                rows.append((h, what, r, meta(os.path.join(out, "cotton-breen-%s-fall%s.meta" % (h, t)))))
    if rows:
        lines.append("### The perturbation's amplitude and band (cotton-breen, the fall method)")
        lines.append("")
        lines.append("| spacing | perturbation | n, DC +- 95 %, nodes | CPU s / specimen | commit |")
        lines.append("|---|---|---|---|---|")
        for h, what, r, m in rows:
            lines.append("| %s | %s | %s | %.1f | %s |" % (h.replace("cm", " cm"), what, ens(r),
                                                         cpu_per(r), m.get("commit", "")))
        lines.append("")
    fv = [("", "the shipped fall"), ("-nofold", "no fold phase (`--fall-fold-time 0`)"),
          ("-nofold-step2", "no fold phase, twice the step (`--fall-step 4.9ms`)"),
          ("-nofold-step2-noswing", "and no swing (`--fall-swing 0`)"),
          ("-nofold-step2-half", "and half the fall time (`--fall-time 0.39s`)")]
    rows = []
    for h in SPACINGS:
        acc = load(os.path.join(out, "cotton-breen-%s-accurate.json" % h))
        for t, what in fv:
            r = load(os.path.join(out, "cotton-breen-%s-fall%s.json" % (h, t)))
            if acc and r and load(os.path.join(out, "cotton-breen-%s-fall-nofold.json" % h)):
                rows.append((h, what, r, acc))
    if rows:
        lines.append("### Simpler falls against the accurate ensembles (cotton-breen)")
        lines.append("")
        lines.append("| spacing | fall | n, DC +- 95 %, nodes | CPU s / specimen | redone | "
                     "DC - accurate | p_nodes | p_dc_dist |")
        lines.append("|---|---|---|---|---|---|---|---|")
        for h, what, r, acc in rows:
            c = compare_py(acc, r)
            lines.append("| %s | %s | %s | %.1f | %s | %+.4f | %s | %s |" %
                         (h.replace("cm", " cm"), what, ens(r), cpu_per(r), r.get("fall_redone"),
                          r["dc"] - acc["dc"], c[0], c[1]))
        lines.append("")
    return lines


def compare_py(a, b):
    """p_nodes and p_dc_dist of drape compare A B (the DRAPE_BIN binary)"""
    import tempfile
    drape = os.environ.get("DRAPE_BIN", "./drape")
    with tempfile.TemporaryDirectory() as d:
        pa, pb = os.path.join(d, "a.json"), os.path.join(d, "b.json")
        for p, r in ((pa, a), (pb, b)):
            with open(p, "w") as f:
                json.dump(r, f)
        try:
            c = json.loads(subprocess.run([drape, "compare", pa, pb], capture_output=True,
                                          text=True, check=False).stdout)
            return "%.3f" % c["p_nodes"], "%.3f" % c["p_dc_dist"]
        except (OSError, ValueError, KeyError):
            return "", ""


def main():
    out, tag, doc, fabrics = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4].split()
    work = sys.argv[5] if len(sys.argv) > 5 else None
    lines = []
    for f in fabrics:
        p = fabric_props(f, out)
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
        lines.append("Halving the spacing (docs/model.md 6: the mean moves by less than 0.01 and "
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
    if not tag:
        lines += extra_tables(out, work, fabrics)
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
