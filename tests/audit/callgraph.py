#!/usr/bin/env python3
"""Stack and code size of what a generated controller really calls.

Reads GCC's call graphs (`-fcallgraph-info=su`, one .ci file per translation
unit) and the objects' section sizes (`-ffunction-sections`, via
`arm-none-eabi-size -A`), then, from the entry points (the functions with
external linkage defined in the controller and sensor files), prints

    <text bytes of the reachable functions> <worst stack path bytes> <path> <library calls>

The worst path is the largest sum of frames along any call chain (the
generated code has no recursion: a cycle is an error). Library routines the
graph names without a frame (memset, libgcc's soft-double helpers, libm) are
listed, not counted: their stack is the toolchain's.

Usage: callgraph.py ENTRY_FILES... -- CI_FILES... -- OBJECTS...
"""

import os
import re
import subprocess
import sys

NODE = re.compile(r'node: \{ title: "([^"]+)" label: "([^"]*)"')
EDGE = re.compile(r'edge: \{ sourcename: "([^"]+)" targetname: "([^"]+)"')
FRAME = re.compile(r"\\n(\d+) bytes \((\w+)")


def split_args(argv):
    groups, cur = [], []
    for a in argv:
        if a == "--":
            groups.append(cur)
            cur = []
        else:
            cur.append(a)
    groups.append(cur)
    if len(groups) != 3:
        sys.exit("usage: callgraph.py ENTRY_FILES... -- CI_FILES... -- OBJECTS...")
    return groups


def main():
    entry_files, ci_files, objects = split_args(sys.argv[1:])
    frames, where, calls = {}, {}, {}
    for path in ci_files:
        with open(path, encoding="utf-8") as f:
            for line in f:
                m = NODE.search(line)
                if m:
                    title, label = m.groups()
                    fm = FRAME.search(label)
                    if fm:
                        if fm.group(2) != "static":
                            sys.exit(f"callgraph: {title} has a {fm.group(2)} frame")
                        frames[title] = int(fm.group(1))
                        parts = label.split("\\n")
                        where[title] = os.path.basename(parts[1].split(":")[0]) if len(parts) > 1 else ""
                    continue
                m = EDGE.search(line)
                if m:
                    calls.setdefault(m.group(1), set()).add(m.group(2))
    sizes = {}
    for obj in objects:
        out = subprocess.run(
            ["arm-none-eabi-size", "-A", obj], capture_output=True, text=True, check=True
        ).stdout
        for line in out.splitlines():
            cols = line.split()
            if len(cols) >= 2 and cols[0].startswith(".text.") and cols[1].isdigit():
                name = cols[0][len(".text."):]
                sizes[name] = sizes.get(name, 0) + int(cols[1])
    entries = sorted(
        t for t, file in where.items() if file in entry_files and ":" not in t
    )
    if not entries:
        sys.exit("callgraph: no entry point found")

    def resolve(name):
        # Static functions are titled "file.c:name" in their unit's graph.
        if name in frames:
            return name
        for t in frames:
            if t.endswith(":" + name):
                return t
        return None

    best = {}

    def worst(fn, stack):
        if fn in stack:
            sys.exit(f"callgraph: recursion through {fn}")
        if fn in best:
            return best[fn]
        depth, path = 0, []
        for callee in sorted(calls.get(fn, ())):
            c = resolve(callee)
            if c is None:
                continue
            d, p = worst(c, stack | {fn})
            if d > depth:
                depth, path = d, p
        best[fn] = (frames.get(fn, 0) + depth, [fn] + path)
        return best[fn]

    reach, todo, library = set(), list(entries), set()
    while todo:
        fn = todo.pop()
        if fn in reach:
            continue
        reach.add(fn)
        for callee in calls.get(fn, ()):
            c = resolve(callee)
            if c is None:
                library.add(callee)
            else:
                todo.append(c)
    text = sum(sizes.get(fn.split(":")[-1], 0) for fn in reach)
    depth, path = max((worst(e, frozenset()) for e in entries), key=lambda x: x[0])
    names = ">".join(p.split(":")[-1] for p in path)
    print(text, depth, names, ",".join(sorted(library)) or "none")


if __name__ == "__main__":
    main()
