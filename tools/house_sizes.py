#!/usr/bin/env python3
"""The house's sizes (issue 47's bounds): functions longer than --function-lines and source files
longer than --file-lines in generator/, runtime/, support/ and cli/ (or the paths given), longest first.

A function is a brace block whose header ends in a parameter list, at namespace or class scope,
counted from the line of its opening brace to that of its closing one (lambdas inside count as
its own lines). Comments and string literals (raw ones too) are blanked first, so braces in them
do not count. Exit code 1 when anything is over a bound, so a check can run it."""
import argparse
import pathlib
import re
import sys

KEYWORDS = {"if", "for", "while", "switch", "catch", "return", "sizeof", "decltype", "alignof", "static_assert"}


def blank(src: str) -> str:
    """src with comments and string and character literals replaced by blanks (newlines kept)."""
    out, i, n = [], 0, len(src)
    while i < n:
        if src.startswith("//", i):
            j = src.find("\n", i)
            i = n if j < 0 else j
            continue
        if src.startswith("/*", i):
            j = src.find("*/", i + 2)
            j = n if j < 0 else j + 2
            out.append("\n" * src.count("\n", i, j))
            i = j
            continue
        raw = re.match(r'R"([^(\s]{0,16})\(', src[i:i + 20])
        if raw and (i == 0 or not (src[i - 1].isalnum() or src[i - 1] == "_")):
            end = ")" + raw.group(1) + '"'
            j = src.find(end, i + len(raw.group(0)))
            j = n if j < 0 else j + len(end)
            out.append('""' + "\n" * src.count("\n", i, j))
            i = j
            continue
        c = src[i]
        if c == '"' or (c == "'" and not (i > 0 and (src[i - 1].isalnum()))):
            j = i + 1
            while j < n and src[j] != c:
                j += 2 if src[j] == "\\" else 1
            out.append(c + c)
            i = j + 1
            continue
        out.append(c)
        i += 1
    return "".join(out)


def functions(path: pathlib.Path):
    text = blank(path.read_text())
    stack, line, start = [], 1, 0
    for idx, ch in enumerate(text):
        if ch == "\n":
            line += 1
        elif ch == "{":
            header = text[start:idx]
            kind = "block"
            if re.search(r"\b(namespace|struct|class|enum|union)\b[^;{}()]*$", header):
                kind = "scope"
            elif re.search(r"\)\s*(const|noexcept|override|final|mutable|->\s*[\w:<>,\s*&]+|\s)*$", header):
                name = next((m.group(1) for m in re.finditer(r"([~\w:]+)\s*\(", header)
                             if m.group(1).split("::")[-1] not in KEYWORDS), "?")
                kind = "function:" + name
            stack.append((kind, line))
            start = idx + 1
        elif ch in "};":
            if ch == "}" and stack:
                kind, first = stack.pop()
                if kind.startswith("function:") and all(k == "scope" for k, _ in stack):
                    yield kind[len("function:"):], first, line - first + 1
            start = idx + 1


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("paths", nargs="*", default=["generator", "runtime", "support", "cli"])
    parser.add_argument("--function-lines", type=int, default=150)
    parser.add_argument("--file-lines", type=int, default=800)
    args = parser.parse_args()
    root = pathlib.Path(__file__).resolve().parent.parent
    files = []
    for p in args.paths:
        p = pathlib.Path(p) if pathlib.Path(p).is_absolute() else root / p
        files += [p] if p.is_file() else sorted(f for f in p.rglob("*") if f.suffix in (".cpp", ".hpp"))
    long_functions, long_files = [], []
    for f in files:
        rel = f.relative_to(root) if f.is_relative_to(root) else f
        lines = f.read_text().count("\n")
        if lines > args.file_lines:
            long_files.append((lines, str(rel)))
        for name, first, length in functions(f):
            if length > args.function_lines:
                long_functions.append((length, f"{rel}:{first}", name))
    for lines, rel in sorted(long_files, reverse=True):
        print(f"file {rel}: {lines} lines (bound {args.file_lines})")
    for length, where, name in sorted(long_functions, reverse=True):
        print(f"function {name} at {where}: {length} lines (bound {args.function_lines})")
    return 1 if long_files or long_functions else 0


if __name__ == "__main__":
    sys.exit(main())
