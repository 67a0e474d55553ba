"""Checks that libtunetrace's folders depend on each other one way only (docs/ARCHITECTURE.md).

    /usr/bin/python3 -m tools.check_layers BUILD_DIR

Two views of the same rule, both from the tree as built:
  - calls: every tt_* symbol an object file of core/src/<folder> uses and another folder's
    object defines (`nm`), i.e. what the linker resolves, public API calls included;
  - includes: every "folder/header.h" a source or header of core/src/<folder> includes.
A folder may use only folders of a lower layer (LAYERS below); two folders of one layer may
not use each other, so there can be no cycle. The host program's files must form no cycle
either (no function calls back into its caller's file): checked on host/*.o the same way.
Prints both graphs; exit status 1 naming each edge that breaks the rule, 0 otherwise."""
import argparse
import collections
import glob
import os
import re
import subprocess
import sys

# Lower layers first. A folder depends only on folders listed on earlier lines.
LAYERS = [
    ["util"],                      # errors, files, strings, matrices, rng + hash
    ["plugin", "params", "scene"],  # loader + host services; parameter spaces; scene data
    ["io/ply"],                    # PLY reader (mesh data), shared by io/pbrt and io
    ["io/pbrt"],                   # pbrt-v4 importer (builds scenes)
    ["io"],                        # scene.json, mesh import, image I/O, format dispatch
    ["render"],                    # camera, film, samplers, BSDFs, lights, path, textures
    ["tuning"],                    # tuning database and the tuning loop
    ["session"],                   # the render session over all of the above
]
RANK = {folder: i for i, layer in enumerate(LAYERS) for folder in layer}

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SRC = os.path.join(ROOT, "core", "src")


def folder_of(rel):
    """core/src-relative path -> its folder, the longest one named in LAYERS
    ("io/pbrt/pbrt_parse.c" -> "io/pbrt", "util/include/tt_util/rng.h" -> "util")."""
    d = os.path.dirname(rel)
    while d and d not in RANK:
        d = os.path.dirname(d)
    return d or os.path.dirname(rel)


def sources():
    out = []
    for dirpath, _, names in os.walk(SRC):
        for n in names:
            if n.endswith((".c", ".cpp", ".h")):
                out.append(os.path.relpath(os.path.join(dirpath, n), SRC))
    return sorted(out)


def nm(args, obj):
    r = subprocess.run(["nm"] + args + [obj], capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit(f"check_layers: nm {obj}: {r.stderr.strip()}")
    return [line.split() for line in r.stdout.splitlines()]


def call_edges(build):
    objdirs = glob.glob(os.path.join(build, "core", "libtunetrace.so*.p"))
    if len(objdirs) != 1:
        sys.exit(f"check_layers: {build}/core: expected one libtunetrace.so*.p object folder, "
                 f"found {len(objdirs)} (build the library first)")
    by_obj = {}
    for rel in sources():
        if not rel.endswith(".h"):
            by_obj["src_" + rel.replace("/", "_") + ".o"] = rel
    defined = collections.defaultdict(set)
    used = {}
    for obj in sorted(glob.glob(os.path.join(objdirs[0], "*.o"))):
        rel = by_obj.get(os.path.basename(obj))
        if rel is None:
            sys.exit(f"check_layers: {obj}: no source in core/src matches this object "
                     "(stale build folder?)")
        for p in nm(["-g", "--defined-only"], obj):
            if len(p) == 3 and p[2].startswith("tt_"):
                defined[p[2]].add(rel)
        used[rel] = {p[1] for p in nm(["-u"], obj) if len(p) == 2 and p[1].startswith("tt_")}
    edges = collections.defaultdict(set)
    for rel, syms in used.items():
        for s in syms:
            for d in defined.get(s, ()):
                if folder_of(d) != folder_of(rel):
                    edges[(folder_of(rel), folder_of(d))].add(f"{rel} -> {s} ({d})")
    return edges


def include_edges():
    edges = collections.defaultdict(set)
    inc = re.compile(r'^\s*#\s*include\s+"([^"]+)"', re.M)
    for rel in sources():
        with open(os.path.join(SRC, rel), encoding="utf-8") as f:
            text = f.read()
        for h in inc.findall(text):
            target = os.path.normpath(os.path.join(folder_of(rel), h)) if h.startswith(".") else h
            if os.path.exists(os.path.join(SRC, target)):
                if folder_of(target) != folder_of(rel):
                    edges[(folder_of(rel), folder_of(target))].add(f'{rel} includes "{h}"')
            elif "/" in h:
                sys.exit(f'check_layers: core/src/{rel}: includes "{h}", which is not in core/src')
    return edges


def host_edges(build):
    """(caller file, callee file) -> symbols, over the objects of the host executable."""
    objdir = os.path.join(build, "host", "host.p")
    objs = sorted(glob.glob(os.path.join(objdir, "*.o")))
    if not objs:
        sys.exit(f"check_layers: {objdir}: no objects (build the host first)")
    defined, used = {}, {}
    for obj in objs:
        name = os.path.basename(obj)[:-2]
        for p in nm(["-g", "--defined-only"], obj):
            if len(p) == 3:
                defined[p[2]] = name
        used[name] = {p[1] for p in nm(["-u"], obj) if len(p) == 2}
    edges = collections.defaultdict(set)
    for name, syms in used.items():
        for sym in syms:
            d = defined.get(sym)
            if d and d != name:
                edges[(name, d)].add(sym)
    return edges


def find_cycle(edges):
    """One cycle of the directed graph as a list of nodes, or None."""
    succ = collections.defaultdict(list)
    for a, b in edges:
        succ[a].append(b)
    state, stack = {}, []

    def visit(n):
        state[n] = 1
        stack.append(n)
        for m in sorted(succ[n]):
            if state.get(m) == 1:
                return stack[stack.index(m):] + [m]
            if not state.get(m):
                c = visit(m)
                if c:
                    return c
        stack.pop()
        state[n] = 2
        return None

    for n in sorted(succ):
        if not state.get(n):
            c = visit(n)
            if c:
                return c
    return None


def main():
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("build", metavar="BUILD_DIR", help="the build tree (its object files)")
    build = ap.parse_args().build
    folders = sorted({folder_of(r) for r in sources()})
    unknown = [f for f in folders if f not in RANK]
    if unknown:
        print("check_layers: folders not in LAYERS (add them to tools/check_layers.py and "
              "docs/ARCHITECTURE.md): " + ", ".join(unknown))
        return 1
    bad = 0
    for kind, edges in (("calls", call_edges(build)), ("includes", include_edges())):
        print(f"{kind}:")
        for (a, b), why in sorted(edges.items()):
            ok = RANK[a] > RANK[b]
            print(f"  {a:9} -> {b:9} {'ok' if ok else 'NOT ALLOWED'} ({len(why)} uses)")
            if not ok:
                bad += 1
                for w in sorted(why)[:8]:
                    print(f"      {w}")
    print("layers: " + " < ".join("{" + ", ".join(layer) + "}" for layer in LAYERS))
    hedges = host_edges(build)
    print("host files (caller -> callee):")
    for (a, b), syms in sorted(hedges.items()):
        print(f"  {a:12} -> {b:12} {', '.join(sorted(syms))}")
    cycle = find_cycle(hedges)
    if cycle:
        bad += 1
        print("host: NOT ALLOWED, a cycle: " + " -> ".join(cycle))
    print("check_layers: " + ("ok, no folder uses a folder of its own or a higher layer, and "
                              "the host's files form no cycle" if not bad else
                              f"{bad} edges or cycles break the layering"))
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
