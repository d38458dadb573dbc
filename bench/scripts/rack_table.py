#!/usr/bin/env python3
"""rack.md from a bench/scripts/rack_series.sh run: per rack, the generator's and the
preprocess's figures, index bytes per triangle, and per flight the medians over the passes of
`tetrapage fly` in memory (--preload) and paged (steps/s with the spread, p99, page-ins); the
peers' table (peers_table.py over the harness's reports) follows.

    rack_table.py OUT REPEATS STEPS COMMIT LOAD_START LOAD_END SECONDS NAME...
"""
import json
import os
import statistics
import subprocess
import sys


def load(path):
    with open(path) as f:
        return json.load(f)


def wall(path):
    """Seconds and peak KiB that /usr/bin/time wrote."""
    seconds, kib = open(path).read().split()[:2]
    return float(seconds), int(kib)


def stage_seconds(report, name):
    return sum(s["seconds"] for s in report["stages"] if s["name"].lower().startswith(name))


def pipeline_rows(out, names):
    rows = ["| rack | triangles | boards | distinct parts | generate s | preprocess s | of it: ingest (STEP read, "
            "tessellation) s | triangles/s | preprocess peak RSS MiB | index MiB | index B/triangle |",
            "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for name in names:
        d = os.path.join(out, name)
        gen, pre = load(f"{d}/generate.json"), load(f"{d}/preprocess.json")
        index_bytes = os.path.getsize(f"{d}/rack.tpi")
        rows.append(f"| {name} | {pre['triangles_read']:,} | {gen['boards']} | {len(gen['parts'])} | "
                    f"{wall(f'{d}/generate.time')[0]:.1f} | {pre['seconds']:.1f} | {stage_seconds(pre, 'ingest'):.1f} | "
                    f"{pre['triangles_per_second']:,.0f} | {pre['peak_rss_bytes'] / 2**20:.0f} | "
                    f"{index_bytes / 2**20:.1f} | {index_bytes / pre['triangles_read']:.1f} |")
    return rows


def fly_rows(out, names, repeats):
    rows = ["| rack | flight | steps | collisions | in memory steps/s (spread) | p99 us | paged steps/s (spread) | "
            "p99 us | page-ins | paged / in memory |",
            "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for name in names:
        d = os.path.join(out, name, "runs")
        for flight in ("insert", "billiard"):
            mem = [load(f"{d}/{flight}-{r}.mem.json") for r in range(1, repeats + 1)]
            paged = [load(f"{d}/{flight}-{r}.paged.json") for r in range(1, repeats + 1)]
            rate = lambda runs: [r["steps_per_second"] for r in runs]
            med = lambda runs, f: statistics.median(f(r) for r in runs)
            m, p = statistics.median(rate(mem)), statistics.median(rate(paged))
            rows.append(f"| {name} | {flight} | {mem[0]['steps']} | {mem[0]['collisions']} | "
                        f"{m:,.0f} ({min(rate(mem)):,.0f}-{max(rate(mem)):,.0f}) | "
                        f"{med(mem, lambda r: r['latency_us']['p99']):.1f} | "
                        f"{p:,.0f} ({min(rate(paged)):,.0f}-{max(rate(paged)):,.0f}) | "
                        f"{med(paged, lambda r: r['latency_us']['p99']):.1f} | {med(paged, lambda r: r['page_ins']):.0f} | "
                        f"{p / m:.2f} |")
    return rows


def peers_table(out, names, repeats):
    cells = []
    for name in names:
        for flight in ("insert", "billiard"):
            prefix = os.path.join(out, name, "runs", f"peers-{flight}")
            if os.path.exists(f"{prefix}-1.json"):
                cells += ["--cell", prefix, name, flight]
    if not cells:
        return ["(no peer runs)"]
    script = os.path.join(os.path.dirname(os.path.abspath(__file__)), "peers_table.py")
    subprocess.run([sys.executable, script, os.path.join(out, "peers.md"), "--repeats", str(repeats),
                    "--columns", "rack", "flight", "--summary"] + cells, check=True, stdout=subprocess.DEVNULL)
    return [open(os.path.join(out, "peers.md")).read()]


def main():
    out, repeats, steps, commit, load_start, load_end, seconds = sys.argv[1:8]
    names, repeats = sys.argv[8:], int(repeats)
    cpu = next(l.split(":", 1)[1].strip() for l in open("/proc/cpuinfo") if l.startswith("model name"))
    lines = ["# Real CAD parts: racks of KiCad boards", "",
             f"`bench/scripts/rack_series.sh` (`make bench-rack`), commit {commit}, {seconds} s; machine: {cpu}, "
             f"{os.cpu_count()} cores; load average at start {load_start}, at end {load_end}; {repeats} passes "
             f"(medians, spread min-max); billiard flights of {steps} poses.", ""]
    lines += pipeline_rows(out, names) + [""] + fly_rows(out, names, repeats) + [""] + peers_table(out, names, repeats)
    print("\n".join(lines))


if __name__ == "__main__":
    main()
