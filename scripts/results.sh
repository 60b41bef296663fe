#!/usr/bin/env bash
# Regenerates the tables of doc/results.md (and, with --plots, the PR plots in doc/images/) with
# openable_offline + openable_eval on ../shared/data (Gardens Point Walking, Nordland summer/winter).
#
#   scripts/results.sh [--plots] [--out DIR] [--bin DIR] [--only main|explore|recommended]
#
#   --bin DIR   folder holding openable_offline and openable_eval (default: the first of
#               devel/lib/openable_ros of a catkin workspace above or beside the package, or PATH)
#   --out DIR   work folder for the matrices and metrics (default: /tmp/openable_results); runs already
#               present there are reused, delete it to start afresh
#   --plots     also write the PR plots of doc/results.md into doc/images/
#
# Sequential on purpose (one run at a time): about 30-45 minutes for everything on a shared 2-core
# machine (the main tables ~25, --only explore ~15, recommended + plots ~2).
# Prints the Markdown tables on stdout. Needs python3 (standard library only).
set -euo pipefail
{ # read whole before running: the script can be edited while it runs
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
out=/tmp/openable_results
bin=""
plots=0
only=all
while [[ $# -gt 0 ]]; do
  case "$1" in
    --plots) plots=1; shift ;;
    --out) out="$2"; shift 2 ;;
    --bin) bin="$2"; shift 2 ;;
    --only) only="$2"; shift 2 ;;
    -h|--help) sed -n 2,14p "$0"; exit 0 ;;
    *) echo "unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done
if [[ -z "$bin" ]]; then
  for candidate in "$here"/../../devel/lib/openable_ros "$here"/../../../devel/lib/openable_ros \
                   "$here"/build/*/devel/lib/openable_ros; do
    if [[ -x "$candidate/openable_offline" && -x "$candidate/openable_eval" ]]; then bin="$candidate"; break; fi
  done
fi
if [[ -n "$bin" ]]; then offline="$bin/openable_offline"; evaluate="$bin/openable_eval"
else offline="$(command -v openable_offline)"; evaluate="$(command -v openable_eval)"; fi
data="$here/../shared/data"
[[ -d "$data/gardens_point" && -d "$data/nordland" ]] || { echo "no ../shared/data beside the package" >&2; exit 1; }
mkdir -p "$out"

OFFLINE="$offline" EVALUATE="$evaluate" DATA="$data" OUT="$out" ROOT="$here" PLOTS="$plots" ONLY="$only" \
python3 - <<'PYTHON'
import hashlib, json, os, subprocess, sys

OFFLINE, EVALUATE, DATA, OUT, ROOT = (os.environ[k] for k in ('OFFLINE', 'EVALUATE', 'DATA', 'OUT', 'ROOT'))
PLOTS, ONLY = os.environ['PLOTS'] == '1', os.environ['ONLY']
DEFAULT = ROOT + '/config/paper.yaml'  # the paper's defaults: the baseline of every table
GP, NL = DATA + '/gardens_point', DATA + '/nordland'
# name: (reference, query, tolerance T)
PAIRS = {
    'day_left -> day_right': (GP + '/day_left', GP + '/day_right', 2),
    'day_right -> night_right': (GP + '/day_right', GP + '/night_right', 2),
    'day_left -> night_right': (GP + '/day_left', GP + '/night_right', 2),
    'Nordland summer -> winter': (NL + '/summer', NL + '/winter', 1),
}
GARDENS = [p for p in PAIRS if not p.startswith('Nordland')]
NORDLAND = 'Nordland summer -> winter'
DESCRIPTORS = ['LDB', 'BRIEF', 'BRISK', 'ORB', 'FREAK', 'SIFT', 'SURF', 'HOG']


def run(pair, sets, config=DEFAULT):
    """openable_offline + openable_eval (all queries, and near-black queries masked on Nordland)."""
    ref, query, tolerance = PAIRS[pair]
    key = hashlib.md5(json.dumps([pair, sorted(sets.items()), os.path.basename(config)]).encode()).hexdigest()[:12]
    folder = os.path.join(OUT, key)
    if not os.path.exists(folder + '/timings.json'):
        cmd = [OFFLINE, '--config', config, '--reference', ref, '--query', query, '--output', folder]
        for k, v in sets.items():
            cmd += ['--set', f'{k}={v}']
        subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
    result = {'dir': folder}
    for masked in ([False, True] if pair == NORDLAND else [False]):
        ev = folder + ('/eval_masked' if masked else '/eval')
        if not os.path.exists(ev + '/metrics.json'):
            cmd = [EVALUATE, '--matrix', folder, '--tolerance', str(tolerance), '--output', ev]
            if masked:
                cmd += ['--mask-dark', query]
            subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
        result['masked' if masked else 'all'] = json.load(open(ev + '/metrics.json'))
    t = json.load(open(folder + '/timings.json'))
    # Time per query frame without image decoding: preprocessing + description + matching.
    result['ms'] = sum(t[k]['per_frame_ms'] for k in ('preprocess', 'describe', 'match'))
    return result


def cells(r, which='all'):
    m = r[which]
    return [f"{m['recall_at_1']:.3f}", f"{m['auc']:.3f}", f"{m['max_recall_at_100_precision']:.3f}"]


def table(header, rows):
    print('| ' + ' | '.join(header) + ' |')
    print('|' + '---|' * len(header))
    for row in rows:
        print('| ' + ' | '.join(str(c) for c in row) + ' |')
    print()


# Preprocessing per descriptor for the main table, chosen on day_right -> night_right (explore section):
# patch 64; SeqSLAM-style patch normalisation of 8x8 blocks for every descriptor but HOG, whose own block
# normalisation does better without it. Nordland frames are 64x32: patch 32, no patch normalisation
# (it lowered recall@1 for HOG, LDB and SIFT at every L tried, explore section).
def gardens_sets(d, L, inv):
    return dict(descriptor=d, patch_size=64, patch_normalization=0 if d == 'HOG' else 8,
                sequence_length=L, illumination_invariance=str(inv).lower())


def nordland_sets(d, L, inv):
    return dict(descriptor=d, patch_size=32, patch_normalization=0,
                sequence_length=L, illumination_invariance=str(inv).lower())


GARDENS_L = [1, 20]
NORDLAND_L = [1, 50]

if ONLY in ('all', 'main'):
    print('### Every descriptor, Gardens Point (T = 2)\n')
    print('recall@1 / AUC / max recall at 100 % precision; ms = preprocessing + description + matching per query frame.\n')
    rows = []
    for d in DESCRIPTORS:
        for L in GARDENS_L:
            for inv in (False, True):
                row = [d, L, 'on' if inv else 'off']
                ms = []
                for pair in GARDENS:
                    r = run(pair, gardens_sets(d, L, inv))
                    row += [' / '.join(cells(r))]
                    ms.append(r['ms'])
                row.append(f'{sum(ms) / len(ms):.2f}')
                rows.append(row)
                print('  ', row, file=sys.stderr, flush=True)
    table(['descriptor', 'L', 'invariance'] + GARDENS + ['ms/frame'], rows)

    print('### Every descriptor, Nordland summer -> winter (T = 1, 1800 frames)\n')
    rows = []
    for d in DESCRIPTORS:
        for L in NORDLAND_L:
            for inv in (False, True):
                r = run(NORDLAND, nordland_sets(d, L, inv))
                rows.append([d, L, 'on' if inv else 'off', ' / '.join(cells(r)), ' / '.join(cells(r, 'masked')),
                             f"{r['ms']:.3f}"])
                print('  ', rows[-1], file=sys.stderr, flush=True)
    table(['descriptor', 'L', 'invariance', 'all queries', 'near-black queries masked', 'ms/frame'], rows)

def eval_with_mask(folder, pair, mask, name):
    """openable_eval with an explicit query mask (list of 0/1), e.g. near-black frames and the warm-up."""
    ev = folder + '/eval_' + name
    if not os.path.exists(ev + '/metrics.json'):
        os.makedirs(ev, exist_ok=True)
        with open(ev + '/mask.txt', 'w') as f:
            f.write(''.join(f'{int(v)}\n' for v in mask))
        subprocess.run([EVALUATE, '--matrix', folder, '--tolerance', str(PAIRS[pair][2]), '--mask', ev + '/mask.txt',
                        '--output', ev], check=True, stdout=subprocess.DEVNULL)
    return json.load(open(ev + '/metrics.json'))


def normalise_rows(src, dst, window):
    """Each row divided by its second-best distance outside +-window frames of the best one: the row
    minimum becomes best / second best = 1 - uniqueness (LoopDetector's min_uniqueness rule), so
    openable_eval then ranks the queries by uniqueness instead of by raw distance."""
    import array, ast, math
    b = open(src, 'rb').read()
    hl = int.from_bytes(b[8:10], 'little')
    h = ast.literal_eval(b[10:10 + hl].decode())
    assert h['descr'] == '<f4' and not h['fortran_order'], h
    a = array.array('f')
    a.frombytes(b[10 + hl:])
    r, c = h['shape']
    for i in range(r):
        row = a[i * c:(i + 1) * c]
        v = [(x, j) for j, x in enumerate(row) if not math.isnan(x)]
        if not v:
            continue
        d, j = min(v)
        second = min((x for x, k in v if abs(k - j) > window), default=float('nan'))
        s = second if second > 0 else float('nan')
        for k in range(c):
            a[i * c + k] = row[k] / s
    os.makedirs(os.path.dirname(dst), exist_ok=True)
    open(dst, 'wb').write(b[:10 + hl] + a.tobytes())


def dark_mask(result):
    lines = [l.strip() for l in open(result['dir'] + '/eval_masked/query_mask.txt') if l.strip() and not l.startswith('#')]
    return [l == '1' for l in lines]


def config_value(path, key):
    for line in open(path):
        if line.split('#')[0].strip().startswith(key + ':'):
            return line.split('#')[0].split(':', 1)[1].strip()
    raise KeyError(key)


if ONLY in ('all', 'recommended'):
    print('### Recommended configurations\n')
    print('warm-up = the first L - 1 queries (partial sequences) also left out of the evaluation.\n')
    rows = []
    for config, pairs in (('gardens_point.yaml', GARDENS), ('nordland.yaml', [NORDLAND])):
        path = ROOT + '/config/' + config
        L = int(config_value(path, 'sequence_length'))
        for pair in pairs:
            r = run(pair, {}, path)
            n = r['all']['evaluated_queries'] + r['all']['masked_queries']
            rows.append([config, pair, 'all queries'] + cells(r) + [f"{r['ms']:.2f}"])
            if pair == NORDLAND:
                rows.append([config, pair, 'near-black masked'] + cells(r, 'masked') + [''])
                base = dark_mask(r)
            else:
                base = [True] * n
            warm = [ok and i >= L - 1 for i, ok in enumerate(base)]
            m = eval_with_mask(r['dir'], pair, warm, 'warmup')
            rows.append([config, pair, ('near-black and ' if pair == NORDLAND else '') + 'warm-up masked',
                         f"{m['recall_at_1']:.3f}", f"{m['auc']:.3f}", f"{m['max_recall_at_100_precision']:.3f}", ''])
            unique = r['dir'] + '/uniqueness'
            if not os.path.exists(unique + '/distance_matrix.npy'):
                normalise_rows(r['dir'] + '/distance_matrix.npy', unique + '/distance_matrix.npy',
                               int(config_value(path, 'uniqueness_window')))
            for label, mask in (('', base), (' and warm-up', warm)):
                m = eval_with_mask(unique, pair, mask, 'mask' + label.replace(' and ', '_'))
                rows.append([config, pair, 'ranked by uniqueness' + (', near-black' if pair == NORDLAND else '') +
                             (label if label else '') + (' masked' if pair == NORDLAND or label else ''),
                             f"{m['recall_at_1']:.3f}", f"{m['auc']:.3f}", f"{m['max_recall_at_100_precision']:.3f}", ''])
    table(['config', 'pair', 'queries', 'recall@1', 'AUC', 'max recall @ 100 % precision', 'ms/frame'], rows)

if ONLY in ('all', 'explore'):
    print('### Exploration on day_right -> night_right (T = 2), recall@1 / AUC / max recall at 100 % precision\n')
    rows = []
    for d in DESCRIPTORS:
        for ps in (32, 64):
            for pn in (0, 8):
                row = [d, ps, pn]
                for L in (1, 10, 20):
                    r = run('day_right -> night_right', dict(descriptor=d, patch_size=ps, patch_normalization=pn,
                                                              sequence_length=L))
                    row.append(' / '.join(cells(r)))
                rows.append(row)
                print('  ', row, file=sys.stderr, flush=True)
    table(['descriptor', 'patch', 'patch_normalization', 'L = 1', 'L = 10', 'L = 20'], rows)

if PLOTS:
    images = ROOT + '/doc/images'
    os.makedirs(images, exist_ok=True)

    def overlay(file, title, pair, runs, masked=False):
        cmd = [EVALUATE, '--tolerance', str(PAIRS[pair][2]), '--output', os.path.join(OUT, 'plot_' + file),
               '--title', title]
        for name, sets, config, *of in runs:  # optional 4th item: the pair of that run (same T and size)
            cmd += ['--matrix', run(of[0] if of else pair, sets, config)['dir'], '--name', name]
        if masked:
            cmd += ['--mask-dark', PAIRS[pair][1]]
        subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
        shutil.copy(os.path.join(OUT, 'plot_' + file, 'pr_curve.png'), os.path.join(images, file + '.png'))

    import shutil
    for pair, file in (('day_right -> night_right', 'pr_day_right_night_right_L20'),
                       ('day_left -> night_right', 'pr_day_left_night_right_L20'),
                       ('day_left -> day_right', 'pr_day_left_day_right_L20')):
        overlay(file, pair + ', every descriptor, L = 20, T = 2', pair,
                [(d, gardens_sets(d, 20, False), DEFAULT) for d in DESCRIPTORS])
    overlay('pr_day_right_night_right_hog_L', 'day_right -> night_right, HOG patch 128, T = 2', 'day_right -> night_right',
            [(f'L = {L}', dict(descriptor='HOG', patch_size=128, patch_normalization=0, sequence_length=L), DEFAULT)
             for L in (1, 10, 20, 30)])
    overlay('pr_gardens_point_recommended', 'config/gardens_point.yaml (HOG, patch 128, L = 20), T = 2',
            'day_right -> night_right', [(p, {}, ROOT + '/config/gardens_point.yaml', p) for p in GARDENS])
    overlay('pr_nordland_L50_masked', 'Nordland summer -> winter, L = 50, T = 1, near-black masked', NORDLAND,
            [(d, nordland_sets(d, 50, False), DEFAULT) for d in DESCRIPTORS], masked=True)
    overlay('pr_nordland_hog_L_masked', 'Nordland summer -> winter, HOG patch 32, T = 1, near-black masked', NORDLAND,
            [(f'L = {L}', dict(descriptor='HOG', patch_size=32, patch_normalization=0, sequence_length=L), DEFAULT)
             for L in (1, 20, 50, 100)], masked=True)
    print('PR plots written to doc/images/', file=sys.stderr)
PYTHON
exit
}
