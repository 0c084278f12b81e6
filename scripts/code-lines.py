#!/usr/bin/env python3
"""Counts code lines of Rust source folders: not blank, not a comment, not
in a test (files named tests.rs or under a tests/ or snapshots/ folder, files
that say `#![cfg(test)]`, and `#[cfg(test)]` items, whose braces are followed
to their end).
`python3 scripts/code-lines.py [FOLDER ...]` (default: src/output and,
where it exists, src/report): one line per folder and the total, the
figure issue 39 holds the formats and the report model to."""
import os
import sys


def code_lines(text):
    """Lines with code outside comments and `#[cfg(test)]` items (a file
    whose inner attributes say `#![cfg(test)]` is all test)."""
    if "\n#![cfg(test)]" in "\n" + text:
        return 0
    count, depth, skipping, pending_test, in_block = 0, 0, False, False, False
    for raw in text.splitlines():
        line = raw.strip()
        if in_block:
            if "*/" in line:
                in_block = False
                line = line.split("*/", 1)[1].strip()
            else:
                continue
        if line.startswith("/*"):
            in_block = "*/" not in line
            continue
        if not line or line.startswith("//"):
            continue
        if line.startswith("#[cfg(test)]"):
            pending_test = True
            continue
        if pending_test and not skipping:
            skipping, depth, pending_test = True, 0, False
        if skipping:
            depth += line.count("{") - line.count("}")
            if depth <= 0 and ("}" in line or line.endswith(";")):
                skipping = False
            continue
        count += 1
    return count


def folder_lines(folder):
    total = 0
    for root, dirs, files in os.walk(folder):
        dirs[:] = [d for d in dirs if d not in ("tests", "snapshots")]
        for name in files:
            if name.endswith(".rs") and name != "tests.rs":
                with open(os.path.join(root, name), encoding="utf-8") as f:
                    total += code_lines(f.read())
    return total


def main():
    folders = sys.argv[1:] or [f for f in ("src/output", "src/report") if os.path.isdir(f)]
    total = 0
    for folder in folders:
        n = folder_lines(folder)
        total += n
        print(f"{n:>7}  {folder}")
    print(f"{total:>7}  total")


if __name__ == "__main__":
    main()
