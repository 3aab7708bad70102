"""tests/python/test_lmc.py: the Python module lmc (src/python/lmcmodule.c).

Run by ctest as test_python (label fast; tests/python/run_pytest.py, which
skips with a message when NumPy or pytest is missing), with PYTHONPATH at
the build tree's python/ and LMC_BINARY the built command line, or by hand:

    PYTHONPATH=build/python LMC_BINARY=build/lmc python3 -m pytest tests/python

What it checks:
  - load: width/height from <default>s given as keywords; a missing file
    raises FileNotFoundError naming the file.
  - render: the image of pt (--threads 1, and 2) and of pssmlt equals bit
    for bit the EXR `lmc render` writes for the same scene, seed and flags,
    and r.save writes the same bytes; the stats' keys and counts; the error
    layer (error='on') round-trips through save and read(layer='error').
  - flags: a bad flag and a bad value raise ValueError naming the flag, as
    the command line's messages do; keywords as the CLI's choices.
  - the GIL is released while rendering (another thread runs meanwhile).
  - read and compare: compare's figures equal `lmc compare`'s printed ones
    (9 significant digits); arrays and paths alike; sizes must match.
  - target: pt, bdpt and mmlt (length=k); grad against Richardson
    extrapolated central differences of f; the mean of F(u) over uniform u
    against the b of a render (both estimate E[F]); batched = one by one;
    labels sum to F, and without absolute directions each is f(u, label);
    wrong shapes, NaN and numbers outside [0, 1) raise.
  - progress: the callable's images and seconds at the snapshots and the
    end, the image still lmc render's bit for bit (pt, lmc); an exception
    from it stops the render and carries the image so far (e.lmc_result).
  - Ctrl-C: SIGINT to a child python during a render: KeyboardInterrupt
    from lmc.render after the render stopped; the image it carries, saved
    in the finally block, reads back finite and of the right shape.
  - hessian: against Richardson-extrapolated central differences of grad
    (mmlt, bdpt), symmetric, with the C target's f and gradient.
  - memory (marker memory): the resident set over 1,000 renders and 10^6
    evaluations of f, and tracemalloc over 10^4 single calls.
  - the MALA chain of docs/python.md, run from the docs: its image's mean
    against the emitting box's exact value, b E[1/f] against P(f > 0).
  - value (and its alias contribution): luminance f, raster on the grown
    film, bdpt's a label's; batched evaluation releases the GIL (a thread
    ticks meanwhile) and two threads on one target get the same numbers.
  - sample_bootstrap: its b equals bit for bit the b_bootstrap of a pssmlt
    render with the same seed and --bootstrap n (pt and bdpt states); a
    z-test against a render of another seed and against the mean of f
    over uniform u; the states' f, labels and numbers against t.f; the
    same samples on 1 and 2 threads; bad n, seed and threads raise.
  - the seed sweep of docs/python.md, run from the docs (its plot only
    where matplotlib is installed): relMSE falls as 1 / spp for each seed.
"""
import gc
import os
import re
import signal
import subprocess
import sys
import threading
import time
import tracemalloc

import pytest

np = pytest.importorskip("numpy")
if os.environ.get("LMC_REQUIRE_MODULE"):
    import lmc  # under ctest the module must be there
else:
    lmc = pytest.importorskip("lmc")

SOURCE = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
CORNELL = os.path.join(SOURCE, "scenes", "cornell-box", "scene.xml")
W, H = 48, 36  # the Cornell box small: every render below takes well under a second


def lmc_binary():
    path = os.environ.get("LMC_BINARY")
    if not path:  # beside the module's python/ folder in a build tree
        path = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(lmc.__file__))), "lmc")
    if not os.path.exists(path):
        pytest.skip(f"no lmc binary at {path} (set LMC_BINARY)")
    return path


def run_cli(*args):
    r = subprocess.run([lmc_binary(), *args], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    return r.stdout


@pytest.fixture(scope="module")
def scene():
    return lmc.load(CORNELL, width=W, height=H)


def bits(a):
    return np.ascontiguousarray(a, dtype=np.float32).view(np.uint32)


# --- load -------------------------------------------------------------------------


def test_load_params(scene):
    assert (scene.width, scene.height) == (W, H)
    assert scene.path == CORNELL
    assert scene.lights >= 1 and scene.warnings == 0
    other = lmc.load(CORNELL, width=20, height=10)
    assert (other.width, other.height) == (20, 10)


def test_load_missing_file(tmp_path):
    missing = str(tmp_path / "no-such-scene.xml")
    with pytest.raises(FileNotFoundError, match="no-such-scene.xml"):
        lmc.load(missing)


def test_load_bad_spectra():
    with pytest.raises(ValueError, match="spectra"):
        lmc.load(CORNELL, spectra="cubic")


# --- render against the command line ----------------------------------------------------


@pytest.mark.parametrize("integrator,flags,cli_flags", [
    ("pt", dict(spp=4, seed=1, threads=1), ["--spp", "4", "--seed", "1", "--threads", "1"]),
    ("pt", dict(spp=4, seed=7, threads=2, maxdepth=4),
     ["--spp", "4", "--seed", "7", "--threads", "2", "--maxdepth", "4"]),
    ("pssmlt", dict(spp=2, seed=3, threads=2, bootstrap=5000, chains=32, largestep=0.25),
     ["--spp", "2", "--seed", "3", "--threads", "2", "--bootstrap", "5000", "--chains", "32",
      "--largestep", "0.25"]),
])
def test_render_equals_cli(scene, tmp_path, integrator, flags, cli_flags):
    r = lmc.render(scene, integrator=integrator, **flags)
    out = str(tmp_path / "cli.exr")
    run_cli("render", CORNELL, "-D", f"width={W}", "-D", f"height={H}", "--integrator",
            integrator, *cli_flags, "-q", "-o", out)
    cli = lmc.read(out)
    assert r.image.shape == (H, W, 3) and r.image.dtype == np.float32
    assert cli.shape == r.image.shape
    assert np.array_equal(bits(cli), bits(r.image)), "the image differs from lmc render's"
    assert r.image.max() > 0.0
    mine = str(tmp_path / "py.exr")
    r.save(mine)
    with open(mine, "rb") as a, open(out, "rb") as b:
        assert a.read() == b.read(), "r.save's EXR differs from lmc render's"
    # The figures.
    st = r.stats
    assert st["integrator"] == integrator and (st["width"], st["height"]) == (W, H)
    assert st["spp"] == flags["spp"] and st["rays"] > 0 and st["seconds"] > 0.0
    if integrator == "pt":
        assert st["samples"] == flags["spp"] * W * H
        assert "b" not in st
    else:
        assert st["mutations"] == flags["spp"] * W * H
        assert st["mutations_per_second"] > 0.0 and st["b"] > 0.0 and st["b_se"] > 0.0


def test_render_error_layer_and_png(scene, tmp_path):
    r = lmc.render(scene, integrator="pt", spp=4, threads=2, error="on")
    assert r.error is not None and r.error.shape == (H, W, 3)
    assert np.all(r.error >= 0.0) and r.error.max() > 0.0
    path = str(tmp_path / "e.exr")
    r.save(path)
    assert np.array_equal(bits(lmc.read(path, layer="error")), bits(r.error))
    assert np.array_equal(bits(lmc.read(path)), bits(r.image))
    png = str(tmp_path / "e.png")
    r.save(png, exposure="auto")
    assert lmc.read(png).shape == (H, W, 3)
    with pytest.raises(ValueError, match="exposure"):
        r.save(png, exposure=100)
    assert lmc.render(scene, spp=1).error is None


def test_render_resolution(scene):
    r = lmc.render(scene, spp=1, resolution=(16, 12))
    assert r.image.shape == (12, 16, 3)
    assert (scene.width, scene.height) == (W, H)  # the scene keeps its own
    assert lmc.render(scene, spp=1, resolution="20x10").image.shape == (10, 20, 3)
    with pytest.raises(ValueError, match="--resolution"):
        lmc.render(scene, spp=1, resolution="big")


# --- flags --------------------------------------------------------------------------------


@pytest.mark.parametrize("flags,name", [
    (dict(largestep=1.5), "--largestep"),         # out of its range
    (dict(spp="many"), "--spp"),                  # not a number
    (dict(adapt="sometimes"), "--adapt"),         # not one of its choices
    (dict(step_range=(0.5, 0.1)), "--step-range"),  # a pair out of order
    (dict(integrator="magic"), "--integrator"),   # no such integrator
    (dict(no_such_flag=1), "no_such_flag"),       # no such flag
    (dict(threads=[2]), "--threads"),             # a value of no flag's type
    (dict(output="x.exr"), "--output"),           # the command line's files
])
def test_bad_flags(scene, flags, name):
    with pytest.raises(ValueError, match=re.escape(name)):
        lmc.render(scene, **{"spp": 1, **flags})
    with pytest.raises(ValueError, match=re.escape(name)):
        lmc.target(scene, space="pt", **flags)


def test_flag_messages_are_the_cli_s(scene):
    """The same message as lmc render prints for the same bad value."""
    r = subprocess.run([lmc_binary(), "render", CORNELL, "--largestep", "1.5", "-o", "/dev/null"],
                       capture_output=True, text=True, timeout=60)
    assert r.returncode == 2
    with pytest.raises(ValueError) as e:
        lmc.render(scene, largestep=1.5)
    assert str(e.value) in r.stderr


def test_flag_values(scene):
    # bools as on/off, numbers as numbers, None as not given
    r = lmc.render(scene, integrator="direct", spp=1, hide_emitters=True, sampler=None)
    assert r.stats["integrator"] == "direct"
    r = lmc.render(scene, integrator="lmc", spp=1, bootstrap=2000, chains=16, adapt="none",
                   largestep=0.3, direct="mcmc")
    assert r.stats["integrator"] == "lmc" and r.stats["mutations"] == W * H


def test_strict_refuses_a_scene_with_warnings(tmp_path):
    xml = tmp_path / "warned.xml"
    xml.write_text('<scene version="0.6.0"><shape type="sphere"><bsdf type="diffuse"/></shape>'
                   '<sensor type="perspective"><film type="hdrfilm"><integer name="width" '
                   'value="8"/><integer name="height" value="8"/></film></sensor></scene>')
    s = lmc.load(str(xml))  # no emitter: a warning
    assert s.warnings >= 1
    with pytest.raises(ValueError, match="--strict"):
        lmc.render(s, spp=1, strict=True)
    assert lmc.render(s, spp=1).image.max() == 0.0


def test_render_releases_the_gil(scene):
    done = threading.Event()
    res = {}

    def work():
        res["r"] = lmc.render(scene, integrator="pt", spp=128, threads=1)
        done.set()

    th = threading.Thread(target=work)
    ticks = 0
    t0 = time.perf_counter()
    th.start()
    while not done.is_set():
        ticks += 1
        time.sleep(0.001)
    th.join()
    seconds = time.perf_counter() - t0
    # Held, the GIL would leave this loop a tick or two; released, it ticks
    # about once a millisecond while the render runs (0.3 s here; 10 ticks
    # leave room for a loaded machine).
    assert res["r"].stats["seconds"] > 0.05, "the render was too short to tell"
    assert ticks >= 10, (ticks, seconds)


# --- progress and Ctrl-C ---------------------------------------------------------------------


@pytest.mark.parametrize("integrator,flags,cli_flags", [
    ("pt", dict(spp=24, seed=5, threads=2), ["--spp", "24", "--seed", "5", "--threads", "2"]),
    ("lmc", dict(spp=6, seed=3, threads=2, bootstrap=5000, chains=32, adapt="none"),
     ["--spp", "6", "--seed", "3", "--threads", "2", "--bootstrap", "5000", "--chains", "32",
      "--adapt", "none"]),
])
def test_progress_calls_and_same_image(scene, tmp_path, integrator, flags, cli_flags):
    """progress(image, seconds) at the drivers' snapshots and at the end; the
    image is still lmc render's bit for bit."""
    calls = []

    def progress(image, seconds):
        assert image.shape == (H, W, 3) and image.dtype == np.float32
        calls.append((image, seconds))

    r = lmc.render(scene, integrator=integrator, progress=progress, progress_interval=0.001,
                   **flags)
    out = str(tmp_path / "cli.exr")
    run_cli("render", CORNELL, "-D", f"width={W}", "-D", f"height={H}", "--integrator",
            integrator, *cli_flags, "-q", "-o", out)
    assert np.array_equal(bits(lmc.read(out)), bits(r.image)), "progress changed the image"
    # At least one snapshot between rounds (passes of pt; rounds of the
    # chains), then the final image with the render's seconds.
    assert len(calls) >= 2, len(calls)
    seconds = [s for _, s in calls]
    assert all(0.0 < a <= b for a, b in zip(seconds, seconds[1:])), seconds
    assert seconds[-1] == r.stats["seconds"]
    assert np.array_equal(bits(calls[-1][0]), bits(r.image))
    assert calls[-1][0] is not r.image  # a copy: the callable may keep it
    # The images so far are images of the scene, normalised as at the end:
    # their means within 25% of the final one (a pass of pt or a round of
    # the chains over 1728 pixels is far less noisy than that).
    final = float(r.image.mean())
    for image, _ in calls[:-1]:
        assert np.all(np.isfinite(image))
        assert abs(float(image.mean()) - final) < 0.25 * final, (image.mean(), final)


class Enough(Exception):
    pass


def test_progress_exception_stops_the_render(scene):
    calls = []

    def progress(image, seconds):
        calls.append(seconds)
        raise Enough("stop here")

    t0 = time.perf_counter()
    with pytest.raises(Enough, match="stop here") as e:
        lmc.render(scene, integrator="pt", time=20, threads=2, progress=progress,
                   progress_interval=0.01)
    assert time.perf_counter() - t0 < 10.0, "the render ran on after the exception"
    assert len(calls) == 1, "called again after raising"
    r = e.value.lmc_result  # the image of the passes so far
    assert r.stats["interrupted"] and not r.stats["timed_out"]
    assert r.stats["spp"] >= 1 and r.stats["seconds"] < 10.0
    assert r.image.shape == (H, W, 3) and np.all(np.isfinite(r.image)) and r.image.max() > 0
    # The same from the chains' driver.
    with pytest.raises(Enough) as e:
        lmc.render(scene, integrator="lmc", time=4, threads=2, bootstrap=5000, chains=16,
                   progress=progress, progress_interval=0.01)
    st = e.value.lmc_result.stats  # (its direct-light pass takes a share of the 4 s first)
    assert st["interrupted"] and st["seconds"] < 3.0 and len(calls) == 2
    # The stop is not left behind for the next render.
    r = lmc.render(scene, integrator="pt", spp=2)
    assert not r.stats["interrupted"] and r.stats["spp"] == 2


def test_progress_bad_arguments(scene):
    with pytest.raises(TypeError, match="progress"):
        lmc.render(scene, spp=1, progress=42)
    for bad in (0.0, -1.0, "often", float("nan")):
        with pytest.raises(ValueError, match="progress_interval"):
            lmc.render(scene, spp=1, progress=print, progress_interval=bad)
    assert lmc.render(scene, spp=1, progress=None).stats["spp"] == 1


CTRL_C_CHILD = r"""
import sys, time, traceback
import lmc

scene = lmc.load(sys.argv[1], width=48, height=36)
out = sys.argv[2]
calls_after = []

def progress(image, seconds):
    print("rendering", flush=True)  # the parent sends SIGINT now

t0 = time.perf_counter()
r = None
try:
    lmc.render(scene, integrator="pt", time=4, threads=2, progress=progress,
               progress_interval=0.05)
except KeyboardInterrupt as e:
    r = e.lmc_result
    frames = [f.name for f in traceback.extract_tb(e.__traceback__)]
    print("frames", ",".join(frames), flush=True)
    raise
finally:
    if r is not None:
        r.save(out)
        print("stats", r.stats["interrupted"], r.stats["timed_out"], r.stats["seconds"],
              time.perf_counter() - t0, flush=True)
"""


def test_ctrl_c_raises_keyboard_interrupt_after_the_render(tmp_path):
    """SIGINT during a render in a child python: the render stops, then
    KeyboardInterrupt is raised from lmc.render (not from inside the
    progress callable), and the image saved in its finally block is valid."""
    child = tmp_path / "child.py"
    child.write_text(CTRL_C_CHILD)
    out = str(tmp_path / "interrupted.exr")
    env = dict(os.environ, PYTHONPATH=os.path.dirname(os.path.abspath(lmc.__file__)))
    p = subprocess.Popen([sys.executable, str(child), CORNELL, out], stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, text=True, env=env)
    try:
        line = p.stdout.readline()
        assert line.strip() == "rendering", (line, p.stderr.read())
        t_sent = time.perf_counter()
        p.send_signal(signal.SIGINT)
        stdout, stderr = p.communicate(timeout=60)
    finally:
        if p.poll() is None:
            p.kill()
            p.wait()
    # Python's exit after an uncaught KeyboardInterrupt: killed by SIGINT.
    assert p.returncode == -signal.SIGINT, (p.returncode, stderr)
    assert "KeyboardInterrupt" in stderr, stderr
    lines = dict(l.split(" ", 1) for l in stdout.splitlines() if " " in l)
    frames = lines["frames"].split(",")
    assert frames == ["<module>"], frames  # raised by lmc.render itself
    interrupted, timed_out, seconds, caught = lines["stats"].split()
    assert interrupted == "True" and timed_out == "False"
    # The render stopped before its 4 s, and the exception came after it.
    assert float(seconds) < 4.0 and float(caught) >= float(seconds), lines["stats"]
    assert time.perf_counter() - t_sent < 30.0
    img = lmc.read(out)
    assert img.shape == (36, 48, 3)
    assert np.all(np.isfinite(img)) and img.max() > 0.0


# --- memory ------------------------------------------------------------------------------------


def resident_mb():
    """The process's resident set in MB (/proc/self/statm's second field, in pages)."""
    gc.collect()
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 2.0**20


# The bound on growth after a warm-up. A leak of anything a render or a
# target call makes exceeds it: a leaked Result holds its 24x24 image
# (6.9 KB; 1,000 of them 6.6 MB), a leaked film 32 KB per render, a leaked
# output of t.f 80 KB per batch of 10^4 (100 batches: 7.6 MB). What
# remains is the allocator's noise, well under 1 MB here.
GROWTH_MB = 4.0


@pytest.mark.memory
def test_memory_renders():
    """1,000 renders of a tiny scene (24x24, pt, 1 spp; half of them with a
    progress callable, called at least at the end) leave the resident set
    where 100 renders of warm-up put it."""
    if not os.path.exists("/proc/self/statm"):
        pytest.skip("no /proc/self/statm")
    tiny = lmc.load(CORNELL, width=24, height=24)
    seen = []

    def progress(image, seconds):
        seen.append(image.shape)

    def renders(n):
        for i in range(n):
            r = lmc.render(tiny, integrator="pt", spp=1, threads=1,
                           progress=progress if i % 2 else None)
            assert r.image.shape == (24, 24, 3) and r.stats["spp"] == 1

    renders(100)
    before = resident_mb()
    renders(1000)
    grown = resident_mb() - before
    assert len(seen) >= 550
    assert grown < GROWTH_MB, f"the resident set grew {grown:.2f} MB over 1,000 renders"


@pytest.mark.memory
def test_memory_target_calls():
    """10^6 evaluations of f in 100 batches of 10^4, then 10^4 single calls:
    the resident set stays where the warm-up put it, and the single calls
    leave no Python objects behind (tracemalloc: a leaked float per call
    would be 240 KB)."""
    if not os.path.exists("/proc/self/statm"):
        pytest.skip("no /proc/self/statm")
    tiny = lmc.load(CORNELL, width=8, height=8)
    t = lmc.target(tiny, space="pt", maxdepth=4)
    U = np.random.default_rng(10).random((10000, t.dim))
    for _ in range(3):
        F = t.f(U)
    before = resident_mb()
    for _ in range(100):
        assert np.array_equal(t.f(U), F)
    grown = resident_mb() - before
    assert grown < GROWTH_MB, f"the resident set grew {grown:.2f} MB over 10^6 evaluations"
    for u in U[:1000]:
        t.f(u)
    tracemalloc.start()
    try:
        base = tracemalloc.get_traced_memory()[0]
        total = 0.0
        for u in U:
            total += t.f(u)
        traced = tracemalloc.get_traced_memory()[0] - base
    finally:
        tracemalloc.stop()
    assert total == pytest.approx(F.sum(), rel=1e-12)
    assert traced < 64 * 1024, f"10^4 single calls left {traced} bytes traced"
    assert resident_mb() - before < GROWTH_MB


# --- the docs' Markov chain --------------------------------------------------------------------


def test_target_through_media():
    """lmc.target on a scene with participating media (tests/data/media/
    furnace.xml: fogs that do not absorb in a box whose walls emit L =
    (1, 2, 3), so every pixel is exactly L): f runs through the media, its
    mean over uniform states is the image's integral over the film grown
    by the box filter, lum(L) (W + 1) (H + 1), within 4 standard errors, on
    the pt and bdpt states (every path length, up to 40 segments: longer
    ones carry a negligible share here); the pt states' gradient through
    them against a central difference, the other derivatives refused with
    a message naming the media."""
    scene = lmc.load(os.path.join(SOURCE, "tests", "data", "media", "furnace.xml"))
    exact = (0.2126 * 1 + 0.7152 * 2 + 0.0722 * 3) * (scene.width + 1) * (scene.height + 1)
    checked = 0
    for space in ("pt", "bdpt"):
        t = lmc.target(scene, space=space, direct="mcmc", maxdepth=40)
        F = t.f(np.random.default_rng(7).random((100_000, t.dim)))
        se = F.std(ddof=1) / np.sqrt(len(F))
        assert np.all(np.isfinite(F)) and se > 0
        assert abs(F.mean() - exact) < 4 * se, (space, F.mean(), exact, se)
        u = np.full(t.dim, 0.5)
        if space == "pt":
            # The gradient through the media (path_eval_pt), against a
            # central difference along one flight's distance number.
            x = np.random.default_rng(3).random((2000, t.dim))
            x = x[t.f(x) > 0][0]
            g, h = t.grad(x), 1e-6
            assert np.all(np.isfinite(g)) and np.any(g != 0)
            k = 3  # the first bounce's flight distance (camera 2, then u_ch, u_t)
            xp, xm = x.copy(), x.copy()
            xp[k] += h
            xm[k] -= h
            fd = (t.f(xp) - t.f(xm)) / (2 * h)
            assert abs(fd - g[k]) <= 1e-3 * abs(fd) + 1e-6 * t.f(x), (fd, g[k])
        else:
            with pytest.raises(ValueError, match="participating media"):
                t.grad(u, label=0)
        with pytest.raises(ValueError, match="participating media"):
            t.hessian(u, label=0)
        checked += 1
    assert checked == 2


def docs_block(marker):
    """The python block after `marker` in docs/python.md."""
    with open(os.path.join(SOURCE, "docs", "python.md")) as f:
        text = f.read()
    m = re.search(re.escape(marker) + r".*?\n```python\n(.*?)\n```", text, re.S)
    assert m, f"no python block after {marker!r} in docs/python.md"
    return m.group(1)


def test_docs_mala(monkeypatch, capsys):
    """The NumPy MALA chain of docs/python.md, run as it is, on the emitting
    box, whose pixels are exactly sum_{k=3}^{8} 0.5^k (the chains' paths).

    Standard errors: the 128 chains are independent (started from distinct
    bootstrap samples), so the spread of each chain's figure over the
    chains gives the standard error of their mean; b's (a mean of 50,000
    independent f) multiplies every chain's image alike and is added in
    relative terms. Each figure must lie within 4 of them of its exact
    value (4 figures: a false alarm about once in 4,000 runs; fixed seeds
    make it a fixed outcome)."""
    monkeypatch.chdir(SOURCE)
    ns = {}
    exec(compile(docs_block("<!-- test_docs_mala"), "docs/python.md", "exec"), ns)
    assert "mean" in capsys.readouterr().out
    exact = sum(0.5**k for k in range(3, 9))  # 0.24609375
    b, F, image, images = ns["b"], ns["F"], ns["image"], ns["images"]
    W, H = ns["W"], ns["H"]
    assert image.shape == (H, W, 3) and np.all(np.isfinite(image))
    rel_b = F.std(ddof=1) / np.sqrt(len(F)) / b
    # b: the mean of f over uniform u is the image's integral over the film
    # grown by the box filter's radius 0.5 ((W + 1) (H + 1) pixels).
    b_exact = exact * (W + 1) * (H + 1)
    assert abs(b - b_exact) < 4 * rel_b * b, (b, b_exact)
    # The chains move: MALA's acceptance neither ~0 nor ~1.
    rate = ns["rate"]
    assert 0.1 < rate < 0.9, rate
    # The mean image value, and the gray box's channels alike.
    per_chain = images.mean(axis=(1, 2, 3))
    se = per_chain.mean() * np.hypot(per_chain.std(ddof=1) / np.sqrt(len(per_chain)) /
                                     per_chain.mean(), rel_b)
    assert abs(image.mean() - exact) < 4 * se, (image.mean(), exact, se)
    assert np.allclose(image[..., 0], image[..., 2], rtol=1e-12)
    # The chains sample f / b: E[1/f] over their states is P(f > 0) / b.
    # (Without the Metropolis-Hastings test the same chains give 1.08 +-
    # 0.016; with the ratio inverted 1.19: both fail here.)
    hb = b * ns["mean_inv_f"]
    se_h = hb.mean() * np.hypot(hb.std(ddof=1) / np.sqrt(len(hb)) / hb.mean(), rel_b)
    p_support = (F > 0).mean()
    assert abs(hb.mean() - p_support) < 4 * se_h, (hb.mean(), p_support, se_h)


def test_docs_mala_rings(monkeypatch, capsys):
    """The NumPy MALA chains of docs/python.md on ring-caustics (32x24, every
    path length) against lmc's own Langevin chains (`integrator="lmc",
    adapt="none"`, 6 seeds): the image means agree within 4 standard errors
    of their difference (MALA's from the spread over its independent chains
    and b's relative error; lmc's from the spread over the seeds), and the
    chains move."""
    monkeypatch.chdir(SOURCE)
    ns = {}
    exec(compile(docs_block("<!-- test_docs_mala:"), "docs/python.md", "exec"), ns)
    exec(compile(docs_block("<!-- test_docs_mala_rings"), "docs/python.md", "exec"), ns)
    assert "NumPy MALA" in capsys.readouterr().out
    assert ns["images"].shape == (512, 24, 32, 3) and np.all(np.isfinite(ns["images"]))
    assert 0.05 < ns["rate"] < 0.9, ns["rate"]
    assert len(ns["runs"]) == 6 and ns["lmc_se"] > 0 and ns["se"] > 0
    diff, sd = ns["mean"] - ns["lmc_mean"], np.hypot(ns["se"], ns["lmc_se"])
    assert abs(diff) < 4 * sd, (ns["mean"], ns["lmc_mean"], sd)


def test_docs_seed_sweep(tmp_path, monkeypatch, capsys):
    """The seed sweep of docs/python.md, run as it is, in a folder where
    its scene path resolves (the plot, where matplotlib is installed, lands
    there). pt is unbiased with a finite variance on the diffuse sphere,
    so relMSE ~ c / spp + (the reference's own): a log-log slope near -1
    for the mean over the seeds (the reference's error, 1/32 of the last
    point's, bends it by about 0.03), and every seed's relMSE about 32
    times lower at 32 spp than at 1 (each point averages ~800 pixels: a
    few percent of spread; 21 leaves room). The seeds' images differ."""
    os.symlink(os.path.join(SOURCE, "tests"), tmp_path / "tests")
    monkeypatch.chdir(tmp_path)
    ns = {}
    exec(compile(docs_block("<!-- test_docs_seed_sweep"), "docs/python.md", "exec"), ns)
    out = capsys.readouterr().out
    assert "slope" in out and "seed 4" in out
    relmse, spps = ns["relmse"], ns["spps"]
    assert relmse.shape == (len(ns["seeds"]), len(spps)) and np.all(relmse > 0)
    assert -1.15 < ns["slope"] < -0.85, ns["slope"]
    assert np.all(relmse[:, -1] < relmse[:, 0] / 21), relmse
    assert len(set(relmse[:, 0])) == len(ns["seeds"])  # the seeds' images differ
    if ns["plt"] is not None:
        assert (tmp_path / "convergence.png").stat().st_size > 0


def test_target_value(scene):
    """value: its luminance is f, its raster position on the grown film;
    batched = one by one; contribution is the same function; bdpt needs a
    label, and a label's value has f(u, l) as its luminance."""
    t = lmc.target(scene, space="pt")
    U = np.random.default_rng(11).random((500, t.dim))
    value, raster = t.value(U)
    assert value.shape == (500, 3) and raster.shape == (500, 2)
    lum = value @ np.array([0.212671, 0.715160, 0.072169])  # rgb_luminance's weights
    assert np.allclose(lum, t.f(U), rtol=1e-12, atol=1e-300)
    assert np.all(raster > -1.0) and np.all(raster[:, 0] < W + 1) and np.all(raster[:, 1] < H + 1)
    v0, r0 = t.value(U[0])
    assert v0.shape == (3,) and np.array_equal(v0, value[0]) and np.array_equal(r0, raster[0])
    cv, cr = t.contribution(U)  # the alias
    assert np.array_equal(cv, value) and np.array_equal(cr, raster)
    assert np.array_equal(t.contribution(u=U[0], label=None)[0], v0)
    tb = lmc.target(scene, space="bdpt")
    for method in (tb.value, tb.contribution):
        with pytest.raises(ValueError, match="label"):
            method(np.full(tb.dim, 0.5))
    rng, n = np.random.default_rng(12), 0
    while n < 20:
        u = rng.random(tb.dim)
        for label, f in tb.labels(u).items():
            v, r = tb.value(u, label=label)
            assert v @ np.array([0.212671, 0.715160, 0.072169]) == pytest.approx(
                tb.f(u, label=label), rel=1e-12)
            n += 1


def test_target_batches_release_the_gil(scene):
    """A batch of f runs without the GIL: a thread ticks meanwhile. Two
    threads evaluating one target (its lock) get what one thread gets."""
    t = lmc.target(scene, space="bdpt", maxdepth=8)
    U = np.random.default_rng(13).random((20000, t.dim))
    done = threading.Event()
    res = {}

    def work():
        t0 = time.perf_counter()
        res["F"] = t.f(U)
        res["seconds"] = time.perf_counter() - t0
        done.set()

    th = threading.Thread(target=work)
    ticks = 0
    th.start()
    while not done.is_set():
        ticks += 1
        time.sleep(0.001)
    th.join()
    assert res["seconds"] > 0.05, "the batch was too short to tell"
    assert ticks >= 10, (ticks, res["seconds"])  # held, the GIL would allow a tick or two
    out = [None, None]

    def half(i):
        out[i] = t.f(U[i::2])

    ths = [threading.Thread(target=half, args=(i,)) for i in range(2)]
    for x in ths:
        x.start()
    for x in ths:
        x.join()
    assert np.array_equal(out[0], res["F"][0::2]) and np.array_equal(out[1], res["F"][1::2])


def test_target_batches_on_threads_are_one_by_one(scene):
    """A batch of 32 states or more runs on every OpenMP thread, each with a
    scratch of its own: f, grad, value and hessian of every state are bit
    for bit those of a call with that state alone (one thread, the
    target's first scratch), whatever order the threads take them in."""
    t = lmc.target(scene, space="pt", maxdepth=6)
    U = np.random.default_rng(21).random((96, t.dim))
    F, G = t.f(U), t.grad(U)
    V, R = t.value(U)
    checked = 0
    for i in range(len(U)):
        assert F[i] == t.f(U[i])
        assert np.array_equal(G[i], t.grad(U[i]), equal_nan=True)
        v, r = t.value(U[i])
        assert np.array_equal(V[i], v) and np.array_equal(R[i], r)
        checked += 1
    tb = lmc.target(scene, space="bdpt", maxdepth=6)
    rng, X = np.random.default_rng(22), []
    while len(X) < 40:
        u = rng.random(tb.dim)
        if 2 in tb.labels(u):
            X.append(u)
    X = np.array(X)
    fb, gb, hb = tb.hessian(X, label=2, with_grad=True)
    for i in range(len(X)):
        f1, g1, h1 = tb.hessian(X[i], label=2, with_grad=True)
        assert f1 == fb[i] and np.array_equal(g1, gb[i], equal_nan=True)
        assert np.array_equal(h1, hb[i], equal_nan=True)
        checked += 1
    assert checked == 96 + 40


# --- the bootstrap's samples -----------------------------------------------------------------


@pytest.mark.parametrize("space", ["pt", "bdpt"])
def test_sample_bootstrap_is_the_driver_s(scene, space):
    """b of sample_bootstrap(n, seed) is the b_bootstrap of a pssmlt render
    with that seed and --bootstrap n, bit for bit (the same samples, by the
    same functions). Against a render of another seed and against the mean
    of f over uniform u (independent estimates of the same E[F]) it must
    agree within 4 standard errors of the difference."""
    n = 8000
    t = lmc.target(scene, space=space, maxdepth=6)
    bs = t.sample_bootstrap(n, seed=3)
    r = lmc.render(scene, integrator="pssmlt", states=space, spp=1, maxdepth=6, bootstrap=n,
                   chains=16, seed=3)
    assert bs["b"] == r.stats["b_bootstrap"], (bs["b"], r.stats["b_bootstrap"])
    assert bs["b_se"] == r.stats["b_bootstrap_se"]
    assert bs["b_samples"] == n and bs["seed"] == 3
    # b and b_se are the mean of f and its standard error.
    f = bs["f"]
    assert bs["b"] == pytest.approx(f.mean(), rel=1e-12)
    assert bs["b_se"] == pytest.approx(f.std(ddof=1) / np.sqrt(n), rel=1e-9)
    # A render of another seed: an independent estimate.
    r2 = lmc.render(scene, integrator="pssmlt", states=space, spp=1, maxdepth=6, bootstrap=n,
                    chains=16, seed=4)
    z = (bs["b"] - r2.stats["b_bootstrap"]) / np.hypot(bs["b_se"], r2.stats["b_bootstrap_se"])
    assert abs(z) < 4.0, (bs["b"], r2.stats["b_bootstrap"], z)
    assert bs["b"] != r2.stats["b_bootstrap"]  # the seed changes the samples
    # The mean of F over uniform u.
    F = t.f(np.random.default_rng(14).random((n, t.dim)))
    z = (bs["b"] - F.mean()) / np.hypot(bs["b_se"], F.std(ddof=1) / np.sqrt(n))
    assert abs(z) < 4.0, (bs["b"], F.mean(), z)


def test_sample_bootstrap_states(scene):
    """The states: u in [0, 1)^dim; pt's f at u is the sample's f; bdpt's
    label is one with f(u, l) > 0 wherever F > 0, and f(u, l) at the
    state's numbers (the label's own coordinates) is f_state; the same
    samples on one thread and on two."""
    t = lmc.target(scene, space="pt", maxdepth=6)
    bs = t.sample_bootstrap(2000, seed=5, threads=1)
    assert bs["u"].shape == (2000, t.dim) and bs["u"].dtype == np.float64
    assert bs["f"].shape == (2000,) and bs["label"] is None
    assert np.all((bs["u"] >= 0) & (bs["u"] < 1))
    assert np.array_equal(t.f(bs["u"]), bs["f"]) and np.array_equal(bs["f_state"], bs["f"])
    assert 0.05 < (bs["f"] > 0).mean() < 1
    two = t.sample_bootstrap(2000, seed=5, threads=2)
    for key in ("u", "f", "f_state"):
        assert np.array_equal(two[key], bs[key]), key
    assert two["b"] == bs["b"]
    tb = lmc.target(scene, space="bdpt", maxdepth=6)
    bb = tb.sample_bootstrap(2000, seed=5)
    lab, fs, u = bb["label"], bb["f_state"], bb["u"]
    assert lab.shape == (2000,) and np.all((lab >= 0) & (lab < tb.n_labels))
    assert np.array_equal(fs > 0, bb["f"] > 0)
    on = np.nonzero(fs > 0)[0][:300]
    assert len(on) >= 100
    f_l = np.array([tb.f(u[i], label=int(lab[i])) for i in on])
    assert np.allclose(f_l, fs[on], rtol=1e-9, atol=0)
    # The labels of the large step's reading sum to f (F(u)) where the
    # label's coordinates are the large step's (roughness_threshold=2).
    tr = lmc.target(scene, space="bdpt", maxdepth=6, roughness_threshold=2)
    br = tr.sample_bootstrap(500, seed=5)
    assert np.allclose(tr.f(br["u"]), br["f"], rtol=1e-12, atol=0)


def test_sample_bootstrap_mmlt(scene):
    """mmlt's b is its own estimator's (whole BDPT samples of every length),
    as the driver's; it agrees with the mean of the length's f."""
    t = lmc.target(scene, space="mmlt", length=3, maxdepth=6)
    bs = t.sample_bootstrap(4000, seed=2)
    assert bs["b_samples"] >= 4000 and bs["label"] is None
    F = t.f(np.random.default_rng(15).random((20000, t.dim)))
    z = (bs["b"] - F.mean()) / np.hypot(bs["b_se"], F.std(ddof=1) / np.sqrt(len(F)))
    assert abs(z) < 4.0, (bs["b"], F.mean(), z)


def test_sample_bootstrap_errors(scene):
    t = lmc.target(scene, space="pt")
    for n in (0, -5, 2.5, "10", None, True, 2**40):
        with pytest.raises(ValueError, match="n:"):
            t.sample_bootstrap(n, seed=1)
    for seed in (-1, 2**63, 1.5, "1"):
        with pytest.raises(ValueError, match="seed:"):
            t.sample_bootstrap(10, seed=seed)
    with pytest.raises(ValueError, match="threads:"):
        t.sample_bootstrap(10, seed=1, threads=0)
    assert t.sample_bootstrap(1, 2**63 - 1)["u"].shape == (1, t.dim)


# --- read and compare ------------------------------------------------------------------------


def test_compare_equals_cli(scene, tmp_path):
    a = lmc.render(scene, spp=2, seed=1)
    b = lmc.render(scene, spp=8, seed=2)
    pa, pb = str(tmp_path / "a.exr"), str(tmp_path / "b.exr")
    a.save(pa)
    b.save(pb)
    out = run_cli("compare", pa, pb)
    cli = {k: float(v) for k, v in re.findall(r"^(\w+): (\S+)$", out, re.M)}
    for got in (lmc.compare(a.image, b.image), lmc.compare(pa, pb), lmc.compare(pa, b.image)):
        assert set(got) == {"mse", "relmse", "relmse_trimmed", "mean_ratio"}
        for k, v in got.items():
            assert v == pytest.approx(cli[k], rel=1e-8, abs=0), k  # printed with %.9g
    same = lmc.compare(a.image, a.image)
    assert same["mse"] == 0.0 and same["relmse"] == 0.0 and same["mean_ratio"] == 1.0
    # float64 arrays are compared as float32, as the EXR holds them
    assert lmc.compare(a.image.astype(np.float64), b.image) == lmc.compare(a.image, b.image)


def test_compare_and_read_errors(tmp_path):
    with pytest.raises(ValueError, match="4x3"):
        lmc.compare(np.zeros((3, 4, 3)), np.zeros((4, 4, 3)))
    with pytest.raises(ValueError, match="shape"):
        lmc.compare(np.zeros((3, 4)), np.zeros((3, 4)))
    with pytest.raises(FileNotFoundError, match="nothing.exr"):
        lmc.read(str(tmp_path / "nothing.exr"))


# --- the target --------------------------------------------------------------------------------


def states_with_light(t, rng, n, label=None, lo=0.05, hi=0.95):
    """n states u (inside [lo, hi] so that steps of 1e-5 stay in [0, 1)) with f > 0."""
    out = []
    while len(out) < n:
        U = lo + (hi - lo) * rng.random((256, t.dim))
        F = t.f(U, label=label)
        out.extend(U[F > 0])
    return np.array(out[:n])


def check_grad(t, U, label=None):
    """t.grad against Richardson-extrapolated central differences of t.f.

    D(h) = (f(u + h e_i) - f(u - h e_i)) / 2h has error c h^2 + O(h^4) plus
    rounding about eps f / h; R = (4 D(h/2) - D(h)) / 3 removes the h^2
    term. With h = 1e-5, f up to ~1e3 and gradients up to ~1e4 (the film
    numbers times W) the rounding is ~1e-8 and h^4 terms far below: R
    agrees with the exact derivative to ~1e-8 relative where f is smooth
    around u. A coordinate whose stencil crosses a discontinuity (a
    visibility edge, a light triangle's border, a lobe or roulette choice)
    shows it as D(h) and D(h/2) disagreeing; those are left out, and at
    least 90% of the coordinates must be smooth (assert_checked). Tolerance 1e-6 relative
    to |g| + 1e-3 f (the plain f and the dual one agree to ~1e-9).
    """
    h = 1e-5
    checked = crossed = 0
    worst = 0.0
    for u in U:
        f = t.f(u, label=label)
        g = t.grad(u, label=label)
        assert np.all(np.isfinite(g)), "a state with f > 0 must have a gradient"
        E = np.eye(t.dim)
        d = {}
        for step in (h, h / 2):
            fp = t.f(u + step * E, label=label)  # batched: every coordinate at once
            fm = t.f(u - step * E, label=label)
            d[step] = (fp - fm) / (2 * step)
        R = (4 * d[h / 2] - d[h]) / 3
        for i in range(t.dim):
            if g[i] == 0.0 and d[h][i] == 0.0 and d[h / 2][i] == 0.0:
                continue
            if abs(d[h][i] - d[h / 2][i]) > 1e-3 * (abs(d[h / 2][i]) + 1e-3 * f):
                crossed += 1
                continue
            err = abs(R[i] - g[i]) / (abs(g[i]) + 1e-3 * f)
            worst = max(worst, err)
            assert err < 1e-6, f"coordinate {i}: grad {g[i]!r}, differences {R[i]!r} (f {f!r})"
            checked += 1
    return checked, crossed, worst


def assert_checked(checked, crossed, least):
    """Most coordinates smooth around their states, and enough of them checked."""
    assert checked >= 0.9 * (checked + crossed) and checked >= least, (checked, crossed)


def test_target_pt_grad(scene):
    t = lmc.target(scene, space="pt")
    assert t.space == "pt" and t.n_labels == 0 and t.dim > 2
    U = states_with_light(t, np.random.default_rng(1), 8)
    assert_checked(*check_grad(t, U)[:2], least=40)


def test_target_bdpt_grad(scene):
    t = lmc.target(scene, space="bdpt")
    assert t.space == "bdpt" and t.n_labels > 0
    rng = np.random.default_rng(2)
    n = checked = crossed = 0
    for u in states_with_light(t, rng, 40):
        labels = t.labels(u)
        assert sum(labels.values()) == pytest.approx(t.f(u), rel=1e-12)
        for label in sorted(labels, key=labels.get)[-2:]:  # the two largest
            s, tt = t.strategy(label)
            assert s >= 0 and tt >= 1
            if not t.f(u, label=label) > 0:  # u read as the label's own coordinates
                continue
            c, x, _ = check_grad(t, u[None, :], label=label)
            checked, crossed, n = checked + c, crossed + x, n + 1
        if n >= 6:
            break
    assert n >= 6
    assert_checked(checked, crossed, least=20)


def test_target_bdpt_without_absolute_directions(scene):
    """roughness_threshold=2: a label reads the large step's numbers, so
    f(u, l) is the label's share of F(u) exactly."""
    t = lmc.target(scene, space="bdpt", roughness_threshold=2)
    n = 0
    for u in np.random.default_rng(3).random((100, t.dim)):
        for label, f in t.labels(u).items():
            assert t.f(u, label=label) == f
            n += 1
    assert n >= 100


def test_target_mean_is_b(scene):
    """E[F(u)] over uniform u is the b a render's bootstrap estimates."""
    t = lmc.target(scene, space="bdpt", maxdepth=6)
    F = t.f(np.random.default_rng(4).random((20000, t.dim)))
    r = lmc.render(scene, integrator="pssmlt", spp=1, maxdepth=6, bootstrap=20000, chains=16)
    b, b_se = r.stats["b_bootstrap"], r.stats["b_bootstrap_se"]
    se = np.hypot(F.std() / np.sqrt(len(F)), b_se)
    assert abs(F.mean() - b) < 4.0 * se, (F.mean(), b, se)


def test_target_mmlt(scene):
    with pytest.raises(ValueError, match="length"):
        lmc.target(scene, space="mmlt")
    t = lmc.target(scene, space="mmlt", length=4)
    assert t.length == 4 and t.n_labels == 0
    U = states_with_light(t, np.random.default_rng(5), 4)
    assert_checked(*check_grad(t, U)[:2], least=20)
    with pytest.raises(ValueError, match="space"):
        lmc.target(scene, space="path")


def check_hessian(t, u, label=None):
    """t.hessian at u against Richardson-extrapolated central differences of t.grad.

    Column i of the Hessian is dg/du_i. D(h) = (g(u + h e_i) - g(u - h e_i)) / 2h
    has the error c h^2 + O(h^4) plus rounding ~ eps_g |g| / h, where eps_g
    ~ 1e-13 is the relative rounding of the AD gradient: with h = 1e-5 that
    is ~1e-8 |g|. R = (4 D(h/2) - D(h)) / 3 removes the h^2 term, leaving
    O(h^4) ~ 1e-20 times the fifth derivatives and the rounding (times 5/3).
    So R matches the exact Hessian to ~1e-8 of |H_ij| + |g|; the tolerance is
    1e-6 relative to |H_ij| + 1e-3 (max |g| + f), a hundredfold margin. A
    column whose stencil crosses a discontinuity (D(h) and D(h/2) disagree)
    is left out, as in check_grad. Also checked: the Hessian is exactly
    symmetric, and so is R to the tolerance (the gradient is consistent);
    f and grad from the same evaluation are the C target's: grad equal to
    t.grad bit for bit, f to t.f's plain evaluation within 1e-9 (the dual
    numbers' f and the plain f round differently).
    """
    f, g, Hm = t.hessian(u, label=label, with_grad=True)
    assert Hm.shape == (t.dim, t.dim) and np.all(np.isfinite(Hm))
    assert np.array_equal(Hm, Hm.T), "the Hessian is not symmetric"
    assert np.array_equal(Hm, t.hessian(u, label=label))
    assert np.array_equal(g, t.grad(u, label=label))
    assert f == pytest.approx(t.f(u, label=label), rel=1e-9)
    h = 1e-5
    E = np.eye(t.dim)
    d = {}
    for step in (h, h / 2):
        d[step] = (t.grad(u + step * E, label=label) - t.grad(u - step * E, label=label)) / (2 * step)
    R = (4 * d[h / 2] - d[h]) / 3  # row i: dg/du_i
    scale = 1e-3 * (np.abs(g).max() + f)
    crossed = np.any(np.abs(d[h] - d[h / 2]) > 1e-3 * (np.abs(d[h / 2]) + scale), axis=1)
    smooth = ~crossed
    err = np.abs(R - Hm) / (np.abs(Hm) + scale)
    worst = err[smooth].max() if smooth.any() else 0.0
    i, j = np.unravel_index(np.argmax(np.where(smooth[:, None], err, 0.0)), err.shape)
    assert worst < 1e-6, f"H[{i}, {j}] = {Hm[i, j]!r}, differences {R[i, j]!r}"
    sym = np.abs(R - R.T)[np.ix_(smooth, smooth)] / (np.abs(Hm[np.ix_(smooth, smooth)]) + scale)
    assert sym.size == 0 or sym.max() < 1e-6
    return int(smooth.sum()), int(crossed.sum()), int(np.count_nonzero(Hm))


def test_target_hessian_mmlt(scene):
    t = lmc.target(scene, space="mmlt", length=4)
    U = states_with_light(t, np.random.default_rng(7), 4)
    checked = crossed = nonzero = 0
    for u in U:
        c, x, nz = check_hessian(t, u)
        checked, crossed, nonzero = checked + c, crossed + x, nonzero + nz
    assert checked >= 0.9 * (checked + crossed) and nonzero >= 40, (checked, crossed, nonzero)
    # Batched: (N, dim, dim), each the one-by-one matrix; NaN without light.
    Hb = t.hessian(U)
    assert Hb.shape == (len(U), t.dim, t.dim)
    assert all(np.array_equal(Hb[k], t.hessian(U[k])) for k in range(len(U)))
    rng = np.random.default_rng(8)
    dark = next(u for u in rng.random((1000, t.dim)) if t.f(u) == 0.0)
    assert np.all(np.isnan(t.hessian(dark)))


def test_target_hessian_bdpt(scene):
    t = lmc.target(scene, space="bdpt")
    rng = np.random.default_rng(9)
    n = checked = crossed = 0
    for u in states_with_light(t, rng, 40):
        labels = t.labels(u)
        label = max(labels, key=labels.get)
        if not t.f(u, label=label) > 0:
            continue
        c, x, nz = check_hessian(t, u, label=label)
        assert nz > 0
        checked, crossed, n = checked + c, crossed + x, n + 1
        if n >= 4:
            break
    assert n >= 4 and checked >= 0.9 * (checked + crossed), (n, checked, crossed)
    with pytest.raises(ValueError, match="label"):
        t.hessian(u)  # a label's, as the gradient
    with pytest.raises(ValueError, match="Hessian"):
        lmc.target(scene, space="pt").hessian(u[:0])  # pt's states have none


def test_target_shapes_and_values(scene):
    t = lmc.target(scene, space="pt")
    rng = np.random.default_rng(6)
    U = rng.random((5, t.dim))
    F = t.f(U)
    assert F.shape == (5,) and isinstance(t.f(U[0]), float)
    assert np.array_equal(F, [t.f(u) for u in U])
    G = t.grad(U)
    assert G.shape == (5, t.dim) and t.grad(U[0]).shape == (t.dim,)
    assert np.array_equal(G[0], t.grad(U[0]), equal_nan=True)
    assert t.f(list(U[0])) == F[0]  # any sequence of numbers
    for bad in (np.zeros(t.dim + 1), np.zeros((2, t.dim - 1)), np.zeros((1, 2, t.dim)),
                np.zeros(0)):
        with pytest.raises(ValueError, match="shape"):
            t.f(bad)
        with pytest.raises(ValueError, match="shape"):
            t.grad(bad)
    u = U[0].copy()
    u[3] = np.nan
    with pytest.raises(ValueError, match=r"u\[3\]"):
        t.f(u)
    u[3] = 1.0
    with pytest.raises(ValueError, match=r"\[0, 1\)"):
        t.grad(u)
    with pytest.raises(ValueError, match="label"):
        t.f(U[0], label=0)  # pt states have no labels
    tb = lmc.target(scene, space="bdpt")
    with pytest.raises(ValueError, match="label"):
        tb.grad(rng.random(tb.dim))  # the gradient is a label's
    with pytest.raises(ValueError, match="label"):
        tb.f(rng.random(tb.dim), label=tb.n_labels)
