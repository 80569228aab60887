#!/usr/bin/env python3
"""bench/RESULTS.md, "Issue 15 (session 6)": `--multi-emitter full` against `simplify` for
N = 1, 2, 4, 8 polygon lights (scenes from multi_emitter_scenes.py).

Usage: multi_emitter_bench.py MEBAKE OUTDIR NAME=MESH [NAME=MESH ...] [--lights 1,2,4,8]
       [--no-bounces] [--points 1000] [--time-limit 20]
NAME "bunny" and "cornell" use the scenes of session 5 (the bunny's ring, the Cornell box's
ceiling lights); any other NAME gets the bunny's ring scaled to its bounding box.

Per scene and mode, direct light only (`NAMEN.json`, max_bounces 0): leaves, direct rays
(classify + penumbra), CPU s (user+sys of the solve), the debug log's CPU s of the
extremal-boundary pass and of the fit. With bounces (`NAMENb.json`, unless --no-bounces):
`mebake reference` on the full solve, then relative RMS of both modes against it and
"L2 s-f" = RMS over the reference points of (B simplify - B full) / mean B full.
One JSON object per row on stdout, and a markdown table at the end."""
import json
import math
import os
import re
import shutil
import subprocess
import sys


def run(cmd, log=None):
    with open(log or os.devnull, "w") as err:
        subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=err)


def timed(cmd, log):
    """Runs cmd under /usr/bin/time; returns (CPU s, peak RSS MB)."""
    tfile = log + ".time"
    run(["/usr/bin/time", "-f", "%U %S %M", "-o", tfile] + cmd, log)
    u, s, rss = open(tfile).read().split()[-3:]
    return float(u) + float(s), int(rss) // 1024


def load():
    return float(open("/proc/loadavg").read().split()[0])


def solve(mebake, base, out, scene, mode):
    shutil.rmtree(out, ignore_errors=True)
    shutil.copytree(base, out)
    log = out + ".log"
    cpu, rss = timed([mebake, "-v", "solve", out, "--scene", scene, "--multi-emitter", mode,
                      "--threads", "2", "--stats", out + ".stats.json"], log)
    st = json.load(open(out + ".stats.json"))
    rk = st.get("rays_by_kind", {})
    boundary = fit = 0.0
    for line in open(log):
        m = re.search(r"boundary samples \(([\d.]+) CPU s\).*fit ([\d.]+) CPU s", line)
        if m:
            boundary += float(m.group(1))
            fit += float(m.group(2))
        m = re.search(r"direct light fit ([\d.]+) CPU s", line)
        if m:
            fit += float(m.group(1))
    return {"leaves": st["leaves"], "classify": rk.get("classify", 0),
            "penumbra": rk.get("penumbra", 0), "cpu": cpu, "rss_mb": rss,
            "boundary_cpu": boundary, "fit_cpu": fit, "load": load()}


def compare(mebake, bake, ref, out):
    run([mebake, "compare", bake, ref, "--points", "-o", out])
    d = json.load(open(out))
    return d["error"]["relative_rms"], [sum(p["bake_B"]) / 3 for p in d["points"]]


def main():
    args = sys.argv[1:]
    opts = {"--lights": "1,2,4,8", "--points": "1000", "--time-limit": "20"}
    bounces = "--no-bounces" not in args
    args = [a for a in args if a != "--no-bounces"]
    for k in list(opts):
        if k in args:
            i = args.index(k)
            opts[k] = args[i + 1]
            del args[i:i + 2]
    mebake, outdir, inputs = os.path.abspath(args[0]), args[1], args[2:]
    os.makedirs(outdir, exist_ok=True)
    here = os.path.dirname(os.path.abspath(__file__))
    bases = {}
    for arg in inputs:
        name, mesh = arg.split("=", 1)
        bases[name] = os.path.join(outdir, f"base-{name}.mebake")
        if not os.path.exists(os.path.join(bases[name], "manifest.json")):
            run([mebake, "ingest", mesh, "-o", bases[name]])
    scans = [f"{n}={b}" for n, b in bases.items() if n not in ("bunny", "cornell")]
    run([sys.executable, os.path.join(here, "multi_emitter_scenes.py"),
         os.path.join(outdir, "scenes")] + scans)
    rows = []
    for name, base in bases.items():
        for n in [int(x) for x in opts["--lights"].split(",")]:
            scene = os.path.join(outdir, "scenes", f"{name}{n}")
            row = {"scene": f"{name} {n}"}
            for mode in ("full", "simplify"):
                row[mode] = solve(mebake, base, os.path.join(outdir, f"{name}{n}-{mode}"),
                                  scene + ".json", mode)
            if bounces:
                b = {m: os.path.join(outdir, f"{name}{n}b-{m}") for m in ("full", "simplify")}
                for mode in ("full", "simplify"):
                    row[mode]["bounces"] = solve(mebake, base, b[mode], scene + "b.json", mode)
                ref = os.path.join(outdir, f"ref-{name}{n}b.json")
                run([mebake, "reference", b["full"], "--scene", scene + "b.json", "--points",
                     opts["--points"], "--time-limit", opts["--time-limit"], "-o", ref])
                rf, bf = compare(mebake, b["full"], ref, ref + ".full.json")
                rs, bs = compare(mebake, b["simplify"], ref, ref + ".simplify.json")
                mean = sum(bf) / len(bf)
                row["rms_full"], row["rms_simplify"] = rf, rs
                row["l2_sf"] = math.sqrt(sum((x - y) ** 2 for x, y in zip(bs, bf)) / len(bf)) / mean
            print(json.dumps(row), flush=True)
            rows.append(row)
    print("\n| scene | mode | leaves | direct rays | CPU s (direct only) | boundary / fit CPU s "
          "| CPU s (bounces) | peak RSS MB | load | RMS vs ref | L2 s-f |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        for mode in ("full", "simplify"):
            m = r[mode]
            bo = m.get("bounces", {})
            rms = f"{100 * r['rms_' + mode]:.2f} %" if "rms_full" in r else ""
            l2 = f"{r['l2_sf']:.4f}" if mode == "simplify" and "l2_sf" in r else ""
            bt = f"{m['boundary_cpu']:.2f} / {m['fit_cpu']:.2f}"
            print(f"| {r['scene']} | {mode} | {m['leaves']} | "
                  f"{(m['classify'] + m['penumbra']) / 1e6:.2f}M | {m['cpu']:.1f} | {bt} | "
                  f"{bo.get('cpu', float('nan')):.1f} | {m['rss_mb']} | {m['load']:.1f} | {rms} | {l2} |")


if __name__ == "__main__":
    main()
