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
    # Microseconds: every benchmark's time in its own unit converted.
    scale = {"ns": 1e-3, "us": 1.0, "ms": 1e3, "s": 1e6}
    cpu = {r["name"]: r["cpu_time"] * scale[r.get("time_unit", "us")] for r in runs}
    counters = {r["name"]: r for r in runs}

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
    config_table(cpu, counters)


def config_table(cpu, counters):
    """The shipped configurations (config/*.yaml): description against one pass over the image, matching
    against one pass over the map, and the memory of the map."""
    read = cpu.get("BM_ImageRead/640x480")
    if read is None:
        return
    print()
    print("| config | bytes a place | describe 640x480 (us) | images/s | describe / image read |")
    print("|---|---:|---:|---:|---:|")
    for config in ("gardens_point", "nordland", "default"):
        t = cpu.get(f"BM_ConfigDescribe/{config}")
        if t is None:
            continue
        size = counters[f"BM_ConfigDescribe/{config}"].get("descriptor_bytes", 0)
        print(f"| {config} | {size:,.0f} | {t:,.0f} | {1e6 / t:,.0f} | {t / read:.1f}x |")
    print(f"\n(one pass over the 640x480 BGR image: {read:.1f} us)\n")
    print("| config | N | match (ms/frame) | memory read (ms) | match / read | map memory "
          "| at any pace (ms/frame) | pace / match | pace / read | a run published (ms/frame) |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for config in ("gardens_point", "nordland", "default"):
        for n in (100000, 1000000, 10000000):
            name = f"{config}/{n}"
            match, memory = cpu.get(f"BM_ConfigMatch/{name}"), cpu.get(f"BM_ConfigMemoryRead/{name}")
            if match is None or memory is None:
                continue
            map_bytes = counters[f"BM_ConfigMatch/{name}"].get("map_bytes", 0)
            pace = cpu.get(f"BM_ConfigPaceMatch/{name}")
            at_pace = (f"{pace / 1e3:,.2f} | {pace / match:.1f}x | {pace / memory:.1f}x" if pace is not None
                       else "- | - | -")
            published = cpu.get(f"BM_ConfigPaceMatchPublished/{name}")
            at_pace += f" | {published / 1e3:,.2f}" if published is not None else " | -"
            print(f"| {config} | {n:,} | {match / 1e3:,.2f} | {memory / 1e3:,.2f} | {match / memory:.2f}x | "
                  f"{map_bytes / 1e6:,.0f} MB | {at_pace} |")
    two_channel_table(cpu)
    length_table(cpu)


def two_channel_table(cpu):
    """A configuration with a view channel (default.yaml): what a frame of the detector pays, both channels'
    matchers, against today's matcher (the diagonal sums, one channel) and one read of both channels' maps."""
    rows = []
    for config in ("gardens_point", "nordland", "default"):
        for n in (100000, 1000000, 10000000):
            name = f"{config}/{n}"
            two, read = cpu.get(f"BM_ConfigTwoChannelMatch/{name}"), cpu.get(f"BM_ConfigTwoChannelRead/{name}")
            today, one = cpu.get(f"BM_ConfigMatch/{name}"), cpu.get(f"BM_ConfigPaceMatch/{name}")
            if two is None or read is None or today is None:
                continue
            one_channel = f"{one / 1e3:,.2f}" if one is not None else "-"
            rows.append(f"| {config} | {n:,} | {today / 1e3:,.2f} | {one_channel} | {two / 1e3:,.2f} | "
                        f"{read / 1e3:,.2f} | {two / today:.1f}x | {two / read:.2f}x |")
    if not rows:
        return
    print()
    print("| config | N | today's matcher (ms/frame) | one channel at any pace (ms/frame) | two channels (ms/frame) "
          "| read of both maps (ms) | two channels / today's | two channels / read |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|")
    for row in rows:
        print(row)


def length_table(cpu):
    """gardens_point at N = 1e7 with other sequence lengths: a frame reads each descriptor once, whatever L."""
    memory = cpu.get("BM_ConfigMemoryRead/gardens_point/10000000")
    rows = [(length, cpu.get(f"BM_ConfigMatchLength/gardens_point/10000000/{length}")) for length in (10, 50, 100, 300)]
    if memory is None or all(t is None for _, t in rows):
        return
    print()
    print("| gardens_point, N = 1e7, L | match (ms/frame) | match / read |")
    print("|---:|---:|---:|")
    for length, match in rows:
        if match is not None:
            print(f"| {length} | {match / 1e3:,.2f} | {match / memory:.2f}x |")


if __name__ == "__main__":
    main(sys.argv[1])
