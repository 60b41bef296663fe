#!/usr/bin/env python3
"""Turns openable_bench's JSON output into the Markdown table of doc/performance.md.

Every ratio is between two benchmarks of the same run (CPU time), so it does not depend on how fast the
machine is: the online matcher against the naive O(N * L) reference, against itself at L = 1, and against
streaming the same descriptor bytes from memory once.
"""
import json
import sys


def main(path):
    with open(path) as f:
        runs = json.load(f)["benchmarks"]
    cpu = {r["name"]: r["cpu_time"] for r in runs}  # microseconds (the benchmarks use kMicrosecond)

    print("| descriptor | us per 640x480 image | images/s |")
    print("|---|---:|---:|")
    for name, t in cpu.items():
        if name.startswith("BM_Describe/"):
            print(f"| {name.split('/', 1)[1]} | {t:.0f} | {1e6 / t:.0f} |")
    print()
    print("| N | L | sequence match (us/frame) | naive O(N*L) (us) | naive / online | L / L=1 | online / memory read |")
    print("|---:|---:|---:|---:|---:|---:|---:|")
    for n in (1000, 10000, 100000, 1000000):
        read = cpu.get(f"BM_MemoryRead/{n}")
        one = cpu.get(f"BM_SequenceMatch/{n}/1")
        for length in (1, 10, 300):
            online = cpu.get(f"BM_SequenceMatch/{n}/{length}")
            if online is None:
                continue
            naive = cpu.get(f"BM_NaiveSequenceMatch/{n}/{length}")
            cells = [
                f"{n:,}", str(length), f"{online:,.1f}",
                f"{naive:,.0f}" if naive else "-",
                f"{naive / online:,.1f}x" if naive else "-",
                f"{online / one:.2f}" if one else "-",
                f"{online / read:.2f}" if read else "-",
            ]
            print("| " + " | ".join(cells) + " |")
    print()
    for n in (1000, 10000, 100000, 1000000):
        read = cpu.get(f"BM_MemoryRead/{n}")
        if read:
            print(f"- memory read of {n:,} descriptors ({n * 176 / 1e6:.1f} MB): {read:,.1f} us "
                  f"({n * 176 / read / 1e3:.1f} GB/s)")


if __name__ == "__main__":
    main(sys.argv[1])
