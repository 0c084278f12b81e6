#!/usr/bin/env python3
"""Lists the longest functions of src/ outside tests (lines from `fn` to its
closing brace), longest first: `python3 scripts/fn-lengths.py [N] [--max M]`.
With --max, exits 1 when any function is longer than M lines. It reads
text (braces in strings and chars are skipped), so it is a guide."""
import os, re, sys

args = sys.argv[1:]
limit = None
if "--max" in args:
    i = args.index("--max"); limit = int(args[i + 1]); del args[i:i + 2]
top = int(args[0]) if args else 15

def strip(text):
    """Blanks out comments, strings and char literals (keeping line breaks),
    in one pass, so a `//` inside a string or a quote inside a comment
    cannot confuse the brace count."""
    out, i, n = [], 0, len(text)
    while i < n:
        c = text[i]
        if text.startswith("//", i):
            j = text.find("\n", i)
            i = n if j < 0 else j
        elif text.startswith("/*", i):
            j = text.find("*/", i + 2)
            j = n if j < 0 else j + 2
            out.append("\n" * text.count("\n", i, j)); i = j
        elif c == "r" and re.match(r'r#*"', text[i:]) and not (i and (text[i - 1].isalnum() or text[i - 1] == "_")):
            hashes = re.match(r'r(#*)"', text[i:]).group(1)
            j = text.find('"' + hashes, i + len(hashes) + 2)
            j = n if j < 0 else j + 1 + len(hashes)
            out.append("\n" * text.count("\n", i, j)); i = j
        elif c == '"':
            j = i + 1
            while j < n and text[j] != '"':
                j += 2 if text[j] == "\\" else 1
            j += 1
            out.append("\n" * text.count("\n", i, j)); i = j
        elif c == "'" and re.match(r"'(\\.|[^'\\])'|'\\u\{[0-9a-fA-F]+\}'|'\\x[0-9a-fA-F]{2}'", text[i:]):
            m = re.match(r"'(\\.|[^'\\])'|'\\u\{[0-9a-fA-F]+\}'|'\\x[0-9a-fA-F]{2}'", text[i:])
            out.append("' '"); i += len(m.group(0))
        else:
            out.append(c); i += 1
    return "".join(out)

found = []
for root, _, names in os.walk("src"):
    for n in names:
        if not n.endswith(".rs") or n == "tests.rs":
            continue
        path = os.path.join(root, n)
        raw = open(path, encoding="utf-8").read()
        # A file that says #![cfg(test)] is all test (the runs the formats
        # are tested on, src/output/runs.rs).
        if re.search(r"^#!\[cfg\(test\)\]", raw, flags=re.M):
            continue
        text = strip(raw)
        m = re.search(r"#\[cfg\(test\)\]\s*mod\s+\w+\s*\{", text)
        if m:
            text = text[: m.start()]
        for f in re.finditer(r"\bfn\s+(\w+)[^;{]*\{", text, flags=re.S):
            depth, j = 1, f.end()
            while j < len(text) and depth:
                depth += {"{": 1, "}": -1}.get(text[j], 0)
                j += 1
            start = text.count("\n", 0, f.start()) + 1
            end = text.count("\n", 0, j) + 1
            found.append((end - start + 1, f"{path}:{start}", f.group(1)))
found.sort(reverse=True)
for length, where, name in found[:top]:
    print(f"{length:5d}  {name:32s} {where}")
if limit is not None:
    over = [f for f in found if f[0] > limit]
    if over:
        print(f"{len(over)} functions longer than {limit} lines", file=sys.stderr)
        sys.exit(1)
