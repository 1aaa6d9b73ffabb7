#!/usr/bin/env python3
"""The module graph of each crate, checked for import cycles and for layers imported upward.

    python3 scripts/layers.py                 # every crate below; exit 1 on any violation
    python3 scripts/layers.py --graph host-sim   # print that crate's edges and stop

Requirement (docs/ARCHITECTURE "Layers"): each module imports only modules below it, and no
module imports a module that imports it back, directly or through others.

Nodes. Every `.rs` file of a crate's `src/` is one module, named by its path as rustc names
it: `src/lib.rs` is `crate`, `src/a.rs` and `src/a/mod.rs` are `a`, `src/a/b.rs` is `a::b`.
A binary root (`src/main.rs` beside a `src/lib.rs`) is the node `main`: its `<lib>::x` paths
are edges into the library. Inline `mod x { ... }` blocks (tests, say) belong to their file.

Edges. Module M has an edge to module N when M's code (comments and string literals
stripped) names a path that resolves to N:
- `crate::a::b::c` (also inside `use crate::{...}` trees, and the library's own name in a
  binary root): the longest prefix `a::b` that is a module, so an item path resolves to
  the module that defines or re-exports it;
- `super::x` and `self::x`: resolved from M (inside an inline module, each `super` first
  leaves that inline module, which is still M);
- a bare `x::y` where `x` is a child module of M or, when M glob-imports its parent
  (`use super::*`), a sibling.
Not edges: a module naming itself, and a module naming one of its own descendants (a parent
declares its children with `mod`, and re-exporting or calling them is how a directory
module presents itself; its children importing it back is therefore not a cycle). Doc
comments (intra-doc links) are comments and are not edges. Paths into other crates are not
edges: cargo already forbids cycles between crates.

Checks. (1) Cycles: every strongly connected component of more than one module is a
failure, printed as one concrete cycle `a -> b -> ... -> a`, each edge with the file and
line of its first import. (2) Layers: for a crate with a layer table (LAYERS, below: data,
top layer first), an edge from a module to a module of a higher layer is a failure,
printed with its file and line. A module is in the layer of the longest prefix listed;
the crate root (`crate`) and a module listed nowhere are in no layer and are not checked
(the script prints those so a new module is placed on purpose).

Exit status: 0 when every crate passes, 1 on any failure, 2 on bad arguments.
"""

import os
import re
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

# The crates checked: (directory, library name as other crates spell it).
CRATES = [
    ("host-sim", "dexter_sim"),
    ("shared", "dexter_core"),
    ("firmware", "dexter_firmware"),
    ("drivers", "dexter_drivers"),
    ("rig", "dexter_rig"),
]

# Layer tables, top layer first: (layer name, module prefixes in it). The host follows
# docs/ARCHITECTURE's "Layers": the CLI (and the registry, which lists the systems) over
# the verbs, the systems over the one System trait, the models over the engine, the
# effects and the closed loop; HIL over the controller seam it implements
# (`controller::StepController`); the output, plotting, streaming and scene-file helpers
# at the bottom.
LAYERS = {
    "host-sim": [
        ("cli", ["main", "cli"]),
        ("verbs", ["verbs"]),
        ("systems", ["systems"]),
        ("system", ["system"]),
        ("model", ["model"]),
        ("engine", ["engine", "effects", "closed_loop"]),
        ("hil", ["hil"]),
        ("controller", ["controller"]),
        ("helpers", ["output", "plot", "filmstrip", "stream", "progress", "scene", "grid",
                     "period", "shard"]),
    ],
}

# Violations known and accepted (substrings of the failure lines): printed as known, and
# not failed on while `--known-ok` is given. Empty: every crate passes.
KNOWN = []


def strip(text):
    """The code with comments and string/char literals blanked (newlines kept)."""
    out = []
    i, n = 0, len(text)
    while i < n:
        c = text[i]
        if text.startswith("//", i):
            j = text.find("\n", i)
            j = n if j < 0 else j
            out.append(" " * (j - i))
            i = j
        elif text.startswith("/*", i):
            depth, j = 1, i + 2
            while j < n and depth:
                if text.startswith("/*", j):
                    depth, j = depth + 1, j + 2
                elif text.startswith("*/", j):
                    depth, j = depth - 1, j + 2
                else:
                    j += 1
            out.append(re.sub(r"[^\n]", " ", text[i:j]))
            i = j
        elif c == "r" and re.match(r'r#*"', text[i:i + 8]) and not (
                i and (text[i - 1].isalnum() or text[i - 1] == "_")):
            m = re.match(r'r(#*)"', text[i:])
            close = '"' + m.group(1)
            j = text.find(close, i + len(m.group(0)))
            j = n if j < 0 else j + len(close)
            out.append(re.sub(r"[^\n]", " ", text[i:j]))
            i = j
        elif c == '"':
            j = i + 1
            while j < n and text[j] != '"':
                j += 2 if text[j] == "\\" else 1
            j += 1
            out.append(re.sub(r"[^\n]", " ", text[i:j]))
            i = j
        elif c == "'":
            m = re.match(r"'(\\.[^']*|[^\\'])'", text[i:])
            if m:  # a char literal (else a lifetime)
                out.append(" " * len(m.group(0)))
                i += len(m.group(0))
            else:
                out.append(c)
                i += 1
        else:
            out.append(c)
            i += 1
    return "".join(out)


def module_files(crate_dir):
    """{module name: file} for the crate's src/ (see the docstring's Nodes)."""
    src = os.path.join(crate_dir, "src")
    mods = {}
    has_lib = os.path.exists(os.path.join(src, "lib.rs"))
    for dirpath, _, files in os.walk(src):
        for f in files:
            if not f.endswith(".rs"):
                continue
            rel = os.path.relpath(os.path.join(dirpath, f), src)[:-3].split(os.sep)
            if rel == ["lib"] or (rel == ["main"] and not has_lib):
                name = "crate"
            elif rel == ["main"]:
                name = "main"
            elif rel[0] == "bin":
                continue
            else:
                if rel[-1] == "mod":
                    rel = rel[:-1]
                name = "::".join(rel)
            mods[name] = os.path.join(dirpath, f)
    return mods


def use_paths(tree):
    """The (path, name bound) pairs of one `use` tree: `a::{b, c::{d, e as f}, self}` gives
    (a::b, b), (a::c::d, d), (a::c::e, f), (a, a)."""
    tree = re.sub(r"\s*(::|[{},])\s*", r"\1", " ".join(tree.split()))

    def split_top(s):
        parts, depth, cur = [], 0, ""
        for ch in s:
            if ch == "," and depth == 0:
                parts.append(cur)
                cur = ""
                continue
            depth += ch == "{"
            depth -= ch == "}"
            cur += ch
        if cur:
            parts.append(cur)
        return parts

    def expand(s):
        i = s.find("{")
        if i < 0:
            path, _, alias = s.partition(" as ")
            path = path.strip()
            if path.endswith("::self"):
                path = path[:-len("::self")]
            return [(path, alias.strip() or path.split("::")[-1])]
        prefix, inner = s[:i], s[i + 1:s.rfind("}")]
        out = []
        for part in split_top(inner):
            for p, alias in expand(part.strip()):
                if p == "self":
                    out.append((prefix.rstrip(":"), alias if alias != "self"
                                else prefix.rstrip(":").split("::")[-1]))
                else:
                    out.append((prefix + p, alias))
        return out

    return [(p, a) for p, a in expand(tree.strip()) if p]


PATH = re.compile(r"(?<![\w:])((?:[A-Za-z_]\w*)(?:\s*::\s*(?:[A-Za-z_]\w*|\*))+)")
USE = re.compile(r"\buse\s+([^;]*);")
INLINE_MOD = re.compile(r"\bmod\s+([A-Za-z_]\w*)\s*\{")


def inline_depths(code):
    """For each offset, the depth of inline `mod x { }` blocks around it."""
    depth_at = [0] * (len(code) + 1)
    opens = []  # brace depth at which each open inline module started
    brace = 0
    pending = {m.end() - 1 for m in INLINE_MOD.finditer(code)}
    cur = 0
    for i, ch in enumerate(code):
        if ch == "{":
            brace += 1
            if i in pending:
                opens.append(brace)
                cur += 1
        elif ch == "}":
            if opens and opens[-1] == brace:
                opens.pop()
                cur -= 1
            brace -= 1
        depth_at[i] = cur
    return depth_at


class Module:
    """One file's code and how its paths resolve (see the docstring's Edges)."""

    def __init__(self, name, path, mods, lib_name):
        self.name, self.path, self.mods, self.lib_name = name, path, mods, lib_name
        with open(path, encoding="utf-8") as f:
            self.code = strip(f.read())
        self.depth_at = inline_depths(self.code)
        self.own = [] if name == "crate" else name.split("::")
        self.glob_parent = re.search(r"\buse\s+super\s*::\s*\*\s*;", self.code) is not None
        self.uses = [(m.start(), m.end(), use_paths(m.group(1)),
                      re.search(r"\bpub(\s*\([^)]*\))?\s*$", self.code[:m.start()]) is not None)
                     for m in USE.finditer(self.code)]

    def absolute(self, segs, at):
        """The path `segs` (written at offset `at`) from the crate root, or None."""
        if not segs:
            return None
        head = segs[0]
        own = self.own
        if head == "crate" or (head == self.lib_name and self.name == "main"):
            return segs[1:]
        if head in ("super", "self"):
            ups, k = 0, 0
            while k < len(segs) and segs[k] in ("super", "self"):
                ups += segs[k] == "super"
                k += 1
            ups -= self.depth_at[at]
            if ups <= 0:
                return own + segs[k:] if k < len(segs) else None
            if ups > len(own):
                return None
            return own[:len(own) - ups] + segs[k:]
        child = "::".join(own + [head])
        sibling = "::".join(own[:-1] + [head])
        if child in self.mods and child != self.name:
            return own + segs
        if self.glob_parent and own and sibling in self.mods and sibling != self.name:
            return own[:-1] + segs
        return None  # another crate, a type's associated item, a local module

    def reexports(self):
        """{name: absolute path} of this module's `pub use` items."""
        out = {}
        for start, _, paths, public in self.uses:
            if not public:
                continue
            for p, alias in paths:
                segs = [x for x in p.split("::") if x]
                if alias == "*" or "*" in segs:
                    continue
                absolute = self.absolute(segs, start)
                if absolute:
                    out[alias] = absolute
        return out


def target(absolute, mods, reexports):
    """The module a path from the crate root resolves to: the longest prefix that is a
    module, following re-exports (`pub use`) to the module they name."""
    segs = list(absolute)
    for _ in range(16):  # re-export chains are short; a loop of them is not followed
        best, k_best = "crate", 0
        redirected = None
        for k in range(len(segs) + 1):
            cand = "::".join(segs[:k]) or "crate"
            if cand not in mods:
                break
            best, k_best = cand, k
            if k < len(segs) and segs[k] in reexports.get(cand, {}):
                if "::".join(segs[:k + 1]) not in mods:
                    redirected = reexports[cand][segs[k]] + segs[k + 1:]
                    break
        if redirected is None:
            return best
        segs = redirected
    return best


def edges_of(m, mods, reexports):
    """[(target module, line)] of module `m` (see Edges)."""
    found = []

    def line_of(at):
        return m.code.count("\n", 0, at) + 1

    for start, _, paths, _ in m.uses:
        for p, _ in paths:
            segs = [x for x in p.split("::") if x and x != "*"]
            absolute = m.absolute(segs, start)
            if absolute is not None:
                found.append((target(absolute, mods, reexports), line_of(start)))
    for hit in PATH.finditer(m.code):
        if any(a <= hit.start() < b for a, b, _, _ in m.uses):
            continue
        segs = [x.strip() for x in hit.group(1).split("::")]
        absolute = m.absolute([x for x in segs if x != "*"], hit.start())
        if absolute is not None:
            found.append((target(absolute, mods, reexports), line_of(hit.start())))
    out = []
    for t, line in found:
        if t == m.name or m.name == "crate" or t.startswith(m.name + "::"):
            continue  # itself, or a parent naming its descendant
        out.append((t, line))
    return out


def graph(crate_dir, lib_name):
    """({module: {target: (file, line)}}, {module: file})."""
    mods = module_files(crate_dir)
    parsed = {n: Module(n, p, mods, lib_name) for n, p in sorted(mods.items())}
    reexports = {n: m.reexports() for n, m in parsed.items()}
    g = {}
    for name, m in parsed.items():
        g[name] = {}
        for t, line in edges_of(m, mods, reexports):
            g[name].setdefault(t, (os.path.relpath(m.path, ROOT), line))
    return g, mods


def cycles(g):
    """One cycle (a list of modules, first == last) per strongly connected component."""
    index, low, stack, on, comps = {}, {}, [], set(), []
    counter = [0]

    def visit(v):
        # iterative Tarjan
        work = [(v, iter(sorted(g.get(v, {}))))]
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        while work:
            node, it = work[-1]
            advanced = False
            for w in it:
                if w not in g:
                    continue
                if w not in index:
                    index[w] = low[w] = counter[0]
                    counter[0] += 1
                    stack.append(w)
                    on.add(w)
                    work.append((w, iter(sorted(g.get(w, {})))))
                    advanced = True
                    break
                if w in on:
                    low[node] = min(low[node], index[w])
            if advanced:
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[node])
            if low[node] == index[node]:
                comp = []
                while True:
                    w = stack.pop()
                    on.discard(w)
                    comp.append(w)
                    if w == node:
                        break
                if len(comp) > 1:
                    comps.append(sorted(comp))

    for v in sorted(g):
        if v not in index:
            visit(v)
    out = []
    for comp in comps:
        members = set(comp)
        start = comp[0]
        # shortest way back to start inside the component (breadth first)
        prev, frontier, seen = {}, [start], {start}
        found = None
        while frontier and not found:
            nxt = []
            for u in frontier:
                for w in sorted(g[u]):
                    if w == start:
                        found = u
                        break
                    if w in members and w not in seen:
                        seen.add(w)
                        prev[w] = u
                        nxt.append(w)
                if found:
                    break
            frontier = nxt
        path = [start]
        u = found
        while u != start:
            path.append(u)
            u = prev[u]
        path.append(start)
        path = [start] + list(reversed(path[1:-1])) + [start]
        out.append((path, comp))
    return out


def layer_of(name, table):
    """(rank, layer name) of module `name` (rank 0 = top), or None."""
    best = None
    for rank, (layer, prefixes) in enumerate(table):
        for p in prefixes:
            if name == p or name.startswith(p + "::"):
                if best is None or len(p) > best[2]:
                    best = (rank, layer, len(p))
    return best and best[:2]


def check(crate, g, table):
    """The failures of one crate's graph: printable lines."""
    fails = []
    for path, comp in cycles(g):
        hops = []
        for a, b in zip(path, path[1:]):
            f, line = g[a][b]
            hops.append(f"    {a} -> {b}   ({f}:{line})")
        fails.append(f"{crate}: import cycle {' -> '.join(path)}"
                     f" (component: {', '.join(comp)})\n" + "\n".join(hops))
    if table:
        for a in sorted(g):
            la = layer_of(a, table)
            if la is None:
                continue
            for b, (f, line) in sorted(g[a].items()):
                lb = layer_of(b, table)
                if lb is not None and lb[0] < la[0]:
                    fails.append(f"{crate}: {a} (layer {la[1]}) imports {b} (higher layer"
                                 f" {lb[1]})   ({f}:{line})")
    return fails


def main(argv):
    known_ok = "--known-ok" in argv
    argv = [a for a in argv if a != "--known-ok"]
    if argv[:1] == ["--graph"]:
        if len(argv) != 2:
            print("usage: layers.py --graph CRATE_DIR", file=sys.stderr)
            return 2
        lib = dict(CRATES).get(argv[1], argv[1].replace("-", "_"))
        g, _ = graph(os.path.join(ROOT, argv[1]), lib)
        for a in sorted(g):
            for b, (f, line) in sorted(g[a].items()):
                print(f"{a} -> {b}   ({f}:{line})")
        return 0
    if argv:
        print(__doc__.splitlines()[2], file=sys.stderr)
        return 2
    failed = 0
    for crate, lib in CRATES:
        g, _ = graph(os.path.join(ROOT, crate), lib)
        table = LAYERS.get(crate)
        if table:
            loose = [m for m in sorted(g) if m != "crate" and layer_of(m, table) is None]
            if loose:
                print(f"{crate}: in no layer (unchecked): {', '.join(loose)}")
        fails = check(crate, g, table)
        edges = sum(len(v) for v in g.values())
        for f in fails:
            is_known = any(k in f for k in KNOWN)
            tag = "known (fixed on another branch)" if is_known else "FAIL"
            print(f"{tag}: {f}")
            failed += not (is_known and known_ok)
        if not fails:
            print(f"{crate}: {len(g)} modules, {edges} edges: no cycles"
                  + (", layers respected" if table else ""))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
