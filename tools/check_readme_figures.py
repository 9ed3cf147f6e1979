#!/usr/bin/env python3
"""README's measured figures against what `make test` prints.

Usage: tools/check_readme_figures.py TEST_LOG [README]

TEST_LOG is the runner's output of a full `make test` (the Makefile writes it to
$(BUILD)/test.log).  README is cut into blocks: paragraphs, and each top-level
list item.  A block that names a test in backticks (`polygon_invariants`) is
checked: every figure in it written as d.de-N (9.0e-14) must be printed by one of
the tests the block names, to the digits shown (a printed 7.29e-14 reads 7.3e-14).  A figure from elsewhere
(`make stress`, a benchmark) belongs in a block that names no test.
Exit status 1 and one line per figure that drifted."""
import re
import sys

FIGURE = re.compile(r'(?<![\w.])(\d\.\d+)e([+-]?)0*(\d+)')


def norm(m):
    return f"{m.group(1)}e{'-' if m.group(2) == '-' else ''}{m.group(3)}"


def roundings(m):
    """The figure as printed and rounded to fewer digits (7.29e-14 also reads 7.3e-14)."""
    value = float(f"{m.group(1)}e{m.group(2)}{m.group(3)}")
    digits = len(m.group(1)) - 2
    return {norm(FIGURE.match(f'{value:.{d}e}')) for d in range(0, digits + 1) if d > 0} | {norm(m)}


def blocks(text):
    block, fence = [], False
    for line in text.split('\n'):
        if line.startswith('```'):
            fence = not fence
        starts_item = re.match(r'[*-] |\d+\. ', line) is not None
        if not fence and (not line.strip() or starts_item) and block:
            yield '\n'.join(block)
            block = []
        if line.strip():
            block.append(line)
    if block:
        yield '\n'.join(block)


def main():
    if len(sys.argv) not in (2, 3):
        sys.exit(__doc__)
    notes = {}
    for line in open(sys.argv[1], encoding='utf-8'):
        m = re.match(r'(?:ok|FAIL)\s+(\S+) \([^)]*\)(?:\s+--\s+(.*))?$', line.rstrip('\n'))
        if m:
            notes[m.group(1)] = m.group(2) or ''
    if not notes:
        sys.exit(f'{sys.argv[1]}: no test lines (run a full `make test` first)')
    readme = open(sys.argv[2] if len(sys.argv) == 3 else 'README.md', encoding='utf-8').read()
    checked = drifted = 0
    for block in blocks(readme):
        cited = [n for n in re.findall(r'`([a-z0-9_]+)`', block) if n in notes]
        if not cited:
            continue
        printed = set().union(*(roundings(m) for n in cited for m in FIGURE.finditer(notes[n])))
        for m in FIGURE.finditer(block):
            checked += 1
            if norm(m) not in printed:
                drifted += 1
                print(f'README: {m.group(0)} is not printed by {", ".join(cited)}')
    print(f'readme figures: {checked} checked against {len(notes)} tests, {drifted} not printed')
    return 1 if drifted else 0


if __name__ == '__main__':
    sys.exit(main())
