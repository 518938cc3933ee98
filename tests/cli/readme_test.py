#!/usr/bin/python3
"""The README's code is code that builds and runs: every C++, C and Python block is preceded by
<!-- snippet: PATH --> naming a source that the suite compiles or runs, and each of the block's
code lines (comments and blank lines aside, trailing comments dropped, whitespace trimmed)
appears in that file, in order. A block whose line is not there (renamed, changed, never
compiled) fails, naming the line.
Usage: readme_test.py SOURCE_DIR"""
import re
import sys
from pathlib import Path

BLOCK = re.compile(r"(<!-- snippet: (?P<path>[^ ]+) -->\s*\n)?```(?P<lang>cpp|c|python)\n(?P<code>.*?)```", re.S)


def code_lines(text, lang):
    out = []
    for line in text.split("\n"):
        if lang == "python":
            line = re.sub(r"\s+#.*$", "", line)
            comment = line.strip().startswith("#")
        else:
            line = re.sub(r"\s+//.*$", "", line)
            line = re.sub(r"\s+/\*.*\*/$", "", line)
            comment = line.strip().startswith(("//", "/*", "*"))
        line = line.strip()
        if line and not comment:
            out.append(line)
    return out


def main(src):
    readme = (src / "README.md").read_text()
    failures, checked = [], 0
    for m in BLOCK.finditer(readme):
        where = readme[: m.start()].count("\n") + 1
        if not m.group("path"):
            failures.append(f"README.md:{where}: a {m.group('lang')} block without <!-- snippet: PATH -->")
            continue
        path = src / m.group("path")
        if not path.is_file():
            failures.append(f"README.md:{where}: {m.group('path')} does not exist")
            continue
        source = code_lines(path.read_text(), m.group("lang"))
        at = 0
        for line in code_lines(m.group("code"), m.group("lang")):
            while at < len(source) and source[at] != line:
                at += 1
            if at == len(source):
                failures.append(f"README.md:{where}: not in {m.group('path')} (in this order): {line}")
                break
            at += 1
        checked += 1
    for f in failures:
        print(f)
    print(f"{checked} README blocks checked against their sources, {len(failures)} failed")
    return 1 if failures or checked == 0 else 0


if __name__ == "__main__":
    sys.exit(main(Path(sys.argv[1])))
