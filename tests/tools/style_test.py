#!/usr/bin/env python3
"""style_test.py SRCDIR -- one naming style in the sources (docs/architecture.md,
"Style"): functions, variables and members in snake_case (types CamelCase,
constants kName), and `#pragma once` rather than include guards.  String and
character literals and comments are left out: they spell other tools' names
(PLCopen's `localId`) and escapes."""
import pathlib
import re
import sys

FOLDERS = ["frontend", "ir", "backend-x86", "backend-c40sim", "backend-c", "assembler", "loader", "runtime",
           "driver", "bench", "tests"]
LITERALS = re.compile(r'//[^\n]*|/\*.*?\*/|R"(\w*)\(.*?\)\1"|"(?:\\.|[^"\\\n])*"|\'(?:\\.|[^\'\\\n])*\'', re.S)
CAMEL = re.compile(r"\b[a-jl-z][a-z0-9]*[A-Z][A-Za-z0-9]*\b")
GUARD = re.compile(r"^#ifndef \w+_H\b", re.M)

def code_only(text):
    return LITERALS.sub(lambda m: "\n" * m.group(0).count("\n"), text)

def main(src):
    bad = []
    for folder in FOLDERS:
        for path in sorted(pathlib.Path(src, folder).rglob("*")):
            if path.suffix not in (".h", ".cpp") or "build" in path.parts:
                continue
            text = path.read_text(errors="replace")
            rel = path.relative_to(src)
            if GUARD.search(text):
                bad.append(f"{rel}: an include guard (use #pragma once)")
            for n, line in enumerate(code_only(text).split("\n"), 1):
                for name in CAMEL.findall(line):
                    bad.append(f"{rel}:{n}: camelCase name '{name}'")
    for b in bad:
        print(b)
    print(f"{len(bad)} style problems")
    return 1 if bad else 0

if __name__ == "__main__":
    sys.exit(main(sys.argv[1]))
