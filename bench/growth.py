#!/usr/bin/env python3
"""The growth table of docs/performance.md (issue 15): time and peak memory of `pandora analyze` on
generated large stages (bench/large_stage.py) against region voxels, cameras, triangles and
threads, one quantity varied at a time around a base case, with the exponent of a least-squares
power law fitted to each series (time ~ N^b); and the field list at the base case (coverage alone,
the base four, all nine), with each run's peak against coverage alone's (issue 33).

    python3 bench/growth.py [--pandora build/pandora] [--work /tmp/pandora-growth] [--quick]
                            [--series voxels,cameras,triangles,threads,fields] [--json growth.json]

Each run is `pandora analyze` under /usr/bin/time (wall seconds, peak resident memory); the field
evaluation's own seconds, rays and region voxels come from its summary.json. Prints a Markdown
table and the fitted exponents.
"""
import argparse
import json
import math
import os
import pathlib
import subprocess
import sys

HERE = pathlib.Path(__file__).resolve().parent


ALL_NINE = ("coverage,cameras,resolution,sigma_max,sigma_mean,triangulation_angle,condition,"
            "sigma_max_steady,sigma_mean_steady")


def run(pandora, work, name, triangles, cameras, voxel, threads, fields):
    scene = work / f"{name}.json"
    motion = ["--motion"] if "steady" in fields else []  # the steady fields need a motion model
    subprocess.run([sys.executable, str(HERE / "large_stage.py"), str(scene), "--triangles", str(triangles),
                    "--cameras", str(cameras), "--voxel", str(voxel)] + motion, check=True, capture_output=True)
    out = work / f"{name}.out"
    timed = subprocess.run(["/usr/bin/time", "-f", "%e %M", pandora, "analyze", str(scene), "--out", str(out),
                            "--threads", str(threads), "--fields", fields, "--quiet"],
                           capture_output=True, text=True)
    if timed.returncode != 0:
        raise SystemExit(f"{name}: pandora analyze failed: {timed.stderr.strip()}")
    wall, rss_kb = timed.stderr.strip().splitlines()[-1].split()
    summary = json.loads((out / "summary.json").read_text())
    row = {
        "name": name, "triangles": triangles, "cameras": cameras, "voxel_m": voxel, "threads": threads,
        "region_voxels": summary["region_voxels"], "rays": summary["timing"]["rays"],
        "field_s": summary["timing"]["seconds"], "wall_s": float(wall), "peak_mb": int(rss_kb) / 1024,
        "vdb_mb": (out / "fields.vdb").stat().st_size / 2**20, "fields": fields,
    }
    print(f"  {name}: {row['region_voxels']} voxels, {cameras} cameras, ~{triangles} triangles, {threads} threads: "
          f"fields {row['field_s']:.2f} s, wall {row['wall_s']:.2f} s, peak {row['peak_mb']:.0f} MB", flush=True)
    return row


def fit(xs, ys):
    """Least-squares b of y = a x^b."""
    lx = [math.log(x) for x in xs]
    ly = [math.log(y) for y in ys]
    mx, my = sum(lx) / len(lx), sum(ly) / len(ly)
    den = sum((x - mx) ** 2 for x in lx)
    return sum((x - mx) * (y - my) for x, y in zip(lx, ly)) / den if den > 0 else float("nan")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--pandora", default="build/pandora")
    ap.add_argument("--work", default="/tmp/pandora-growth")
    ap.add_argument("--fields", default="coverage,cameras,resolution,sigma_max")
    ap.add_argument("--quick", action="store_true", help="smaller series (a smoke run)")
    ap.add_argument("--series", default="voxels,cameras,triangles,threads,fields",
                    help="comma-separated series to run")
    ap.add_argument("--json", help="also write the rows and exponents here")
    a = ap.parse_args()
    work = pathlib.Path(a.work)
    work.mkdir(parents=True, exist_ok=True)
    base = dict(triangles=300000, cameras=24, voxel=0.06, threads=os.cpu_count() or 1)
    series = {
        "voxels": ("region_voxels", [dict(base, voxel=v) for v in ((0.12, 0.08) if a.quick else (0.12, 0.09, 0.06, 0.045, 0.035))]),
        "cameras": ("cameras", [dict(base, cameras=c) for c in ((6, 12) if a.quick else (6, 12, 24, 48))]),
        "triangles": ("triangles", [dict(base, triangles=t) for t in ((10000, 100000) if a.quick else (10000, 100000, 300000, 1000000))]),
        "threads": ("threads", [dict(base, threads=t) for t in sorted({1, base["threads"]})]),
        "fields": (None, [dict(base, fields=f) for f in ("coverage", a.fields, ALL_NINE)]),
    }
    rows, exponents = [], {}
    wanted = a.series.split(",")
    for label, (key, cases) in series.items():
        if label not in wanted:
            continue
        print(f"{label}:", flush=True)
        got = [run(a.pandora, work, f"{label}_{i}", c["triangles"], c["cameras"], c["voxel"], c["threads"],
                   c.get("fields", a.fields))
               for i, c in enumerate(cases)]
        for r in got:
            r["series"] = label
        rows += got
        if key is None:  # the field list: each peak against coverage alone's
            for r in got:
                r["peak_vs_coverage"] = r["peak_mb"] / got[0]["peak_mb"]
            continue
        xs = [r[key] for r in got]
        exponents[label] = {"field_s": fit(xs, [r["field_s"] for r in got]),
                            "wall_s": fit(xs, [r["wall_s"] for r in got]),
                            "peak_mb": fit(xs, [r["peak_mb"] for r in got])}
    print()
    print("| Series | Region voxels | Cameras | Triangles (asked) | Threads | Rays | Fields (s) | Wall (s) | Peak (MB) | fields.vdb (MB) |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    names = {"coverage": "coverage", a.fields: "base four", ALL_NINE: "all nine"}
    for r in rows:
        series = r["series"]
        if "peak_vs_coverage" in r:
            series = f"fields: {names.get(r['fields'], r['fields'])} ({r['peak_vs_coverage']:.2f}x coverage's peak)"
        print(f"| {series} | {r['region_voxels']:,} | {r['cameras']} | {r['triangles']:,} | {r['threads']} | {r['rays']:,} | "
              f"{r['field_s']:.2f} | {r['wall_s']:.2f} | {r['peak_mb']:.0f} | {r['vdb_mb']:.1f} |")
    print()
    print("| Against | Field time exponent | Wall time exponent | Peak memory exponent |")
    print("|---|---|---|---|")
    for label, e in exponents.items():
        print(f"| {label} | {e['field_s']:.2f} | {e['wall_s']:.2f} | {e['peak_mb']:.2f} |")
    if a.json:
        pathlib.Path(a.json).write_text(json.dumps({"rows": rows, "exponents": exponents}, indent=1) + "\n")


if __name__ == "__main__":
    main()
