#!/usr/bin/env python3
"""How many of a command's threads want a core, over its run (Linux only).

    python3 docs/eval/runnable_threads.py [--every SECONDS] -- COMMAND [ARG ...]

Every interval (default 0.5 s) it sums, over the command's threads, the time each spent
running and the time each spent runnable but waiting for a core
(`/proc/PID/task/TID/schedstat`), divided by the interval. The sum is the number of
threads that *wanted* a core, whatever else the machine was running: on a shared
machine another job's load halves what "running" shows, not what "wanted" shows. A
program that keeps both cores of a 2-core machine busy reads 2.0; a serial phase
reads 1.0. The command's stderr lines are printed with their times, so the phases of
`desal eval` (without `--quiet`) can be matched against the figures.

At the end it prints the mean of each column and the seconds in which fewer than 1.5
threads wanted a core. Child processes (MeshLab's Python) are not counted: their
threads are not the command's.
"""

import argparse
import glob
import subprocess
import sys
import threading
import time


def sample(pid):
    running = waiting = 0
    for path in glob.glob(f"/proc/{pid}/task/*/schedstat"):
        try:
            run_ns, wait_ns, _ = open(path).read().split()
        except (OSError, ValueError):
            continue  # a thread that ended between the listing and the read
        running += int(run_ns)
        waiting += int(wait_ns)
    return running, waiting


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--every", type=float, default=0.5, help="seconds between samples")
    parser.add_argument("command", nargs=argparse.REMAINDER)
    args = parser.parse_args()
    command = args.command[1:] if args.command[:1] == ["--"] else args.command
    if not command:
        parser.error("no command given")

    child = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    start = time.monotonic()

    def echo_stderr():
        for line in child.stderr:
            print(f"{time.monotonic() - start:8.2f} | {line.rstrip()}", flush=True)

    threading.Thread(target=echo_stderr, daemon=True).start()
    rows = []
    last = (time.monotonic(), sample(child.pid))
    while child.poll() is None:
        time.sleep(args.every)
        now, counts = time.monotonic(), sample(child.pid)
        if child.poll() is not None:
            break  # the last sample may miss threads that already ended
        interval = (now - last[0]) * 1e9
        running = (counts[0] - last[1][0]) / interval
        wanted = (counts[0] + counts[1] - last[1][0] - last[1][1]) / interval
        rows.append((now - last[0], running, wanted))
        print(f"{now - start:8.2f}   running {running:4.2f}   wanted {wanted:4.2f}", flush=True)
        last = (now, counts)
    total = sum(dt for dt, _, _ in rows) or 1.0

    def mean(column):
        return sum(row[0] * row[column] for row in rows) / total

    below = sum(dt for dt, _, wanted in rows if wanted < 1.5)
    print(
        f"exit {child.returncode}; {time.monotonic() - start:.1f} s; mean running {mean(1):.2f}, "
        f"wanted {mean(2):.2f}; {below:.1f} s with fewer than 1.5 threads wanting a core"
    )
    sys.exit(child.returncode)


if __name__ == "__main__":
    main()
