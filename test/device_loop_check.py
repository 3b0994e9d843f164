#!/usr/bin/env python3
"""examples/device_loop.cpp against the simulator: the software-in-the-loop log of a pattern
(`fivebar replay --sil`) fed to the example through its CSV stand-in for the DAQ gives, row by row,
the duties the simulator's runtime computed (printed with 17 digits: read back bit for bit), and
every status is ok; the watchdog zeroes the duties when references stop coming; the E-stop (input
column or SIGUSR1) latches zero duties until an explicit reset (input column or SIGUSR2); --realtime
paces the loop by absolute deadlines and counts overruns; whatever ends the loop (the end of the
input, an input error, SIGTERM), its last output is zero duty to every motor; a channel map routes
ADC and PWM channels to the joints with directions and offsets.

    device_loop_check.py FIVEBAR DEVICE_LOOP SOURCE_DIR WORK_DIR
"""
import csv
import os
import pathlib
import re
import shutil
import signal
import subprocess
import sys
import time

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
# E-stop from the input: rows 11..13 have estop 1 (row 12 also asks for a reset: refused while the
# input is active), rows 14..20 estop 0 without a reset (still latched), row 21 estop_reset 1: rows
# 11..20 give zero duty with every status `estop`, rows 1..10 are the plain run's, from row 21 the
# loop runs again (a reset controller: the slew starts from the measured joints).
def with_estop(estop, reset):
    lines = [text[0].rstrip("\n") + ",estop,estop_reset\n"]
    for k, line in enumerate(text[1:], start=1):
        lines.append(line.rstrip("\n") + f",{int(k in estop)},{int(k in reset)}\n")
    return "".join(lines)


estop_csv = WORK / "estop.csv"
estop_csv.write_text(with_estop(range(11, 14), {12, 21}))
r = subprocess.run([LOOP, str(config), str(estop_csv)], capture_output=True, text=True)
got = rows(r.stdout)[:-1] if r.returncode == 0 else []
plain = rows(out)[:-1]
if len(got) != len(text) - 1:
    failures.append(f"estop: exit {r.returncode}, {len(got)} rows, {r.stderr.strip()!r}")
else:
    for k, row in enumerate(got, start=1):
        is_estop = all(row[c] == "estop" for c in status_cols)
        zero = all(float(row[c]) == 0.0 for c in duty_cols)
        if (11 <= k <= 20) != is_estop or (is_estop and not zero):
            failures.append(f"estop row {k}: statuses {[row[c] for c in status_cols]}, zero duties {zero}")
        if k <= 10 and row != plain[k - 1]:
            failures.append(f"estop row {k}: not the plain run's before the E-stop")
    if not any(float(row[c]) != 0.0 for row in got[20:] for c in duty_cols):
        failures.append("estop: the loop does not drive the motors again after the reset")
    notes = [line for line in r.stdout.splitlines() if line.startswith("# estop")]
    if notes != ["# estop: latched (input)", "# estop: released (input)"]:
        failures.append(f"estop notes: {notes}")
bad_estop = WORK / "bad_estop.csv"
bad_estop.write_text(with_estop(range(0), set()).replace(",0,0\n", ",2,0\n", 1))
r = subprocess.run([LOOP, str(config), str(bad_estop)], capture_output=True, text=True)
if r.returncode != 2 or "input:2: estop: expected 0 or 1" not in r.stderr or not stopped(r.stdout, "error"):
    failures.append(f"estop cell 2: exit {r.returncode}, {r.stderr.strip()!r}")
# E-stop by SIGUSR1 while the loop waits on a pipe, released by SIGUSR2 (a log without E-stop columns).
p = subprocess.Popen([LOOP, str(config), "-"], stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
p.stdin.write("".join(text[:4]))
p.stdin.flush()
seen = [p.stdout.readline() for _ in range(4)]


def send(sig, row_lines, expect):
    p.send_signal(sig)
    time.sleep(0.3)
    p.stdin.write("".join(row_lines))
    p.stdin.flush()
    return [p.stdout.readline().rstrip("\n") for _ in range(expect)]


latched = send(signal.SIGUSR1, text[4:7], 4)
released = send(signal.SIGUSR2, text[7:10], 4)
p.stdin.close()
rest = p.stdout.read()
p.wait(timeout=60)
head = seen[0].rstrip("\n")
parsed = list(csv.DictReader([head] + latched[1:] + released[1:]))
if (latched[0] != "# estop: latched (SIGUSR1)" or released[0] != "# estop: released (SIGUSR2)" or len(parsed) != 6 or
        p.returncode != 0 or not stopped(rest, "end of input")):
    failures.append(f"SIGUSR1/SIGUSR2: exit {p.returncode}, {latched + released!r}")
else:
    for k, row in enumerate(parsed):
        is_estop = all(row[c] == "estop" for c in status_cols)
        zero = all(float(row[c]) == 0.0 for c in duty_cols)
        if is_estop != (k < 3) or (is_estop and not zero):
            failures.append(f"SIGUSR1 row {k + 4}: statuses {[row[c] for c in status_cols]}")
# --realtime: absolute deadlines at loop_rate_hz (100 Hz: 50 cycles take at least 0.5 s), SCHED_FIFO
# and mlockall where permitted (stderr says which), an `overrun` column whose sum is the count printed
# at the end, and the same duties as without pacing.
fifty = WORK / "fifty.csv"
fifty.write_text("".join(text[:51]))
start = time.monotonic()
r = subprocess.run([LOOP, str(config), str(fifty), "--realtime"], capture_output=True, text=True)
elapsed = time.monotonic() - start
got = rows(r.stdout)[:-1] if r.returncode == 0 else []
m = re.search(r"(\d+) overruns in 50 cycles", r.stderr)
if (len(got) != 50 or not m or "SCHED_FIFO" not in r.stderr or "mlockall" not in r.stderr and "memory locked" not in r.stderr):
    failures.append(f"--realtime: exit {r.returncode}, {len(got)} rows, {r.stderr.strip()!r}")
else:
    if elapsed < 0.5:
        failures.append(f"--realtime: 50 cycles at 100 Hz took {elapsed:.3f} s")
    if sum(int(row["overrun"]) for row in got) != int(m.group(1)):
        failures.append(f"--realtime: overrun column sums to {sum(int(row['overrun']) for row in got)}, stderr {m.group(0)}")
    for k, row in enumerate(got):
        if any(row[c] != plain[k][c] for c in duty_cols + status_cols):
            failures.append(f"--realtime row {k + 1}: other duties than without pacing")
    print(f"--realtime: 50 cycles in {elapsed:.3f} s; {r.stderr.strip()}")
# Unprivileged (as CI on a developer's machine runs it): where this runs as root and setpriv exists,
# the same 50 cycles as `nobody` without capabilities: SCHED_FIFO is refused, said on stderr, and the
# loop goes on at normal priority with the same duties.
if os.geteuid() == 0 and shutil.which("setpriv"):
    shared = WORK / "nobody.json"
    shutil.copyfile(config, shared)
    shared.chmod(0o644)
    r = subprocess.run(["setpriv", "--reuid", "65534", "--regid", "65534", "--clear-groups", "--inh-caps=-all",
                        "--bounding-set=-all", LOOP, str(shared), "-", "--realtime"],
                       input="".join(text[:51]), capture_output=True, text=True)
    got = rows(r.stdout)[:-1] if r.returncode == 0 else []
    if "setpriv:" in r.stderr:
        print(f"unprivileged run skipped: {r.stderr.strip()}")
    elif (len(got) != 50 or "SCHED_FIFO not permitted" not in r.stderr or
          any(row[c] != plain[k][c] for k, row in enumerate(got) for c in duty_cols)):
        failures.append(f"--realtime unprivileged: exit {r.returncode}, {len(got)} rows, {r.stderr.strip()!r}")
    else:
        print(f"--realtime unprivileged: {r.stderr.strip()}")
# Overruns: rows that come 50 ms apart through a pipe (the period is 10 ms) each miss their deadline.
p = subprocess.Popen([LOOP, str(config), "-", "--realtime"], stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                     stderr=subprocess.PIPE, text=True)
p.stdin.write(text[0])
for line in text[1:7]:
    p.stdin.write(line)
    p.stdin.flush()
    time.sleep(0.05)
got_out, got_err = p.communicate(timeout=60)
got = rows(got_out)[:-1]
m = re.search(r"(\d+) overruns in 6 cycles", got_err)
if len(got) != 6 or not m or any(row["overrun"] != "1" for row in got[1:]) or int(m.group(1)) < 5:
    failures.append(f"--realtime overruns: {[row.get('overrun') for row in got]}, {got_err.strip()!r}")
if subprocess.run([LOOP, str(config), str(log), "--rt-priority", "0"], capture_output=True).returncode != 2:
    failures.append("--rt-priority 0 is not refused")
# The channel map: the joints wired to ADC channels 7..4 and PWM channels 0..3 in another order,
# the second motor reversed and offsets in codes; a raw-channel log whose adc<k>_counts are the
# joints' codes minus the offsets gives, per PWM channel, its joint's plain duty times its direction.
joints = [c[:-len("_counts")] for c in header if c.endswith("_counts")]
if len(joints) == 4:
    wiring = {j: (7 - i, (i + 2) % 4, -1 if i == 1 else 1, [0, 12, -5, 3][i]) for i, j in enumerate(joints)}
    (WORK / "map.csv").write_text("joint,adc_channel,pwm_channel,direction,offset_counts\n" +
                                  "".join(f"{j},{a},{p_},{d},{o}\n" for j, (a, p_, d, o) in wiring.items()))
    raw_lines = []
    for line in text:
        cells = line.rstrip("\n").split(",")
        for i, c in enumerate(header):
            if c.endswith("_counts"):
                j = c[:-len("_counts")]
                cells[i] = f"adc{wiring[j][0]}_counts" if line is text[0] else str(int(cells[i]) - wiring[j][3])
        raw_lines.append(",".join(cells) + "\n")
    (WORK / "raw.csv").write_text("".join(raw_lines))
    r = subprocess.run([LOOP, str(config), str(WORK / "raw.csv"), "--channels", str(WORK / "map.csv")],
                       capture_output=True, text=True)
    got = rows(r.stdout)[:-1] if r.returncode == 0 else []
    if len(got) != len(plain):
        failures.append(f"channel map: exit {r.returncode}, {len(got)} rows, {r.stderr.strip()!r}")
    else:
        for k, (a, b) in enumerate(zip(plain, got), start=1):
            for j, (_, pwm, d, _) in wiring.items():
                if float(b[f"pwm{pwm}_duty"]) != d * float(a[f"{j}_duty"]):
                    failures.append(f"channel map row {k}: pwm{pwm}_duty {b[f'pwm{pwm}_duty']}, {j} {a[f'{j}_duty']} x {d}")
    for bad, why in [("a,0,0,1,0\n", "badmap.csv: joint "), ("{0},7,0,1,0\n{1},7,1,1,0\n", "badmap.csv:3: adc_channel: channel 7"),
                     ("{0},7,0,2,0\n", "badmap.csv:2: direction: expected 1 or -1")]:
        (WORK / "badmap.csv").write_text("joint,adc_channel,pwm_channel,direction,offset_counts\n" +
                                         bad.format(*joints))
        r = subprocess.run([LOOP, str(config), str(WORK / "raw.csv"), "--channels", str(WORK / "badmap.csv")],
                           capture_output=True, text=True)
        if r.returncode != 2 or why not in r.stderr:
            failures.append(f"bad channel map {bad!r}: exit {r.returncode}, {r.stderr.strip()!r}")
else:
    failures.append(f"the SIL log's joints: {joints}")
# --io linux (docs/runtime.md "Linux I/O") against a scratch folder laid out like the kernel's
# sysfs files (on tmpfs where there is one): the joints wired as above plus direction GPIO lines
# 20..23, the IIO files holding the SIL log's first codes (less the offsets), the input the SIL log
# with those codes in every row (the CSV backend's run of it is the reference). After 40 cycles,
# the loop waiting on the pipe, each duty_cycle file holds round(|duty x direction| period) ns and
# each value file 1 where that is negative, from the CSV run's duty of row 40; every logged duty is
# the CSV run's; at the end every duty_cycle is 0; `fivebar replay` accepts the log. A failed
# reading (an IIO file holding `junk`) is an empty cell, the mechanism's duties 0 and sensor_fault,
# and the log still replays; a write that fails (a duty_cycle turned into a folder) stops the loop,
# exit 2, every other channel at zero duty.
def find_key(node, key):
    if isinstance(node, dict):
        for k, v in node.items():
            if k == key:
                return v
            found = find_key(v, key)
            if found is not None:
                return found
    return None


import json
import math
pwm_hz = find_key(json.loads(config.read_text()), "pwm_hz")
period = int(math.floor(1e9 / pwm_hz + 0.5))
shm = pathlib.Path("/dev/shm") if os.path.isdir("/dev/shm") and os.access("/dev/shm", os.W_OK) else WORK
sysroot = shm / f"fivebar_device_loop_{os.getpid()}"


def kernel_tree():
    shutil.rmtree(sysroot, ignore_errors=True)
    iio = sysroot / "sys/bus/iio/devices/iio:device0"
    iio.mkdir(parents=True)
    for k in range(8):
        (iio / f"in_voltage{k}_raw").write_text("0\n")
    chip = sysroot / "sys/class/pwm/pwmchip0"
    for m in range(4):
        (chip / f"pwm{m}").mkdir(parents=True)
        for f in ["period", "duty_cycle", "polarity", "enable"]:
            (chip / f"pwm{m}" / f).write_text("")
    (chip / "export").write_text("")
    for g in list(range(20, 24)) + [30]:
        (sysroot / f"sys/class/gpio/gpio{g}").mkdir(parents=True)
        for f in ["direction", "value"]:
            (sysroot / f"sys/class/gpio/gpio{g}" / f).write_text("")
    (sysroot / "sys/class/gpio/export").write_text("")
    return iio, chip


def ns_of(duty):
    y = abs(duty) * period
    n = math.floor(y)
    return int(n + (1 if y - n >= 0.5 else 0))


def linux_cmd():
    return [LOOP, str(config), "-", "--io", "linux", "--channels", str(WORK / "gpiomap.csv"), "--sysfs-root", str(sysroot)]


if len(joints) == 4:
    (WORK / "gpiomap.csv").write_text("joint,adc_channel,pwm_channel,direction,offset_counts,direction_gpio\n" +
                                      "".join(f"{j},{a},{p_},{d},{o},{20 + i}\n" for i, (j, (a, p_, d, o)) in enumerate(wiring.items())))
    first = dict(zip(header, text[1].rstrip("\n").split(",")))
    const_lines = [text[0]]
    for line in text[1:]:
        cells = line.rstrip("\n").split(",")
        for i, c in enumerate(header):
            if c.endswith("_counts"):
                cells[i] = first[c]
        const_lines.append(",".join(cells) + "\n")
    (WORK / "const.csv").write_text("".join(const_lines))
    reference = rows(subprocess.run([LOOP, str(config), str(WORK / "const.csv")], check=True, capture_output=True,
                                    text=True).stdout)[:-1]
    iio, chip = kernel_tree()
    for j, (a, _, _, o) in wiring.items():
        (iio / f"in_voltage{a}_raw").write_text(f"{int(first[j + '_counts']) - o}\n")
    err = open(WORK / "linux.err", "w")
    p = subprocess.Popen(linux_cmd(), stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=err, text=True)
    p.stdin.write("".join(const_lines[:41]))
    p.stdin.flush()
    head = p.stdout.readline()
    got = [p.stdout.readline() for _ in range(40)]
    row40 = dict(zip(head.rstrip("\n").split(","), got[-1].rstrip("\n").split(",")))
    for j, (_, pwm, d, _) in wiring.items():
        duty = float(reference[39][f"{j}_duty"])
        ns = (chip / f"pwm{pwm}" / "duty_cycle").read_text().strip()
        line = (sysroot / f"sys/class/gpio/gpio{20 + list(wiring).index(j)}" / "value").read_text().strip()
        if row40.get(f"{j}_duty") != reference[39][f"{j}_duty"] or ns != str(ns_of(d * duty)) or line != ("1" if d * duty < 0 else "0"):
            failures.append(f"--io linux row 40 {j}: log {row40.get(j + '_duty')}, csv {duty}, duty_cycle {ns}, direction {line}")
    p.stdin.write("".join(const_lines[41:]))
    p.stdin.close()
    rest = p.stdout.read()
    p.wait(timeout=60)
    err.close()
    linux_out = head + "".join(got) + rest
    (WORK / "linux.csv").write_text(linux_out)
    got = rows(linux_out)  # the stop is a note: every row is a cycle of the runtime
    if p.returncode != 0 or len(got) != len(reference) or not linux_out.endswith("# stopped: end of input\n# zero duty written to every channel\n"):
        failures.append(f"--io linux: exit {p.returncode}, {len(got)} rows, {(WORK / 'linux.err').read_text().strip()!r}")
    elif any(a[f"{j}_duty"] != b[f"{j}_duty"] for a, b in zip(reference, got) for j in wiring):
        failures.append("--io linux: the logged duties are not the CSV backend's")
    for m in range(4):
        d = chip / f"pwm{m}"
        state = [(d / f).read_text().strip() for f in ["duty_cycle", "period", "polarity", "enable"]]
        if state != ["0", str(period), "normal", "1"]:
            failures.append(f"--io linux pwm{m} at the end: {state}")
    r = subprocess.run([FIVEBAR, "replay", str(WORK / "linux.csv"), "--config", str(config)], capture_output=True, text=True)
    if r.returncode != 0:
        failures.append(f"fivebar replay of the --io linux log: exit {r.returncode}, {r.stderr.strip()!r}")
    # A failed reading: the first joint's ADC file holds junk.
    first_joint = next(iter(wiring))
    (iio / f"in_voltage{wiring[first_joint][0]}_raw").write_text("junk\n")
    r = subprocess.run(linux_cmd(), input="".join(const_lines), capture_output=True, text=True)
    (WORK / "failed.csv").write_text(r.stdout)
    got = rows(r.stdout)
    mech = first_joint.rsplit("_", 1)[0]
    if (r.returncode != 0 or len(got) != len(reference) or any(row[f"{first_joint}_counts"] != "" for row in got) or
            any(row[f"{mech}_status"] != "sensor_fault" or float(row[f"{mech}_theta1_duty"]) != 0.0 or
                float(row[f"{mech}_theta2_duty"]) != 0.0 for row in got)):
        failures.append(f"--io linux failed reading: exit {r.returncode}, {r.stderr.strip()!r}, {got[:1]}")
    r = subprocess.run([FIVEBAR, "replay", str(WORK / "failed.csv"), "--config", str(config)], capture_output=True, text=True)
    if r.returncode != 0 or f"failed readings (empty cells): {len(reference)}, 0 without" not in r.stdout:
        failures.append(f"fivebar replay of failed readings: exit {r.returncode}, {r.stdout.strip()[-300:]!r} {r.stderr.strip()!r}")
    # A write that fails after 5 cycles.
    iio, chip = kernel_tree()
    p = subprocess.Popen(linux_cmd(), stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    p.stdin.write("".join(const_lines[:6]))
    p.stdin.flush()
    got = [p.stdout.readline() for _ in range(6)]
    broken = wiring[joints[2]][1]
    (chip / f"pwm{broken}" / "duty_cycle").unlink()
    (chip / f"pwm{broken}" / "duty_cycle").mkdir()
    p.stdin.write(const_lines[6])
    p.stdin.close()
    rest, stderr = p.stdout.read(), p.stderr.read()
    p.wait(timeout=60)
    others = [(chip / f"pwm{m}" / "duty_cycle").read_text().strip() for m in range(4) if m != broken]
    if p.returncode != 2 or f"pwm{broken}/duty_cycle: Is a directory" not in stderr or others != ["0", "0", "0"]:
        failures.append(f"--io linux failed write: exit {p.returncode}, {stderr.strip()!r}, others {others}")
    # The E-stop line (--estop-gpio 30): reading 1, every cycle is a zero-duty note, no row, the
    # files at zero; reading 0, the run is the one without the line.
    iio, chip = kernel_tree()
    for j, (a, _, _, o) in wiring.items():
        (iio / f"in_voltage{a}_raw").write_text(f"{int(first[j + '_counts']) - o}\n")
    (sysroot / "sys/class/gpio/gpio30/value").write_text("1\n")
    r = subprocess.run(linux_cmd() + ["--estop-gpio", "30"], input="".join(const_lines), capture_output=True, text=True)
    notes = [line for line in r.stdout.splitlines() if line.startswith("# estop: t = ")]
    duties = [(chip / f"pwm{m}" / "duty_cycle").read_text().strip() for m in range(4)]
    if (r.returncode != 0 or rows(r.stdout) or len(notes) != len(reference) or "# estop: latched (input)" not in r.stdout or
            duties != ["0"] * 4 or (sysroot / "sys/class/gpio/gpio30/direction").read_text().strip() != "in"):
        failures.append(f"--estop-gpio pressed: exit {r.returncode}, {len(rows(r.stdout))} rows, {len(notes)} notes, {duties}")
    (sysroot / "sys/class/gpio/gpio30/value").write_text("0\n")
    r = subprocess.run(linux_cmd() + ["--estop-gpio", "30"], input="".join(const_lines), capture_output=True, text=True)
    if r.returncode != 0 or r.stdout != linux_out:
        failures.append(f"--estop-gpio released: exit {r.returncode}, the output differs from the run without the line")
    # --io linux needs the direction lines in the map.
    r = subprocess.run([LOOP, str(config), str(WORK / "const.csv"), "--io", "linux", "--channels", str(WORK / "map.csv"),
                        "--sysfs-root", str(sysroot)], capture_output=True, text=True)
    if r.returncode != 2 or "direction_gpio" not in r.stderr:
        failures.append(f"--io linux without direction_gpio: exit {r.returncode}, {r.stderr.strip()!r}")
    for bad in [["--io", "spi"], ["--pwm-chip", "x"], ["--sysfs-root", str(sysroot)]]:
        r = subprocess.run([LOOP, str(config), str(WORK / "const.csv")] + bad, capture_output=True, text=True)
        if r.returncode != 2 or bad[0] not in r.stderr:
            failures.append(f"{bad}: exit {r.returncode}, {r.stderr.strip()!r}")
    shutil.rmtree(sysroot, ignore_errors=True)
    print(f"--io linux: {len(reference)} cycles, period {period} ns")
if nonzero < len(logged):
    failures.append(f"only {nonzero} non-zero duties: the pattern does not drive the motors")
for f in failures[:20]:
    print("FAIL", f)
print(f"{len(logged)} cycles, {len(failures)} failures")
sys.exit(1 if failures else 0)
