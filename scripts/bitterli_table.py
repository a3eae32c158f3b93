#!/usr/bin/env python3
"""Per-scene table of `photon check` over Benedikt Bitterli's scenes in pbrt-v4 form.

Usage: scripts/bitterli_table.py PHOTON_BINARY BITTERLI_DIR
(BITTERLI_DIR holds <scene>/pbrt/scene-v4.pbrt, e.g. a checkout of github:gonsolo/bitterli;
never commit its files). Prints a Markdown table: scene, whether it loads, the first problem
that is not a file absent from the checkout, and how many problems are absent files.
"""
import glob, os, subprocess, sys

photon, root = sys.argv[1], sys.argv[2]
print('| scene | loads | first problem other than an absent file | absent files |')
print('|---|---|---|---|')
for path in sorted(glob.glob(os.path.join(root, '*', 'pbrt', 'scene-v4.pbrt'))):
    name = path.split(os.sep)[-3]
    out = subprocess.run([photon, 'check', path], capture_output=True, text=True).stdout
    problems = [l.strip() for l in out.splitlines() if l.startswith('  ') and 'note:' not in l]
    absent = [p for p in problems if 'No such file' in p or 'absent' in p]
    # Errors caused by an absent file (an unknown texture it defined) are not counted.
    other = [p for p in problems if p not in absent and 'unknown spectrum texture' not in p
             and 'unknown float texture' not in p]
    first = other[0].split(': ', 1)[1] if other else ''
    where = other[0].split(': ', 1)[0].rsplit('/', 1)[-1] if other else ''
    status = 'yes' if not problems else 'no'
    print(f'| {name} | {status} | {where + " " + first if other else "-"} | {len(absent)} |')
