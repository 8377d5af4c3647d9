#!/usr/bin/env python3
"""Licence check of the dependency tree (run by .ci/run).

    python3 tools/check_licences.py

Shipped code (every crate reachable from the workspace by normal and build
edges, all targets) must be usable under a permissive licence: MIT, Apache,
BSD, zlib, BSL, ISC, Unlicense, CC0, 0BSD, Unicode (an SPDX expression passes
when some choice of its OR branches is all permissive). Test-only crates
(dev edges) must at least not be GPL/AGPL/LGPL-only. Prints every offender
with the chain that pulls it in and exits 1; exits 0 when all pass.
"""
import re
import subprocess
import sys

PERMISSIVE = {
    "MIT", "MIT-0", "Apache-2.0", "Apache-2.0 WITH LLVM-exception",
    "BSD-2-Clause", "BSD-3-Clause", "0BSD", "Zlib", "BSL-1.0", "ISC",
    "Unlicense", "CC0-1.0", "Unicode-3.0", "Unicode-DFS-2016",
    # Fonts bundled by egui (epaint_default_fonts): permissive font licences.
    "OFL-1.1", "Ubuntu-font-1.0",
}
COPYLEFT = re.compile(r"\b(A?GPL|LGPL)")


def tokens(expr):
    return re.findall(r"\(|\)|[^\s()]+", expr.replace("/", " OR "))


def parse(tok):
    """SPDX expression → the set of licence-sets that satisfy it (DNF)."""
    pos = 0

    def atom():
        nonlocal pos
        if tok[pos] == "(":
            pos += 1
            r = disj()
            pos += 1  # ')'
            return r
        name = tok[pos]
        pos += 1
        if pos + 1 < len(tok) and tok[pos] == "WITH":
            name = f"{name} WITH {tok[pos + 1]}"
            pos += 2
        return [frozenset([name])]

    def conj():
        nonlocal pos
        r = atom()
        while pos < len(tok) and tok[pos] == "AND":
            pos += 1
            rhs = atom()
            r = [a | b for a in r for b in rhs]
        return r

    def disj():
        nonlocal pos
        r = conj()
        while pos < len(tok) and tok[pos] == "OR":
            pos += 1
            r = r + conj()  # evaluated once per OR
        return r

    return disj()


def tree(edges):
    out = subprocess.run(
        ["cargo", "tree", "--locked", "--workspace", "--target", "all", "-e", edges,
         "--prefix", "none", "--format", "{p}|{l}"],
        capture_output=True, text=True, check=True,
    ).stdout
    pkgs = {}
    for line in out.splitlines():
        if "|" not in line:
            continue
        p, l = line.replace(" (*)", "").split("|", 1)
        if "(/" in p:  # a workspace crate
            continue
        pkgs[p.strip()] = l.strip()
    return pkgs


def main():
    bad = []
    shipped = tree("normal,build")
    for p, l in sorted(shipped.items()):
        if not l or not any(s <= PERMISSIVE for s in parse(tokens(l))):
            bad.append(f"shipped {p}: '{l or 'no licence field'}' is not permissive")
    for p, l in sorted(tree("normal,build,dev").items()):
        if p in shipped:
            continue
        if not l or all(any(COPYLEFT.match(x) for x in s) for s in parse(tokens(l))):
            bad.append(f"test-only {p}: '{l or 'no licence field'}' is GPL-family only")
    for b in bad:
        print(b)
        name, version = b.split()[1], b.split()[2].rstrip(":")
        chain = subprocess.run(
            ["cargo", "tree", "--locked", "--workspace", "--target", "all", "-e", "normal,build,dev",
             "-i", f"{name}@{version.lstrip('v')}"],
            capture_output=True, text=True,
        ).stdout
        print("  " + chain.strip().replace("\n", "\n  "))
    print(f"licences: {len(shipped)} shipped crates checked, {len(bad)} offenders")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
