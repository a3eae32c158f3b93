"""The Python module against the command line: same images bit for bit, same errors, same
metrics; Ctrl-C, progress callbacks and memory release."""

import gc
import json
import os
import signal
import subprocess
import sys
import textwrap
import time
import weakref

import numpy as np
import OpenEXR  # the EXR is read by OpenEXR's own Python binding, not by photon
import pytest

import photon
from conftest import ROOT, rss_bytes, run_cli

LAYERS = ["direct", "specular", "caustic", "indirect"]


def read_layers(path):
    """The EXR's beauty and component layers as float32 arrays (height, width, 3)."""
    with OpenEXR.File(str(path)) as f:
        ch = f.channels()
        out = {"beauty": np.asarray(ch["RGB"].pixels, dtype=np.float32)}
        for name in LAYERS:
            out[name] = np.asarray(ch[name].pixels, dtype=np.float32)
    return out


def assert_bit_equal(arrays, exr):
    assert sorted(arrays) == sorted(["beauty", *LAYERS])
    for name, want in exr.items():
        got = arrays[name]
        assert got.dtype == np.float32 and got.shape == want.shape, name
        # Bit patterns, so that -0.0 against 0.0 or NaN payloads would also show.
        assert np.array_equal(got.view(np.uint32), want.view(np.uint32)), (
            f"{name}: {np.count_nonzero(got != want)} pixels differ, "
            f"max |diff| {np.abs(got - want).max()}"
        )
    assert float(exr["beauty"].mean()) > 0.0


@pytest.mark.parametrize(
    "options, flags",
    [
        (dict(spp=2, seed=3), ["--spp", "2", "--seed", "3"]),
        (
            dict(passes=3, pass_spp=1, seed=5, integrator="path"),
            ["--passes", "3", "--pass-spp", "1", "--seed", "5", "--integrator", "path"],
        ),
        (
            dict(progressive=True, passes=range(1, 3), global_photons=5000, caustic_photons=5000),
            ["--progressive", "--passes", "1..3", "--global-photons", "5000",
             "--caustic-photons", "5000"],
        ),
        (
            dict(spp=2, seed=4, integrator="vcm", merge_radius="2px"),
            ["--spp", "2", "--seed", "4", "--integrator", "vcm", "--merge-radius", "2px"],
        ),
        (
            dict(spp=2, seed=6, spectral=True, final_gather=False),
            ["--spp", "2", "--seed", "6", "--spectral", "--no-final-gather"],
        ),
    ],
    ids=["photonmap", "path-passes", "progressive-range", "vcm", "spectral"],
)
def test_arrays_equal_the_cli_exr(tmp_path, cli, glass, options, flags):
    scene = photon.load(glass, resolution=(48, 40))
    # Two threads here, one in the CLI: the image may not depend on the thread count.
    got = scene.render(threads=2, **options)
    exr = tmp_path / "cli.exr"
    run_cli(cli, "render", glass, "--res", "48x40", "--threads", "1", "--no-png", "-o", exr, *flags)
    assert_bit_equal(got, read_layers(exr))
    total = sum(got[n].astype(np.float64) for n in LAYERS)
    assert np.abs(total - got["beauty"]).max() <= 1e-5 * max(1.0, float(got["beauty"].max()))


def test_render_options_replace_load_options(glass):
    scene = photon.load(glass, resolution=(16, 8), spp=1)
    assert scene.resolution == (16, 8)
    assert scene.render(resolution=(12, 10))["beauty"].shape == (10, 12, 3)
    # The load-time option is back for the next render.
    assert scene.render()["beauty"].shape == (8, 16, 3)


def test_loading_errors_carry_the_location(tmp_path):
    bad = tmp_path / "bad.pbrt"
    bad.write_text('WorldBegin\nShape "sphere"\n  "float radius" [ 1 2 oops ]\n')
    with pytest.raises(photon.PhotonError) as e:
        photon.load(bad)
    message = str(e.value)
    assert message.startswith(f"{bad}:3:"), message
    assert isinstance(e.value, ValueError)
    with pytest.raises(photon.PhotonError, match="No such file|not found|cannot"):
        photon.load(tmp_path / "missing.pbrt")


def test_option_errors_are_the_cli_messages(glass):
    scene = photon.load(glass, resolution=(8, 8), spp=1)
    with pytest.raises(photon.PhotonError, match="--spp"):
        scene.render(spp=0)
    with pytest.raises(photon.PhotonError, match="no such option"):
        scene.render(sppp=4)
    with pytest.raises(photon.PhotonError, match="not available here"):
        scene.render(output="x.exr")
    with pytest.raises(photon.PhotonError, match="--integrator"):
        photon.load(glass, integrator="magic")
    with pytest.raises(photon.PhotonError, match="switch"):
        scene.render(progressive=3)


@pytest.mark.parametrize(
    "options",
    [dict(spp=8), dict(passes=6, pass_spp=2), dict(time=1.0)],
    ids=["tiles", "passes", "time"],
)
def test_progress_grows_to_one(glass, options):
    scene = photon.load(glass, resolution=(96, 96), integrator="path")
    calls = []
    scene.render(progress=calls.append, **options)
    print(options, len(calls), [round(c, 3) for c in calls[:8]])
    assert calls and calls[-1] == 1.0, calls
    assert all(0.0 <= a < b <= 1.0 for a, b in zip(calls, calls[1:])), calls
    assert len(calls) >= 2 and calls[0] < 1.0, calls


def test_an_exception_in_the_callback_stops_the_render(glass):
    scene = photon.load(glass, resolution=(256, 256), spp=64, integrator="path")

    def stop(fraction):
        raise RuntimeError("enough")

    t0 = time.monotonic()
    with pytest.raises(RuntimeError, match="enough"):
        scene.render(progress=stop)
    stopped = time.monotonic() - t0
    t0 = time.monotonic()
    scene.render(spp=1, resolution=(64, 64))  # the stop flag is cleared for the next render
    print(f"stopped after {stopped:.2f} s; a small render afterwards took "
          f"{time.monotonic() - t0:.2f} s")


SIGINT_CHILD = textwrap.dedent(
    """
    import sys, time, photon
    scene = photon.load(sys.argv[1], resolution=(512, 512), spp=4096, integrator="path")
    started = []
    def progress(fraction):
        if not started:
            started.append(1)
            print("started", flush=True)
    t0 = time.monotonic()
    try:
        scene.render(progress=progress)
        print("finished", flush=True)
    except KeyboardInterrupt:
        print(f"interrupted {time.monotonic() - t0:.2f}", flush=True)
        img = scene.render(spp=1, resolution=(8, 8))["beauty"]
        print(f"again {img.shape}", flush=True)
    """
)


def test_ctrl_c_interrupts_a_render(glass):
    child = subprocess.Popen(
        [sys.executable, "-c", SIGINT_CHILD, str(glass)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        assert child.stdout.readline().strip() == "started"
        time.sleep(0.3)
        child.send_signal(signal.SIGINT)
        # The full render would take hours; a working Ctrl-C ends it within a tile.
        out, err = child.communicate(timeout=120)
    finally:
        child.kill()
    lines = out.split("\n")
    assert lines[0].startswith("interrupted"), (out, err)
    assert lines[1] == "again (8, 8, 3)", (out, err)
    print(out)


MEMORY_CHILD = textwrap.dedent(
    """
    import ctypes, gc, sys, weakref, photon
    from conftest import rss_bytes
    trim = ctypes.CDLL("libc.so.6").malloc_trim
    keep, sizes = [], []
    base = rss_bytes()
    for i in range(8):
        scene = photon.load(sys.argv[1], resolution=(192, 192), spp=1)
        layers = scene.render(global_photons=1_000_000, caustic_photons=200_000)
        peak = rss_bytes()
        arrays = sum(a.nbytes for a in layers.values())
        ref = weakref.ref(scene)
        if sys.argv[2] == "keep":
            keep.append((scene, layers))
        del scene, layers
        gc.collect()
        trim(0)
        sizes.append(rss_bytes())
        if i == 0:
            print(peak - base, arrays, flush=True)
        print(sizes[-1], ref() is None, flush=True)
    """
)


def memory_cycles(glass, mode):
    """RSS of a process that loads, renders and drops a scene 8 times: (one render's growth,
    the bytes of one render's arrays, [(RSS after each cycle, whether the scene object was
    freed)])."""
    # One malloc arena, trimmed after each cycle: freed memory goes back to the system
    # instead of staying in the arenas of the render's threads, so the RSS is the live memory.
    env = dict(os.environ, MALLOC_ARENA_MAX="1", PYTHONPATH=str(ROOT / "python" / "tests"))
    r = subprocess.run(
        [sys.executable, "-c", MEMORY_CHILD, str(glass), mode],
        capture_output=True, text=True, env=env, timeout=600,
    )
    assert r.returncode == 0, r.stderr
    lines = r.stdout.split()
    one, arrays = int(lines[0]), int(lines[1])
    cycles = [(int(lines[i]), lines[i + 1] == "True") for i in range(2, len(lines), 2)]
    return one, arrays, cycles


def test_memory_is_released_with_the_scene(glass):
    one, arrays, cycles = memory_cycles(glass, "drop")
    sizes = [s for s, _ in cycles]
    print(f"one render: +{one / 2**20:.0f} MB, arrays {arrays / 2**20:.1f} MB; "
          "RSS after each cycle (MB):", [round(s / 2**20) for s in sizes])
    assert all(freed for _, freed in cycles)
    # Six more cycles may not keep a quarter of what one render took, nor a quarter of the
    # arrays they returned (what keeping them would hold: the test below).
    assert sizes[-1] - sizes[1] < one / 4, (one, sizes)
    assert sizes[-1] - sizes[1] < 6 * arrays / 4, (arrays, sizes)


def test_the_memory_check_sees_a_kept_scene(glass):
    # The same measure when the scenes and images are kept: it must see them (the arrays at
    # least; a kept scene holds its geometry, not the render's photon maps).
    one, arrays, cycles = memory_cycles(glass, "keep")
    sizes = [s for s, _ in cycles]
    assert not any(freed for _, freed in cycles)
    assert sizes[-1] - sizes[1] > 6 * arrays * 0.9, (arrays, sizes)


def test_compare_equals_the_cli(tmp_path, cli, glass):
    a, b = tmp_path / "a.exr", tmp_path / "b.exr"
    for path, seed in [(a, 1), (b, 2)]:
        run_cli(cli, "render", glass, "--res", "32x32", "--spp", "1", "--seed", seed,
                "--threads", "1", "--no-png", "-o", path)
    want = json.loads(run_cli(cli, "compare", a, b, "--json"))
    assert photon.compare(a, b) == want
    assert photon.compare(str(a), read_layers(b)["beauty"]) == want
    assert want["overall"]["relmse"] > 0
    with pytest.raises(photon.PhotonError):
        photon.compare(np.zeros((4, 4, 3)), np.zeros((5, 4, 3)))
    with pytest.raises(photon.PhotonError, match="shape"):
        photon.compare(np.zeros((4, 4)), np.zeros((4, 4)))
