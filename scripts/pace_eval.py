#!/usr/bin/env python3
"""Loop closure at another pace: builds one stream from two real traversals of the same route, the second
(or the first) resampled to a pace profile, runs openable_offline on it in loop-closure mode and scores what
it published with openable_eval against the stream's own ground truth.

  scripts/pace_eval.py --first DIR --second DIR --config FILE.yaml --out DIR [--profile P]... [--first-profile P]
                       [--tolerance T] [--frames N] [--start S] [--bin DIR] [--set key=value]... [--camera-info FILE]
                       [--jobs N] [--markdown] [--misses] [--trace]

A profile resamples a traversal of n frames (no synthetic image: frames are skipped or repeated):
  1x            every frame once (the first pass's pace)
  2x, 3x, 10x   every 2nd / 3rd / 10th frame (faster); any factor >= 1, e.g. 1.5x
  0.5x, 0.33x   each frame 2 / 3 times (slower); any factor < 1
  stops:N       every frame once, with two stops of N frames (the frame at 1/3 and at 2/3 repeated N times)
  stop:N        every frame once, with one stop of N frames (the frame at 1/2 repeated N times)
  varying[:P]   a pace varying smoothly between 0.5x and 2x (a sine of period P frames, default 100)
  ramp:A,B       a pace changing linearly from A x at the start to B x at the end
  parts:F1,F2,.. the traversal in equal parts, each at its pace factor (parts:1,2: the first half at 1x)
  random:SEED   a pace drawn at random in [0.4x, 2.5x] every 10 frames, with a stop of 30 to 150 frames
Ground truth: a frame of the second traversal that shows place k is a true loop with every frame of the first
traversal that shows a place within T of k (openable_eval --pairs). The first traversal has no loop.

--camera-info FILE verifies candidates geometrically with that camera (openable_offline --camera-info).
--frames N takes the first N frames of each traversal (a short route), --start S skips the first S of each first.
Prints one line per profile: published, wrong, precision, recall (and --markdown, a table row); --misses adds where
the recall went: the statuses (in decisions.csv) of the frames that have a true loop and got no right one published.
--trace writes OUT/PROFILE/trace.csv, one row per frame of the second traversal: the place it shows, its best match
as a place of the first traversal (or `own` when it is a frame of the second), how far off that is (match - place),
its status, score and pace (decisions.csv): where a run lags or leads the revisit, frame by frame.
"""
import argparse
import concurrent.futures
import json
import math
import os
import random
import re
import subprocess
import sys


def profile_indices(profile, n):
    """Frame indices (into a traversal of n frames) a robot driving `profile` would see, in order."""
    match = re.fullmatch(r'(\d+(?:\.\d+)?)x', profile)
    if match:
        factor = float(match.group(1))
        if factor <= 0:
            raise ValueError('pace factor must be > 0: ' + profile)
        count = int(math.ceil(n / factor - 1e-9))
        return [min(n - 1, int(math.floor(i * factor + 1e-9))) for i in range(count)]
    match = re.fullmatch(r'(stops?):(\d+)', profile)
    if match:
        stop = int(match.group(2))
        at = (n // 3, (2 * n) // 3) if match.group(1) == 'stops' else (n // 2,)
        out = []
        for i in range(n):
            out.append(i)
            if i in at:
                out.extend([i] * stop)
        return out
    match = re.fullmatch(r'varying(?::(\d+))?', profile)
    if match:
        period = float(match.group(1) or 100)
        out, position, t = [], 0.0, 0
        while position < n:
            out.append(int(position))
            position += 2.0 ** math.sin(2.0 * math.pi * t / period)  # 0.5x .. 2x
            t += 1
        return out
    match = re.fullmatch(r'ramp:([\d.]+),([\d.]+)', profile)
    if match:
        start, end = float(match.group(1)), float(match.group(2))
        out, position = [], 0.0
        while position < n:
            out.append(int(position))
            position += start + (end - start) * position / n
        return out
    match = re.fullmatch(r'parts:([\d.]+(?:,[\d.]+)*)', profile)
    if match:
        factors = [float(f) for f in match.group(1).split(',')]
        out, position = [], 0.0
        while position < n:
            out.append(int(position))
            position += factors[min(len(factors) - 1, int(position * len(factors) / n))]
        return out
    match = re.fullmatch(r'random:(\d+)', profile)
    if match:
        rng = random.Random(int(match.group(1)))
        out, position, t, pace = [], 0.0, 0, 1.0
        stop_at, stop = rng.randrange(n // 4, 3 * n // 4), rng.randrange(30, 151)
        while position < n:
            if t % 10 == 0:
                pace = rng.uniform(0.4, 2.5)
            out.append(int(position))
            if int(position) >= stop_at and stop > 0:
                out.extend([int(position)] * stop)
                stop = 0
            position += pace
            t += 1
        return out
    raise ValueError('unknown pace profile: ' + profile)


def images(folder):
    names = [f for f in os.listdir(folder) if f.lower().endswith(('.png', '.jpg', '.jpeg', '.pgm', '.ppm', '.bmp'))]
    natural = lambda s: [int(p) if p.isdigit() else p for p in re.split(r'(\d+)', s)]
    return [os.path.join(folder, f) for f in sorted(names, key=natural)]


def decisions(out):
    """out/run/decisions.csv as one dict a frame (openable_offline's columns), in frame order."""
    with open(os.path.join(out, 'run', 'decisions.csv')) as f:
        header = f.readline().strip().split(',')
        return [dict(zip(header, line.strip().split(','))) for line in f]


def write_trace(out, rows, first_places, second_places):
    """out/trace.csv from the frames' decisions (--trace)."""
    lines = ['frame,place,match,off,status,score,pace']
    for frame in range(len(first_places), len(rows)):
        row, place = rows[frame], second_places[frame - len(first_places)]
        match = int(row['match'])
        if match < 0:
            matched, off = '', ''
        elif match < len(first_places):
            matched, off = str(first_places[match]), str(first_places[match] - place)
        else:
            matched, off = 'own', ''
        lines.append(','.join([str(frame), str(place), matched, off, row['status'], row['score'], row['pace']]))
    with open(os.path.join(out, 'trace.csv'), 'w') as f:
        f.write('\n'.join(lines) + '\n')


def build_stream(args, profile, out):
    """Writes out/stream/ (symbolic links to the real frames) and out/pairs.txt; returns the places the stream's frames
    show (indices into each traversal, in order): the first traversal's and the second's."""
    first, second = images(args.first)[args.start:], images(args.second)[args.start:]
    n = min(len(first), len(second), args.frames or len(first))
    first_places = profile_indices(args.first_profile, n)
    second_places = profile_indices(profile, n)
    stream = os.path.join(out, 'stream')
    os.makedirs(stream, exist_ok=True)
    for name in os.listdir(stream):
        os.remove(os.path.join(stream, name))
    frames = [first[k] for k in first_places] + [second[k] for k in second_places]
    ext = lambda path: os.path.splitext(path)[1]
    for i, path in enumerate(frames):
        os.symlink(os.path.abspath(path), os.path.join(stream, 'frame%06d%s' % (i, ext(path))))
    total = len(frames)
    with open(os.path.join(out, 'pairs.txt'), 'w') as f:
        f.write('# shape=%dx%d\n' % (total, total))
        for q, k in enumerate(second_places):
            for m, place in enumerate(first_places):
                if abs(place - k) <= args.tolerance:
                    f.write('%d %d\n' % (len(first_places) + q, m))
    return first_places, second_places


# One profile's line as main() prints it (without --markdown).
LINE = re.compile(r'(\S+)\s+frames\s+\d+\s+published\s+(\d+)\s+wrong\s+(\d+)\s+precision\s+\S+\s+recall\s+(\S+)')


def evaluate(first, second, tolerance, config, out, profiles, bin_dir, jobs=2, sets=(), first_profile='1x', start=0,
             frames=0):
    """This script on one pair of traversals, in a process of its own (scripts/pace_sweep.py and pace_sets.py run
    many): [(profile, published, wrong, recall)]. Exits with the script's error output when it fails."""
    command = [sys.executable, os.path.abspath(__file__), '--bin', bin_dir, '--jobs', str(jobs), '--first', first,
               '--second', second, '--tolerance', str(tolerance), '--config', config, '--first-profile', first_profile,
               '--out', out, '--start', str(start), '--frames', str(frames)]
    for key_value in sets:
        command += ['--set', key_value]
    for profile in profiles:
        command += ['--profile', profile]
    run = subprocess.run(command, capture_output=True, text=True)
    if run.returncode != 0:
        sys.exit('pace_eval: %s then %s failed:\n%s' % (first, second, run.stderr[-2000:]))
    return [(m.group(1), int(m.group(2)), int(m.group(3)), float(m.group(4)))
            for m in map(LINE.match, run.stdout.splitlines()) if m]


def tool_environment(bin_dir):
    """The environment the tools in bin_dir run in: the libraries beside them come first. The tools find the core
    library through the RUNPATH of the workspace they were built in, so a copy of the tools from another build (to
    compare two builds) would otherwise run that workspace's current library, not its own."""
    env = dict(os.environ)
    env['LD_LIBRARY_PATH'] = os.path.abspath(bin_dir) + (':' + env['LD_LIBRARY_PATH'] if env.get('LD_LIBRARY_PATH') else '')
    return env


def run(args, profile):
    out = os.path.join(args.out, re.sub(r'[^A-Za-z0-9.]+', '_', profile))
    os.makedirs(out, exist_ok=True)
    first_places, second_places = build_stream(args, profile, out)
    frames = len(first_places) + len(second_places)
    command = [os.path.join(args.bin, 'openable_offline'), '--quiet', '--config', args.config,
               '--reference', os.path.join(out, 'stream'), '--output', os.path.join(out, 'run')]
    for assignment in args.set:
        command += ['--set', assignment]
    if args.camera_info:
        command += ['--camera-info', args.camera_info]
    env = tool_environment(args.bin)
    subprocess.run(command, check=True, stdout=subprocess.DEVNULL, env=env)
    subprocess.run([os.path.join(args.bin, 'openable_eval'), '--published', os.path.join(out, 'run', 'loop_closures.csv'),
                    '--pairs', os.path.join(out, 'pairs.txt'), '--frames', str(frames),
                    '--output', os.path.join(out, 'eval')], check=True, stdout=subprocess.DEVNULL, env=env)
    with open(os.path.join(out, 'eval', 'metrics.json')) as f:
        metrics = json.load(f)
    # decisions.csv is read only for what was asked: pace_sets.py and pace_sweep.py run thousands of profiles without.
    rows = decisions(out) if args.trace or args.misses else []
    if args.trace:
        write_trace(out, rows, first_places, second_places)
    return profile, frames, metrics, misses(out, rows) if args.misses else {}


def misses(out, rows):
    """Status counts of the frames with a true loop that got no right loop closure published."""
    truth = {}
    with open(os.path.join(out, 'pairs.txt')) as f:
        for line in f:
            if not line.startswith('#'):
                query, match = map(int, line.split())
                truth.setdefault(query, set()).add(match)
    counts = {}
    for row in rows:
        query, match = int(row['query']), int(row['match'])
        if query in truth and not (row['status'] == 'published' and match in truth[query]):
            status = row['status'] if row['status'] != 'published' else 'published_wrong'
            counts[status] = counts.get(status, 0) + 1
    return counts


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument('--first', required=True)
    parser.add_argument('--second', required=True)
    parser.add_argument('--config', required=True)
    parser.add_argument('--out', required=True)
    parser.add_argument('--profile', action='append', default=[])
    parser.add_argument('--first-profile', default='1x')
    parser.add_argument('--tolerance', type=int, default=2)
    parser.add_argument('--frames', type=int, default=0)
    parser.add_argument('--start', type=int, default=0)
    parser.add_argument('--misses', action='store_true')
    parser.add_argument('--trace', action='store_true')
    parser.add_argument('--bin', default=os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', 'build', 'ws',
                                                      'devel', 'lib', 'openable_ros'))
    parser.add_argument('--set', action='append', default=[])
    parser.add_argument('--camera-info', default='')
    parser.add_argument('--jobs', type=int, default=2)
    parser.add_argument('--markdown', action='store_true')
    args = parser.parse_args()
    profiles = args.profile or ['1x']
    for p in profiles + [args.first_profile]:
        profile_indices(p, 10)  # refuse an unknown profile before running anything
    with concurrent.futures.ThreadPoolExecutor(max_workers=args.jobs) as pool:
        results = list(pool.map(lambda p: run(args, p), profiles))
    for profile, frames, m, missed in results:
        published, wrong = int(m['published']), int(m['wrong'])
        precision = m['precision'] if published else 1.0
        where = ', '.join('%s %d' % (k, v) for k, v in sorted(missed.items(), key=lambda kv: -kv[1]))
        if args.markdown:
            print('| %s | %d / %d / %.3f / %.3f |%s' % (profile, published, wrong, precision, m['recall'],
                                                        ' %s |' % where if args.misses else ''))
        else:
            print('%-10s frames %5d  published %5d  wrong %4d  precision %.3f  recall %.3f%s'
                  % (profile, frames, published, wrong, precision, m['recall'],
                     '  misses: ' + where if args.misses else ''))
    sys.stdout.flush()


if __name__ == '__main__':
    main()
