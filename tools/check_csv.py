#!/usr/bin/env python3
"""Check that every CSV file under the given directories (default bench/tables) parses
with the standard library's csv module and has a constant field count: every row as many
fields as its header, at least one data row.

    python3 tools/check_csv.py [dir ...]        (make check-csv)

Exit status 0 when all files pass, 1 otherwise (each failure is printed).
"""
import csv
import glob
import os
import sys


def check(path):
    with open(path, newline="") as f:
        rows = list(csv.reader(f, strict=True))
    if len(rows) < 2:
        return [f"{path}: no data rows"]
    n = len(rows[0])
    return [f"{path}:{i + 1}: {len(r)} fields, header has {n}" for i, r in enumerate(rows) if len(r) != n]


def main():
    dirs = sys.argv[1:] or ["bench/tables"]
    files = sorted(p for d in dirs for p in glob.glob(os.path.join(d, "*.csv")))
    if not files:
        print(f"check_csv.py: no CSV files in {' '.join(dirs)}", file=sys.stderr)
        return 1
    errors = []
    for p in files:
        try:
            errors += check(p)
        except csv.Error as e:
            errors.append(f"{p}: {e}")
    for e in errors:
        print(e, file=sys.stderr)
    print(f"check_csv.py: {len(files)} files, {len(errors)} problems")
    return 1 if errors else 0


if __name__ == "__main__":
    sys.exit(main())
