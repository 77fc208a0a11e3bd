#!/usr/bin/env python3
"""report.py: regenerate the tables of docs/performance.md from the CSV
files of `drape bench` (called by scripts/bench.sh).

    report.py OUT_DIR DOC TIME_COLUMN

Each block between
    <!-- BEGIN GENERATED: scripts/bench.sh NAME -->
    <!-- END GENERATED: NAME -->
is replaced; a block that is missing from DOC is appended at the end.
NAME is `machine`, `kernels`, or a scene name with OUT_DIR/NAME.csv.
Blocks of scenes that have no CSV are left as they are.
"""
import csv
import math
import os
import sys

OUT, DOC, TIME = sys.argv[1:4]
TIME_LABEL = "CPU s" if TIME == "cpu_s" else "wall s"


def rows_of(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def num(v):
    try:
        x = float(v)
        return x if math.isfinite(x) else None
    except (TypeError, ValueError):
        return None


def g(v, fmt="%.3g"):
    x = num(v)
    return "-" if x is None else fmt % x


def knob(r):
    """The swept setting of a row: rtol, or animate's fixed step (issue 16)."""
    if r.get("step_s") and num(r.get("rtol")) is None:
        return "h " + g(r["step_s"], "%.3g") + " s"
    return g(r["rtol"], "%.3g")


def cnt(v):
    return v if v not in (None, "") else "-"


def interp(points, e):
    """log-log interpolation of time at error e on points [(err, t)]
    sorted by error; None outside the range."""
    if not points or e < points[0][0] or e > points[-1][0]:
        return None
    for (e0, t0), (e1, t1) in zip(points, points[1:]):
        if e0 <= e <= e1:
            if e1 == e0:
                return min(t0, t1)
            w = (math.log(e) - math.log(e0)) / (math.log(e1) - math.log(e0))
            return math.exp((1 - w) * math.log(t0) + w * math.log(t1))
    return points[-1][1] if e == points[-1][0] else None


def curve(rows, integ, err):
    pts = []
    for r in rows:
        if r["role"] == "sweep" and r["status"] == "ok" and r["integrator"] == integ:
            e, t = num(r[err]), num(r[TIME])
            if e and e > 0 and t and t > 0:
                pts.append((e, t))
    pts.sort()
    return pts


def order(rows):
    seen = []
    for r in rows:
        if r["role"] == "sweep" and r["integrator"] not in seen:
            seen.append(r["integrator"])
    return seen


def speedups(rows, err, base="gsl-msbdf"):
    """For each integrator: time(base) / time(integrator) at equal error, at
    9 log-spaced error levels across the overlap of the two curves."""
    out = []
    b = curve(rows, base, err)
    for integ in order(rows):
        if integ == base:
            continue
        c = curve(rows, integ, err)
        if len(b) < 2 or len(c) < 2:
            out.append((integ, None, None, None, None))
            continue
        lo, hi = max(b[0][0], c[0][0]), min(b[-1][0], c[-1][0])
        if lo >= hi:
            out.append((integ, None, None, None, None))
            continue
        ratios = []
        for k in range(9):
            e = math.exp(math.log(lo) + (math.log(hi) - math.log(lo)) * k / 8)
            tb, tc = interp(b, e), interp(c, e)
            if tb and tc:
                ratios.append(tb / tc)
        ratios.sort()
        med = ratios[len(ratios) // 2] if ratios else None
        out.append((integ, med, ratios[0] if ratios else None,
                    ratios[-1] if ratios else None, (lo, hi)))
    return out


def fastest(rows, err):
    """For decade error targets: the cheapest run reaching err <= target."""
    errs = [num(r[err]) for r in rows if r["role"] == "sweep" and r["status"] == "ok"]
    errs = [e for e in errs if e and e > 0]
    if not errs:
        return []
    top = math.floor(math.log10(max(errs)))
    bottom = math.ceil(math.log10(min(errs)))
    out = []
    for d in range(top, bottom - 1, -1):
        target = 10.0 ** d
        best = None
        per = {}
        for r in rows:
            if r["role"] != "sweep" or r["status"] != "ok":
                continue
            e, t = num(r[err]), num(r[TIME])
            if e is None or t is None or e > target:
                continue
            i = r["integrator"]
            if i not in per or t < per[i][0]:
                per[i] = (t, knob(r))
            if best is None or t < best[0]:
                best = (t, i, knob(r))
        if best:
            out.append((target, best, per))
    return out


def scene_block(name, rows):
    L = []
    ref = [r for r in rows if r["role"] == "ref"]
    chk = [r for r in rows if r["role"] == "ref-check"]
    sweep = [r for r in rows if r["role"] == "sweep"]
    r0 = rows[0]
    has_dc = any(num(r["dc"]) is not None for r in rows)
    default = next((r["integrator"] for r in rows if r["default"] == "1"), "")
    L.append(f"Scene `{name}`: {r0['scene']}, fabric {r0['fabric']}, {r0['particles']} particles "
             f"({r0['free_particles']} free), specimen size {g(r0['size_m'])} m, horizon "
             f"t_end = {g(r0['t_end_s'])} s, {r0['samples']} sample times; "
             + ("the default `auto` is swept as its own row." if default == "auto"
                else f"`auto` resolves to `{default}` here." if default
                else "the default `auto` was not swept."))
    L.append("")
    if ref:
        r = ref[0]
        s = (f"Reference: `{r['integrator']}` at rtol {g(r['rtol'])} ({r['status']}, "
             f"{g(r[TIME])} {TIME_LABEL}, {cnt(r['steps'])} steps).")
        if chk:
            c = chk[0]
            if c["status"] == "ok":
                s += (f" The check `{c['integrator']}` at the same rtol ({g(c[TIME])} {TIME_LABEL}) "
                      f"agrees to err_pos_rel {g(c['err_pos_rel'])}, err_final_rel "
                      f"{g(c['err_final_rel'])}, err_final_v_rel {g(c['err_final_v_rel'])}")
                if has_dc:
                    s += f", err_dc {g(c['err_dc'])}"
                s += "."
                small = [num(x["err_pos_rel"]) for x in sweep if x["status"] == "ok"]
                small = [e for e in small if e and e > 0]
                ag = num(c["err_pos_rel"])
                if small and ag is not None:
                    ratio = min(small) / ag if ag > 0 else math.inf
                    s += (f" The smallest error plotted is {g(min(small))}, "
                          f"{'%.2g' % ratio if math.isfinite(ratio) else 'infinitely many'} "
                          f"times the disagreement.")
            else:
                s += f" The check `{c['integrator']}` did not finish ({c['status']}): the reference is not confirmed."
        L.append(s)
        L.append("")
    plots = [("pos", "err_pos_rel")] + [("final", "err_final_rel")] + ([("dc", "err_dc")] if has_dc else [])
    L.append(" ".join(f"![{name} {m}](performance/{name}-{m}.png)" for m, _ in plots))
    L.append("")
    L.append("SVG: " + ", ".join(f"[{m}](performance/{name}-{m}.svg)" for m, _ in plots)
             + f"; raw data: [`performance/{name}.csv`](performance/{name}.csv).")
    L.append("")
    hdr = ["integrator", "rtol (animate: step)", "status", "wall s", "CPU s", "steps", "RHS", "Jac", "setups",
           "err_pos_rel", "err_final_rel"] + (["DC", "err_dc"] if has_dc else [])
    L.append("| " + " | ".join(hdr) + " |")
    L.append("|" + "---|" * len(hdr))
    for r in sweep:
        integ = r["integrator"] + (" (default)" if r["default"] == "1" else "")
        cells = [integ, knob(r), r["status"], g(r["wall_s"]), g(r["cpu_s"]),
                 cnt(r["steps"]), cnt(r["rhs_evals"]), cnt(r["jac_evals"]), cnt(r["lin_setups"]),
                 g(r["err_pos_rel"], "%.2e"), g(r["err_final_rel"], "%.2e")]
        if has_dc:
            cells += [g(r["dc"], "%.4f"), g(r["err_dc"], "%.1e")]
        L.append("| " + " | ".join(cells) + " |")
    L.append("")
    fails = [r for r in sweep if r["status"] == "failed" and r["message"]]
    for r in fails[:6]:
        L.append(f"- `{r['integrator']}` at {knob(r)} failed: {r['message'][:200]}")
    if fails:
        L.append("")
    # equal-error speed-ups over gsl-msbdf
    sp = speedups(rows, "err_pos_rel")
    if any(s[1] for s in sp):
        L.append(f"Time of `gsl-msbdf` divided by the time of each integrator at equal err_pos_rel "
                 f"({TIME_LABEL}; log-log interpolation at 9 error levels across the error range "
                 f"both curves cover; median and range):")
        L.append("")
        L.append("| integrator | msbdf time / its time (median) | range | error range compared |")
        L.append("|---|---|---|---|")
        for integ, med, lo, hi, rng in sp:
            name_i = integ + (" (default)" if integ == default else "")
            if med is None:
                L.append(f"| {name_i} | - | - | no overlap |")
            else:
                L.append(f"| {name_i} | {med:.3g} | {lo:.3g}-{hi:.3g} | {rng[0]:.1e} to {rng[1]:.1e} |")
        L.append("")
    fr = fastest(rows, "err_pos_rel")
    if fr:
        integs = order(rows)
        L.append(f"Cheapest run reaching err_pos_rel <= target ({TIME_LABEL}; rtol in brackets; "
                 f"- = no run of that integrator got there):")
        L.append("")
        L.append("| target | fastest | " + " | ".join(integs) + " |")
        L.append("|---|---|" + "---|" * len(integs))
        for target, best, per in fr:
            cells = [f"{target:.0e}", f"{best[1]} {best[0]:.3g}"]
            for i in integs:
                cells.append(f"{per[i][0]:.3g} ({per[i][1]})" if i in per else "-")
            L.append("| " + " | ".join(cells) + " |")
        L.append("")
    return L


def kernels_block(rows):
    L = []
    hdr = ["side", "particles", "free", "nnz(K)", "RHS ms", "K, D ms", "first-order J ms",
           "CHOLMOD factor of S ms", "RHS us / free particle", "K, D us / free particle",
           "CHOLMOD solve ms"]
    L.append("| " + " | ".join(hdr) + " |")
    L.append("|" + "---|" * len(hdr))
    for r in rows:
        L.append("| " + " | ".join([r["side"], r["particles"], r["free_particles"], r["nnz_K"],
                                    g(r["rhs_ms"]), g(r["jac_ms"]), g(r["jac_first_order_ms"]),
                                    g(r["schur_factor_ms"]), g(r["rhs_us_per_free"]),
                                    g(r["jac_us_per_free"]), g(r.get("schur_solve_ms") or "")])
                 + " |")
    L.append("")
    big = [r for r in rows if num(r["free_particles"]) and num(r["free_particles"]) >= 1000]
    if len(big) >= 2:
        a, b = big[0], big[-1]
        na, nb = num(a["free_particles"]), num(b["free_particles"])
        parts = []
        for col, label in [("rhs_ms", "RHS"), ("jac_ms", "K, D"), ("jac_first_order_ms", "first-order J"),
                           ("schur_factor_ms", "CHOLMOD factor"), ("schur_solve_ms", "CHOLMOD solve")]:
            ta, tb = num(a.get(col) or ""), num(b.get(col) or "")
            if ta and tb:
                parts.append(f"{label} n^{math.log(tb / ta) / math.log(nb / na):.2f}")
        L.append(f"Growth from {int(na)} to {int(nb)} free particles (exponent of a power law "
                 f"through the two points): " + ", ".join(parts) + ".")
        L.append("")
    L.append("![kernels](performance/kernels.png) ([SVG](performance/kernels.svg), "
             "[CSV](performance/kernels.csv))")
    L.append("")
    return L


def machine_block():
    L = []
    info = {}
    p = os.path.join(OUT, "machine.txt")
    if os.path.exists(p):
        for line in open(p):
            if "=" in line:
                k, v = line.rstrip("\n").split("=", 1)
                info[k] = v
    L.append(f"Machine: {info.get('cpu', 'unknown')}, {info.get('cores', '?')} cores, "
             f"{info.get('mem', '?')} memory, {info.get('os', '')}; last run: drape "
             f"{info.get('commit', '?')}, built with `{info.get('cflags', '?')}`, "
             f"{info.get('date', '?')} (each row below says which build made it). "
             f"Times in the tables and plots: `{TIME}` (BENCH_TIME).")
    L.append("")
    p = os.path.join(OUT, "runs.csv")
    if os.path.exists(p):
        L.append("| name | command (after `drape bench`) | drape | built with | date | elapsed s | "
                 "load before | load after |")
        L.append("|---|---|---|---|---|---|---|---|")
        for r in rows_of(p):
            L.append(f"| {r['name']} | `{r['args']}` | {r.get('commit') or '?'} | "
                     f"`{r.get('cflags') or '?'}` | {r.get('date') or '?'} | {r['elapsed_s']} | "
                     f"{r['load_before']} | {r['load_after']} |")
        L.append("")
    return L


def replace_block(text, name, lines):
    begin = f"<!-- BEGIN GENERATED: scripts/bench.sh {name} -->"
    end = f"<!-- END GENERATED: {name} -->"
    block = "\n".join([begin, ""] + lines + [end])
    if begin in text and end in text:
        a = text.index(begin)
        b = text.index(end) + len(end)
        return text[:a] + block + text[b:]
    return text.rstrip("\n") + "\n\n" + block + "\n"


def main():
    text = open(DOC).read() if os.path.exists(DOC) else "# Performance\n"
    text = replace_block(text, "machine", machine_block())
    kp = os.path.join(OUT, "kernels.csv")
    if os.path.exists(kp):
        text = replace_block(text, "kernels", kernels_block(rows_of(kp)))
    names = []
    p = os.path.join(OUT, "runs.csv")
    if os.path.exists(p):
        names = [r["name"] for r in rows_of(p) if r["name"] != "kernels"]
    for name in names:
        cp = os.path.join(OUT, name + ".csv")
        if os.path.exists(cp):
            rows = rows_of(cp)
            if rows:
                text = replace_block(text, name, scene_block(name, rows))
    tmp = DOC + ".tmp"
    with open(tmp, "w") as f:
        f.write(text)
    os.replace(tmp, DOC)


main()
