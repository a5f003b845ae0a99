#!/usr/bin/env python3
"""How evenly PoCL's pthread device shares each kernel launch among its threads.

PoCL compiles every kernel into its own shared object (~/.cache/pocl/kcache/.../NAME.so), so
CPU-time samples of `perf record -e cpu-clock` name the kernel that ran, and their thread id
names the PoCL worker thread that ran it. The queue is in order, so one launch is a run of
consecutive samples of one kernel object. For each launch this sums the samples per thread;
the busiest thread's share of the launch's CPU time is its critical path (0.5 with 2 threads
sharing evenly, 1.0 when one thread did everything). It is a property of the launch shape and
of PoCL's dealing, nearly independent of the machine's load, unlike wall-clock times.

Usage:
  perf record -e cpu-clock -F 4000 -o run.data -- build/vct_bench --quick --frames 2
  bench/thread_balance.py run.data [--min-ms 0.5]

Prints one line per kernel object: launches, CPU ms per launch (median), busiest thread's
ms per launch (median), and the busiest thread's share of all that kernel's CPU time.
"""
import argparse
import collections
import re
import statistics
import subprocess
import sys

KERNEL_SO = re.compile(r"\(([^)]*/pocl/kcache/([^/]+/[^/]+)/([^/]+)/([^/]+)/[^/)]+\.so)\)")


def samples(perf_data):
    """(time s, tid, kernel key or None) for every sample, in time order."""
    out = subprocess.run(["perf", "script", "-i", perf_data, "-F", "tid,time,ip,dso"],
                         capture_output=True, text=True, check=True).stdout
    rows = []
    for line in out.splitlines():
        parts = line.split()
        if len(parts) < 3:
            continue
        tid, time = int(parts[0]), float(parts[1].rstrip(":"))
        m = KERNEL_SO.search(line)
        # Key: kernel name, its local size and the program hash (one build configuration).
        key = f"{m.group(3)} [{m.group(4)}] {m.group(2)[:6]}" if m else None
        rows.append((time, tid, key))
    rows.sort()
    return rows


def launches(rows, period_ms):
    """Runs of consecutive kernel samples of one kernel object: {key: [{tid: ms}, ...]}."""
    result = collections.defaultdict(list)
    current, per_tid = None, None
    for _, tid, key in rows:
        if key is None:  # host code, PoCL's scheduler, the OS: does not end a launch
            continue
        if key != current:
            if current is not None:
                result[current].append(per_tid)
            current, per_tid = key, collections.Counter()
        per_tid[tid] += period_ms
    if current is not None:
        result[current].append(per_tid)
    return result


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("perf_data")
    ap.add_argument("--freq", type=float, default=4000.0, help="perf record -F (samples per second)")
    ap.add_argument("--min-ms", type=float, default=0.5, help="skip kernels under this CPU ms per launch")
    args = ap.parse_args()
    period_ms = 1000.0 / args.freq
    table = []
    for key, runs in launches(samples(args.perf_data), period_ms).items():
        total = [sum(r.values()) for r in runs]
        busiest = [max(r.values()) for r in runs]
        if statistics.median(total) < args.min_ms:
            continue
        table.append((key, len(runs), statistics.median(total), statistics.median(busiest),
                      sum(busiest) / sum(total)))
    table.sort(key=lambda t: -t[2] * t[1])
    print(f"{'kernel [local size] program':60s} {'runs':>5s} {'CPU ms':>8s} {'busiest':>8s} {'share':>6s}")
    for key, n, cpu, top, share in table:
        print(f"{key:60s} {n:5d} {cpu:8.2f} {top:8.2f} {share:6.3f}")


if __name__ == "__main__":
    sys.exit(main())
