#!/usr/bin/env python3
"""Recall and wrong loops at every steady pace from 1.0x to 2.9x, not only at the profiles' few factors.

  scripts/pace_sweep.py --out DIR [--config FILE.yaml] [--bin DIR] [--set key=value]... [--jobs N] [--plot FILE.png]

The matcher follows 17 paces (1.15^k, 1/3x to 3x); a revisit at a pace between two of them is followed by
slips, and its recall depends on where its pace falls. The fixed profiles of scripts/pace_eval.py (2x, 2.5x,
...) land on or near some of those paces, so a change of the matcher or of its paces is judged here, on a pace
grid that knows nothing of them: Gardens Point day_right then night_right and day_right then day_left at
1.0x, 1.1x, ..., 2.9x; Nordland summer then winter at every second factor; and the revisit slower than the
first pass (the first traversal at 1.2x ... 2.7x, the second at 1x: repeated frames would be a standstill).
62 streams; prints a markdown table (recall, wrong loops in brackets) and the totals, published / wrong /
summed recall, over all streams and over the 40 whose factor none of 1.0x, 1.5x, 2.0x, 2.5x is. --plot draws
recall and precision against the pace, with the paces followed, through gnuplot (apt-get install gnuplot-nox).
"""
import argparse
import os
import shutil
import subprocess
import sys

import pace_eval  # this folder

HERE = os.path.dirname(os.path.abspath(__file__))
DATA = os.path.join(HERE, '..', '..', 'shared', 'data')
FACTORS = ['%.1fx' % (1 + 0.1 * k) for k in range(20)]
ROUND_FACTORS = {'1.0x', '1.5x', '2.0x', '2.5x'}


def streams():
    """(label, first, second, tolerance, second-traversal profiles, first-traversal profile)."""
    gp = os.path.join(DATA, 'gardens_point')
    nl = os.path.join(DATA, 'nordland')
    out = [('GP day_right then night_right', gp + '/day_right', gp + '/night_right', 2, FACTORS, '1x'),
           ('GP day_right then day_left', gp + '/day_right', gp + '/day_left', 2, FACTORS, '1x'),
           ('Nordland summer then winter', nl + '/summer', nl + '/winter', 1, FACTORS[::2], '1x')]
    for first_pace in FACTORS[2::3]:
        out.append(('GP day_right then night_right, first pass at ' + first_pace, gp + '/day_right',
                    gp + '/night_right', 2, ['1x'], first_pace))
        out.append(('GP day_right then day_left, first pass at ' + first_pace, gp + '/day_right', gp + '/day_left',
                    2, ['1x'], first_pace))
    return out


def plot(results, out, png):
    """Recall (lines) and precision (circles; 1 where nothing was published) of each fast stream against its pace."""
    if not shutil.which('gnuplot'):
        sys.exit('pace_sweep: --plot needs gnuplot (apt-get install gnuplot-nox)')
    labels = list(dict.fromkeys(r[0] for r in results if not r[1].startswith('1/')))
    series = []
    for index, label in enumerate(labels):
        data = os.path.join(out, 'sweep%d.dat' % index)
        with open(data, 'w') as f:
            for r in results:
                if r[0] == label and not r[1].startswith('1/'):
                    f.write('%s %.4f %.4f\n' % (r[1][:-1], r[4], (r[2] - r[3]) / r[2] if r[2] else 1.0))
        series.append((data, label.replace('_', '\\_')))
    colours = ['#1f77b4', '#d62728', '#2ca02c']
    lines = ['set terminal pngcairo size 900,560 font "DejaVu Sans,11"', "set output '%s'" % png,
             'set title "recall (lines), precision (circles), dashed: the paces followed"',
             'set xlabel "pace of the second traversal (x the first pass\'s)"',
             'set ylabel "recall / precision of the published set"', 'set xrange [0.95:2.95]', 'set yrange [0:1.05]',
             'set key bottom left', 'set grid ytics',
             # The paces PaceMatcher follows: 1.15^k in sixtieths of a place a frame.
             'do for [k=0:8] { p = floor(1.15**k * 60 + 0.5) / 60.0; if (p <= 2.95) '
             '{ set arrow from p, graph 0 to p, graph 1 nohead lc rgb "#bbbbbb" dt 2 } }']
    plots = []
    for (data, label), colour in zip(series, colours):
        plots.append("'%s' u 1:2 w lp lw 2 pt 7 ps 0.8 lc rgb '%s' t '%s, recall'" % (data, colour, label))
        plots.append("'%s' u 1:3 w p pt 6 ps 1.2 lc rgb '%s' notitle" % (data, colour))
    lines.append('plot ' + ', '.join(plots))
    subprocess.run(['gnuplot'], input='\n'.join(lines) + '\n', text=True, check=True)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument('--out', required=True)
    parser.add_argument('--config', default=os.path.join(HERE, '..', 'config', 'default.yaml'))
    parser.add_argument('--bin', default=os.path.join(HERE, '..', 'build', 'ws', 'devel', 'lib', 'openable_ros'))
    parser.add_argument('--set', action='append', default=[])
    parser.add_argument('--jobs', type=int, default=2)
    parser.add_argument('--plot', default='')
    args = parser.parse_args()
    results = []  # (label, factor, published, wrong, recall)
    for index, (label, first, second, tolerance, profiles, first_pace) in enumerate(streams()):
        for profile, published, wrong, recall in pace_eval.evaluate(
                first, second, tolerance, args.config, os.path.join(args.out, 'stream%02d' % index), profiles, args.bin,
                args.jobs, args.set, first_profile=first_pace):
            factor = profile if first_pace == '1x' else '1/' + first_pace
            results.append((label, factor, published, wrong, recall))
    fast = [r for r in results if not r[1].startswith('1/')]
    print('| stream | ' + ' | '.join(f[:-1] for f in FACTORS) + ' |')
    print('|---|' + '---:|' * len(FACTORS))
    for label in dict.fromkeys(r[0] for r in fast):
        cell = {r[1]: '%.2f%s' % (r[4], ' (%d)' % r[3] if r[3] else '') for r in fast if r[0] == label}
        print('| %s | %s |' % (label, ' | '.join(cell.get(f, '') for f in FACTORS)))
    for r in results:
        if r[1].startswith('1/'):
            print('%s: published %d, wrong %d, recall %.3f' % (r[0], r[2], r[3], r[4]))

    def total(rows):
        return '%d streams, published %d / wrong %d / summed recall %.2f' % (
            len(rows), sum(r[2] for r in rows), sum(r[3] for r in rows), sum(r[4] for r in rows))

    print('all: ' + total(results))
    print('between round factors: ' + total([r for r in fast if r[1] not in ROUND_FACTORS]))
    if args.plot:
        plot(results, args.out, args.plot)


if __name__ == '__main__':
    main()
