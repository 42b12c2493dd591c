#!/usr/bin/env python3
"""Where a dualcal process's threads spend each millisecond (docs/performance.md, "Sixth pass").

Record one run with call stacks, from a build with frame pointers and line tables:

    CARGO_TARGET_DIR=target-prof CARGO_PROFILE_RELEASE_DEBUG=line-tables-only \\
      RUSTFLAGS="-C force-frame-pointers=yes" cargo build --release --no-default-features --bin dualcal
    perf record -F 20000 -e cpu-clock --call-graph fp -o perf.data -- \\
      target-prof/release/dualcal calibrate paper --out p.json --quiet
    perf script -i perf.data -F tid,time,ip,sym > stacks.txt
    tools/perf_timeline.py stacks.txt

Recorded over several runs (`perf record … -- sh -c 'for i in $(seq 30); do …; done'`), the
timeline mixes the runs, and the totals per stage at the end are the figure to read.

Each sample is named by the first stage below found on its stack (outermost stages last in the list,
so the innermost named stage wins) and put in its millisecond and thread; each line of the output is
one millisecond, one column per thread: the most frequent name and the number of samples. The totals
per name follow. Sampling this densely slows the run about twofold: read proportions, not times.
"""
import collections
import re
import signal
import sys

STAGES = [
    ("urdf_rs", "urdf"),
    ("csv", "csv"),
    ("clap", "clap"),
    ("screen_model", "screen result"),
    ("quality::screen", "screen nominal"),
    ("frames::nominal", "screen nominal"),
    ("Workspace::load", "load"),
    ("distance_identifiability", "identifiability"),
    ("at_solution", "re-check"),
    ("BaseProblem", "step 2"),
    ("SqpState", "sqp"),
    ("uncertainty::", "uncertainty"),
    ("metrics::", "tables"),
    ("run_stage", "stage"),
    ("run_command", "command"),
    ("wait_until", "idle (spinning)"),
    ("_dl_", "dynamic loader"),
]


def read(path):
    samples, current = [], None
    with open(path, encoding="utf-8", errors="replace") as f:
        for line in f:
            head = re.match(r"\s*(\d+)\s+([\d.]+):", line)
            if head:
                current = (int(head.group(1)), float(head.group(2)), [])
                samples.append(current)
            elif line.strip() and current is not None:
                current[2].append(line.strip())
    return samples


def name(stack):
    for pattern, stage in STAGES:
        if any(pattern in frame for frame in stack):
            return stage
    leaf = stack[0].split(" ", 1)[-1] if stack else "?"
    return "other: " + leaf[:24]


def main():
    signal.signal(signal.SIGPIPE, signal.SIG_DFL)  # `| head` ends the output quietly
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    samples = read(sys.argv[1])
    if not samples:
        sys.exit(f"{sys.argv[1]}: no samples (was it written by `perf script -F tid,time,ip,sym`?)")
    t0 = min(t for _, t, _ in samples)
    threads = sorted({tid for tid, _, _ in samples})
    cells = collections.defaultdict(collections.Counter)
    totals = collections.Counter()
    for tid, t, stack in samples:
        stage = name(stack)
        cells[(threads.index(tid), int((t - t0) * 1000))][stage] += 1
        totals[stage] += 1
    last = max(ms for _, ms in cells) + 1
    print(f"{len(samples)} samples, {len(threads)} threads, {last} ms")
    for ms in range(last):
        row = []
        for th in range(len(threads)):
            c = cells.get((th, ms))
            row.append(f"{c.most_common(1)[0][0][:18]:<18}{sum(c.values()):3d}" if c else " " * 21)
        print(f"{ms:4d} " + " | ".join(row))
    print()
    for stage, n in totals.most_common():
        print(f"{n:6d}  {100 * n / len(samples):5.1f} %  {stage}")


if __name__ == "__main__":
    main()
