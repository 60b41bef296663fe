#!/usr/bin/env python3
"""Scores two channels' loops joined: what a detector running two matchers and two decisions side by side would
publish (doc/results.md, "Two channels"), from two runs of scripts/pace_sets.py on the same set.

  scripts/pace_join.py FIRST SECOND [--bin DIR] [--only-first PREFIX]... [--json FILE]

FIRST and SECOND are the --out folders of two pace_sets.py runs of one set without --clean (for example the shipped
configuration, and the same with --set lateral_shift=0.12). For each stream and profile the two loop_closures.csv
are joined frame by frame: FIRST's loop where both published one for a frame, SECOND's where only it did. The join is
scored by openable_eval against the stream's pairs, as pace_eval.py scores one run. A stream whose name starts with an
--only-first PREFIX takes FIRST's loops alone (a channel that would not exist there, as views on Nordland's 64x32
frames). Prints one line per stream and profile, then the totals, as pace_sets.py does.
"""
import argparse
import csv
import glob
import json
import os
import subprocess
import tempfile

import pace_sets  # this folder: the rows and totals it prints

HERE = os.path.dirname(os.path.abspath(__file__))


def read_loops(path):
    """(header, {query frame: row}) of a loop_closures.csv."""
    with open(path, newline='') as f:
        rows = list(csv.reader(f))
    return rows[0], {row[0]: row for row in rows[1:]}


def joined_loops(first_path, second_path, second_too):
    """The header both files share (the shorter one) and the joined rows in frame order."""
    header, first = read_loops(first_path)
    second_header, second = read_loops(second_path) if second_too else (header, {})
    if len(second_header) < len(header):
        header = second_header
    rows = dict(second)
    rows.update(first)
    return header, [rows[q][:len(header)] for q in sorted(rows, key=int)]


def score(bin_dir, loops_csv, stream_dir, work):
    """openable_eval of one joined set of loops: (published, wrong, recall)."""
    frames = len(os.listdir(os.path.join(stream_dir, 'stream')))
    subprocess.run([os.path.join(bin_dir, 'openable_eval'), '--published', loops_csv, '--pairs',
                    os.path.join(stream_dir, 'pairs.txt'), '--frames', str(frames), '--output', work],
                   check=True, stdout=subprocess.DEVNULL)
    with open(os.path.join(work, 'metrics.json')) as f:
        metrics = json.load(f)
    return int(metrics['published']), int(metrics['wrong']), float(metrics['recall'])


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument('first')
    parser.add_argument('second')
    parser.add_argument('--bin', default=os.path.join(HERE, '..', 'build', 'ws', 'devel', 'lib', 'openable_ros'))
    parser.add_argument('--only-first', action='append', default=[])
    parser.add_argument('--json', default='')
    args = parser.parse_args()
    pattern = os.path.join(args.first, '*', '*', 'run', 'loop_closures.csv')
    results = {}
    with tempfile.TemporaryDirectory() as work:
        for first_csv in sorted(glob.glob(pattern)):
            relative = os.path.relpath(os.path.dirname(os.path.dirname(first_csv)), args.first)
            second_csv = os.path.join(args.second, relative, 'run', 'loop_closures.csv')
            if not os.path.exists(second_csv):
                raise SystemExit('pace_join: %s has no run in %s' % (relative, args.second))
            stream = relative.split(os.sep)[0]
            second_too = not any(stream.startswith(prefix) for prefix in args.only_first)
            header, rows = joined_loops(first_csv, second_csv, second_too)
            loops_csv = os.path.join(work, 'loop_closures.csv')
            with open(loops_csv, 'w', newline='') as f:
                writer = csv.writer(f)
                writer.writerow(header)
                writer.writerows(rows)
            key = relative.replace(os.sep, ' ')
            results[key] = score(args.bin, loops_csv, os.path.dirname(os.path.dirname(first_csv)),
                                 os.path.join(work, 'eval'))
            pace_sets.print_row(key, *results[key])
    if not results:
        raise SystemExit('pace_join: no runs in %s (pace_sets.py without --clean keeps them)' % args.first)
    pace_sets.report('joined', results, args.json)


if __name__ == '__main__':
    main()
