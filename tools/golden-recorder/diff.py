#!/usr/bin/env python3
"""Diff recorded golden episodes field by field.

  diff.py A.json.gz B.json.gz            # one pair
  diff.py DIR_A DIR_B [prefix]           # every file of DIR_A that DIR_B also has

Exact comparison: same keys (and key order, reported separately), same JSON types (int vs float
vs bool vs null), doubles equal bit for bit; observation vectors (`obs`) compared as float32.
header.generator is ignored.  Differences are grouped by field pattern (list indices -> [*],
step number -> steps[*]) with the first few examples.
"""
import gzip
import json
import os
import re
import sys
from collections import OrderedDict, defaultdict

import numpy as np

IGNORE = {"header.generator"}


def load(path):
    with gzip.open(path, 'rt', encoding='utf-8') as f:
        text = f.read()
    return text, json.loads(text, object_pairs_hook=OrderedDict)


def jtype(v):
    if v is None:
        return 'null'
    if isinstance(v, bool):
        return 'bool'
    if isinstance(v, int):
        return 'int'
    if isinstance(v, float):
        return 'float'
    if isinstance(v, str):
        return 'str'
    if isinstance(v, list):
        return 'list'
    return 'dict'


def compare(a, b, path, out, in_obs=False):
    if path in IGNORE:
        return
    ta, tb = jtype(a), jtype(b)
    if ta != tb:
        out.append((path, 'type %s vs %s: %s | %s' % (ta, tb, short(a), short(b))))
        return
    if ta == 'dict':
        ka, kb = list(a.keys()), list(b.keys())
        if set(ka) != set(kb):
            out.append((path, 'keys only in A %s, only in B %s' % (
                sorted(set(ka) - set(kb)), sorted(set(kb) - set(ka)))))
        elif ka != kb:
            out.append((path + '{order}', 'key order %s vs %s' % (ka, kb)))
        for k in ka:
            if k in b:
                compare(a[k], b[k], path + '.' + k if path else k, out, in_obs or k == 'obs')
    elif ta == 'list':
        if len(a) != len(b):
            out.append((path, 'length %d vs %d' % (len(a), len(b))))
        for i, (x, y) in enumerate(zip(a, b)):
            compare(x, y, '%s[%d]' % (path, i), out, in_obs)
    elif ta == 'float' and in_obs:
        if np.float32(a).tobytes() != np.float32(b).tobytes():
            out.append((path, '%r vs %r (f32)' % (a, b)))
    elif ta == 'float':
        if a != b and not (a != a and b != b):
            out.append((path, '%r vs %r (diff %.3g)' % (a, b, a - b)))
    elif a != b:
        out.append((path, '%r vs %r' % (a, b)))


def short(v):
    s = json.dumps(v)
    return s if len(s) < 80 else s[:77] + '...'


def pattern(path):
    p = re.sub(r'^steps\[\d+\]', 'steps[*]', path)
    p = re.sub(r'\[\d+\]', '[*]', p)
    p = re.sub(r'\.(human_vel|goals|slot_of)\.\d+', r'.\1.*', p)
    return p


def diff_files(fa, fb, verbose=3):
    ta, a = load(fa)
    tb, b = load(fb)
    out = []
    compare(a, b, '', out)
    same_bytes = ta == tb
    groups = defaultdict(list)
    for p, msg in out:
        groups[pattern(p)].append((p, msg))
    return same_bytes, out, groups


def main():
    a, b = sys.argv[1], sys.argv[2]
    prefix = sys.argv[3] if len(sys.argv) > 3 else ''
    if os.path.isdir(a):
        names = sorted(n for n in os.listdir(a) if n.endswith('.json.gz') and n.startswith(prefix)
                       and os.path.exists(os.path.join(b, n)))
        pairs = [(os.path.join(a, n), os.path.join(b, n)) for n in names]
    else:
        pairs = [(a, b)]
    n_exact = 0
    n_bytes = 0
    for fa, fb in pairs:
        same_bytes, out, groups = diff_files(fa, fb)
        n_bytes += same_bytes
        n_exact += not out
        name = os.path.basename(fa)
        if not out:
            print('%s: IDENTICAL%s' % (name, ' (byte-identical JSON)' if same_bytes else ' (values; text differs)'))
            continue
        print('%s: %d differences in %d fields' % (name, len(out), len(groups)))
        for pat, items in groups.items():
            print('   %-60s %5d  e.g. %s: %s' % (pat, len(items), items[0][0], items[0][1]))
    print('SUMMARY: %d/%d files identical in every field (%d byte-identical)' % (n_exact, len(pairs), n_bytes))
    sys.exit(0 if n_exact == len(pairs) else 1)


if __name__ == '__main__':
    main()
