#!/usr/bin/env python3
"""The scale series' tables and plots (bench/scripts/scale_series.sh writes the JSON reports).

    scale_table.py OUT_DIR

Writes OUT_DIR/scale.md and OUT_DIR/scale.csv (one row per model, object and run), and with
gnuplot installed OUT_DIR/plots/*.png: step latency (p50, p99) against the budget, steps per
second against the model's triangles (resident and under 10 %), and the time to the first answer.
"""
import glob
import json
import os
import re
import shutil
import subprocess
import sys

out = sys.argv[1]
ORDER = {"all": 0, "10pct": 1, "10pct-noprefetch": 2, "64m": 3}


def model_key(name):
    digits = re.match(r"\D*(\d+)", name)
    return (re.sub(r"[\d-].*", "", name), int(digits.group(1)) if digits else 0, name)


rows = []
for d in sorted(glob.glob(f"{out}/*/"), key=lambda p: model_key(os.path.basename(p.rstrip("/")))):
    name = os.path.basename(d.rstrip("/"))
    try:
        pre = json.load(open(f"{d}/preprocess.json"))
        ins = json.load(open(f"{d}/inspect.json"))
    except FileNotFoundError:
        continue
    for f in sorted(glob.glob(f"{d}/fly-*.json")):
        m = re.match(r".*/fly-(.+)-(\d+)\.json", f)
        r = json.load(open(f))
        rows.append(dict(model=name, triangles=pre.get("triangles_read", 0), regions=pre.get("regions", 0),
                         index_bytes=ins.get("file_bytes", 0), shard_bytes=ins["shard_decoded_bytes"],
                         object=int(m.group(2)), run=m.group(1),
                         **{k: r[k] for k in ("steps_per_second", "budget_bytes", "peak_rss_bytes", "page_ins",
                                              "bytes_read_per_step", "cache_hit_rate", "open_to_first_answer_ms",
                                              "disagreements", "collisions")},
                         p50=r["latency_us"]["p50"], p99=r["latency_us"]["p99"], max=r["latency_us"]["max"],
                         page_p50=r["page_in_latency_us"]["p50"], page_p99=r["page_in_latency_us"]["p99"]))
rows.sort(key=lambda r: (model_key(r["model"]), r["object"], ORDER.get(r["run"], 9)))


def mib(b):
    return b / 2**20


lines = ["| model | triangles | regions | index MiB | object | run | budget MiB | steps/s | 1/p50 | p50 us | p99 us | max us | "
         "page-in p50/p99 us | bytes read/step | hit rate | peak RSS MiB | RSS - budget MiB | open to 1st answer ms | "
         "disagreements |",
         "|---|---:|---:|---:|---:|---|---:|---:|---:|---:|---:|---:|---|---:|---:|---:|---:|---:|---:|"]
for r in rows:
    budget = "all" if r["run"] == "all" else f"{mib(r['budget_bytes']):.0f}"
    over = "-" if r["run"] == "all" else f"{mib(r['peak_rss_bytes'] - r['budget_bytes']):.0f}"
    lines.append(f"| {r['model']} | {r['triangles']:,} | {r['regions']:,} | {mib(r['index_bytes']):.0f} | {r['object']} | "
                 f"{r['run']} | {budget} | {r['steps_per_second']:.0f} | {1e6 / max(r['p50'], 1e-9):.0f} | "
                 f"{r['p50']:.1f} | {r['p99']:.0f} | {r['max']:.0f} | {r['page_p50']:.0f} / {r['page_p99']:.0f} | "
                 f"{r['bytes_read_per_step']:.0f} | {r['cache_hit_rate']:.4f} | {mib(r['peak_rss_bytes']):.0f} | {over} | "
                 f"{r['open_to_first_answer_ms']:.1f} | {r['disagreements']} |")
open(f"{out}/scale.md", "w").write("\n".join(lines) + "\n")
with open(f"{out}/scale.csv", "w") as f:
    keys = list(rows[0].keys()) if rows else []
    f.write(",".join(keys) + "\n")
    for r in rows:
        f.write(",".join(str(r[k]) for k in keys) + "\n")
print("\n".join(lines))

# Issue 4's preprocess figures: throughput, index size and peak memory against --memory.
pre_lines = ["| model | triangles | seconds | M triangles/s | index MiB | B/triangle | --memory MiB | peak RSS MiB | "
             "stages (s) |", "|---|---:|---:|---:|---:|---:|---:|---:|---|"]
for d in sorted(glob.glob(f"{out}/*/"), key=lambda p: model_key(os.path.basename(p.rstrip("/")))):
    try:
        pre = json.load(open(f"{d}/preprocess.json"))
    except FileNotFoundError:
        continue
    stages = ", ".join(f"{s['name']} {s['seconds']:.1f}" for s in pre.get("stages", []))
    pre_lines.append(f"| {os.path.basename(d.rstrip('/'))} | {pre['triangles_read']:,} | {pre['seconds']:.1f} | "
                     f"{pre['triangles_per_second'] / 1e6:.2f} | {mib(pre['bytes_written']):.0f} | "
                     f"{pre['bytes_per_triangle']:.1f} | {mib(pre['memory_budget_bytes']):.0f} | "
                     f"{mib(pre['peak_rss_bytes']):.0f} | {stages} |")
open(f"{out}/preprocess.md", "w").write("\n".join(pre_lines) + "\n")
print()
print("\n".join(pre_lines))

if not rows or shutil.which("gnuplot") is None:
    sys.exit(0)
plots = f"{out}/plots"
os.makedirs(plots, exist_ok=True)
largest = max(r["object"] for r in rows)
scenes = sorted({r["model"] for r in rows}, key=model_key)
with open(f"{plots}/budget.dat", "w") as f:
    # Latency against the budget as a fraction of the decoded shards, the largest object.
    for model in scenes:
        f.write(f"# {model}\n")
        for r in sorted((r for r in rows if r["model"] == model and r["object"] == largest and "noprefetch" not in r["run"]),
                        key=lambda r: r["budget_bytes"]):
            fraction = 1.0 if r["run"] == "all" else r["budget_bytes"] / r["shard_bytes"]
            f.write(f"{fraction} {r['p50']} {r['p99']}\n")
        f.write("\n\n")
# The scaling curve follows one region size: the one with the most scene sizes ("" = the default).
def region_of(model):
    return model.partition("-r")[2]


region_sizes = {}
for r in rows:
    if r["model"].startswith("scene"):
        region_sizes.setdefault(region_of(r["model"]), set()).add(r["triangles"])
curve_region = max(region_sizes, key=lambda k: (len(region_sizes[k]), k == "")) if region_sizes else ""
with open(f"{plots}/scaling.dat", "w") as f:
    for run in ("all", "10pct"):
        for obj in sorted({r["object"] for r in rows}):
            f.write(f"# {run} object {obj}\n")
            for r in sorted((r for r in rows if r["run"] == run and r["object"] == obj and r["model"].startswith("scene")
                             and region_of(r["model"]) == curve_region), key=lambda r: r["triangles"]):
                f.write(f"{r['triangles']} {r['steps_per_second']} {r['p99']} {r['open_to_first_answer_ms']} "
                        f"{mib(r['peak_rss_bytes'])}\n")
            f.write("\n\n")
objects = sorted({r["object"] for r in rows})
script = ["set terminal pngcairo size 900,560 font ',10'", "set grid", "set key outside right",
          "set output 'latency-vs-budget.png'", "set logscale xy",
          f"set title 'Step latency against the budget ({largest}-triangle object; budget / decoded shards)'",
          "set xlabel 'budget / decoded shards'", "set ylabel 'us'"]
plot = []
for i, model in enumerate(scenes):
    plot.append(f"'budget.dat' index {i} using 1:3 with linespoints lw 2 title '{model} p99'")
    plot.append(f"'budget.dat' index {i} using 1:2 with linespoints dt 2 title '{model} p50'")
script.append("plot " + ", ".join(plot))
script += ["set output 'scaling.png'", "set title 'Steps per second against the model (scenes; solid: resident, dashed: 10 % budget)'",
           "set xlabel 'triangles'", "set ylabel 'steps per second'"]
plot = []
for k, (run, dash) in enumerate((("all", 1), ("10pct", 2))):
    for j, obj in enumerate(objects):
        plot.append(f"'scaling.dat' index {k * len(objects) + j} using 1:2 with linespoints dt {dash} lw 2 "
                    f"title '{obj} tri, {run}'")
script.append("plot " + ", ".join(plot))
script += ["set output 'open-time.png'", "set title 'Open to first answer (scenes, resident run)'", "set ylabel 'ms'"]
script.append("plot " + ", ".join(f"'scaling.dat' index {j} using 1:4 with linespoints lw 2 title '{obj} tri'"
                                  for j, obj in enumerate(objects)))
open(f"{plots}/scale.gp", "w").write("\n".join(script) + "\n")
subprocess.run(["gnuplot", "scale.gp"], cwd=plots, check=False)
