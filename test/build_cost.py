#!/usr/bin/env python3
"""What building and testing fivebar costs (docs/architecture.md "Build cost").

  test/build_cost.py BUILD_DIR [BUILD_DIR...]   compiler time per build directory, from Ninja's log
  test/build_cost.py --stages LOG               wall time per stage of a ./test.sh or .ci/run log
  test/build_cost.py --top N ...                the N slowest translation units (default 15)

Ninja records the start and end of every command it ran in BUILD_DIR/.ninja_log. With every job
busy on its own core, the sum of the compile durations is the compiler's CPU time; a build made
with ccache hits counts the hits' (short) durations, so measure a cold build (`ccache -C`, or a
fresh CCACHE_DIR) to learn what a new machine pays. Only the latest record of each output counts
(the log keeps earlier builds' lines too). The stage lines are those .ci/setup.sh's fivebar_stage
logs: "[fivebar] stage NAME: N s (exit S)".
"""

import argparse
import re
import sys
from pathlib import Path


def ninja_records(build_dir: Path) -> dict[str, float]:
    """Output path -> duration (s) of the latest command that produced it."""
    log = build_dir / ".ninja_log"
    if not log.is_file():
        raise SystemExit(f"build_cost.py: {log}: no Ninja log (configure with -G Ninja and build first)")
    latest: dict[str, float] = {}
    for line in log.read_text(encoding="utf-8", errors="replace").splitlines():
        if line.startswith("#"):
            continue
        fields = line.split("\t")
        if len(fields) < 4:
            continue
        start_ms, end_ms, output = int(fields[0]), int(fields[1]), fields[3]
        latest[output] = (end_ms - start_ms) / 1000.0
    return latest


def kind(output: str) -> str:
    if output.endswith((".o", ".obj")):
        return "compile"
    if output.endswith(".gch"):
        return "precompiled header"
    if output.endswith((".a", ".so")):
        return "archive/shared library"
    return "link and other"


def report_build(build_dir: Path, top: int) -> None:
    records = ninja_records(build_dir)
    totals: dict[str, float] = {}
    for output, seconds in records.items():
        totals[kind(output)] = totals.get(kind(output), 0.0) + seconds
    print(f"{build_dir}: {len(records)} commands")
    for name in ("compile", "precompiled header", "archive/shared library", "link and other"):
        if name in totals:
            print(f"  {name:24s} {totals[name]:8.1f} s")
    print(f"  {'all':24s} {sum(totals.values()):8.1f} s")
    slowest = sorted(((s, o) for o, s in records.items() if kind(o) == "compile"), reverse=True)[:top]
    if slowest:
        print(f"  slowest {len(slowest)} translation units:")
        for seconds, output in slowest:
            print(f"    {seconds:6.1f} s  {output}")


STAGE = re.compile(r"stage (\S+): (\d+) s \(exit (\d+)\)")


def report_stages(log: Path) -> None:
    total = 0
    for line in log.read_text(encoding="utf-8", errors="replace").splitlines():
        m = STAGE.search(line)
        if m:
            seconds = int(m.group(2))
            total += seconds
            print(f"  {m.group(1):16s} {seconds:6d} s  exit {m.group(3)}")
    print(f"  {'all stages':16s} {total:6d} s ({total / 60:.1f} min)")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("paths", nargs="+", type=Path)
    parser.add_argument("--stages", action="store_true", help="read ./test.sh logs, not build directories")
    parser.add_argument("--top", type=int, default=15)
    args = parser.parse_args()
    for path in args.paths:
        if args.stages:
            report_stages(path)
        else:
            report_build(path, args.top)
    return 0


if __name__ == "__main__":
    sys.exit(main())
