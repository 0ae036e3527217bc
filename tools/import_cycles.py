#!/usr/bin/env python3
"""Import cycles between the source files of each crate of the workspace.

Each `crates/<crate>/src/**.rs` file is a module. A file imports another when its code
(comments and the unit tests at its end left out) names a path `crate::a::b…` or `super::…` that resolves to that
module (the deepest module the path names). The import graph's strongly connected
components with more than one file are the cycles; a file's own sub-modules do not count
as imports of it. Prints each cycle, and exits with 1 if there is any.

Usage: python3 tools/import_cycles.py   (standard library only)
"""
import pathlib
import re
import sys

PATH = re.compile(r"\b(crate|super)((?:::[a-z_][a-z0-9_]*)+)")


def modules(src):
    """{module path tuple: file} of one crate's src directory."""
    out = {}
    for f in src.rglob("*.rs"):
        parts = list(f.relative_to(src).with_suffix("").parts)
        if parts[-1] in ("mod", "lib", "main"):
            parts = parts[:-1]
        out[tuple(parts)] = f
    return out


def code(text):
    """The text without comments (line comments, doc comments, block comments) and without
    its unit tests (from `#[cfg(test)]` on: the test module closes each file)."""
    text = text.split("#[cfg(test)]", 1)[0]
    text = re.sub(r"/\*.*?\*/", "", text, flags=re.S)
    return "\n".join(line.split("//", 1)[0] for line in text.splitlines())


def imports(mods, own, text):
    """Modules named by the paths in `text` of module `own`."""
    found = set()
    for root, rest in PATH.findall(code(text)):
        names = rest.strip(":").split("::")
        base = [] if root == "crate" else list(own[:-1])
        path = base + names
        while path and tuple(path) not in mods:
            path.pop()
        target = tuple(path)
        if path and target != own and target != own[: len(target)]:
            found.add(target)
    return found


def cycles(graph):
    """Strongly connected components with more than one node (Tarjan)."""
    index, low, stack, on, out, counter = {}, {}, [], set(), [], [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    sys.setrecursionlimit(10000)
    for v in graph:
        if v not in index:
            visit(v)
    return out


def main():
    root = pathlib.Path(__file__).resolve().parent.parent
    found = 0
    for src in sorted(root.glob("crates/*/src")):
        mods = modules(src)
        graph = {m: imports(mods, m, f.read_text()) for m, f in mods.items()}
        for comp in cycles(graph):
            found += 1
            names = ", ".join(str(mods[m].relative_to(root)) for m in comp)
            print(f"cycle in {src.parent.name}: {names}")
    if not found:
        print("no import cycles")
    return 1 if found else 0


if __name__ == "__main__":
    sys.exit(main())
