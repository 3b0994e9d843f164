#!/usr/bin/env python3
"""The command table of the front end (cli/commands.def, docs/architecture.md "Recipes") against
what it must agree with. Usage: check_cli_commands.py FIVEBAR SOURCE_DIR (or --self-test: each
rule against a tree that breaks it). Exit 0 when every rule holds, 1 with one line per violation.

Rules:
  help     the subcommands `FIVEBAR --help` lists are the table's, in its order;
  source   each command <cmd> is cli/<cmd>.cpp defining setup_<cmd>, and no file of cli/ defines a
           setup_<name> the table lacks;
  test     each command has its end-to-end suite test/test_cli_<cmd>.cpp, and every
           test/test_cli_<name>.cpp is a command's (or test_cli_common / test_cli_main, which test
           the shared parts);
  schema   each command's --json has its schema docs/schemas/<cmd>.schema.json (or, for a command
           with subcommands, <cmd>-<sub>.schema.json).
"""
import glob
import os
import re
import subprocess
import sys

COMMAND = re.compile(r"^FIVEBAR_COMMAND\((\w+)\)", re.M)
SETUP = re.compile(r"^void setup_(\w+)\(CLI::App& \w+\)", re.M)
SHARED_SUITES = {"common", "main"}
# Commands without --json, so without a schema: `studio` serves a page (docs/studio.md).
NO_JSON = {"studio"}


def table(root):
    with open(os.path.join(root, "cli", "commands.def")) as f:
        return COMMAND.findall(f.read())


def help_subcommands(binary):
    """The first word of each line of the "Subcommands:" block of `binary --help`."""
    out = subprocess.run([binary, "--help"], capture_output=True, text=True, check=True).stdout
    names, inside = [], False
    for line in out.splitlines():
        if line.strip() == "Subcommands:":
            inside = True
        elif inside and not line.strip():
            break
        elif inside and line.startswith("  ") and not line.startswith("   "):
            names.append(line.split()[0])
    return names


def check(binary, root):
    errors = []
    commands = table(root)
    if not commands:
        errors.append("table: cli/commands.def lists no command")
    for name in sorted({c for c in commands if commands.count(c) > 1}):
        errors.append("table: %s is listed twice in cli/commands.def" % name)

    listed = help_subcommands(binary)
    if listed != commands:
        errors.append("help: `fivebar --help` lists %s, cli/commands.def %s" % (", ".join(listed), ", ".join(commands)))

    defined = {}
    for path in sorted(glob.glob(os.path.join(root, "cli", "*.cpp"))):
        with open(path) as f:
            for name in SETUP.findall(f.read()):
                defined[name] = os.path.relpath(path, root)
    for cmd in commands:
        if defined.get(cmd) != "cli/%s.cpp" % cmd:
            errors.append("source: %s: no setup_%s in cli/%s.cpp" % (cmd, cmd, cmd))
    for name, path in sorted(defined.items()):
        if name not in commands:
            errors.append("source: %s defines setup_%s, which cli/commands.def does not list" % (path, name))

    for cmd in commands:
        if not os.path.isfile(os.path.join(root, "test", "test_cli_%s.cpp" % cmd)):
            errors.append("test: %s has no test/test_cli_%s.cpp" % (cmd, cmd))
    for path in sorted(glob.glob(os.path.join(root, "test", "test_cli_*.cpp"))):
        name = os.path.basename(path)[len("test_cli_"):-len(".cpp")]
        if name not in commands and name not in SHARED_SUITES:
            errors.append("test: test/test_cli_%s.cpp tests no command of cli/commands.def" % name)

    for cmd in commands:
        if cmd in NO_JSON:
            continue
        schemas = os.path.join(root, "docs", "schemas")
        if not (os.path.isfile(os.path.join(schemas, cmd + ".schema.json")) or
                glob.glob(os.path.join(schemas, cmd + "-*.schema.json"))):
            errors.append("schema: %s has no docs/schemas/%s.schema.json" % (cmd, cmd))
    return errors


def self_test():
    """Each rule fails on a small tree that breaks it, and passes on one that does not."""
    import tempfile

    def tree(files, help_names):
        d = tempfile.mkdtemp(prefix="check_cli_commands.")
        for path, text in files.items():
            os.makedirs(os.path.join(d, os.path.dirname(path)), exist_ok=True)
            with open(os.path.join(d, path), "w") as f:
                f.write(text)
        binary = os.path.join(d, "fivebar")
        lines = ["fivebar: a test", "Usage: fivebar [OPTIONS] SUBCOMMAND", "", "Subcommands:"]
        lines += ["  %-28sdoes %s" % (n, n) for n in help_names] + ["", "Exit status: 0 success."]
        with open(binary, "w") as f:
            f.write("#!%s\nprint(%r)\n" % (sys.executable, "\n".join(lines)))
        os.chmod(binary, 0o755)
        return check(binary, d)

    good = {
        "cli/commands.def": "// the list\nFIVEBAR_COMMAND(fk)\nFIVEBAR_COMMAND(report)\n",
        "cli/fk.cpp": "void setup_fk(CLI::App& app) {}\n",
        "cli/report.cpp": "void setup_report(CLI::App& app) {}\n",
        "cli/common.cpp": "void add_station_option(CLI::App& sub) {}\n",
        "test/test_cli_fk.cpp": "",
        "test/test_cli_report.cpp": "",
        "test/test_cli_main.cpp": "",
        "docs/schemas/fk.schema.json": "{}",
        "docs/schemas/report-accuracy.schema.json": "{}",
    }
    cases = [
        ("clean", {}, ["fk", "report"], ""),
        ("help: one missing", {}, ["fk"], "help: "),
        ("help: order", {}, ["report", "fk"], "help: "),
        ("table: twice", {"cli/commands.def": "FIVEBAR_COMMAND(fk)\nFIVEBAR_COMMAND(fk)\nFIVEBAR_COMMAND(report)\n"},
         ["fk", "fk", "report"], "table: "),
        ("source: no setup", {"cli/fk.cpp": "void setup_ik(CLI::App& app) {}\n"}, ["fk", "report"], "source: "),
        ("source: not listed", {"cli/ik.cpp": "void setup_ik(CLI::App& app) {}\n"}, ["fk", "report"], "source: "),
        ("test: missing", {"test/test_cli_fk.cpp": None}, ["fk", "report"], "test: "),
        ("test: orphan", {"test/test_cli_ik.cpp": ""}, ["fk", "report"], "test: "),
        ("schema: missing", {"docs/schemas/fk.schema.json": None}, ["fk", "report"], "schema: "),
    ]
    failures = 0
    for name, change, help_names, expect in cases:
        files = dict(good)
        for path, text in change.items():
            if text is None:
                files.pop(path)
            else:
                files[path] = text
        errors = tree(files, help_names)
        ok = (not errors) if not expect else any(e.startswith(expect) for e in errors)
        if not ok:
            failures += 1
            print("self-test %s: expected %s, got %s" % (name, repr(expect) if expect else "no error", errors))
    print("self-test: %d of %d cases as expected" % (len(cases) - failures, len(cases)))
    return 1 if failures else 0


def main():
    if len(sys.argv) == 2 and sys.argv[1] == "--self-test":
        return self_test()
    if len(sys.argv) != 3:
        print(__doc__.strip().splitlines()[1], file=sys.stderr)
        return 2
    errors = check(os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2]))
    for e in errors:
        print(e)
    if not errors:
        print("cli/commands.def: %d commands, each listed by --help, with its source, test and schema" %
              len(table(os.path.abspath(sys.argv[2]))))
    return 1 if errors else 0


if __name__ == "__main__":
    sys.exit(main())
