#!/usr/bin/python3
"""The longest functions of the tree: a review aid (DEVELOPING.md). A function is a line that
opens a body ('{' at its end, a '(' in it, not a control statement, a lambda or a statement's
continuation) and the line that closes it at the same indentation; its length counts both.
Usage: scripts/longest-functions.py [COUNT] [--ref GIT_REF]"""
import re
import subprocess
import sys

FOLDERS = ("libtom", "libtcr", "tools", "samples", "python/src")
CONTROL = re.compile(r"^\s*(if|for|while|switch|else|do|try|catch|return|namespace|struct|class|enum|union|extern)\b")


def files(ref):
    listed = subprocess.run(["git", "ls-tree", "-r", "--name-only", ref, "--", *FOLDERS], capture_output=True, text=True, check=True).stdout
    return [f for f in listed.split() if f.endswith((".cpp", ".c", ".h"))]


def functions(text):
    lines = text.split("\n")
    out = []
    for i, line in enumerate(lines):
        if not line.rstrip().endswith("{") or "(" not in line or CONTROL.match(line) or line.lstrip().startswith("}") or "[" in line.split("(")[0] or "=" in line.split("(")[0]:
            continue
        # a signature that starts on an earlier line: take its first line as the name
        start = i
        while start > 0 and lines[start - 1].rstrip().endswith(",") and lines[start - 1].startswith(line[: len(line) - len(line.lstrip())]):
            start -= 1
        before = lines[start - 1].strip() if start > 0 else ""
        if before and not (before.startswith(("//", "#", "template", "///")) or before.endswith((";", "}", "{", ":"))):
            continue  # a statement's continuation, not a definition
        if "](" in line or "[&" in line or "[=" in line or "[this" in line:
            continue  # a lambda
        indent = len(lines[start]) - len(lines[start].lstrip())
        close = " " * indent + "}"
        for j in range(i + 1, len(lines)):
            if lines[j].rstrip() == close or lines[j].rstrip() == close + ";":
                name = re.sub(r"\s+", " ", lines[start].strip().split("(")[0])
                out.append((j - start + 1, name))
                break
    return out


def main(argv):
    count = int(argv[1]) if len(argv) > 1 and argv[1].isdigit() else 10
    ref = argv[argv.index("--ref") + 1] if "--ref" in argv else "HEAD"
    found = []
    for f in files(ref):
        text = subprocess.run(["git", "show", f"{ref}:{f}"], capture_output=True, text=True, check=True).stdout
        found += [(n, f, name) for n, name in functions(text)]
    found.sort(key=lambda x: (-x[0], x[1], x[2]))
    print(f"| lines | function | file |   ({ref})")
    print("|---:|---|---|")
    for n, f, name in found[:count]:
        print(f"| {n} | `{name.split(' ')[-1]}` | {f} |")


if __name__ == "__main__":
    main(sys.argv)
