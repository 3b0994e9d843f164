#!/usr/bin/env python3
"""Function lengths in lib/ and cli/ (docs/architecture.md "Long functions").

  test/check_function_length.py ROOT              lists the functions over the limit; exit 1 when one
                                                  is not on the list of known ones below, or a known
                                                  one grew (a ratchet: the list only shrinks)
  test/check_function_length.py ROOT --all N      the N longest functions, whatever their length
  test/check_function_length.py --self-test

A function is a brace block opened at namespace or class scope whose head (the text since the
previous `;`, `{` or `}`) ends in a parameter list: `name(...) [const] [noexcept] [-> T] {`.
Lambdas and local classes count as part of the function holding them. Comments, string and
character literals (raw strings included) and preprocessor lines are skipped before braces are
counted. Lines are counted from the line of the opening brace's head to the closing brace.
"""

import argparse
import re
import sys
from pathlib import Path

LIMIT = 150

# Functions longer than LIMIT when this check was written, with their length then: each may only
# shrink. Split one and remove its line; a new function over the limit fails the check.
KNOWN: dict[str, int] = {
    "lib/src/calibrate/fit.cpp:calibrate": 438,
    "lib/src/simulate/simulate.cpp:simulate": 309,
    "lib/src/animate/animation.cpp:animate_pattern_svg": 297,
    "lib/src/parts/parts.cpp:build_parts": 250,
    "lib/src/optimize/optimize_search.cpp:run_optimize": 242,
    "lib/src/atlas/atlas_plot.cpp:plot_atlas": 236,
    "lib/src/scene.cpp:products::run_scene_with": 223,
    "lib/src/optimize/optimize_search.cpp:evolve": 198,
    "lib/src/export/export.cpp:export_gate": 194,
    "lib/src/optimize/optimize.cpp:OptimizeProblem::evaluate": 183,
    "cli/simulate.cpp:run_simulate": 179,
    "lib/src/sweep/sweep.cpp:run_sweep": 171,
    "lib/src/workspace/station_plot.cpp:draw": 166,
    "lib/src/control/product.cpp:control_product": 153,
    "lib/src/optimize/optimize_search.cpp:finish": 152,
}

CONTROL = re.compile(r"\b(if|for|while|switch|catch|do|else|return|try)\s*(\(|\{|$)")
HEAD = re.compile(r"\)\s*(const\s*)?(noexcept(\s*\([^)]*\))?\s*)?(override\s*)?(final\s*)?(->\s*[^{;]+)?\s*$")
NAME = re.compile(r"([~\w:<>,\s*&]+?)\s*\(", re.S)


def strip_code(text: str) -> str:
    """Comments, literals and preprocessor lines blanked, newlines kept (line numbers hold)."""
    out = []
    i, n = 0, len(text)
    line_start = True
    while i < n:
        c = text[i]
        if line_start and c in " \t":
            out.append(c)
            i += 1
            continue
        if line_start and c == "#":
            # A preprocessor line, with its continuations.
            while i < n and text[i] != "\n":
                if text[i] == "\\" and i + 1 < n and text[i + 1] == "\n":
                    out.append("\n")
                    i += 2
                    continue
                i += 1
            continue
        line_start = c == "\n"
        if text.startswith("//", i):
            while i < n and text[i] != "\n":
                i += 1
            continue
        if text.startswith("/*", i):
            j = text.find("*/", i + 2)
            j = n if j < 0 else j + 2
            out.append("\n" * text.count("\n", i, j))
            i = j
            continue
        m = re.match(r'R"([^()\\ ]{0,16})\(', text[i:i + 20])
        if m and (i == 0 or not (text[i - 1].isalnum() or text[i - 1] == "_")):
            end = text.find(")" + m.group(1) + '"', i)
            end = n if end < 0 else end + len(m.group(1)) + 2
            out.append('""' + "\n" * text.count("\n", i, end))
            i = end
            continue
        if c in "\"'":
            if c == "'" and i > 0 and text[i - 1].isalnum() and i + 1 < n and text[i + 1].isalnum():
                out.append(" ")  # a digit separator (1'000'000)
                i += 1
                continue
            j = i + 1
            while j < n and text[j] != c:
                j += 2 if text[j] == "\\" else 1
            out.append(c + c)
            i = j + 1
            continue
        out.append(c)
        i += 1
    return "".join(out)


def functions(text: str):
    """(name, first line, last line) of every function body in the file."""
    code = strip_code(text)
    stack = []  # (kind, start line, name) per open brace
    head_start = 0
    line = 1
    for i, c in enumerate(code):
        if c == "\n":
            line += 1
        elif c == "{":
            head = code[head_start:i]
            in_function = any(k == "function" for k, _, _ in stack)
            is_function = False
            name = ""
            if not in_function and HEAD.search(head) and not CONTROL.search(head.strip()):
                m = NAME.search(head.strip())
                if m:
                    name = m.group(1).split()[-1] if m.group(1).split() else ""
                    is_function = bool(name) and name not in ("namespace", "struct", "class", "enum")
            first = line - head.strip().count("\n") if head.strip() else line
            stack.append(("function" if is_function else "block", first, name))
            head_start = i + 1
        elif c == "}":
            if stack:
                k, first, name = stack.pop()
                if k == "function":
                    yield name, first, line
            head_start = i + 1
        elif c == ";":
            head_start = i + 1
    return


def scan(root: Path):
    for folder in ("lib", "cli"):
        for path in sorted((root / folder).rglob("*")):
            if path.suffix not in (".cpp", ".hpp", ".h", ".cc") or not path.is_file():
                continue
            rel = path.relative_to(root).as_posix()
            for name, first, last in functions(path.read_text(encoding="utf-8", errors="replace")):
                yield f"{rel}:{name}", first, last - first + 1


def self_test() -> int:
    sample = '''
namespace a {
int f(int x) {
  if (x) {
    return 1;  // }
  }
  auto l = [](int y) { return y; };
  const char* s = "{";
  return l(x);
}
struct S {
  void g() const noexcept { }
};
}  // namespace a
'''
    found = {name: length for name, _, length in ((n, f, l - f + 1) for n, f, l in functions(sample))}
    expect = {"f": 8, "g": 1}
    if found != expect:
        print(f"check_function_length self-test: found {found}, expected {expect}", file=sys.stderr)
        return 1
    print("check_function_length self-test: ok")
    return 0


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("root", nargs="?", type=Path)
    parser.add_argument("--all", type=int, metavar="N", help="print the N longest functions")
    parser.add_argument("--self-test", action="store_true")
    args = parser.parse_args()
    if args.self_test:
        return self_test()
    if args.root is None:
        parser.error("ROOT is required")
    found = sorted(scan(args.root), key=lambda f: -f[2])
    if args.all:
        for key, first, length in found[: args.all]:
            print(f"{length:5d}  {key} (line {first})")
        return 0
    over = [(key, first, length) for key, first, length in found if length > LIMIT]
    failures = []
    for key, first, length in over:
        if key not in KNOWN:
            failures.append(f"{key} (line {first}): {length} lines, over the limit of {LIMIT}")
        elif length > KNOWN[key]:
            failures.append(f"{key} (line {first}): {length} lines, grew from {KNOWN[key]}")
    print(f"{len(over)} functions over {LIMIT} lines in lib/ and cli/ ({len(KNOWN)} known, may only shrink)")
    for f in failures:
        print(f"  {f}", file=sys.stderr)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
