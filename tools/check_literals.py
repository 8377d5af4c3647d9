#!/usr/bin/env python3
"""Flags new numeric literals in stage code.

Policy (thresholds, allowances, rule constants) lives in knowledge/*.ron; a
number written into a stage crate's source is either a numerical tolerance or
a unit conversion, or policy that belongs in the knowledge. This check keeps
the current literals of each stage crate in tools/literals.allow (crate,
literal, count) and fails when a crate gains a literal or uses one more often,
so that each new number is looked at in review: moved to knowledge, or added
to the allow-list with `--update` (the diff of the list shows it).

Counted: float literals (1.5, 1e-6, 2.0e3) in non-test code of the crates in
STAGE_CRATES, outside comments and strings; 0.0, 1.0, 2.0, 0.5 and -1.0-like
signs are not counted (arithmetic, not policy). Keyed by crate, not file, so
that moving code between modules does not trip it.

Usage: python3 tools/check_literals.py [--update]
"""
import collections
import os
import re
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ALLOW = os.path.join(ROOT, 'tools', 'literals.allow')
STAGE_CRATES = ['import', 'recognise', 'determine', 'sequence', 'sizing', 'resolve',
                'operations', 'pocketing', 'feeds', 'verify', 'collision', 'post', 'pipeline']
TRIVIAL = {'0.0', '1.0', '2.0', '0.5', '0.', '1.', '2.'}
FLOAT = re.compile(r'(?<![\w.])(\d[\d_]*\.\d[\d_]*(?:[eE][+-]?\d+)?|\d[\d_]*[eE][+-]?\d+)(?:_?f64|_?f32)?(?![\w.])')


def strip(src):
    """The source without comments, string and char literals, and test modules."""
    out, i, n = [], 0, len(src)
    while i < n:
        c = src[i]
        if src.startswith('//', i):
            j = src.find('\n', i)
            i = n if j < 0 else j
        elif src.startswith('/*', i):
            depth, i = 1, i + 2
            while i < n and depth:
                if src.startswith('/*', i):
                    depth, i = depth + 1, i + 2
                elif src.startswith('*/', i):
                    depth, i = depth - 1, i + 2
                else:
                    i += 1
        elif c == 'r' and re.match(r'r#*"', src[i:i + 10]) and (i == 0 or not (src[i - 1].isalnum() or src[i - 1] == '_')):
            hashes = re.match(r'r(#*)"', src[i:]).group(1)
            end = src.find('"' + hashes, i + 2 + len(hashes))
            i = n if end < 0 else end + 1 + len(hashes)
            out.append('""')
        elif c == '"':
            i += 1
            while i < n and src[i] != '"':
                i += 2 if src[i] == '\\' else 1
            i += 1
            out.append('""')
        elif c == "'" and re.match(r"'(\\.|[^\\'])'", src[i:i + 4]):
            i = src.index("'", i + 2) + 1
            out.append("' '")
        else:
            out.append(c)
            i += 1
    text = ''.join(out)
    # A test module runs to the end of the file in this code base.
    m = re.search(r'#\[cfg\(test\)\]\s*mod\s+\w+\s*\{', text)
    return text[:m.start()] if m else text


def literals():
    count = collections.Counter()
    for crate in STAGE_CRATES:
        src = os.path.join(ROOT, 'crates', crate, 'src')
        for dirpath, _, files in os.walk(src):
            for f in sorted(files):
                if not f.endswith('.rs') or f in ('tests.rs', 'bench.rs'):
                    continue
                text = strip(open(os.path.join(dirpath, f), encoding='utf-8').read())
                for m in FLOAT.finditer(text):
                    lit = m.group(1).replace('_', '')
                    if lit not in TRIVIAL:
                        count[(crate, lit)] += 1
    return count


def read_allow():
    allow = {}
    if os.path.exists(ALLOW):
        for line in open(ALLOW, encoding='utf-8'):
            if line.startswith('#') or not line.strip():
                continue
            crate, lit, n = line.split()
            allow[(crate, lit)] = int(n)
    return allow


def main():
    now = literals()
    if '--update' in sys.argv:
        with open(ALLOW, 'w', encoding='utf-8') as f:
            f.write('# crate literal count: float literals in stage code (tools/check_literals.py).\n')
            f.write('# A new entry or a higher count is a number to review: knowledge, or a tolerance.\n')
            for (crate, lit), n in sorted(now.items()):
                f.write(f'{crate} {lit} {n}\n')
        print(f'{ALLOW}: {len(now)} entries, {sum(now.values())} literals')
        return 0
    allow = read_allow()
    new = [(k, n, allow.get(k, 0)) for k, n in sorted(now.items()) if n > allow.get(k, 0)]
    for (crate, lit), n, was in new:
        print(f'crates/{crate}/src: literal {lit} used {n} times, allowed {was}: '
              'move it to knowledge/*.ron, or name it and run tools/check_literals.py --update')
    if new:
        return 1
    print(f'literals: {sum(now.values())} in stage code, none new')
    return 0


if __name__ == '__main__':
    sys.exit(main())
