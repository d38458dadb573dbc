"""The Python module's cost per call against the C++ API's, on the same index, object and flight
(docs/BENCHMARKS.md, "From Python"). The index is preloaded in both; each pass starts a new
object (built before the clock starts); the median pass of --repeat is reported, with the
spread (min-max) over the passes.

    PYTHONPATH=build/python python3 bench/python/overhead.py INDEX OBJECT FLIGHT \\
        --cpp build/bench/tetrapage_bench_query_loop [--repeat 5]

Ways of asking, per pose:
  C++ collides / query    the C++ loop (tetrapage_bench_query_loop)
  batch                   obj.collides(poses), all K poses in one call
  single pose             obj.collides(poses[k]), one call per pose
  single query            obj.query(poses[k], mode="all_contacts"): contacts with geometry
  threads                 the flight cut into --threads stretches flown by as many Python
                          threads, one object each (the GIL released): the wall time per pose
"""

import argparse
import statistics
from concurrent.futures import ThreadPoolExecutor
import subprocess
import time

import numpy as np

import tetrapage


def passes(repeat, run, prepare=lambda: None):
    """Seconds of each of `repeat` calls of run(prepare()), prepare() not timed."""
    times = []
    for _ in range(repeat):
        prepared = prepare()
        start = time.perf_counter()
        run(prepared)
        times.append(time.perf_counter() - start)
    return times


def cpp_figures(cpp, index, obj, flight, repeat):
    out = subprocess.run([cpp, index, obj, flight, "--repeat", str(repeat)], check=True,
                         capture_output=True, text=True).stdout
    figures = {}
    for line in out.splitlines():
        words = line.split()
        if len(words) == 3 and words[2] == "us/pose":
            figures[words[0]] = float(words[1])
    return figures, out.splitlines()[0]


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("index")
    parser.add_argument("object")
    parser.add_argument("flight")
    parser.add_argument("--cpp", required=True, help="tetrapage_bench_query_loop")
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--threads", type=int, default=2)
    args = parser.parse_args()

    cpp, cpp_line = cpp_figures(args.cpp, args.index, args.object, args.flight, args.repeat)
    index = tetrapage.Index(args.index, memory=1 << 40)
    index.preload()
    mesh = tetrapage.read_mesh(args.object)
    poses = tetrapage.read_poses(args.flight)
    rows = list(poses)  # one (7,) array per pose, as a caller's loop would hold them

    def new_object():
        return index.object(mesh)

    def batch(obj):
        obj.collides(poses)

    def single(obj):
        for pose in rows:
            obj.collides(pose)

    def single_query(obj):
        for pose in rows:
            obj.query(pose, mode="all_contacts")

    parts = np.array_split(poses, args.threads)  # each thread flies a stretch of the flight
    pool = ThreadPoolExecutor(max_workers=args.threads)
    list(pool.map(lambda part: None, parts))  # the threads started before the clock

    def threads(objects):
        list(pool.map(lambda job: job[0].collides(job[1]), zip(objects, parts)))

    per_pose = 1e6 / len(poses)
    print(f"C++: {cpp_line}")
    print()
    print("| way of asking | us per pose (median) | spread over passes | C++ us per pose | overhead us per call | ratio |")
    print("|---|---:|---:|---:|---:|---:|")
    for name, run, reference in [(f"batch of {len(poses)}: collides(poses)", batch, "collides"),
                                 ("single pose: collides(pose)", single, "collides"),
                                 ("single pose: query(pose, all_contacts)", single_query, "query")]:
        times = [t * per_pose for t in passes(args.repeat, run, new_object)]
        middle = statistics.median(times)
        calls = 1 if name.startswith("batch") else len(poses)
        overhead = (middle - cpp[reference]) * len(poses) / calls
        print(f"| {name} | {middle:.3f} | {min(times):.3f}-{max(times):.3f} | {cpp[reference]:.3f} | "
              f"{overhead:.3f} | {middle / cpp[reference]:.2f} |")
    times = [t * per_pose for t in passes(args.repeat, threads, lambda: [new_object() for _ in parts])]
    middle = statistics.median(times)
    print(f"| {args.threads} threads, one object each: collides(a stretch of the flight) | "
          f"{middle:.3f} | {min(times):.3f}-{max(times):.3f} | {cpp['collides']:.3f} | - | "
          f"{middle / cpp['collides']:.2f} |")


if __name__ == "__main__":
    main()
