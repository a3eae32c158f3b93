#!/usr/bin/env python3
"""Independent references for scenes/cornell-glass.pbrt and scenes/cornell-textured.pbrt, rendered
by Mitsuba 3 (llvm_ad_rgb, `path`).

Renders --xml (cornell-glass.xml by default, next to this script) in passes of PASS_SPP samples per pixel, each with its
own seed, accumulates them in float64 and, after every pass, rewrites
  OUT.exr   the mean of all passes (float32 RGB EXR), so a partial result is always usable, and
  OUT.json  spp, seconds, Mitsuba version, variant and the reference's estimated own relMSE.
Passes alternate between two independent halves A and B; with nA, nB passes in each,
  est_relmse_of_reference = relMSE(A, B) * nA*nB / (nA+nB)^2     (= relMSE(A, B)/4 when nA = nB),
relMSE(x, ref) = mean((x - ref)^2 / (ref^2 + 0.01)) with ref = the mean of all passes (as `photon compare`).
It stops when the next pass would not fit in the time budget.

Reproduce (what was run; ~25 min on a shared 2-core machine, nice'd):
  python3 -m venv venv && venv/bin/pip install mitsuba==3.9.1 numpy
  nice -n 10 venv/bin/python render_reference.py --minutes 25 \
      --out /work/mitsuba-ref/cornell-glass-reference --json cornell-glass-reference.json
  nice -n 5 venv/bin/python render_reference.py --xml cornell-textured.xml --res 64 \
      --pass-spp 4096 --minutes 6 --out cornell-textured-reference-64   (49152 spp, 158 s)
  nice -n 15 venv/bin/python render_reference.py --xml glass-on-metal.xml --res 128 \
      --pass-spp 4096 --minutes 14 --out glass-on-metal-reference-128   (389120 spp, 836 s)
LLVM: Dr.Jit needs a recent libLLVM. The system's LLVM 14/15 failed here ("LLVM ERROR: Cannot
select: fminimum"), so DRJIT_LIBLLVM_PATH is pointed at rustup's libLLVM 22 when it is not set.
"""
import argparse, glob, json, os, time

if 'DRJIT_LIBLLVM_PATH' not in os.environ:
    cands = sorted(glob.glob(os.path.expanduser('~/.rustup/toolchains/stable-*/lib/libLLVM.so.*')))
    if cands:
        os.environ['DRJIT_LIBLLVM_PATH'] = cands[-1]

import numpy as np
import mitsuba as mi

ap = argparse.ArgumentParser()
ap.add_argument('--minutes', type=float, default=25.0, help='wall-time budget')
ap.add_argument('--max-spp', type=int, default=1 << 20)
ap.add_argument('--pass-spp', type=int, default=256)
ap.add_argument('--res', type=int, default=256)
ap.add_argument('--seed0', type=int, default=1000, help='pass i uses seed seed0 + i')
ap.add_argument('--variant', default='llvm_ad_rgb')
ap.add_argument('--xml', default='cornell-glass.xml', help='scene, relative to this script')
ap.add_argument('--out', default='cornell-glass-reference', help='EXR path without .exr')
ap.add_argument('--json', default=None, help='JSON path (default: OUT.json)')
args = ap.parse_args()

mi.set_variant(args.variant)
xml = os.path.join(os.path.dirname(os.path.abspath(__file__)), args.xml)
t0 = time.time()
scene = mi.load_file(xml, res=str(args.res), spp=str(args.pass_spp))


def write(sums, counts, wall, render_s, passes):
    mean = (sums[0] + sums[1]) / (counts[0] + counts[1])
    tmp = args.out + '.tmp.exr'
    mi.Bitmap(mean.astype(np.float32), mi.Bitmap.PixelFormat.RGB).write(tmp)
    os.replace(tmp, args.out + '.exr')
    info = {
        'renderer': f'mitsuba {mi.__version__} {args.variant} path',
        'scene': f'scenes/mitsuba/{args.xml} (= scenes/{args.xml[:-4]}.pbrt)',
        'mitsuba_version': mi.__version__,
        'variant': args.variant,
        'max_depth': 9,
        'resolution': [args.res, args.res],
        'spp': passes * args.pass_spp,
        'passes': passes,
        'pass_spp': args.pass_spp,
        'seeds': [args.seed0, args.seed0 + passes - 1],
        'wall_seconds': wall,
        'render_seconds': render_s,
        'llvm': os.environ.get('DRJIT_LIBLLVM_PATH', ''),
        'mean_rgb': mean.reshape(-1, 3).mean(axis=0).tolist(),
    }
    if counts[0] and counts[1]:
        a, b = sums[0] / counts[0], sums[1] / counts[1]
        k = counts[0] * counts[1] / (counts[0] + counts[1]) ** 2
        info['halves_spp'] = [counts[0] * args.pass_spp, counts[1] * args.pass_spp]
        info['relmse_half_a_vs_half_b'] = float(np.mean((a - b) ** 2 / (mean ** 2 + 0.01)))
        info['est_relmse_of_reference'] = info['relmse_half_a_vs_half_b'] * k
        info['est_rmse_of_reference'] = float(np.sqrt(np.mean((a - b) ** 2) * k))
    with open(args.json or args.out + '.json', 'w') as f:
        json.dump(info, f, indent=2)
    return info


sums = [np.zeros((args.res, args.res, 3)), np.zeros((args.res, args.res, 3))]
counts = [0, 0]
render_s, last, i = 0.0, 0.0, 0
budget = args.minutes * 60
while (i + 1) * args.pass_spp <= args.max_spp and time.time() - t0 + last * 1.1 < budget:
    t = time.time()
    img = np.array(mi.render(scene, seed=args.seed0 + i), dtype=np.float64)[..., :3]
    last = time.time() - t
    render_s += last
    sums[i % 2] += img
    counts[i % 2] += 1
    i += 1
    info = write(sums, counts, time.time() - t0, render_s, i)
    print(f"pass {i}: {info['spp']} spp, {info['wall_seconds']:.0f} s, "
          f"est relMSE {info.get('est_relmse_of_reference', float('nan')):.3g}", flush=True)
