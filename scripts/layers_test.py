#!/usr/bin/env python3
"""Tests of scripts/layers.py on tiny hand-written crates whose edges are known by hand.

    python3 scripts/layers_test.py
"""

import contextlib
import io
import os
import sys
import tempfile
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import layers  # noqa: E402


def crate(files):
    """A temporary crate with `files` ({path under src/: code}); returns its directory."""
    d = tempfile.mkdtemp(prefix="layers_test_")
    for rel, code in files.items():
        path = os.path.join(d, "src", rel)
        os.makedirs(os.path.dirname(path), exist_ok=True)
        with open(path, "w", encoding="utf-8") as f:
            f.write(code)
    return d


def edges(files, lib="fake"):
    g, _ = layers.graph(crate(files), lib)
    return {a: set(t) for a, t in g.items()}


def failures(files, table=None, lib="fake"):
    g, _ = layers.graph(crate(files), lib)
    return layers.check("fake", g, table)


class Edges(unittest.TestCase):
    def test_use_trees_and_inline_paths_are_edges(self):
        e = edges({
            "lib.rs": "pub mod a; pub mod b; pub mod c;",
            "a.rs": "use crate::{b::{X, Y as Z}, c};\nfn f() { crate::c::g(); }",
            "b.rs": "", "c.rs": "pub fn g() {}",
        })
        self.assertEqual(e["a"], {"b", "c"})

    def test_comments_strings_and_doc_links_are_not_edges(self):
        e = edges({
            "lib.rs": "pub mod a; pub mod b;",
            "a.rs": '//! See [`crate::b`].\n/* use crate::b; */\nconst S: &str = "crate::b::x";\n'
                    'const R: &str = r#"use crate::b;"#; const C: char = \'"\';',
            "b.rs": "",
        })
        self.assertEqual(e["a"], set())

    def test_a_parent_naming_its_children_is_not_an_edge(self):
        e = edges({
            "lib.rs": "pub mod p;",
            "p/mod.rs": "mod child; pub use child::X; fn f() { child::g(); self::child::g(); }",
            "p/child.rs": "use super::Y; pub struct X; pub fn g() {}",
        })
        self.assertEqual(e["p"], set())
        self.assertEqual(e["p::child"], {"p"})

    def test_super_inside_an_inline_module_is_its_own_file(self):
        e = edges({
            "lib.rs": "pub mod p;",
            "p/mod.rs": "pub mod q;",
            "p/q.rs": "fn f() {}\n#[cfg(test)]\nmod tests {\n    use super::*;\n    use super::super::Z;\n}",
        })
        self.assertEqual(e["p::q"], {"p"})

    def test_a_path_through_a_reexport_reaches_the_defining_module(self):
        e = edges({
            "lib.rs": "pub mod a; pub mod deep; pub use deep::inner::{thing as alias};",
            "a.rs": "use crate::alias::X;",
            "deep/mod.rs": "pub mod inner;",
            "deep/inner/mod.rs": "pub mod thing;",
            "deep/inner/thing.rs": "pub struct X;",
        })
        self.assertEqual(e["a"], {"deep::inner::thing"})

    def test_a_binary_root_reaches_the_library_by_name(self):
        e = edges({
            "lib.rs": "pub mod cli;",
            "cli.rs": "pub fn main() {}",
            "main.rs": "fn main() { fake::cli::main() }",
        })
        self.assertEqual(e["main"], {"cli"})

    def test_glob_import_of_the_parent_reaches_siblings(self):
        e = edges({
            "lib.rs": "pub mod p;",
            "p/mod.rs": "mod a; mod b;",
            "p/a.rs": "use super::*;\nfn f() { b::g() }",
            "p/b.rs": "pub fn g() {}",
        })
        self.assertEqual(e["p::a"], {"p", "p::b"})


class Cycles(unittest.TestCase):
    def test_a_direct_cycle_fails_naming_both_files(self):
        f = failures({
            "lib.rs": "pub mod a; pub mod b;",
            "a.rs": "use crate::b::Y;\npub struct X;",
            "b.rs": "use crate::a::X;\npub struct Y;",
        })
        self.assertEqual(len(f), 1)
        self.assertIn("import cycle a -> b -> a", f[0])
        self.assertIn("src/a.rs:1", f[0])
        self.assertIn("src/b.rs:1", f[0])

    def test_a_cycle_through_three_modules_and_super_fails(self):
        f = failures({
            "lib.rs": "pub mod p; pub mod z;",
            "p/mod.rs": "pub mod x; pub mod y;",
            "p/x.rs": "use super::y::Y;",
            "p/y.rs": "use crate::z::Z;",
            "z.rs": "fn f() { crate::p::x::g() }",
        })
        self.assertEqual(len(f), 1)
        self.assertIn("import cycle p::x -> p::y -> z -> p::x", f[0])

    def test_a_cycle_through_a_reexport_fails(self):
        # the physics importing the system's row through the root's old re-export
        f = failures({
            "lib.rs": "pub mod model; pub mod systems; pub use systems::trace;",
            "model.rs": "use crate::trace::Row;\npub fn step() {}",
            "systems/mod.rs": "pub mod trace;",
            "systems/trace.rs": "pub struct Row;\nfn f() { crate::model::step() }",
        })
        self.assertEqual(len(f), 1)
        self.assertIn("model -> systems::trace -> model", f[0])

    def test_a_parent_and_its_children_importing_each_other_pass(self):
        f = failures({
            "lib.rs": "pub mod p;",
            "p/mod.rs": "mod a; mod b; pub use a::A; pub use b::B; pub struct P;",
            "p/a.rs": "use super::P; pub struct A;",
            "p/b.rs": "use super::{A, P}; pub struct B;",
        })
        self.assertEqual(f, [])


class Layers(unittest.TestCase):
    TABLE = [("top", ["cli"]), ("mid", ["systems"]), ("low", ["model"])]

    def test_an_upward_import_fails_naming_the_file(self):
        f = failures({
            "lib.rs": "pub mod cli; pub mod systems; pub mod model;",
            "cli.rs": "use crate::systems::S;",
            "systems.rs": "use crate::model::M; pub struct S;",
            "model.rs": "pub struct M; fn f() { let _ = crate::systems::S; }",
        }, self.TABLE)
        self.assertEqual(len(f), 2, f)  # the cycle and the upward edge
        upward = [x for x in f if "higher layer" in x]
        self.assertEqual(len(upward), 1)
        self.assertIn("model (layer low) imports systems (higher layer mid)", upward[0])
        self.assertIn("src/model.rs:1", upward[0])

    def test_downward_imports_pass_and_the_longest_prefix_decides(self):
        table = [("top", ["cli"]), ("low", ["model"]), ("lowest", ["model::base"])]
        f = failures({
            "lib.rs": "pub mod cli; pub mod model;",
            "cli.rs": "use crate::model::base::B;",
            "model/mod.rs": "pub mod base; pub mod plant;",
            "model/plant.rs": "use super::base::B;",
            "model/base.rs": "pub struct B;",
        }, table)
        self.assertEqual(f, [])
        self.assertEqual(layers.layer_of("model::base", table), (2, "lowest"))
        self.assertEqual(layers.layer_of("model::plant", table), (1, "low"))
        self.assertIsNone(layers.layer_of("output", table))


class Main(unittest.TestCase):
    def test_the_repository_check_runs(self):
        # exit 0 or 1 (what it finds); 2 would be a crash or bad arguments
        with contextlib.redirect_stdout(io.StringIO()), \
                contextlib.redirect_stderr(io.StringIO()):
            self.assertIn(layers.main([]), (0, 1))
            self.assertEqual(layers.main(["--bogus"]), 2)


if __name__ == "__main__":
    unittest.main()
