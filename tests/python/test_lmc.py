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
"""
import os
import re
import subprocess
import threading
import time

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
