#!/usr/bin/env python3
"""Tests of scripts/wcet.py on hand-written listings whose worst cases are counted by hand.

    python3 scripts/wcet_test.py
"""

import os
import sys
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import wcet  # noqa: E402


class FakeAnalyzer:
    """Callees by address, each a listing."""

    def __init__(self, listings):
        self.fns = {}
        for addr, (text, size) in listings.items():
            self.fns[addr] = wcet.Function(f"f{addr:x}", wcet.parse_listing(text), addr,
                                           addr + size)
        self.memo = {}

    def worst(self, addr):
        if addr not in self.memo:
            fn = self.fns[addr]
            self.memo[addr] = {m: wcet.longest_path(fn, m, self, {}) for m in
                               ("instructions", "cycles")}
            self.memo[addr]["best_instructions"] = wcet.longest_path(
                fn, "instructions", self, {}, sign=-1)
        return self.memo[addr]


def listing(*lines):
    return "\n".join(lines) + "\n"


# if (r0 == 0) { r1 = a / b (vdiv) } ; return
DIAMOND = listing(
    "00001000 <f>:",
    "    1000:      \tcmp\tr0, #0",
    "    1002:      \tbne\t0x100c <f+0xc>",
    "    1004:      \tvdiv.f32\ts0, s0, s1",
    "    1008:      \tldr\tr1, [r2]",
    "    100a:      \tb\t0x100e <f+0xe>",
    "    100c:      \tmovs\tr1, #1",
    "    100e:      \tbx\tlr",
)


class Tests(unittest.TestCase):
    def worst(self, text, start=0x1000, size=0x100, callees=None, metric="instructions",
              caps=None):
        an = FakeAnalyzer(callees or {})
        fn = wcet.Function("f", wcet.parse_listing(text), start, start + size)
        return wcet.longest_path(fn, metric, an, caps or {})[0]

    def test_trait_methods_resolve_by_their_rust_path(self):
        # llvm-nm -C leaves the legacy mangling's escapes in a trait method's name
        nm = "_$LT$dexter_core..control..Controller$u20$as$u20$dexter_core..fixed_rate..FixedRate$GT$::step::he9b4685ddad75cce"
        other = nm.replace("control..Controller", "hop_control..HopController")
        syms = [{"addr": 0x10, "size": 4, "name": nm, "mangled": nm},
                {"addr": 0x20, "size": 4, "name": other, "mangled": other}]
        hit = wcet.resolve(syms, "<dexter_core::control::Controller as dexter_core::fixed_rate::FixedRate>::step")
        self.assertEqual(hit["addr"], 0x10)
        self.assertEqual(wcet.rust_path("TiltControllerWith$LT$T$GT$::step"), "TiltControllerWith<T>::step")
        with self.assertRaises(wcet.AnalysisError):
            wcet.resolve(syms, "<dexter_core::control::Controller as dexter_core::fixed_rate::FixedRate>::safe")

    def test_diamond_by_hand(self):
        # long arm: cmp, bne (not taken), vdiv, ldr, b, bx = 6 instructions
        self.assertEqual(self.worst(DIAMOND), 6)
        # cycles: cmp 1 + bne not taken 1 + vdiv 14 + ldr 2 + b 1+3 + bx 1+3 = 26;
        # short arm: cmp 1 + bne taken 1+3 + movs 1 + bx 4 = 10
        self.assertEqual(self.worst(DIAMOND, metric="cycles"), 26)
        an = FakeAnalyzer({})
        fn = wcet.Function("f", wcet.parse_listing(DIAMOND), 0x1000, 0x1100)
        self.assertEqual(wcet.longest_path(fn, "instructions", an, {}, sign=-1)[0], 4)

    def test_it_block_instructions_count_and_conditional_return(self):
        text = listing(
            "00001000 <f>:",
            "    1000:      \tcmp\tr0, #0",
            "    1002:      \tittt\teq",
            "    1004:      \tmoveq\tr1, #1",
            "    1006:      \tvldreq\ts0, [r1]",
            "    100a:      \tbxeq\tlr",
            "    100c:      \tmovs\tr0, #2",
            "    100e:      \tbx\tlr",
        )
        # not taken: cmp, ittt, moveq, vldreq, bxeq, movs, bx = 7
        self.assertEqual(self.worst(text), 7)
        # cycles: 1 + 1 + 1 + 2 + 1 (bxeq not taken) + 1 + (1 + 3) = 11
        self.assertEqual(self.worst(text, metric="cycles"), 11)

    def test_calls_add_the_callee_and_tail_calls_end_the_path(self):
        callee = listing(
            "00002000 <g>:",
            "    2000:      \tvsqrt.f32\ts0, s0",
            "    2004:      \tbx\tlr",
        )
        text = listing(
            "00001000 <f>:",
            "    1000:      \tpush\t{r7, lr}",
            "    1002:      \tbl\t0x2000 <g>",
            "    1006:      \tcbz\tr0, 0x100c <f+0xc>",
            "    1008:      \tpop\t{r7, pc}",
            "    100a:      \tnop",
            "    100c:      \tb.w\t0x2000 <g>",
        )
        callees = {0x2000: (callee, 6)}
        # push, bl, [vsqrt, bx], cbz, then pop (1) or b.w + [vsqrt, bx] (3): 2 + 2 + 1 + 3 = 8
        self.assertEqual(self.worst(text, size=0x10, callees=callees), 8)
        # cycles, taken cbz: push 3, bl 1+3, g 14+4, cbz 1+3, b.w 1+3, g 18 = 51;
        # fall-through: ... cbz 1, pop 1+2+3 = 3+4+18+1+6 = 32
        self.assertEqual(self.worst(text, size=0x10, callees=callees, metric="cycles"), 51)

    def test_literal_pools_are_skipped(self):
        text = listing(
            "00001000 <f>:",
            "    1000:      \tvldr\ts0, [pc, #4]          @ 0x1008 <$d>",
            "    1004:      \tb\t0x100c <f+0xc>",
            "    1006:      \tnop",
            "00001008 <$d>:",
            "    1008:\tcd cc 4c 3d\t.word\t0x3d4ccccd",
            "0000100c <$t>:",
            "    100c:      \tbx\tlr",
        )
        self.assertEqual(self.worst(text), 3)

    def test_jump_table_targets_come_from_the_table(self):
        text = listing(
            "00001000 <f>:",
            "    1000:      \ttbb\t[pc, r0]",
            "00001004 <$d>:",
            "    1004:\t02 03 04 00\t.word\t0x00040302",
            "00001008 <$t>:",
            "    1008:      \tmovs\tr1, #1",
            "    100a:      \tmovs\tr1, #2",
            "    100c:      \tmovs\tr1, #3",
            "    100e:      \tbx\tlr",
        )
        # entries 2, 3, 4 -> 0x1008, 0x100a, 0x100c; (0 lands inside the table: padding)
        self.assertEqual(self.worst(text), 5)  # tbb, movs x3, bx

    def test_a_loop_needs_a_cap_and_counts_cap_iterations(self):
        text = listing(
            "00001000 <f>:",
            "    1000:      \tmovs\tr1, #0",
            "    1002:      \tadds\tr1, #1",
            "    1004:      \tcmp\tr1, r0",
            "    1006:      \tblo\t0x1002 <f+0x2>",
            "    1008:      \tbx\tlr",
        )
        with self.assertRaises(wcet.AnalysisError) as e:
            self.worst(text)
        self.assertIn("--loop-cap 0x1002=N", str(e.exception))
        # 10 iterations of (adds, cmp, blo) after movs, then bx: 1 + 30 + 1
        self.assertEqual(self.worst(text, caps={0x1002: 10}), 32)

    def test_indirect_branches_are_refused(self):
        text = listing("00001000 <f>:", "    1000:      \tblx\tr3", "    1002:      \tbx\tlr")
        with self.assertRaises(wcet.AnalysisError):
            self.worst(text)

    def test_cycle_table(self):
        def c(m, ops=""):
            return wcet.cycles(wcet.Insn(0, m, ops))
        self.assertEqual(c("vdiv.f32"), 14)
        self.assertEqual(c("vsqrt.f32"), 14)
        self.assertEqual(c("vmla.f32"), 3)
        self.assertEqual(c("vmul.f32"), 1)
        self.assertEqual(c("ldr.w"), 2)
        self.assertEqual(c("ldrbeq"), 2)
        self.assertEqual(c("strd", "r2, r5, [r1]"), 3)
        self.assertEqual(c("push", "{r4, r5, r6, r7, lr}"), 6)
        self.assertEqual(c("vpush", "{d8, d9}"), 5)
        self.assertEqual(c("vmov", "r0, r1, d0"), 2)
        self.assertEqual(c("bic", "r6, r3, #1"), 1)

    def test_branch_kinds(self):
        def k(m, ops=""):
            return wcet.kind(wcet.Insn(0, m, ops))
        self.assertEqual(k("ble.w", "0x10"), "bcond")
        self.assertEqual(k("bls", "0x10"), "bcond")
        self.assertEqual(k("blo", "0x10"), "bcond")
        self.assertEqual(k("bl", "0x10"), "bl")
        self.assertEqual(k("b.w", "0x10"), "b")
        self.assertEqual(k("bic", "r0, r0, #1"), None)
        self.assertEqual(k("pop.w", "{r4, pc}"), "ret")
        self.assertEqual(k("pop", "{r4, r5}"), None)
        self.assertEqual(k("ldr", "pc, [sp], #4"), "ret")
        self.assertEqual(k("bx", "r3"), "indirect")


if __name__ == "__main__":
    unittest.main()
