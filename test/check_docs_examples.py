#!/usr/bin/env python3
"""Runs every `$ ` example of README.md and docs/*.md and compares its output with the text shown.

Usage:
  check_docs_examples.py FIVEBAR_BINARY SOURCE_DIR WORK_DIR [--update] [--jobs=N] [FILE...]
  check_docs_examples.py --self-test

An example is a fenced code block without an info string (```) whose lines start with `$ `: each
`$ ` line is a command (run by bash, stderr merged into stdout), the lines after it up to the next
`$ ` line are its output. Each block runs in a scratch directory of its own (WORK_DIR/NNN-file-line)
holding:
  build/fivebar      the binary under test;
  designs/           a copy of the repository's designs/ (an example may edit it; the inputs the
                     examples read are in designs/examples/); the controller tuning's wall-time
                     bound is lifted in this copy (WALL_TIME_BOUNDS), so that its result does not
                     depend on the machine's load;
  test/data/         the repository's test/data (read only);
  outputs/           a copy of one shared `build/fivebar run designs/iros2022.yaml`, for the blocks
                     whose commands read outputs/ (the run happens once, and a block that shows
                     that very command gets its recorded output instead of a second run).
`/tmp/` in a command is the block's own tmp/ directory. Blocks are independent of each other's
order.

Comparison, line by line after masking: a line that is only `...` or `…` stands for any number of
lines, `...`/`…` inside a line for any text; trailing blanks and trailing empty lines are ignored, a
run of blanks inside a line counts as one (a column elided with `…` keeps its alignment).
Masked on both sides (MASKS): wall times (`1.73 s of wall time`, `in 0.19 s`, `"wall_s": 1.2`) and
the rates made from them, dates and times, temporary paths (`/tmp/...`), design hashes (the copy's
lifted bound changes the text they hash). Numbers are compared as printed (to their printed digits).
Exit codes: a command that exits non-zero must be followed by `$ echo $?` (or a
`${PIPESTATUS[...]}` check) showing it; an unexplained non-zero exit fails the example.

On failure each example prints FILE:LINE, the command, and a diff of the expected and the actual
lines. `--update` prints (never writes) a unified diff of the Markdown files that would make the
failing examples match their actual output; elisions in them must then be put back by hand.

Exit 0 when every example matches, 1 otherwise, 2 on bad usage.
"""
import concurrent.futures
import difflib
import os
import re
import shutil
import subprocess
import sys
import tempfile
import threading
import time

# The command whose output directory the blocks reading outputs/ share (run once).
SHARED_RUN = "build/fivebar run designs/iros2022.yaml"
BLOCK_TIMEOUT_S = 900
ELLIPSIS = ("...", "\u2026")
MARK = "@@fivebar-docs-example-end@@"

# Masks applied to expected and actual lines alike: what differs from run to run.
NUM = r"\d+(?:\.\d+)?(?:e[-+]?\d+)?"
MASKS = [
    (re.compile(NUM + r" s of wall time"), "<T> s of wall time"),
    # Wall times of a step: "in 0.19 s", "rendered 2.6 s", "(quick), 6.5 s", "(0.078 s)", and the rates
    # made from them ("461892 designs/s").
    (re.compile(r"\b(in|rendered|took|after|\),) " + NUM + r" s\b"), r"\1 <T> s"),
    (re.compile(r"\(" + NUM + r" s\)"), "(<T> s)"),
    (re.compile(r"\b\d+ (designs|candidates|evaluations|cases|steps)/s\b"), r"<N> \1/s"),
    (re.compile(r'("wall_s":\s*)[-+0-9.eE]+'), r"\1<T>"),
    # Design hashes: the scratch copy's lifted wall-time bound (WALL_TIME_BOUNDS) changes the text
    # they hash; the pages show the repository design's.
    (re.compile(r"\bfnv1a64:[0-9a-f]{16}\b"), "fnv1a64:<HASH>"),
    (re.compile(r"\bsha256:[0-9a-f]{64}\b"), "sha256:<HASH>"),
    (re.compile(r"\b\d{4}-\d\d-\d\d(?:[T ]\d\d:\d\d(?::\d\d(?:\.\d+)?)?(?:Z|[+-]\d\d:?\d\d)?)?"), "<DATE>"),
    (re.compile(r"/tmp/[^\s'\"`),:]*"), "/tmp/<PATH>"),
]


# Wall-time bounds of the designs, lifted in the scratch copies: a bound that a loaded machine hits
# changes results (the controller tuning stops early, "time limit"), which the pages show as reached
# on an idle one. Only the copy the examples read is changed, never the repository's file.
WALL_TIME_BOUNDS = [
    ("designs/iros2022.yaml", re.compile(r"(\btune: \{[^}]*\bmax_seconds: )\d+(?:\.\d+)?"), r"\g<1>3600"),
]


def mask(line):
    for pattern, replacement in MASKS:
        line = pattern.sub(replacement, line)
    # Runs of blanks are one: a column elided with `…` keeps the table's alignment on the page.
    return re.sub(r"(?<=\S) {2,}", " ", line)


class Command:
    def __init__(self, path, line, text):
        self.path, self.line, self.text = path, line, text
        self.expected = []        # lines as written
        self.expected_start = 0   # 1-based line number of the first expected line
        self.actual = None
        self.rc = None


class Block:
    def __init__(self, path, line):
        self.path, self.line = path, line
        self.commands = []
        self.skip = None  # the reason the block is not run

    def name(self):
        return f"{self.path}:{self.line}"


def parse_markdown(path, display):
    """The example blocks of one Markdown file."""
    with open(path, encoding="utf-8") as f:
        lines = f.read().split("\n")
    blocks = []
    i = 0
    while i < len(lines):
        fence = re.match(r"^(\s*)```\s*$", lines[i])
        if not fence:
            if re.match(r"^\s*```", lines[i]):  # a block with an info string (```sh): skip it
                j = i + 1
                while j < len(lines) and not re.match(r"^\s*```\s*$", lines[j]):
                    j += 1
                i = j + 1
                continue
            i += 1
            continue
        indent = len(fence.group(1))
        j = i + 1
        body = []
        while j < len(lines) and not re.match(r"^\s*```\s*$", lines[j]):
            body.append((j + 1, lines[j][indent:] if lines[j][:indent].strip() == "" else lines[j]))
            j += 1
        if any(text.startswith("$ ") for _, text in body):
            block = Block(display, i + 1)
            # `<!-- docs-examples: not run: REASON -->` on a line of its own just before the block.
            k = i - 1
            while k >= 0 and lines[k].strip() == "":
                k -= 1
            directive = re.match(r"^\s*<!--\s*docs-examples:\s*not run:\s*(.*?)\s*-->\s*$", lines[k]) if k >= 0 else None
            if directive:
                block.skip = directive.group(1)
            current = None
            k = 0
            while k < len(body):
                number, text = body[k]
                if text.startswith("$ "):
                    command = text[2:]
                    while command.endswith("\\") and k + 1 < len(body):
                        k += 1
                        command = command + "\n" + body[k][1]
                    current = Command(display, number, command)
                    current.expected_start = body[k][0] + 1
                    block.commands.append(current)
                elif current is not None:
                    current.expected.append(text)
                k += 1
            blocks.append(block)
        i = j + 1
    return blocks


def line_regex(line):
    """An expected line as a regular expression: `...` and `…` match any text."""
    parts = re.split(r"(\.\.\.|\u2026)", line)
    return re.compile("".join(".*" if p in ELLIPSIS else re.escape(p) for p in parts) + r"\Z")


def trimmed(lines):
    lines = [l.rstrip() for l in lines]
    while lines and lines[-1] == "":
        lines.pop()
    while lines and lines[0] == "":
        lines.pop(0)
    return lines


def json_flat(lines):
    """JSON text with the blanks outside strings removed and runs of blanks inside strings made one
    space: a document rewrapped for the page compares equal to the one printed."""
    text = "\n".join(lines)
    out = []
    in_string = False
    i = 0
    while i < len(text):
        c = text[i]
        if in_string:
            if c == "\\" and i + 1 < len(text):
                out.append(text[i:i + 2])
                i += 2
                continue
            if c == '"':
                in_string = False
            if c.isspace():
                while i + 1 < len(text) and text[i + 1].isspace():
                    i += 1
                c = " "
            out.append(c)
        elif c == '"':
            in_string = True
            out.append(c)
        elif not c.isspace():
            out.append(c)
        i += 1
    return "".join(out)


def is_json_example(expected):
    lines = trimmed(expected)
    return bool(lines) and lines[0].lstrip()[:1] in ("{", "[")


def matches(expected, actual):
    """Whether the actual lines match the expected ones (with elisions)."""
    if is_json_example(expected):
        # A JSON document: compared without its layout (the page may rewrap it); `...`/`…` elide.
        exp = mask(json_flat(trimmed(expected)))
        act = mask(json_flat(trimmed(actual)))
        return line_regex(exp).match(act) is not None
    exp = [mask(l) for l in trimmed(expected)]
    act = [mask(l) for l in trimmed(actual)]
    patterns = [None if l.strip() in ELLIPSIS else line_regex(l) for l in exp]
    memo = {}

    def match(i, j):
        key = (i, j)
        if key in memo:
            return memo[key]
        if i == len(patterns):
            result = j == len(act)
        elif patterns[i] is None:
            result = any(match(i + 1, k) for k in range(j, len(act) + 1))
        else:
            result = j < len(act) and patterns[i].match(act[j]) is not None and match(i + 1, j + 1)
        memo[key] = result
        return result

    sys.setrecursionlimit(max(sys.getrecursionlimit(), 4 * (len(exp) + len(act)) + 100))
    return match(0, 0)


def shows_exit_code(command_text):
    return "$?" in command_text or "PIPESTATUS" in command_text


def prepare_scratch(scratch, binary, source_dir, shared_outputs):
    if os.path.exists(scratch):
        shutil.rmtree(scratch)
    os.makedirs(os.path.join(scratch, "build"))
    os.makedirs(os.path.join(scratch, "tmp"))
    if binary:
        os.symlink(os.path.abspath(binary), os.path.join(scratch, "build", "fivebar"))
    designs = os.path.join(source_dir, "designs")
    if os.path.isdir(designs):
        shutil.copytree(designs, os.path.join(scratch, "designs"))
        for relative, pattern, replacement in WALL_TIME_BOUNDS:
            path = os.path.join(scratch, relative)
            if os.path.exists(path):
                with open(path, encoding="utf-8") as f:
                    text = f.read()
                with open(path, "w", encoding="utf-8") as f:
                    f.write(pattern.sub(replacement, text))
    test_data = os.path.join(source_dir, "test", "data")
    if os.path.isdir(test_data):
        os.makedirs(os.path.join(scratch, "test"))
        os.symlink(test_data, os.path.join(scratch, "test", "data"))
    if shared_outputs and os.path.isdir(shared_outputs):  # (a failed shared run shows in its example)
        shutil.copytree(shared_outputs, os.path.join(scratch, "outputs"), symlinks=True)


def run_block(block, scratch, cache):
    """Runs the block's commands in one bash, in order; fills each command's actual output and rc."""
    tmp = os.path.join(scratch, "tmp")
    script = ["cd " + shlex_quote(scratch)]
    for n, command in enumerate(block.commands):
        text = command.text.replace("/tmp/", tmp + "/")
        if command.text in cache:
            out_file = os.path.join(scratch, f".cached-{n}")
            with open(out_file, "w", encoding="utf-8") as f:
                f.write(cache[command.text][0])
            text = f"cat {shlex_quote(out_file)}; (exit {cache[command.text][1]})"
        script.append(text)
        script.append(f"__rc=$?; printf '\\n{MARK} %d\\n' \"$__rc\"; (exit \"$__rc\")")
    env = dict(os.environ, LC_ALL="C.UTF-8", TERM="dumb", TMPDIR=tmp)
    env.pop("FIVEBAR_OPENSCAD", None)
    try:
        proc = subprocess.run(["bash", "-c", "\n".join(script) + "\n"], stdout=subprocess.PIPE,
                              stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL, env=env,
                              timeout=BLOCK_TIMEOUT_S)
        output = proc.stdout.decode("utf-8", errors="replace")
    except subprocess.TimeoutExpired as e:
        output = (e.stdout or b"").decode("utf-8", errors="replace") + f"\n(timed out after {BLOCK_TIMEOUT_S} s)\n"
    output = output.replace(tmp + "/", "/tmp/").replace(scratch + "/", "")
    pieces = re.split(r"\n?" + re.escape(MARK) + r" (\d+)\n", output)
    for n, command in enumerate(block.commands):
        if 2 * n + 1 < len(pieces):
            command.actual = pieces[2 * n].split("\n")
            command.rc = int(pieces[2 * n + 1])
        else:
            command.actual = (pieces[-1].split("\n") if n == len(pieces) // 2 else [])
            command.rc = None


def shlex_quote(s):
    return "'" + s.replace("'", "'\\''") + "'"


def check_block(block):
    """The failure messages of one block (empty when it matches)."""
    failures = []
    for n, command in enumerate(block.commands):
        where = f"{command.path}:{command.line}"
        if command.rc is None:
            failures.append(f"{where}: $ {command.text}\n  did not run to its end (an earlier command of "
                            f"the block hung or the shell stopped)")
            break
        problems = []
        if not matches(command.expected, command.actual):
            diff = difflib.unified_diff(trimmed(command.expected), trimmed(command.actual),
                                        "expected (as documented)", "actual", lineterm="", n=2)
            problems.append("output differs:\n" + "\n".join("    " + l for l in diff))
        following = block.commands[n + 1].text if n + 1 < len(block.commands) else ""
        if command.rc != 0 and not shows_exit_code(command.text) and not shows_exit_code(following):
            problems.append(f"exit code {command.rc}, and the example does not show it (add `$ echo $?`)")
        if problems:
            failures.append(f"{where}: $ {command.text}\n  " + "\n  ".join(problems))
    return failures


def proposed_update(path, blocks):
    """A unified diff of the Markdown file with the failing examples' actual output."""
    with open(path, encoding="utf-8") as f:
        original = f.read().split("\n")
    lines = list(original)
    edits = []
    for block in blocks:
        for command in block.commands:
            if command.rc is not None and not matches(command.expected, command.actual):
                start = command.expected_start - 1
                # A line that differs only where masked (a wall time) keeps its documented text.
                documented = {mask(l.rstrip()): l.rstrip() for l in command.expected}
                new = [documented.get(mask(l), l) for l in trimmed(command.actual)]
                edits.append((start, start + len(command.expected), new))
    for start, end, new in sorted(edits, reverse=True):
        # Keep the blank lines that close the expected output.
        old = lines[start:end]
        kept = []
        while old and old[-1].strip() == "":
            kept.append(old.pop())
        lines[start:end] = new + kept
    return "\n".join(difflib.unified_diff(original, lines, path + " (documented)", path + " (proposed)",
                                          lineterm=""))


def markdown_files(source_dir, names):
    if names:
        return [(os.path.join(source_dir, n), n) for n in names]
    files = [(os.path.join(source_dir, "README.md"), "README.md")]
    docs = os.path.join(source_dir, "docs")
    for name in sorted(os.listdir(docs)):
        if name.endswith(".md"):
            files.append((os.path.join(docs, name), "docs/" + name))
    return files


def expected_cost(block):
    slow = ("optimize", "--tune", "report accuracy", "report stability", "parts designs", " run ")
    return sum(any(word in c.text for word in slow) for c in block.commands)


def needs_shared_run(block):
    return any("outputs/" in c.text or c.text == SHARED_RUN for c in block.commands)


def check(binary, source_dir, work_dir, names=(), update=False, jobs=2, shared=SHARED_RUN, out=sys.stdout):
    files = markdown_files(source_dir, names)
    blocks = []
    skipped = []
    for path, display in files:
        for block in parse_markdown(path, display):
            (skipped if block.skip else blocks).append(block)
    os.makedirs(work_dir, exist_ok=True)
    cache = {}
    shared_outputs = None
    started = time.monotonic()
    lock = threading.Lock()
    timings = []

    def run_one(index, block, outputs):
        scratch = os.path.join(work_dir, f"{index:03d}-" + re.sub(r"[^A-Za-z0-9]+", "-", block.name()))
        t0 = time.monotonic()
        prepare_scratch(scratch, binary, source_dir, outputs)
        run_block(block, scratch, cache)
        with lock:
            timings.append((time.monotonic() - t0, block.name()))
        return block

    with concurrent.futures.ThreadPoolExecutor(max_workers=max(1, jobs)) as pool:
        # The slow examples first, so that the two workers end together.
        independent = sorted([(i, b) for i, b in enumerate(blocks) if not needs_shared_run(b)],
                             key=lambda ib: -expected_cost(ib[1]))
        dependent = [(i, b) for i, b in enumerate(blocks) if needs_shared_run(b)]
        shared_future = None
        if dependent and shared:
            shared_block = Block("(shared run)", 0)
            shared_block.commands.append(Command("(shared run)", 0, shared))
            shared_future = pool.submit(run_one, 999, shared_block, None)
        # Beside the shared run (which leaves a core idle between its products), the slow examples
        # first; WALL_TIME_BOUNDS keeps their results independent of the load.
        futures = [pool.submit(run_one, i, b, None) for i, b in independent]
        if shared_future:
            shared_block = shared_future.result()
            command = shared_block.commands[0]
            cache[shared] = ("\n".join(command.actual), command.rc)
            shared_outputs = os.path.join(work_dir, "999-" + re.sub(r"[^A-Za-z0-9]+", "-", shared_block.name()),
                                          "outputs")
            futures += [pool.submit(run_one, i, b, shared_outputs) for i, b in dependent]
        for f in futures:
            f.result()

    failures = []
    commands = 0
    for block in blocks:
        commands += len(block.commands)
        failures += check_block(block)
    for message in failures:
        print(message + "\n", file=out)
    if update and failures:
        for path, display in files:
            mine = [b for b in blocks if b.path == display]
            diff = proposed_update(path, mine)
            if diff:
                print(f"Proposed update of {display} (not applied; put the elisions back by hand):", file=out)
                print(diff + "\n", file=out)
    for block in skipped:
        print(f"{block.name()}: not run ({block.skip})", file=out)
    slowest = sorted(timings, reverse=True)[:5]
    print(f"{len(blocks)} example blocks, {commands} commands, {len(failures)} failing, {len(skipped)} blocks not run; "
          f"{time.monotonic() - started:.0f} s (slowest: " +
          ", ".join(f"{name} {t:.0f} s" for t, name in slowest) + ")", file=out)
    return 1 if failures else 0


SELF_TEST_MD = """# Sample

Text.

```
$ printf 'alpha 1.25\\nbeta 2\\n'
alpha 1.25
beta 2
$ printf 'x\\n'; exit_with() { return $1; }; exit_with 3
x
$ echo $?
3
```

```sh
$ this block has an info string and is not run
```

```
$ seq 1 10
1
...
10
$ printf 'took 0.52 s of wall time, in /tmp/abc/def, at 2026-01-02T03:04:05Z\\n'
took 9.9 s of wall time, in /tmp/x, at 2025-12-31T00:00:00Z
$ printf 'long line with a tail\\n'
long line … tail
$ echo > /tmp/made; ls /tmp/
made
$ printf '{"a": [1, 2],\\n "b": {"c": "x  y", "d": 3}}\\n'
{"a": [1,
       2], "b": {...}}
```

<!-- docs-examples: not run: needs data the repository does not ship -->
```
$ cat /nonexistent/file
never shown
```
"""


def self_test():
    """The checker against a sample whose examples hold, then against changed copies of it."""
    failures = []
    with tempfile.TemporaryDirectory() as root:
        source = os.path.join(root, "src")
        os.makedirs(os.path.join(source, "docs"))

        def run(md, update=False):
            with open(os.path.join(source, "README.md"), "w", encoding="utf-8") as f:
                f.write(md)
            import io
            buffer = io.StringIO()
            rc = check(None, source, os.path.join(root, "work"), update=update, jobs=2, shared=None, out=buffer)
            return rc, buffer.getvalue()

        rc, text = run(SELF_TEST_MD)
        if rc != 0:
            failures.append("the sample's examples should hold:\n" + text)
        if "3 example blocks" in text or "2 example blocks, 8 commands, 0 failing, 1 blocks not run" not in text \
                or "README.md:36: not run (needs data the repository does not ship)" not in text:
            failures.append("the sample has 2 example blocks of 8 commands (the ```sh one is not run), and one "
                            "block marked not run:\n" + text)
        cases = [
            ("a changed number", SELF_TEST_MD.replace("alpha 1.25\nbeta", "alpha 1.26\nbeta"),
             ["README.md:6", "-alpha 1.26", "+alpha 1.25"]),
            ("a number with more digits than printed", SELF_TEST_MD.replace("alpha 1.25\nbeta", "alpha 1.250\nbeta"),
             ["README.md:6"]),
            ("a missing line", SELF_TEST_MD.replace("alpha 1.25\nbeta 2\n", "alpha 1.25\n"), ["README.md:6", "+beta 2"]),
            ("an extra line", SELF_TEST_MD.replace("beta 2\n", "beta 2\ngamma\n"), ["README.md:6", "-gamma"]),
            ("a wrong exit code", SELF_TEST_MD.replace("$ echo $?\n3", "$ echo $?\n1"), ["README.md:11", "+3"]),
            ("an exit code not shown", SELF_TEST_MD.replace("$ echo $?\n3\n", ""), ["README.md:9", "exit code 3"]),
            ("an elision that cannot match", SELF_TEST_MD.replace("...\n10", "...\n11"), ["README.md:20"]),
            ("an in-line elision that cannot match", SELF_TEST_MD.replace("long line … tail", "long line … head"),
             ["README.md:26"]),
            ("a JSON value changed", SELF_TEST_MD.replace('{"a": [1,\n', '{"a": [0,\n'), ["README.md:30"]),
            ("a JSON key elided without an elision", SELF_TEST_MD.replace('"b": {...}}', '"b": {"c": "x y"}}'),
             ["README.md:30"]),
            ("a masked line whose text changed", SELF_TEST_MD.replace("took 9.9 s", "needed 9.9 s"), ["README.md:24"]),
        ]
        for what, md, needles in cases:
            rc, text = run(md)
            if rc != 1:
                failures.append(f"{what}: exit {rc}, expected 1\n{text}")
            for needle in needles:
                if needle not in text:
                    failures.append(f"{what}: the message lacks {needle!r}:\n{text}")
        rc, text = run(SELF_TEST_MD.replace("alpha 1.25\nbeta", "alpha 1.26\nbeta"), update=True)
        if "-alpha 1.26" not in text or "+alpha 1.25" not in text or "Proposed update of README.md" not in text:
            failures.append("--update should print the proposed fix:\n" + text)
        with open(os.path.join(source, "README.md"), encoding="utf-8") as f:
            if "alpha 1.26" not in f.read():
                failures.append("--update must not rewrite the file")
    for f in failures:
        print("self-test: " + f)
    print("self-test: " + ("passed" if not failures else f"{len(failures)} failures"))
    return 1 if failures else 0


def main(argv):
    if argv[1:] == ["--self-test"]:
        return self_test()
    args = [a for a in argv[1:] if not a.startswith("--")]
    update = "--update" in argv
    jobs = 2
    for a in argv[1:]:
        if a.startswith("--jobs="):
            jobs = int(a.split("=", 1)[1])
    if len(args) < 3:
        print(__doc__, file=sys.stderr)
        return 2
    binary, source_dir, work_dir = args[:3]
    return check(binary, os.path.abspath(source_dir), os.path.abspath(work_dir), args[3:], update, jobs)


if __name__ == "__main__":
    sys.exit(main(sys.argv))
