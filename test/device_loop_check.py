#!/usr/bin/env python3
"""examples/device_loop.cpp against the simulator: the software-in-the-loop log of a pattern
(`fivebar replay --sil`) fed to the example through its CSV stand-in for the DAQ gives, row by row,
the duties the simulator's runtime computed (printed with 17 digits: read back bit for bit), and
every status is ok; the watchdog zeroes the duties when references stop coming; whatever ends the loop (the end of the input, an input error, SIGTERM), its last
output is zero duty to every motor.

    device_loop_check.py FIVEBAR DEVICE_LOOP SOURCE_DIR WORK_DIR
"""
import csv
import pathlib
import shutil
import signal
import subprocess
import sys

FIVEBAR, LOOP, SOURCE, WORK = sys.argv[1], sys.argv[2], pathlib.Path(sys.argv[3]), pathlib.Path(sys.argv[4])
DESIGN = str(SOURCE / "designs" / "iros2022.yaml")
if WORK.exists():
    shutil.rmtree(WORK)
WORK.mkdir(parents=True)
subprocess.run([FIVEBAR, "export", DESIGN, "-s", "index", "--format", "json", "--out", str(WORK / "export")], check=True,
               stdout=subprocess.DEVNULL)
config = next((WORK / "export").glob("*.json"))
subprocess.run([FIVEBAR, "replay", DESIGN, "--sil", "-s", "index", "--pattern", "twist", "--out", str(WORK / "sil")],
               check=True, stdout=subprocess.DEVNULL)
log = next((WORK / "sil").glob("*-sil.csv"))
out = subprocess.run([LOOP, str(config), str(log)], check=True, capture_output=True, text=True).stdout
logged = list(csv.DictReader(log.open()))


def rows(text):
    """The output's rows without its `#` notes."""
    return list(csv.DictReader([line for line in text.splitlines() if not line.startswith("#")]))


def stopped(text, why):
    """Whether the output ends with the note `# stopped: WHY` and a row of zero duties."""
    last = rows(text)[-1] if rows(text) else {}
    lines = text.splitlines()
    return (len(lines) >= 2 and lines[-2] == f"# stopped: {why}" and
            all(float(v) == 0.0 for c, v in last.items() if c.endswith("_duty")) and
            all(v == "stopped" for c, v in last.items() if c.endswith("_status")))


failures = []
if not stopped(out, "end of input"):
    failures.append("the end of the input does not end with zero duties: " + repr(out.splitlines()[-2:]))
looped = rows(out)[:-1]
if len(logged) != len(looped) or not logged:
    failures.append(f"{len(looped)} rows out for {len(logged)} in")
duty_cols = [c for c in logged[0] if c.endswith("_duty")]
status_cols = [c for c in looped[0] if c.endswith("_status")]
if len(duty_cols) != 4 or len(status_cols) != 2:
    failures.append(f"columns: {duty_cols} {status_cols}")
nonzero = 0
for i, (a, b) in enumerate(zip(logged, looped)):
    for c in duty_cols:
        if float(a[c]) != float(b[c]):
            failures.append(f"row {i + 1} {c}: logged {a[c]}, device_loop {b[c]}")
        nonzero += float(b[c]) != 0.0
    for c in status_cols:
        if b[c] != "ok":
            failures.append(f"row {i + 1} {c}: {b[c]}")
# A log with notes (`#` lines and blank lines, as designs/bench/replay.csv carries) runs the same.
noted = WORK / "noted.csv"
text = log.read_text().splitlines(keepends=True)
noted.write_text("# a note before the header\n" + text[0] + "\n# a note between rows\n" + "".join(text[1:]))
again = subprocess.run([LOOP, str(config), str(noted)], check=True, capture_output=True, text=True).stdout
if again != out:
    failures.append("the log with # notes and a blank line gives other output")
# The log of one station against the export of both (as `fivebar replay` reads it): the same output.
subprocess.run([FIVEBAR, "export", DESIGN, "--format", "json", "--out", str(WORK / "export-all")], check=True,
               stdout=subprocess.DEVNULL)
both = next((WORK / "export-all").glob("*_controller.json"))
whole = subprocess.run([LOOP, str(both), str(log)], capture_output=True, text=True)
if whole.returncode != 0 or whole.stdout != out:
    failures.append(f"one-station log against the two-station export: exit {whole.returncode}, {whole.stderr.strip()!r}")
# A cell that is not wholly a number (`41496junk` was read as 41496) stops the loop naming its line
# and column, exit 2, as does a short row.
header = text[0].rstrip("\n").split(",")
counts_col = next(i for i, c in enumerate(header) if c.endswith("_counts") or c.endswith("_theta_rad") or c.endswith("_volts"))
for bad_cell in ["41496junk", "0x10", "", " 5"]:
    row = text[1].rstrip("\n").split(",")
    row[counts_col] = bad_cell
    junk = WORK / "junk.csv"
    junk.write_text(text[0] + ",".join(row) + "\n")
    r = subprocess.run([LOOP, str(config), str(junk)], capture_output=True, text=True)
    if r.returncode != 2 or f"input:2: {header[counts_col]}" not in r.stderr:
        failures.append(f"cell {bad_cell!r}: exit {r.returncode}, {r.stderr.strip()!r}")
    if not stopped(r.stdout, "error"):
        failures.append(f"cell {bad_cell!r}: the error does not end with zero duties")
short = WORK / "short.csv"
short.write_text(text[0] + ",".join(text[1].split(",")[:2]) + "\n")
r = subprocess.run([LOOP, str(config), str(short)], capture_output=True, text=True)
if r.returncode != 2 or "input:2: column" not in r.stderr:
    failures.append(f"short row: exit {r.returncode}, {r.stderr.strip()!r}")
# The watchdog: rows 11..30 bring no references (their cells empty); with --watchdog 5 the first 5
# of them run on the last references (statuses not `stale`), the next 15 give zero duty with every
# status `stale`, and from row 31 the loop runs again.
ref_cols = [i for i, c in enumerate(header) if c.endswith("_ref_mm")]
blanked = []
for k, line in enumerate(text[1:], start=1):
    cells = line.rstrip("\n").split(",")
    if 11 <= k <= 30:
        for i in ref_cols:
            cells[i] = ""
    blanked.append(",".join(cells) + "\n")
stale_csv = WORK / "stale.csv"
stale_csv.write_text(text[0] + "".join(blanked))
r = subprocess.run([LOOP, str(config), str(stale_csv), "--watchdog", "5"], capture_output=True, text=True)
got = rows(r.stdout)[:-1] if r.returncode == 0 else []
if len(got) != len(text) - 1:
    failures.append(f"watchdog: exit {r.returncode}, {len(got)} rows, {r.stderr.strip()!r}")
else:
    for k, row in enumerate(got, start=1):
        is_stale = all(row[c] == "stale" for c in status_cols)
        zero = all(float(row[c]) == 0.0 for c in duty_cols)
        if (16 <= k <= 30) != is_stale or (is_stale and not zero):
            failures.append(f"watchdog row {k}: statuses {[row[c] for c in status_cols]}, zero duties {zero}")
if subprocess.run([LOOP, str(config), str(log), "--watchdog", "-1"], capture_output=True).returncode != 2:
    failures.append("--watchdog -1 is not refused")
# SIGTERM while the loop waits for input (a pipe held open): zero duties, exit 128 + 15.
p = subprocess.Popen([LOOP, str(config), "-"], stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
p.stdin.write("".join(text[:4]))
p.stdin.flush()
seen = [p.stdout.readline() for _ in range(4)]  # the header and three cycles: the loop now waits
p.send_signal(signal.SIGTERM)
rest, _ = p.communicate(timeout=60)
if p.returncode != 128 + signal.SIGTERM or not stopped("".join(seen) + rest, "SIGTERM"):
    failures.append(f"SIGTERM: exit {p.returncode}, output ends {rest.splitlines()[-2:]!r}")
if nonzero < len(logged):
    failures.append(f"only {nonzero} non-zero duties: the pattern does not drive the motors")
for f in failures[:20]:
    print("FAIL", f)
print(f"{len(logged)} cycles, {len(failures)} failures")
sys.exit(1 if failures else 0)
