#!/usr/bin/env python3
"""Includes point one way: every #include of a tetrapage header goes to the same room or a room
below it (tests/README.md, "Layers"), and names a header that exists; a back edge, or a path
that names no room, fails with its file and line.

    check_includes.py SOURCE_ROOT      check the tree
    check_includes.py --self-test      check that the checker finds a back edge and a bad path
"""

import re
import sys
import tempfile
from pathlib import Path

# The rooms from the bottom up: a file may include headers of its own rank or below.
ROOMS = ["formats/base", "formats/mesh", "formats/index",
         "runtime/geometry", "runtime/paging", "runtime/query", "runtime/capi",
         "study", "preprocess", "tools", "front"]
RANK = {room: rank for rank, room in enumerate(ROOMS)}
# Front ends, the top rank: they may use any room, but Python never tools/ (python/README.md).
# study/ (the paper's in-core methods, for the benchmarks) sits beside preprocess, not below it.
FRONT_ENDS = ["bench", "tests", "python", "runtime/examples"]
FORBIDDEN = {"python": ["tools"], "preprocess": ["study"]}
SOURCE_SUFFIXES = {".h", ".hpp", ".cpp", ".c", ".in"}
INCLUDE = re.compile(r'^\s*#\s*include\s*[<"](tetrapage/[^>"]+)[>"]')


def room_of_file(relative):
    text = relative.as_posix()
    for front in FRONT_ENDS:
        if text.startswith(front + "/"):
            return "front", front
    for room in sorted(ROOMS, key=len, reverse=True):
        if text.startswith(room + "/"):
            return room, room
    return None, None


def room_of_header(header):
    """The room an include string names, or None for a path outside every room."""
    parts = header.split("/")
    if header in ("tetrapage/tetrapage.h", "tetrapage/version.h"):
        return "runtime/capi"
    if len(parts) >= 4 and "/".join(parts[1:3]) in RANK:
        return "/".join(parts[1:3])
    if len(parts) >= 3 and parts[1] in ("study", "preprocess", "tools"):
        return parts[1]
    if len(parts) >= 3 and parts[1] == "bench":
        return "front"
    return None


def header_exists(root, header, room):
    if header == "tetrapage/version.h":
        return (root / "cmake" / "version.h.in").exists()
    if room == "front":
        return any(root.glob(f"bench/**/include/{header}"))
    return (root / room / "include" / header).exists() or any(
        root.glob(f"{room}/*/include/{header}"))


def back_edges(root):
    found = []
    for path in sorted(root.rglob("*")):
        relative = path.relative_to(root)
        if path.suffix not in SOURCE_SUFFIXES or not path.is_file() or relative.parts[0].startswith(("build", ".")):
            continue
        room, owner = room_of_file(relative)
        if room is None:
            continue
        for number, line in enumerate(path.read_text(errors="replace").splitlines(), 1):
            match = INCLUDE.match(line)
            if not match:
                continue
            header = match.group(1)
            target = room_of_header(header)
            where = f"{relative}:{number}"
            if target is None or not header_exists(root, header, target):
                found.append(f"{where}: includes {header}, which names no header of any room")
            elif RANK[target] > RANK[room]:
                found.append(f"{where}: includes {header}: {target} lies above {owner}")
            elif target in FORBIDDEN.get(owner, []):
                found.append(f"{where}: includes {header}: {owner} may not use {target}")
    return found


def self_test():
    with tempfile.TemporaryDirectory() as folder:
        root = Path(folder)
        headers = {"formats/base/include/tetrapage/formats/base/Error.h": "",
                   "runtime/query/include/tetrapage/runtime/query/Query.h": "",
                   "tools/include/tetrapage/tools/Random.h": ""}
        sources = {"runtime/geometry/src/Box.cpp": '#include "tetrapage/runtime/query/Query.h"\n',
                   "runtime/query/src/Step.cpp": '#include "tetrapage/formats/base/Error.h"\n'
                                                 '#include "tetrapage/runtime/FlyingObject.h"\n',
                   "python/src/Module.cpp": '#include "tetrapage/tools/Random.h"\n',
                   "tests/runtime/Step_test.cpp": '#include "tetrapage/tools/Random.h"\n'}
        for name, text in {**headers, **sources}.items():
            (root / name).parent.mkdir(parents=True, exist_ok=True)
            (root / name).write_text(text)
        found = back_edges(root)
        expected = ["runtime/geometry/src/Box.cpp:1: includes tetrapage/runtime/query/Query.h: "
                    "runtime/query lies above runtime/geometry",
                    "python/src/Module.cpp:1: includes tetrapage/tools/Random.h: python may not use tools",
                    "runtime/query/src/Step.cpp:2: includes tetrapage/runtime/FlyingObject.h, which "
                    "names no header of any room"]
        if sorted(found) != sorted(expected):
            print("self-test: found\n  " + "\n  ".join(found) + "\nexpected\n  " + "\n  ".join(expected))
            return 1
    print("self-test: the back edge, the forbidden use and the path of no room are found")
    return 0


def main(arguments):
    if arguments == ["--self-test"]:
        return self_test()
    if len(arguments) != 1:
        print(__doc__.strip(), file=sys.stderr)
        return 2
    found = back_edges(Path(arguments[0]).resolve())
    for line in found:
        print(line)
    if found:
        print(f"{len(found)} includes point the wrong way or nowhere", file=sys.stderr)
        return 1
    print("every include points to its own room or one below")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
