#!/usr/bin/env python3
"""Static worst case of one function of a Cortex-M4 (thumbv7em) ELF: instructions and cycles.

    scripts/wcet.py ELF SYMBOL [--loop-cap ADDR=N ...] [--max-instructions N]
                    [--max-cycles N] [--path] [--mca] [--json]

SYMBOL is a demangled Rust path (`dexter_core::tilt_control::TiltControllerWith<T>::step`, or
for a trait method `<dexter_core::control::Controller as dexter_core::fixed_rate::FixedRate>::step`)
or a mangled or plain symbol name; it must match exactly one function (the hash suffix may be left off).

What it does:
1. disassembles the function with llvm-objdump (Debian's `llvm-objdump`, or rustup's
   llvm-tools, or $LLVM_OBJDUMP), skipping literal pools (`$d` mapping symbols);
2. builds the control-flow graph: conditional and unconditional branches, cbz/cbnz, IT
   blocks (a branch or return in an IT block is conditional), tbb/tbh jump tables (read from
   the listing), returns (bx lr, pop {..pc}, ldr pc), tail calls (a branch out of the
   function), traps (udf, bkpt: the path ends there);
3. follows every direct call (bl) into its callee and adds the callee's worst case
   (recursively; recursion and indirect calls/jumps are refused);
4. finds the longest path from the entry to any exit, once counting instructions and once
   counting cycles. A cycle in the graph (a loop) is refused unless its header has a cap,
   `--loop-cap 0xADDR=N` (the header runs at most N times per entry into the loop); then the
   loop counts N times its longest iteration plus its longest way out (nested loops are
   refused).

Instructions are counted the way QEMU's `-icount` counts them: every instruction that is
reached counts once, including the IT instruction and instructions whose IT condition fails.

Cycles use the Cortex-M4 instruction timings (Arm DDI 0439, Cortex-M4 TRM r0p1, table 3-1
"Cortex-M4 instruction set summary" and table 7-1 for the FPU), taking the upper end of each
range so the result is a bound for zero-wait-state memory: a taken branch, call or return
costs 1 + P with P = 3 (the TRM gives P = 1..3 for the pipeline refill), loads and stores 2,
LDRD/STRD 3, LDM/STM/PUSH/POP 1 + N (+ P with pc), MLA/MLS 2, SDIV/UDIV 12, VLDR/VSTR 2,
VPUSH/VPOP/VLDM/VSTM 1 + N, VMLA/VMLS/VNMLA/VNMLS/VFMA/VFMS 3, VDIV and VSQRT 14, other FPU
data processing and core<->FPU moves 1, everything else 1. Flash wait states, bus contention,
interrupts and the FPU's lazy stacking are not modelled: on a part that fetches from flash
with wait states and no cache, add them.

`--mca` also runs llvm-mca (Cortex-M4 scheduling model, -mcpu=cortex-m4) over the
instructions of the worst-cycle path laid out straight (branches left out, their cost
reported separately) as a cross-check of the table.

Exit status: 0, or 1 if a --max-* bound is exceeded, 2 on a usage or analysis error.
"""

import argparse
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile

P_REFILL = 3  # pipeline refill after a taken branch, cycles (TRM: 1..3; the bound takes 3)

CONDS = "eq ne cs hs cc lo mi pl vs vc hi ls ge lt gt le".split()


class AnalysisError(Exception):
    """The function cannot be bounded as it stands (say why, and where)."""


def find_tool(name):
    env = os.environ.get("LLVM_" + name.upper().replace("LLVM-", "").replace("-", "_"))
    if env:
        return env
    path = shutil.which(name)
    if path:
        return path
    try:
        sysroot = subprocess.run(["rustc", "--print", "sysroot"], capture_output=True,
                                 text=True, check=True).stdout.strip()
        for root, _dirs, files in os.walk(os.path.join(sysroot, "lib", "rustlib")):
            if name in files:
                return os.path.join(root, name)
    except (OSError, subprocess.CalledProcessError):
        pass
    raise AnalysisError(f"{name} not found: install Debian's llvm, or "
                        f"`rustup component add llvm-tools`, or set LLVM_OBJDUMP/LLVM_NM")


# ---------------------------------------------------------------------------------------
# instructions


class Insn:
    """One disassembled instruction."""

    def __init__(self, addr, mnemonic, operands):
        self.addr = addr
        self.mnemonic = mnemonic  # as printed, e.g. "vdiv.f32", "bne.w", "ldrbeq"
        self.operands = operands
        self.in_it = False  # conditional through an IT block
        self.table = None  # tbb/tbh: list of target addresses

    def __repr__(self):
        return f"{self.addr:#x}: {self.mnemonic} {self.operands}"

    @property
    def base(self):
        """Mnemonic without width qualifier and data type: bne.w -> bne, vdiv.f32 -> vdiv."""
        return self.mnemonic.split(".")[0]

    def target(self):
        m = re.search(r"0x([0-9a-f]+)", self.operands)
        return int(m.group(1), 16) if m else None

    def reglist(self):
        m = re.search(r"\{([^}]*)\}", self.operands)
        if not m:
            return []
        regs = []
        for part in m.group(1).split(","):
            part = part.strip()
            r = re.fullmatch(r"([a-z]+)(\d+)-\1?(\d+)", part)
            if r:  # ranges such as d8-d9 (rare in llvm-objdump output)
                regs += [f"{r.group(1)}{i}" for i in range(int(r.group(2)), int(r.group(3)) + 1)]
            elif part:
                regs.append(part)
        return regs


def strip_cond(base, stems):
    """Split `base` into (stem, cond) if it is one of `stems` plus a condition code."""
    for stem in stems:
        if base == stem:
            return stem, None
        if base.startswith(stem) and base[len(stem):] in CONDS:
            return stem, base[len(stem):]
    return None, None


def kind(insn):
    """Control-flow kind: 'b', 'bcond', 'cbz', 'bl', 'ret', 'tb', 'trap', 'indirect', None."""
    b = insn.base
    ops = insn.operands.replace(" ", "")
    if b in ("cbz", "cbnz"):
        return "cbz"
    if b in ("tbb", "tbh"):
        return "tb"
    if b in ("udf", "bkpt"):
        return "trap"
    stem, cond = strip_cond(b, ("bl", "blx", "bx", "b"))
    if stem == "b":
        return "bcond" if cond or insn.in_it else "b"
    if stem == "bl":
        return "bl"
    if stem == "blx":
        return "indirect"
    if stem == "bx":
        return "ret" if ops == "lr" else "indirect"
    pstem, _ = strip_cond(b, ("pop", "ldm", "ldr", "mov"))
    if pstem in ("pop", "ldm") and "pc" in insn.reglist():
        return "ret"
    if pstem == "ldr" and ops.startswith("pc,"):
        return "ret" if "[sp]" in ops else "indirect"
    if pstem == "mov" and ops.startswith("pc,"):
        return "indirect"
    return None


def cycles(insn):
    """Cortex-M4 cycles of `insn` without the taken-branch refill (added on the edge)."""
    b = insn.base
    m = insn.mnemonic
    if b.startswith("v"):
        if b.startswith(("vdiv", "vsqrt")):
            return 14
        if b.startswith(("vmla", "vmls", "vnmla", "vnmls", "vfma", "vfms", "vfnma", "vfnms")):
            return 3
        if b.startswith(("vldr", "vstr")):
            return 2
        if b.startswith(("vpush", "vpop", "vldm", "vstm")):
            n = sum(2 if r.startswith("d") else 1 for r in insn.reglist())
            return 1 + n
        if b.startswith("vmov") and insn.operands.count(",") == 2:
            return 2  # two core registers <-> a double or two singles
        return 1
    if b.startswith("it"):
        return 1
    for stem in ("ldrd", "strd"):
        if strip_cond(b, (stem,))[0]:
            return 3
    for stem in ("push", "pop", "ldm", "ldmia", "ldmdb", "stm", "stmia", "stmdb"):
        if strip_cond(b, (stem,))[0]:
            return 1 + len(insn.reglist())
    for stem in ("ldr", "ldrb", "ldrh", "ldrsb", "ldrsh", "str", "strb", "strh", "ldrex",
                 "strex", "ldrexb", "strexb", "ldrexh", "strexh"):
        if strip_cond(b, (stem,))[0]:
            return 2
    for stem in ("sdiv", "udiv"):
        if strip_cond(b, (stem,))[0]:
            return 12
    for stem in ("mla", "mls"):
        if strip_cond(b, (stem,))[0]:
            return 2
    for stem in ("tbb", "tbh"):
        if b == stem:
            return 2
    del m
    return 1


# ---------------------------------------------------------------------------------------
# disassembly


LINE = re.compile(r"^\s*([0-9a-f]+):\s+(?:(?:[0-9a-f]{2}\s)+\s*)?(\S+)(?:\s+(.*?))?\s*$")
LABEL = re.compile(r"^([0-9a-f]+) <(.*)>:$")


def parse_listing(text):
    """Instructions of an llvm-objdump listing, literal pools dropped, IT blocks marked,
    tbb/tbh tables attached."""
    insns = []
    in_data = False
    data = []  # (addr, size, value) of the current data island
    it_left = 0
    pending_table = None
    for raw in text.splitlines():
        line = raw.split("@")[0].rstrip() if "\t.word" not in raw else raw.rstrip()
        lab = LABEL.match(raw.strip())
        if lab:
            name = lab.group(2)
            if name.startswith("$d"):
                in_data = True
            elif name.startswith("$t") or name.startswith("$a"):
                in_data = False
                if pending_table is not None:
                    finish_table(pending_table, data)
                    pending_table = None
                data = []
            else:
                in_data = False
            continue
        m = LINE.match(line)
        if not m:
            continue
        addr = int(m.group(1), 16)
        mnemonic, operands = m.group(2), (m.group(3) or "")
        if in_data or mnemonic.startswith("."):
            val = re.search(r"0x([0-9a-f]+)", operands)
            size = {".byte": 1, ".short": 2, ".word": 4}.get(mnemonic, 0)
            if val and size:
                data.append((addr, size, int(val.group(1), 16)))
            continue
        insn = Insn(addr, mnemonic, operands.split("@")[0].strip())
        if it_left:
            insn.in_it = True
            it_left -= 1
        if insn.base.startswith("it") and re.fullmatch(r"it[te]{0,3}", insn.base):
            it_left = len(insn.base) - 1
        if insn.base in ("tbb", "tbh"):
            pending_table = insn
            data = []
        insns.append(insn)
    if pending_table is not None:
        finish_table(pending_table, data)
    return insns


def finish_table(insn, data):
    """Targets of a tbb/tbh from the data island after it: target = insn + 4 + 2 * entry."""
    if "[pc" not in insn.operands.replace(" ", ""):
        raise AnalysisError(f"{insn}: jump table not based on pc")
    size = 1 if insn.base == "tbb" else 2
    entries = []
    for addr, dsize, value in data:
        if dsize == size:
            entries.append(value)
        elif dsize == 4 and size == 1:
            entries += [(value >> (8 * i)) & 0xFF for i in range(4)]
        elif dsize == 4 and size == 2:
            entries += [value & 0xFFFF, value >> 16]
        elif dsize == 2 and size == 1:
            entries += [value & 0xFF, value >> 8]
        del addr
    if not entries:
        raise AnalysisError(f"{insn}: jump table not found in the listing")
    table_end = insn.addr + 4 + size * len(entries)
    targets = [insn.addr + 4 + 2 * e for e in entries]
    # the island may hold padding after the table: keep entries that land after the table
    insn.table = sorted({t for t in targets if t >= table_end})


# ---------------------------------------------------------------------------------------
# the graph and its longest path


class Function:
    """The control-flow graph of one function."""

    def __init__(self, name, insns, start, end):
        self.name = name
        self.start, self.end = start, end
        self.insns = insns
        self.index = {i.addr: n for n, i in enumerate(insns)}
        if start not in self.index:
            raise AnalysisError(f"{name}: no instruction at its entry {start:#x}")

    def inside(self, addr):
        return self.start <= addr < self.end

    def successors(self, n):
        """(successor index or None for an exit, extra cycles on the edge, callee or None)."""
        insn = self.insns[n]
        k = kind(insn)
        nxt = n + 1 if n + 1 < len(self.insns) else None
        fall = [] if nxt is None else [(nxt, 0, None)]
        if k is None or k == "bl":
            return fall
        if k == "trap":
            return [(None, 0, None)]
        if k == "ret":
            out = [(None, P_REFILL, None)]
            return out + (fall if insn.in_it else [])
        if k == "indirect":
            raise AnalysisError(f"{self.name}: indirect branch or call at {insn}: "
                                "not supported (give the tool a direct call)")
        if k == "tb":
            return [(self.index_of(t, insn), P_REFILL, None) for t in insn.table]
        target = insn.target()
        if target is None:
            raise AnalysisError(f"{self.name}: branch without a target: {insn}")
        if self.inside(target):
            taken = (self.index_of(target, insn), P_REFILL, None)
        else:
            taken = (None, P_REFILL, target)  # tail call
        if k == "b":
            return [taken]
        return [taken] + fall  # bcond, cbz: not taken falls through at no extra cost

    def index_of(self, addr, insn):
        if addr not in self.index:
            raise AnalysisError(f"{self.name}: {insn} jumps to {addr:#x}, not an instruction")
        return self.index[addr]


class Analyzer:
    """Worst cases of functions in one ELF, callees included."""

    def __init__(self, elf, loop_caps=None):
        self.elf = elf
        self.loop_caps = loop_caps or {}
        self.objdump = find_tool("llvm-objdump")
        self.symbols = read_symbols(elf, find_tool("llvm-nm"))
        self.memo = {}
        self.active = []

    def function(self, addr):
        sym = next((s for s in self.symbols if s["addr"] == addr), None)
        if sym is None:
            raise AnalysisError(f"call to {addr:#x}: no function symbol there")
        text = subprocess.run(
            [self.objdump, "-d", "--no-show-raw-insn", "--triple=thumbv7em-none-eabihf",
             "--mcpu=cortex-m4", f"--start-address={addr:#x}",
             f"--stop-address={addr + sym['size']:#x}", self.elf],
            capture_output=True, text=True, check=True).stdout
        return Function(sym["name"], parse_listing(text), addr, addr + sym["size"])

    def worst(self, addr):
        """{'instructions': (n, path), 'cycles': (n, path)} of the function at `addr`."""
        if addr in self.memo:
            return self.memo[addr]
        if addr in self.active:
            raise AnalysisError("recursion: " + " -> ".join(f"{a:#x}" for a in self.active))
        self.active.append(addr)
        fn = self.function(addr)
        result = {metric: longest_path(fn, metric, self, self.loop_caps)
                  for metric in ("instructions", "cycles")}
        try:
            result["best_instructions"] = longest_path(fn, "instructions", self, {}, sign=-1)
        except AnalysisError:
            result["best_instructions"] = (None, [])  # loops: no best case reported
        self.active.pop()
        self.memo[addr] = result
        return result


def read_symbols(elf, nm):
    # both listings sorted by address (-n), so their lines pair up
    out = subprocess.run([nm, "-n", "-C", "-S", "--defined-only", elf], capture_output=True,
                         text=True, check=True).stdout
    mangled = subprocess.run([nm, "-n", "-S", "--defined-only", elf], capture_output=True,
                             text=True, check=True).stdout
    syms = []
    for demangled_line, raw_line in zip(out.splitlines(), mangled.splitlines()):
        parts = demangled_line.split(None, 3)
        raw = raw_line.split(None, 3)
        if len(parts) < 4 or parts[2] not in "tTwW" or parts[3].startswith("$"):
            continue
        syms.append({"addr": int(parts[0], 16) & ~1, "size": int(parts[1], 16),
                     "name": parts[3], "mangled": raw[3] if len(raw) > 3 else parts[3]})
    return syms


LEGACY_ESCAPES = (("$LT$", "<"), ("$GT$", ">"), ("$u20$", " "), ("$C$", ","), ("$RF$", "&"),
                  ("$BP$", "*"), ("$u27$", "'"), ("$u5b$", "["), ("$u5d$", "]"), ("..", "::"))


def rust_path(name):
    """`name` with the legacy mangling's escapes that llvm-nm -C leaves in undone:
    `_$LT$a..B$u20$as$u20$c..T$GT$::f` is `<a::B as c::T>::f`, a trait method's path."""
    if name.startswith("_$"):
        name = name[1:]
    for escape, char in LEGACY_ESCAPES:
        name = name.replace(escape, char)
    return name


def resolve(symbols, wanted):
    def plain(name):
        return re.sub(r"::h[0-9a-f]{16}$", "", name)
    hits = [s for s in symbols
            if wanted in (s["name"], s["mangled"], plain(s["name"]), plain(rust_path(s["name"])))]
    if not hits:
        hits = [s for s in symbols if wanted in s["name"]]
    hits = list({s["addr"]: s for s in hits}.values())
    if len(hits) != 1:
        names = ", ".join(s["name"] for s in hits[:8]) or "none"
        raise AnalysisError(f"symbol {wanted!r} matches {len(hits)} functions: {names}")
    return hits[0]


def insn_cost(insn, metric, analyzer, sign=1):
    if metric == "instructions":
        own = 1
    else:
        own = cycles(insn)
        k = kind(insn)
        if k == "bl" or (k == "ret" and not insn.in_it):
            own += P_REFILL if k == "bl" else 0
    callee = 0
    if kind(insn) == "bl":
        callee = callee_cost(analyzer, insn.target(), metric, sign)
    return own + callee


def callee_cost(analyzer, addr, metric, sign):
    """The callee's worst case (sign 1) or best case in instructions (sign -1)."""
    res = analyzer.worst(addr)
    if sign > 0:
        return res[metric][0]
    if res["best_instructions"][0] is None:
        raise AnalysisError(f"callee at {addr:#x} has loops: no best case")
    return res["best_instructions"][0]


def longest_path(fn, metric, analyzer, loop_caps, sign=1):
    """Longest entry-to-exit path of `fn` in `metric` (sign 1), or the shortest (sign -1,
    loop-free functions only); returns (cost, [instructions on the path])."""
    n = len(fn.insns)
    succ = [fn.successors(i) for i in range(n)]
    cost = [sign * insn_cost(fn.insns[i], metric, analyzer, sign) for i in range(n)]

    def edge_extra(extra, callee):
        c = extra if metric == "cycles" else 0
        if callee is not None:
            c += callee_cost(analyzer, callee, metric, sign)
        return sign * c

    # depth-first search from the entry: back edges mark loops
    entry = fn.index[fn.start]
    order, back, state = [], set(), [0] * n
    stack = [(entry, iter(succ[entry]))]
    state[entry] = 1
    while stack:
        node, it = stack[-1]
        for s, _extra, _callee in it:
            if s is None:
                continue
            if state[s] == 1:
                back.add((node, s))
            elif state[s] == 0:
                state[s] = 1
                stack.append((s, iter(succ[s])))
                break
        else:
            state[node] = 2
            order.append(node)
            stack.pop()
    order.reverse()  # topological order of the graph without back edges

    loops = {}
    for tail, head in back:
        loops.setdefault(head, set()).add(tail)
    bodies = {}
    for head, tails in loops.items():
        addr = fn.insns[head].addr
        if addr not in loop_caps:
            raise AnalysisError(
                f"{fn.name}: loop with header {addr:#x} (back edge from "
                + ", ".join(f"{fn.insns[t].addr:#x}" for t in sorted(tails))
                + f"); give its cap: --loop-cap {addr:#x}=N")
        body = {head}
        work = list(tails)
        pred = [[] for _ in range(n)]
        for i in range(n):
            for s, _e, _c in succ[i]:
                if s is not None:
                    pred[s].append(i)
        while work:
            x = work.pop()
            if x not in body:
                body.add(x)
                work += pred[x]
        bodies[head] = body
    heads = list(bodies)
    for h in heads:
        for h2 in heads:
            if h != h2 and h2 in bodies[h]:
                raise AnalysisError(f"{fn.name}: nested loops ({fn.insns[h].addr:#x} holds "
                                    f"{fn.insns[h2].addr:#x}) are not supported")

    def dag_longest(nodes, start, stop_at_back_to=None):
        """Longest path from `start` over `nodes` (topological order) without back edges:
        best[i] = cost of the heaviest path from start ending at i (inclusive)."""
        best = {start: (cost[start], [start])}
        exits = []  # (total, path) ending at an exit edge
        for i in order:
            if i not in best or i not in nodes:
                continue
            c, path = best[i]
            for s, extra, callee in succ[i]:
                add = edge_extra(extra, callee)
                if s is None or s not in nodes:
                    exits.append((c + add, path, s))
                    continue
                if (i, s) in back:
                    if s == stop_at_back_to:
                        exits.append((c + add, path, "back"))
                    continue
                cand = c + add + cost[s]
                if s not in best or cand > best[s][0]:
                    best[s] = (cand, path + [s])
        return exits

    # collapse each loop: N times its heaviest iteration, plus its heaviest way out
    loop_cost = {}
    for head, body in bodies.items():
        cap = loop_caps[fn.insns[head].addr]
        paths = dag_longest(body, head, stop_at_back_to=head)
        iters = [p for p in paths if p[2] == "back"]
        outs = [p for p in paths if p[2] != "back"]
        if not outs:
            raise AnalysisError(f"{fn.name}: loop at {fn.insns[head].addr:#x} has no exit")
        it_cost = max(p[0] for p in iters) if iters else 0
        loop_cost[head] = ((cap - 1) * it_cost, body)

    # longest path over the graph with loops collapsed into their headers
    in_loop = set().union(*(b for _, b in loop_cost.values())) if loop_cost else set()
    best = {entry: (cost[entry], [entry])}
    done = []
    for i in order:
        if i not in best:
            continue
        c, path = best[i]
        if i in loop_cost:
            extra_iters, body = loop_cost[i]
            # cap - 1 heaviest iterations, then the heaviest way out of the loop
            for total, p, s in dag_longest(body, i):
                if s == "back":
                    continue
                tc = c + extra_iters + total - cost[i]
                if s is None:
                    done.append((tc, path + p[1:]))
                elif s not in best or tc + cost[s] > best[s][0]:
                    best[s] = (tc + cost[s], path + p[1:] + [s])
            continue
        if i in in_loop:
            raise AnalysisError(f"{fn.name}: {fn.insns[i]} is reached inside a loop "
                                "without passing its header (irreducible loop)")
        for s, extra, callee in succ[i]:
            add = edge_extra(extra, callee)
            if s is None:
                done.append((c + add, path))
                continue
            cand = c + add + cost[s]
            if s not in best or cand > best[s][0]:
                best[s] = (cand, path + [s])
    if not done:
        raise AnalysisError(f"{fn.name}: no path from the entry reaches an exit")
    total, path = max(done, key=lambda x: x[0])
    return sign * total, [fn.insns[i] for i in path]


# ---------------------------------------------------------------------------------------
# llvm-mca cross-check


def mca_cycles(path):
    """llvm-mca's Cortex-M4 total cycles for the path's instructions laid out straight
    (branches and calls left out, callees not included), with the table's cycles for the
    same instructions, and the number left out."""
    mca = find_tool("llvm-mca")
    lines = [".syntax unified", ".thumb"]
    left_out = 0
    table = 0
    for insn in path:
        if kind(insn) is not None:
            left_out += 1
            continue
        table += cycles(insn)
        lines.append(f"  {insn.mnemonic} {insn.operands}")
    with tempfile.NamedTemporaryFile("w", suffix=".s", delete=False) as f:
        f.write("\n".join(lines) + "\n")
        name = f.name
    try:
        out = subprocess.run([mca, "-mtriple=thumbv7em-none-eabihf", "-mcpu=cortex-m4",
                              "-iterations=1", name], capture_output=True, text=True)
    finally:
        os.unlink(name)
    m = re.search(r"Total Cycles:\s+(\d+)", out.stdout)
    if not m:
        raise AnalysisError("llvm-mca failed: " + out.stderr.strip()[:500])
    return int(m.group(1)), table, left_out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("elf")
    ap.add_argument("symbol")
    ap.add_argument("--loop-cap", action="append", default=[], metavar="0xADDR=N",
                    help="the loop whose header is at ADDR runs at most N times per entry")
    ap.add_argument("--max-instructions", type=int, help="fail (exit 1) above this bound")
    ap.add_argument("--max-cycles", type=int, help="fail (exit 1) above this bound")
    ap.add_argument("--path", action="store_true", help="print the worst-case paths")
    ap.add_argument("--mca", action="store_true", help="cross-check cycles with llvm-mca")
    ap.add_argument("--json", action="store_true", help="one JSON object on stdout")
    args = ap.parse_args(argv)
    try:
        caps = {}
        for c in args.loop_cap:
            addr, n = c.split("=")
            caps[int(addr, 16)] = int(n)
        an = Analyzer(args.elf, caps)
        sym = resolve(an.symbols, args.symbol)
        res = an.worst(sym["addr"])
        mca = mca_cycles(res["cycles"][1]) if args.mca else None
    except AnalysisError as e:
        print(f"wcet: {e}", file=sys.stderr)
        return 2
    ni, ipath = res["instructions"]
    nc, cpath = res["cycles"]
    nb = res["best_instructions"][0]
    heavy = {m: sum(1 for i in ipath if i.base.startswith(m)) for m in ("vdiv", "vsqrt")}
    report = {"symbol": sym["name"], "address": f"{sym['addr']:#x}", "size_bytes": sym["size"],
              "worst_instructions": ni, "worst_cycles": nc, "best_instructions": nb,
              "worst_instruction_path_vdiv": heavy["vdiv"],
              "worst_instruction_path_vsqrt": heavy["vsqrt"],
              "branch_refill_cycles": P_REFILL}
    if mca:
        report["mca_cycles_straight_line"] = mca[0]
        report["table_cycles_straight_line"] = mca[1]
        report["mca_branches_left_out"] = mca[2]
    if args.json:
        print(json.dumps(report))
    else:
        print(f"{sym['name']} at {sym['addr']:#x} ({sym['size']} bytes)")
        print(f"  worst case: {ni} instructions (vdiv {heavy['vdiv']}, vsqrt {heavy['vsqrt']} "
              f"on that path), {nc} cycles (Cortex-M4 table, P = {P_REFILL}, zero wait states)")
        if nb is not None:
            print(f"  best case: {nb} instructions")
        if mca:
            print(f"  llvm-mca -mcpu=cortex-m4 on the worst-cycle path laid out straight "
                  f"({len(cpath) - mca[2]} instructions; {mca[2]} branches and calls left "
                  f"out): {mca[0]} cycles; the table gives {mca[1]} for the same")
        if args.path:
            for title, path in (("instructions", ipath), ("cycles", cpath)):
                print(f"  worst path by {title} ({len(path)} instructions in this function):")
                for i in path:
                    print(f"    {i.addr:#x}: {i.mnemonic} {i.operands}")
    failed = ((args.max_instructions is not None and ni > args.max_instructions)
              or (args.max_cycles is not None and nc > args.max_cycles))
    if failed:
        print(f"wcet: bound exceeded (max instructions {args.max_instructions}, "
              f"max cycles {args.max_cycles})", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
