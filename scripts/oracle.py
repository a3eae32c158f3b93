#!/usr/bin/env python3
"""pbrt-v4 as the oracle: render a scene with pbrt-v4 and photon at the same size and pixel
filter, and compare the images (issue 17). Not part of CI; needs `pip install OpenEXR numpy
pillow` and a pbrt-v4 built from ../shared/peers/pbrt-v4/.

Subcommands (SCENE is a pbrt-v4 file; variants are written next to it so that relative paths
resolve, named `_oracle-<res>.pbrt`; nothing is written into this repository):

  variant SCENE --res 128            the file with a 0.5-px box filter and the long side 128
  pbrt    SCENE --res 128 --spp N [--integrator path|bdpt|sppm|...] -o OUT.exr [--pbrt BIN]
          renders the variant with pbrt-v4 (2 threads) and prints the wall time
  photon  SCENE --res 128 --time 30s -o OUT.exr [--photon BIN] [--flags '...']
  refs    DIR SCENE... --res 128 --chunk-minutes 5 --rounds N [--integrator X]
          converged references by rounds: each round renders every scene once more with a new
          seed for about --chunk-minutes (spp from a first 16-spp timing), and DIR/<scene>/ref.exr
          is the mean of its chunks so far; ref.json holds spp, seconds and the reference's own
          relMSE (chunk variance / chunks). The file's integrator (its own line for sppm; others -> bdpt).
  table   REFDIR SCENE... --res 128 --seconds 30 [--seeds 2] [--out DIR] [--integrators path,bdpt,sppm]
          [--flags '...']...
          for each scene with a reference REFDIR/<scene>/ref.exr: photon `render --time` once per
          --flags (relMSE,
          the relMSE of its 3x3-median-filtered image: far below relMSE means fireflies), and each
          pbrt-v4 integrator at the spp that fills the same wall time (from 4- and 32-spp
          timings, process wall time both), all against the reference; prints a Markdown row
          per scene (relMSE means over seeds, mean ratio, wall seconds; the ratio of pbrt-v4's
          best to photon's best, also with the reference's own relMSE from ref.json taken off
          both) and appends JSON lines to DIR/table.jsonl
  compare IMAGE.exr REFERENCE.exr [--blocks 8] [--diff DIFF.png] [--side SIDE.png] [--json]
          relMSE = mean((x - r)^2 / (r^2 + 0.01)) over pixels and channels; the same with the
          worst 0.1% of pixels left out ("trimmed"); relMSE of the 3x3-median-filtered image
          (fireflies: the plain value far above this one); mean luminance ratio; the mean
          luminance ratio of each block of an NxN grid (printed as a table, '*' where it is
          off by more than 10%); DIFF.png: log2(x / r) per pixel, blue -1 .. red +1 stop;
          SIDE.png: image, reference and diff side by side (sRGB, same exposure).

  patch   REF.exr CROP.exr... --bounds X0,X1,Y0,Y1 -o OUT.exr [--full 1024]
          a reference with the window [X0,X1) x [Y0,Y1) replaced by the mean of CROP renders of
          that window (pbrt-v4 `--pixelbounds`), where the reference is not converged (a
          caustic seen through glass that only emission hits sample); --full N first
          box-filters REF down to N/(its width); prints each pixel's standard error from the
          spread of the crops

Example:
  scripts/oracle.py pbrt   ~/bitterli/ph/classroom/pbrt/scene-v4.pbrt --spp 4096 -o ref.exr
  scripts/oracle.py photon ~/bitterli/ph/classroom/pbrt/scene-v4.pbrt --time 30s -o ours.exr
  scripts/oracle.py compare ours.exr ref.exr --side side.png
"""
import argparse, json, os, re, shlex, subprocess, sys, time

import numpy as np
import signal

signal.signal(signal.SIGPIPE, signal.SIG_DFL)

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
DEFAULT_PBRT = os.path.join(os.path.dirname(ROOT), "pbrt-build", "build", "pbrt")
DEFAULT_PHOTON = os.path.join(ROOT, "target", "release", "photon")


def read_exr(path):
    """The RGB (beauty) channels of an EXR as float64 HxWx3."""
    import OpenEXR
    with OpenEXR.File(path) as f:
        ch = f.channels()
        if "RGB" in ch:
            return ch["RGB"].pixels.astype(np.float64)
        if "RGBA" in ch:
            return ch["RGBA"].pixels[..., :3].astype(np.float64)
        raise SystemExit(f"{path}: no R, G, B channels (has {sorted(ch)})")


def luminance(im):
    return im[..., 0] * 0.2126 + im[..., 1] * 0.7152 + im[..., 2] * 0.0722


def film_resolution(text):
    text = "\n".join(line.split("#", 1)[0] for line in text.splitlines())

    def get(name):
        m = re.search(r'"integer %s"\s*\[?\s*(\d+)' % name, text)
        return int(m.group(1)) if m else None
    return get("xresolution") or 1280, get("yresolution") or 720


def variant(scene, res):
    """Writes (once) the variant of SCENE with a 0.5-px box filter and the long side `res`."""
    text = open(scene).read()
    w, h = film_resolution(text[: text.index("WorldBegin")])
    if w >= h:
        w, h = res, max(1, round(h * res / w))
    else:
        w, h = max(1, round(w * res / h)), res
    out = os.path.join(os.path.dirname(os.path.abspath(scene)), f"_oracle-{res}.pbrt")
    mv = os.path.join(os.path.dirname(ROOT), "shared", "peers", "pbrt-v4", "make_variant.py")
    subprocess.run([sys.executable, mv, scene, out, "--res", f"{w}x{h}"], check=True)
    drop_empty_meshes(out)
    return out


def drop_empty_meshes(path):
    """Comments out `plymesh` shapes whose file holds no vertex: the stand-ins that
    ../shared/tools/repair_bitterli.py writes for absent meshes load in photon (an empty
    mesh) but pbrt-v4 refuses them, so both renderers get the variant without them."""
    text = open(path).read()
    base = os.path.dirname(path)
    pat = re.compile(r'Shape\s+"plymesh"\s*\n?\s*"string filename"\s*\[?\s*"([^"]+)"\s*\]?')

    def empty(name):
        f = os.path.join(base, name)
        try:
            head = open(f, "rb").read(4096)
        except OSError:
            return False
        m = re.search(rb"element vertex (\d+)", head)
        return m is not None and int(m.group(1)) == 0

    out = pat.sub(lambda m: "# (empty stand-in dropped) " + m.group(0).replace("\n", " ")
                  if empty(m.group(1)) else m.group(0), text)
    if out != text:
        open(path, "w").write(out)


def run_timed(cmd):
    t = time.time()
    r = subprocess.run(cmd, capture_output=True, text=True)
    dt = time.time() - t
    if r.returncode != 0:
        sys.stderr.write(r.stdout[-2000:] + r.stderr[-2000:])
        raise SystemExit(f"{cmd[0]} failed with exit code {r.returncode}")
    return dt, r


def cmd_pbrt(a):
    v = variant(a.scene, a.res)
    src = v
    if a.integrator:
        src = v.replace(".pbrt", f"-{a.integrator}.pbrt")
        text = open(v).read()
        m = re.search(r'"integer maxdepth"\s*\[\s*(\d+)\s*\]', text[: text.index("WorldBegin")])
        depth = m.group(1) if m else "5"
        mv = os.path.join(os.path.dirname(ROOT), "shared", "peers", "pbrt-v4", "make_variant.py")
        w, h = film_resolution(text[: text.index("WorldBegin")])
        subprocess.run([sys.executable, mv, v, src, "--res", f"{w}x{h}", "--integrator",
                        f'Integrator "{a.integrator}" "integer maxdepth" [ {depth} ]'],
                       check=True)
    cmd = [a.pbrt, "--nthreads", str(a.threads), "--spp", str(a.spp), "--outfile",
           os.path.abspath(a.o), src]
    dt, r = run_timed(cmd)
    print(json.dumps({"renderer": "pbrt-v4", "integrator": a.integrator or "file",
                      "spp": a.spp, "seconds": round(dt, 2), "out": a.o}))


def cmd_photon(a):
    v = variant(a.scene, a.res)
    cmd = [a.photon, "render", v, "--time", a.time, "--threads", str(a.threads), "-o",
           os.path.abspath(a.o), "--no-png"] + shlex.split(a.flags)
    dt, r = run_timed(cmd)
    print(json.dumps({"renderer": "photon", "time": a.time, "seconds": round(dt, 2),
                      "out": a.o}))


def write_exr(path, im):
    import OpenEXR
    hdr = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    tmp = path + ".tmp.exr"
    with OpenEXR.File(hdr, {"RGB": im.astype(np.float32)}) as f:
        f.write(tmp)
    os.replace(tmp, path)


def file_integrator(text):
    m = re.search(r'^Integrator\s+"(\w+)"', text, re.M)
    name = m.group(1) if m else "path"
    # sppm stays (consistent, and bdpt's caustic fireflies leave its chunk means unstable: two
    # 3-minute chunks of water-caustic differed by 14%); the file's own line keeps its radius.
    return "bdpt" if name in ("photonmap", "lightpath", "mlt") else name


def cmd_refs(a):
    os.makedirs(a.dir, exist_ok=True)
    failed = set()
    for rnd in range(a.rounds):
        for scene in a.scenes:
            if scene in failed:
                continue
            try:
                ref_round(a, scene)
            except SystemExit as e:
                print(f"{scene}: {e}; left out", flush=True)
                failed.add(scene)


def ref_round(a, scene):
    if True:
        if True:
            name = os.path.basename(os.path.dirname(os.path.dirname(os.path.abspath(scene))))
            d = os.path.join(a.dir, name)
            os.makedirs(d, exist_ok=True)
            meta_path = os.path.join(d, "ref.json")
            meta = json.load(open(meta_path)) if os.path.exists(meta_path) else {"chunks": []}
            text = open(scene).read()
            integ = a.integrator or file_integrator(text)
            v = variant(scene, a.res)
            src = v.replace(".pbrt", f"-{integ}.pbrt")
            if integ == "sppm":
                src = v
            m = re.search(r'"integer maxdepth"\s*\[\s*(\d+)\s*\]', text[: text.index("WorldBegin")])
            depth = m.group(1) if m else "5"
            mv = os.path.join(os.path.dirname(ROOT), "shared", "peers", "pbrt-v4", "make_variant.py")
            w, h = film_resolution(open(v).read().split("WorldBegin")[0])
            if src != v:
                subprocess.run([sys.executable, mv, v, src, "--res", f"{w}x{h}", "--integrator",
                                f'Integrator "{integ}" "integer maxdepth" [ {depth} ]'], check=True)
            if "spp_per_chunk" not in meta:
                out = os.path.join(d, "timing.exr")
                dt, _ = run_timed([a.pbrt, "--nthreads", "2", "--spp", "16", "--seed", "999",
                                   "--outfile", out, src])
                meta["spp_per_chunk"] = max(16, int(16 * a.chunk_minutes * 60 / max(dt, 0.1)) // 16 * 16)
                meta["integrator"] = integ
            k = len(meta["chunks"])
            out = os.path.join(d, f"chunk-{k:03d}.exr")
            dt, _ = run_timed([a.pbrt, "--nthreads", "2", "--spp", str(meta["spp_per_chunk"]),
                               "--seed", str(k), "--outfile", out, src])
            meta["chunks"].append({"file": os.path.basename(out), "seconds": round(dt, 1),
                                   "spp": meta["spp_per_chunk"]})
            # The next chunk's size from this one's time (the machine's load varies).
            want = meta["spp_per_chunk"] * a.chunk_minutes * 60 / max(dt, 0.1)
            want = min(max(want, meta["spp_per_chunk"] / 4), meta["spp_per_chunk"] * 4)
            meta["spp_per_chunk"] = max(16, int(want) // 16 * 16)
            ims = np.stack([read_exr(os.path.join(d, c["file"])) for c in meta["chunks"]])
            mean = ims.mean(axis=0)
            n = len(ims)
            if n > 1:
                var = ims.var(axis=0, ddof=1) / n
                meta["own_relmse"] = float((var / (mean ** 2 + 0.01)).mean())
            meta["spp"] = sum(c["spp"] for c in meta["chunks"])
            meta["seconds"] = round(sum(c["seconds"] for c in meta["chunks"]), 1)
            write_exr(os.path.join(d, "ref.exr"), mean)
            json.dump(meta, open(meta_path, "w"), indent=1)
            print(f"{name}: {integ} {meta['spp']} spp in {meta['seconds']} s, own relMSE "
                  f"{meta.get('own_relmse', float('nan')):.3g}", flush=True)


def pbrt_variant(scene, res, integ):
    """The scene's variant with `integ` as its integrator (the file's own line for sppm when
    the file names it)."""
    v = variant(scene, res)
    text = open(scene).read()
    if integ == "sppm" and re.search(r'^Integrator\s+"sppm"', text, re.M):
        return v
    src = v.replace(".pbrt", f"-{integ}.pbrt")
    m = re.search(r'"integer maxdepth"\s*\[\s*(\d+)\s*\]', text[: text.index("WorldBegin")])
    depth = m.group(1) if m else "5"
    mv = os.path.join(os.path.dirname(ROOT), "shared", "peers", "pbrt-v4", "make_variant.py")
    w, h = film_resolution(open(v).read().split("WorldBegin")[0])
    subprocess.run([sys.executable, mv, v, src, "--res", f"{w}x{h}", "--integrator",
                    f'Integrator "{integ}" "integer maxdepth" [ {depth} ]'], check=True)
    drop_empty_meshes(src)
    return src


def cmd_table(a):
    os.makedirs(a.out, exist_ok=True)
    log = open(os.path.join(a.out, "table.jsonl"), "a")
    integs = [i for i in a.integrators.split(",") if i]  # "": photon only
    runs = a.flags or [""]
    cols = (["scene", "ref own relMSE"] +
            [f"photon `{f or 'default'}` relMSE (3x3-median, mean)" for f in runs] +
            ["photon s"] + [f"pbrt {i} relMSE (spp, s)" for i in integs] +
            ["best pbrt / photon's best", "the same less the reference's own"])
    print("| " + " | ".join(cols) + " |")
    print("|" + "---|" * len(cols))
    for scene in a.scenes:
        name = os.path.basename(os.path.dirname(os.path.dirname(os.path.abspath(scene))))
        ref_path = os.path.join(a.refs, name, "ref.exr")
        if not os.path.exists(ref_path):
            print(f"| {name} | no reference |")
            continue
        ref = read_exr(ref_path)
        meta_path = os.path.join(a.refs, name, "ref.json")
        own = json.load(open(meta_path)).get("own_relmse") if os.path.exists(meta_path) else None
        row = {"scene": name, "seconds": a.seconds, "ref_own_relmse": own, "photon": []}
        v = variant(scene, a.res)
        pcells, secs_all = [], []
        for k, flags in enumerate(runs):
            errs, means, secs, med = [], [], [], []
            for seed in range(a.seeds):
                out = os.path.join(a.out, f"{name}-photon{k}-{seed}.exr")
                dt, _ = run_timed([a.photon, "render", v, "--time", f"{a.seconds}s", "--seed",
                                   str(seed), "--threads", "2", "-o", out, "--no-png"] +
                                  shlex.split(flags))
                c = compare(read_exr(out), ref, 8)
                errs.append(c["relmse"]); means.append(c["mean_ratio"]); secs.append(dt)
                med.append(c["relmse_median3"])
            row["photon"].append({"flags": flags, "relmse": float(np.mean(errs)),
                                  "relmse_seeds": errs, "mean": float(np.mean(means)),
                                  "median3": float(np.mean(med)), "s": float(np.mean(secs))})
            pcells.append(f"{np.mean(errs):.4g} ({np.mean(med):.4g}, {np.mean(means):.3f})")
            secs_all += secs
        cells = []
        for integ in integs:
            try:
                src = pbrt_variant(scene, a.res, integ)
                # Seconds per sample from timings at 4 and n spp, n raised 8x while start-up
                # hides the difference (dragon: 4 and 32 spp took the same time, and the
                # estimate asked for 29M spp).
                def timed(spp):
                    return run_timed([a.pbrt, "--nthreads", "2", "--spp", str(spp), "--outfile",
                                      os.path.join(a.out, "timing.exr"), src])[0]
                t0, n = timed(4), 32
                t1 = timed(n)
                while t1 - t0 < 0.25 * t0 and n < 4096:
                    n *= 8
                    t1 = timed(n)
                b = max((t1 - t0) / (n - 4), 1e-6)
                spp = max(1, int((a.seconds - max(t0 - 4 * b, 0.0)) / b))
                errs, secs = [], []
                for seed in range(a.seeds):
                    out = os.path.join(a.out, f"{name}-pbrt-{integ}-{seed}.exr")
                    dt, _ = run_timed([a.pbrt, "--nthreads", "2", "--spp", str(spp), "--seed",
                                       str(1000 + seed), "--outfile", out, src])
                    errs.append(compare(read_exr(out), ref, 8)["relmse"]); secs.append(dt)
                row[f"pbrt_{integ}"] = {"relmse": float(np.mean(errs)), "spp": spp,
                                        "s": float(np.mean(secs))}
                cells.append(f"{np.mean(errs):.4g} ({spp}, {np.mean(secs):.0f})")
            except SystemExit as e:
                row[f"pbrt_{integ}"] = {"error": str(e)}
                cells.append("fails")
        best = min((row[f"pbrt_{i}"]["relmse"] for i in integs if "relmse" in row[f"pbrt_{i}"]),
                   default=float("nan"))
        ours = min(r["relmse"] for r in row["photon"])
        # A noisy reference adds its own relMSE to every render's in expectation (the render
        # and the reference are independent); less it, the ratio is the one against the
        # converged image (nan when a render is not above it).
        net = float("nan")
        if own is not None and ours > own and best > own:
            net = (best - own) / (ours - own)
        cells = ([name, f"{own if own is not None else float('nan'):.2g}"] + pcells +
                 [f"{np.mean(secs_all):.0f}"] + cells + [f"{best / ours:.2f}", f"{net:.2f}"])
        print("| " + " | ".join(cells) + " |", flush=True)
        log.write(json.dumps(row) + "\n")
        log.flush()


def cmd_patch(a):
    x0, x1, y0, y1 = (int(v) for v in a.bounds.split(","))
    ref = read_exr(a.reference)
    if a.full and ref.shape[1] != a.full:
        k = ref.shape[1] // a.full
        h, w, c = ref.shape
        ref = ref.reshape(h // k, k, w // k, k, c).mean(axis=(1, 3))
    crops = np.stack([read_exr(c) for c in a.crops])
    if crops.shape[1:3] != (y1 - y0, x1 - x0):
        raise SystemExit(f"crops are {crops.shape[2]}x{crops.shape[1]}, bounds {x1 - x0}x{y1 - y0}")
    mean = crops.mean(axis=0)
    lum = lambda im: im.mean(axis=-1)
    se = lum(crops).std(axis=0, ddof=1) / np.sqrt(len(crops)) if len(crops) > 1 else None
    old = ref[y0:y1, x0:x1].copy()
    ref[y0:y1, x0:x1] = mean
    for y in range(y1 - y0):
        print(f"{y0 + y:4d} " + " ".join(
            f"{lum(old)[y, x]:.3f}->{lum(mean)[y, x]:.3f}" + (f"+-{se[y, x]:.3f}" if se is not None else "")
            for x in range(x1 - x0)))
    write_exr(a.o, ref)


def relmse_map(x, r):
    return ((x - r) ** 2 / (r ** 2 + 0.01)).mean(axis=2)


def median3(im):
    p = np.pad(im, ((1, 1), (1, 1), (0, 0)), mode="edge")
    h, w = im.shape[:2]
    stack = [p[dy:dy + h, dx:dx + w] for dy in range(3) for dx in range(3)]
    return np.median(np.stack(stack), axis=0)


def srgb8(im, scale):
    v = np.clip(im * scale, 0, 1)
    v = np.where(v <= 0.0031308, 12.92 * v, 1.055 * v ** (1 / 2.4) - 0.055)
    return (v * 255 + 0.5).astype(np.uint8)


def diff_rgb(x, r):
    lx, lr = luminance(x), luminance(r)
    d = np.log2((lx + 1e-4) / (lr + 1e-4))
    d = np.clip(d, -1, 1)
    out = np.zeros(x.shape[:2] + (3,))
    out[..., 0] = np.where(d > 0, d, 0)
    out[..., 2] = np.where(d < 0, -d, 0)
    out[..., 1] = 0.0
    return (np.clip(out, 0, 1) * 255 + 0.5).astype(np.uint8)


def compare(x, r, blocks=8):
    if x.shape != r.shape:
        raise SystemExit(f"sizes differ: {x.shape[1]}x{x.shape[0]} against {r.shape[1]}x{r.shape[0]}")
    ok = np.isfinite(r).all(axis=2)
    e = relmse_map(np.nan_to_num(x, nan=1e9, posinf=1e9), np.where(ok[..., None], r, 0))[ok]
    srt = np.sort(e)
    keep = srt[: max(1, int(len(srt) * 0.999))]
    med = relmse_map(median3(x), r)[ok]
    lx, lr = luminance(x), luminance(r)
    h, w = lx.shape
    table = []
    for by in range(blocks):
        row = []
        for bx in range(blocks):
            ys, ye = by * h // blocks, (by + 1) * h // blocks
            xs, xe = bx * w // blocks, (bx + 1) * w // blocks
            sr = lr[ys:ye, xs:xe].sum()
            row.append(float(lx[ys:ye, xs:xe].sum() / sr) if sr > 0 else float("nan"))
        table.append(row)
    return {
        "relmse": float(e.mean()),
        "relmse_trimmed": float(keep.mean()),
        "relmse_median3": float(med.mean()),
        "mean_ratio": float(lx[ok].mean() / lr[ok].mean()),
        "blocks": table,
    }


def cmd_compare(a):
    x, r = read_exr(a.image), read_exr(a.reference)
    c = compare(x, r, a.blocks)
    if a.json:
        print(json.dumps(c))
    else:
        print(f"relMSE {c['relmse']:.4g}  trimmed {c['relmse_trimmed']:.4g}  "
              f"3x3-median {c['relmse_median3']:.4g}  mean ratio {c['mean_ratio']:.4f}")
        print(f"block mean ratios ({a.blocks}x{a.blocks}, image / reference):")
        for row in c["blocks"]:
            print("  " + " ".join(f"{v:5.2f}{'*' if abs(v - 1) > 0.1 else ' '}" for v in row))
    from PIL import Image
    if a.diff or a.side:
        d = diff_rgb(x, r)
    if a.diff:
        Image.fromarray(d).save(a.diff)
    if a.side:
        scale = 0.18 / max(1e-6, float(np.median(luminance(r))))
        scale = a.scale if a.scale else scale
        im = np.concatenate([srgb8(x, scale), srgb8(r, scale), d], axis=1)
        k = max(1, 384 // x.shape[0])
        Image.fromarray(im).resize((im.shape[1] * k, im.shape[0] * k), Image.NEAREST).save(a.side)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="cmd", required=True)
    p = sub.add_parser("variant"); p.add_argument("scene"); p.add_argument("--res", type=int, default=128)
    p = sub.add_parser("pbrt"); p.add_argument("scene"); p.add_argument("--res", type=int, default=128)
    p.add_argument("--spp", type=int, required=True); p.add_argument("--integrator")
    p.add_argument("--threads", type=int, default=2); p.add_argument("-o", required=True)
    p.add_argument("--pbrt", default=DEFAULT_PBRT)
    p = sub.add_parser("photon"); p.add_argument("scene"); p.add_argument("--res", type=int, default=128)
    p.add_argument("--time", default="30s"); p.add_argument("--threads", type=int, default=2)
    p.add_argument("-o", required=True); p.add_argument("--photon", default=DEFAULT_PHOTON)
    p.add_argument("--flags", default="", help="more photon render flags, one string")
    p = sub.add_parser("refs"); p.add_argument("dir"); p.add_argument("scenes", nargs="+")
    p.add_argument("--res", type=int, default=128); p.add_argument("--chunk-minutes", type=float, default=5)
    p.add_argument("--rounds", type=int, default=1); p.add_argument("--integrator")
    p.add_argument("--pbrt", default=DEFAULT_PBRT)
    p = sub.add_parser("table"); p.add_argument("refs"); p.add_argument("scenes", nargs="+")
    p.add_argument("--res", type=int, default=128); p.add_argument("--seconds", type=float, default=30)
    p.add_argument("--seeds", type=int, default=2); p.add_argument("--out", default="oracle-table")
    p.add_argument("--integrators", default="path,bdpt,sppm")
    p.add_argument("--flags", action="append", help="photon render flags, one string; repeat for "
                   "several photon runs per scene (the row's best counts)")
    p.add_argument("--pbrt", default=DEFAULT_PBRT); p.add_argument("--photon", default=DEFAULT_PHOTON)
    p = sub.add_parser("patch"); p.add_argument("reference"); p.add_argument("crops", nargs="+")
    p.add_argument("--bounds", required=True); p.add_argument("-o", required=True)
    p.add_argument("--full", type=int)
    p = sub.add_parser("compare"); p.add_argument("image"); p.add_argument("reference")
    p.add_argument("--blocks", type=int, default=8); p.add_argument("--diff"); p.add_argument("--side")
    p.add_argument("--scale", type=float); p.add_argument("--json", action="store_true")
    a = ap.parse_args()
    if a.cmd == "variant":
        print(variant(a.scene, a.res))
    else:
        {"pbrt": cmd_pbrt, "photon": cmd_photon, "compare": cmd_compare, "refs": cmd_refs,
         "table": cmd_table, "patch": cmd_patch}[a.cmd](a)


if __name__ == "__main__":
    main()
