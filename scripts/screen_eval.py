#!/usr/bin/env python3
"""What the screen of a large row (PaceMatcher, `screen_places`) costs in loops, on real images.

  scripts/screen_eval.py --out DIR [--bin DIR] [--profiles "1x 2x ..."] [--places N]

Every stream of scripts/pace_sets.py is a row refined whole (at most 2 chunks of 2,048 places). Here a stream starts
with real frames of other places (Nordland summer and winter, KITTI 07's first 160, EuRoC's revisits: 3,860 frames,
2 chunks), then a Gardens Point pairing at a pace profile (scripts/pace_eval.py's profiles), and runs through
`openable_offline` in loop-closure mode with config/default.yaml twice: the whole row (`screen_places` 0) and screened
down to one refined chunk (`screen_places` N, 2,048 by default). Prints, per pairing and profile, published / wrong /
recall of the Gardens Point revisit (right: within 2 places of its first-pass frame; the prefix's own loops, such as
Nordland's winter revisiting its summer, are not scored) for both, and a markdown table with --markdown.
"""
import argparse
import csv
import os
import shutil
import subprocess

import pace_eval  # this folder

HERE = os.path.dirname(os.path.abspath(__file__))
DATA = os.path.join(HERE, '..', '..', 'shared', 'data')
PAIRINGS = (('day_right', 'night_right'), ('day_right', 'day_left'), ('day_left', 'night_right'))


def prefix():
    """Real frames of other places, in order."""
    frames = []
    for folder in ('nordland/summer', 'nordland/winter', 'kitti/07_first160/image_0', 'stereo/euroc_v101_revisits'):
        frames += pace_eval.images(os.path.join(DATA, folder))
    return frames


def run(args, first, second, profile, screen_places, before):
    gardens = os.path.join(DATA, 'gardens_point')
    places = pace_eval.profile_indices(profile, 200)
    out = os.path.join(args.out, '%s_%s_%s_%d' % (first, second, profile.replace(':', '_').replace(',', '_'),
                                                  screen_places))
    shutil.rmtree(out, ignore_errors=True)
    os.makedirs(os.path.join(out, 'stream'))
    second_frames = pace_eval.images(os.path.join(gardens, second))
    frames = before + pace_eval.images(os.path.join(gardens, first))[:200] + [second_frames[k] for k in places]
    for i, path in enumerate(frames):
        os.symlink(os.path.abspath(path), os.path.join(out, 'stream', 'frame%06d%s' % (i, os.path.splitext(path)[1])))
    subprocess.run([os.path.join(args.bin, 'openable_offline'), '--quiet', '--config',
                    os.path.join(HERE, '..', 'config', 'default.yaml'), '--reference', os.path.join(out, 'stream'),
                    '--output', os.path.join(out, 'run'), '--set', 'screen_places=%d' % screen_places],
                   check=True, stdout=subprocess.DEVNULL)
    first_at, second_at = len(before), len(before) + 200
    published = wrong = 0
    right = set()
    with open(os.path.join(out, 'run', 'loop_closures.csv')) as f:
        for row in csv.DictReader(f):
            query, match = int(row['query']), int(row['match'])
            if query < second_at:
                continue  # the prefix's own loops
            published += 1
            if first_at <= match < second_at and abs(match - first_at - places[query - second_at]) <= 2:
                right.add(query)
            else:
                wrong += 1
    shutil.rmtree(out)
    return published, wrong, len(right) / len(places)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument('--out', required=True)
    parser.add_argument('--bin', default=os.path.join(HERE, '..', 'build', 'ws', 'devel', 'lib', 'openable_ros'))
    parser.add_argument('--profiles', default='1x 2x 0.5x stops:100 varying:100 random:1')
    parser.add_argument('--places', type=int, default=2048)
    parser.add_argument('--markdown', action='store_true')
    args = parser.parse_args()
    before = prefix()
    profiles = args.profiles.split()
    rows = []
    for first, second in PAIRINGS:
        cells = []
        for profile in profiles:
            whole = run(args, first, second, profile, 0, before)
            screened = run(args, first, second, profile, args.places, before)
            print('%s then %s %-12s whole %4d / %3d / %.3f  screened %4d / %3d / %.3f'
                  % (first, second, profile, *whole, *screened), flush=True)
            cells.append('%d / %d / %.3f, the same' % whole if whole == screened else
                         '%d / %d / %.3f; screened %d / %d / %.3f' % (*whole, *screened))
        rows.append('| %s then %s | %s |' % (first, second, ' | '.join(cells)))
    if args.markdown:
        print('| GP pairing (after %d frames of other places) | %s |' % (len(before), ' | '.join(profiles)))
        print('|---|%s' % ('---|' * len(profiles)))
        print('\n'.join(rows))


if __name__ == '__main__':
    main()
