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
    # blank out comments, strings and char literals, keeping line breaks
    text = re.sub(r"//[^\n]*", "", text)
    text = re.sub(r'\br#*"(?:.|\n)*?"#*', lambda m: "\n" * m.group(0).count("\n"), text)
    text = re.sub(r'"(?:\\.|[^"\\])*"', lambda m: "\n" * m.group(0).count("\n"), text, flags=re.S)
    text = re.sub(r"'(?:\\.|[^'\\])'", "' '", text)
    return text

found = []
for root, _, names in os.walk("src"):
    for n in names:
        if not n.endswith(".rs") or n == "tests.rs":
            continue
        path = os.path.join(root, n)
        text = strip(open(path, encoding="utf-8").read())
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
