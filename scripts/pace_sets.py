#!/usr/bin/env python3
"""The stream sets every change of the matcher or the decision is judged on (doc/results.md quotes their totals).

  scripts/pace_sets.py SET --out DIR [--bin DIR] [--set key=value]... [--jobs N] [--json FILE] [--clean]

SET is one of
  pace     90 streams: Gardens Point day_right then night_right, day_right then day_left, day_left then
           night_right and night_right then day_left, Nordland summer then winter and winter then summer
           (config/default.yaml), day_right then night_right and day_right then day_left with
           config/gardens_point.yaml, and the 60-frame short routes day_right then day_left and then night_right;
           each at 1x, 2x, 0.5x, stops:100, 1.25x, 2.5x, ramp:0.5,2, varying:100 and random:1
  holdout  35 streams nothing was tuned on: GP day_left then day_right and night_right then day_right
           (default.yaml), day_left then night_right (gardens_point.yaml), day_right then night_right
           (nordland.yaml), Nordland summer then winter (gardens_point.yaml); at 1x, 1.5x, 0.7x, stops:60,
           varying:150, random:2 and random:3
  short    95 short routes: GP frames 0-59, 100-159 and 140-199 of five pairings, Nordland frames 300-399 and
           1000-1099 both ways; at 1x, 2x, 0.5x, stops:30 and 1.5x
  route40  120 routes of 40 places (a corridor walked twice): GP frames 0-39, 50-89, 100-139 and 150-189 of the
           five pairings, Nordland frames 300-339 and 1000-1039 both ways; at the profiles of `short`
  slow     48 revisits slower than the first pass with frames of their own (not repeated ones, which a standstill
           removes): the first traversal at 1.5x, 2x and 3x (its map sparser), the second at 1x and 1.25x; GP
           day_right then night_right, day_right then day_left, day_left then day_right, night_right then
           day_right, day_left then night_right (default.yaml), day_right then night_right (gardens_point.yaml),
           Nordland summer then winter and winter then summer (nordland.yaml)
(scripts/pace_sweep.py has one more, every steady pace from 1.0x to 2.9x.) Prints one line per stream and profile,
then the totals: published / wrong / summed recall. --json writes {"stream profile": [published, wrong, recall]}, so
two runs can be compared stream by stream. Each stream's runs stay in DIR (a Nordland run's distance matrix alone is
50 MB, the pace set about 1.1 GB); --clean removes them once scored.
"""
import argparse
import json
import os
import shutil

import pace_eval  # this folder

HERE = os.path.dirname(os.path.abspath(__file__))
DATA = os.path.join(HERE, '..', '..', 'shared', 'data')
GP = os.path.join(DATA, 'gardens_point')
NL = os.path.join(DATA, 'nordland')
PACE = '1x 2x 0.5x stops:100 1.25x 2.5x ramp:0.5,2 varying:100 random:1'.split()
HOLDOUT = '1x 1.5x 0.7x stops:60 varying:150 random:2 random:3'.split()
SHORT = '1x 2x 0.5x stops:30 1.5x'.split()
SLOW = '1x 1.25x'.split()
SLOW_FIRST = '1.5x 2x 3x'.split()


def streams(which):
    """(name, first, second, tolerance, config, start, frames, profiles, first_profile)."""
    gp = lambda a, b: (os.path.join(GP, a), os.path.join(GP, b), 2)
    nl = lambda a, b: (os.path.join(NL, a), os.path.join(NL, b), 1)
    if which == 'pace':
        rows = [('gp_dr_nr_def', gp('day_right', 'night_right'), 'default', 0, 0),
                ('gp_dr_dl_def', gp('day_right', 'day_left'), 'default', 0, 0),
                ('gp_dl_nr_def', gp('day_left', 'night_right'), 'default', 0, 0),
                ('gp_nr_dl_def', gp('night_right', 'day_left'), 'default', 0, 0),
                ('nl_s_w_def', nl('summer', 'winter'), 'default', 0, 0),
                ('nl_w_s_def', nl('winter', 'summer'), 'default', 0, 0),
                ('gp_dr_nr_gp', gp('day_right', 'night_right'), 'gardens_point', 0, 0),
                ('gp_dr_dl_gp', gp('day_right', 'day_left'), 'gardens_point', 0, 0),
                ('gp_short_dr_dl', gp('day_right', 'day_left'), 'default', 0, 60),
                ('gp_short_dr_nr', gp('day_right', 'night_right'), 'default', 0, 60)]
        return [(n, *pair, cfg, start, frames, PACE, '1x') for n, pair, cfg, start, frames in rows]
    if which == 'holdout':
        rows = [('gp_dl_dr_def', gp('day_left', 'day_right'), 'default'),
                ('gp_nr_dr_def', gp('night_right', 'day_right'), 'default'),
                ('gp_dl_nr_gp', gp('day_left', 'night_right'), 'gardens_point'),
                ('gp_dr_nr_nl', gp('day_right', 'night_right'), 'nordland'),
                ('nl_s_w_gp', nl('summer', 'winter'), 'gardens_point')]
        return [(n, *pair, cfg, 0, 0, HOLDOUT, '1x') for n, pair, cfg in rows]
    if which == 'slow':
        rows = [('gp_dr_nr_def', gp('day_right', 'night_right'), 'default'),
                ('gp_dr_dl_def', gp('day_right', 'day_left'), 'default'),
                ('gp_dl_dr_def', gp('day_left', 'day_right'), 'default'),
                ('gp_nr_dr_def', gp('night_right', 'day_right'), 'default'),
                ('gp_dl_nr_def', gp('day_left', 'night_right'), 'default'),
                ('gp_dr_nr_gp', gp('day_right', 'night_right'), 'gardens_point'),
                ('nl_s_w_nl', nl('summer', 'winter'), 'nordland'),
                ('nl_w_s_nl', nl('winter', 'summer'), 'nordland')]
        return [('%s_first%s' % (n, fp), *pair, cfg, 0, 0, SLOW, fp) for n, pair, cfg in rows for fp in SLOW_FIRST]
    # Short routes: the same pairings, each from several starts; 'route40' takes 40 places of each, 'short' 60 of
    # Gardens Point and 100 of Nordland (a frame every 10 s there).
    gp_starts, gp_frames, nl_frames = ((0, 50, 100, 150), 40, 40) if which == 'route40' else ((0, 100, 140), 60, 100)
    out = []
    for a, b in (('day_right', 'day_left'), ('day_left', 'day_right'), ('day_right', 'night_right'),
                 ('night_right', 'day_right'), ('day_left', 'night_right')):
        for start in gp_starts:
            out.append(('%s_%s_%s_%d' % (which, a, b, start), *gp(a, b), 'default', start, gp_frames, SHORT, '1x'))
    for a, b in (('summer', 'winter'), ('winter', 'summer')):
        for start in (300, 1000):
            out.append(('%s_%s_%s_%d' % (which, a, b, start), *nl(a, b), 'default', start, nl_frames, SHORT, '1x'))
    return out


def print_row(key, published, wrong, recall):
    """One stream and profile's line (scripts/pace_join.py prints the same)."""
    print('%-40s published %5d  wrong %4d  recall %.3f' % (key, published, wrong, recall), flush=True)


def report(label, results, json_path=''):
    """The totals of {key: [published, wrong, recall]}, and with json_path every row as JSON."""
    print('%s: %d streams, published %d / wrong %d / summed recall %.2f' % (
        label, len(results), sum(r[0] for r in results.values()), sum(r[1] for r in results.values()),
        sum(r[2] for r in results.values())))
    if json_path:
        with open(json_path, 'w') as f:
            json.dump(results, f, indent=0)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument('which', choices=['pace', 'holdout', 'short', 'route40', 'slow'])
    parser.add_argument('--out', required=True)
    parser.add_argument('--bin', default=os.path.join(HERE, '..', 'build', 'ws', 'devel', 'lib', 'openable_ros'))
    parser.add_argument('--set', action='append', default=[])
    parser.add_argument('--jobs', type=int, default=2)
    parser.add_argument('--json', default='')
    parser.add_argument('--clean', action='store_true', help="remove each stream's runs once scored")
    args = parser.parse_args()
    results = {}
    for name, first, second, tolerance, config, start, frames, profiles, first_profile in streams(args.which):
        config_file = os.path.join(HERE, '..', 'config', config + '.yaml')
        for profile, published, wrong, recall in pace_eval.evaluate(
                first, second, tolerance, config_file, os.path.join(args.out, name), profiles, args.bin, args.jobs,
                args.set, first_profile=first_profile, start=start, frames=frames):
            key = '%s %s' % (name, profile)
            results[key] = [published, wrong, recall]
            print_row(key, published, wrong, recall)
        if args.clean:
            shutil.rmtree(os.path.join(args.out, name), ignore_errors=True)
    report(args.which, results, args.json)


if __name__ == '__main__':
    main()
