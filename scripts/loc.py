#!/usr/bin/env python3
"""Lines of Rust source in a tree, tests excluded: what "the host side shrinks" is measured in.

Usage: scripts/loc.py [--rev REV] DIR...   (default DIRs: host-sim/src shared/src)

Counts, per directory, the lines of every `.rs` file except test code: files named `tests.rs`
or under a `tests/` folder, and every item behind `#[cfg(test)]` (its braces are matched).
Blank lines are not counted. With `--rev`, the files are read from that git revision instead
of the working tree, so a before/after pair is one command each.
"""
import subprocess
import sys


def files(rev, root):
    if rev:
        out = subprocess.run(["git", "ls-tree", "-r", "--name-only", rev, root],
                             check=True, capture_output=True, text=True).stdout
    else:
        out = subprocess.run(["git", "ls-files", "--cached", "--others", "--exclude-standard", root],
                             check=True, capture_output=True, text=True).stdout
    return [f for f in out.split() if f.endswith(".rs")]


def read(rev, path):
    if rev:
        return subprocess.run(["git", "show", f"{rev}:{path}"], check=True,
                              capture_output=True, text=True).stdout
    with open(path, encoding="utf-8") as f:
        return f.read()


def is_test_file(path):
    return path.endswith("/tests.rs") or "/tests/" in path


def count(text):
    """Non-blank lines outside `#[cfg(test)]` items."""
    lines = text.splitlines()
    n, i = 0, 0
    while i < len(lines):
        line = lines[i].strip()
        if line == "#[cfg(test)]":
            i = skip_item(lines, i + 1)
            continue
        if line:
            n += 1
        i += 1
    return n


def skip_item(lines, i):
    """Index just past the item starting at line i (a `mod x;` line or a braced block)."""
    depth, opened = 0, False
    while i < len(lines):
        code = lines[i].split("//")[0]
        depth += code.count("{") - code.count("}")
        opened = opened or "{" in code
        i += 1
        if (opened and depth <= 0) or (not opened and code.rstrip().endswith(";")):
            return i
    return i


def main(argv):
    rev = None
    if argv[:1] == ["--rev"]:
        rev, argv = argv[1], argv[2:]
    for root in argv or ["host-sim/src", "shared/src"]:
        total = sum(count(read(rev, f)) for f in files(rev, root) if not is_test_file(f))
        print(f"{root}\t{total}")


if __name__ == "__main__":
    main(sys.argv[1:])
