#!/usr/bin/env python3
"""Medians of repeated tetrapage_bench_peers runs, as Markdown (bench/scripts/peers_series.sh and
peers_foreign.sh).

    peers_table.py OUT.md --repeats R [--columns NAME...] [--preamble FILE] [--summary]
                   --cell PREFIX LABEL... [--cell PREFIX LABEL...]

Each cell is one workload (a scene, an object and its flight) whose runs wrote --report files
PREFIX-1.json .. PREFIX-R.json; LABEL... fills the --columns (default: one column, "object").
Per cell and collider: the median of each figure over the repetitions (and the spread of
steps/s) next to the answers' disagreements ("varies" when they differ between repetitions);
then per cell the ratios of tetrapage in memory to the best peer (the non-tetrapage collider
with the highest median steps/s) and of paged to in memory. --summary adds, over the cells, the
geometric mean of those ratios and how many cells are below 1.0x and 2.0x the best peer.
--preamble puts a file's text first. Writes OUT.md and prints it.
"""
import argparse
import json
import math
import statistics


def disagreement_text(d, key):
    if key not in d:
        return "-"
    return f"{d[key]['false_negatives']} / {d[key]['false_positives']}"


def cell_figures(prefix, repeats):
    """Per collider (in the runs' order): median figures and the table row's cells."""
    reports = [json.load(open(f"{prefix}-{r}.json")) for r in range(1, repeats + 1)]
    names = [run["collider"] for run in reports[0]["runs"]]
    for rep in reports[1:]:
        if [run["collider"] for run in rep["runs"]] != names:
            raise SystemExit(f"{prefix}: the repetitions ran different colliders")
    figures = {}
    for i, name in enumerate(names):
        runs = [rep["runs"][i] for rep in reports]
        med = lambda f: statistics.median(f(run) for run in runs)
        rates = [run["steps_per_second"] for run in runs]
        answers = {(r["collisions"], disagreement_text(r["disagreements"], "oracle"),
                    disagreement_text(r["disagreements"], "same_question")) for r in runs}
        collisions, oracle, same = sorted(answers)[0] if len(answers) == 1 else ("varies", "varies", "varies")
        structures = med(lambda r: r['structure_bytes'])
        structures = f"{structures / 2**20:.1f}" if structures > 0 else "-"
        figures[name] = {
            "rate": med(lambda r: r["steps_per_second"]),
            "p99": med(lambda r: r["latency_us"]["p99"]),
            "row": f"{med(lambda r: r['build_seconds']):.2f} | {med(lambda r: r['build_rss_growth_bytes']) / 2**20:.1f} | {structures} | "
                   f"{med(lambda r: r['peak_rss_bytes']) / 2**20:.1f} | {statistics.median(rates):.0f} ({min(rates):.0f}-{max(rates):.0f}) | "
                   f"{med(lambda r: r['latency_us']['p50']):.1f} | {med(lambda r: r['latency_us']['p95']):.1f} | "
                   f"{med(lambda r: r['latency_us']['p99']):.1f} | {med(lambda r: r['latency_us']['max']):.0f} | "
                   f"{collisions} | {oracle} | {same} |",
        }
    return names, figures


def geometric_mean(values):
    return math.exp(sum(math.log(v) for v in values) / len(values))


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("output")
    parser.add_argument("--repeats", type=int, required=True)
    parser.add_argument("--columns", nargs="+", default=["object"])
    parser.add_argument("--cell", nargs="+", action="append", required=True, metavar="PREFIX LABEL")
    parser.add_argument("--preamble")
    parser.add_argument("--summary", action="store_true")
    args = parser.parse_args()
    width = len(args.columns)
    for cell in args.cell:
        if len(cell) != 1 + width:
            parser.error(f"--cell {' '.join(cell)}: one prefix and {width} labels ({', '.join(args.columns)})")

    head = "| " + " | ".join(args.columns) + " | "
    rule = "|" + "---:|" * width
    rows = [head + "collider | build s | build RSS MiB | structures MiB | peak RSS MiB | steps/s (min-max) | p50 us | p95 us | p99 us | max us | collisions | FN / FP vs oracle | FN / FP vs exact, same question |",
            rule + "---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    ratios = [head + "tetrapage in memory / best peer: steps/s | p99 | best peer | paged / in memory: steps/s |",
              rule + "---:|---:|---|---:|"]
    in_memory, p99s, paged_ratios = [], [], []
    for prefix, *labels in args.cell:
        label = " | ".join(labels)
        names, median = cell_figures(prefix, args.repeats)
        for name in names:
            rows.append(f"| {label} | {name} | {median[name]['row']}")
        peers = [n for n in names if not n.startswith("tetrapage")]
        if "tetrapage" in median and peers:
            best = max(peers, key=lambda n: median[n]["rate"])
            rate = median['tetrapage']['rate'] / median[best]['rate']
            p99 = median['tetrapage']['p99'] / median[best]['p99']
            in_memory.append(rate)
            p99s.append(p99)
            paged = "-"
            if "tetrapage-paged" in median:
                paged_ratios.append(median['tetrapage-paged']['rate'] / median['tetrapage']['rate'])
                paged = f"{paged_ratios[-1]:.2f}x"
            ratios.append(f"| {label} | {rate:.2f}x | {p99:.2f}x | {best} | {paged} |")

    text = ""
    if args.preamble:
        text += open(args.preamble).read().rstrip("\n") + "\n\n"
    text += "\n".join(rows) + "\n\n" + "\n".join(ratios) + "\n"
    if args.summary and in_memory:
        text += (f"\nOver {len(in_memory)} cell{'s' if len(in_memory) > 1 else ''}: tetrapage in memory / best peer, steps/s: geometric mean "
                 f"**{geometric_mean(in_memory):.2f}x** (min {min(in_memory):.2f}x, max {max(in_memory):.2f}x); "
                 f"{sum(r < 1.0 for r in in_memory)} cells below 1.0x, {sum(r < 2.0 for r in in_memory)} below 2.0x "
                 f"(the target: at least 2x in every cell, a geometric mean of at least 1.5x). p99: geometric mean {geometric_mean(p99s):.2f}x "
                 f"(target: at most 0.5x; {sum(r <= 0.5 for r in p99s)} cells meet it).")
        if paged_ratios:
            text += (f" Paged / in memory, steps/s: geometric mean {geometric_mean(paged_ratios):.2f}x "
                     f"({sum(r < 0.5 for r in paged_ratios)} of {len(paged_ratios)} cells below the 0.5x target).")
        text += "\n"
    open(args.output, "w").write(text)
    print(text)


if __name__ == "__main__":
    main()
