#!/usr/bin/env python3
"""bench/python_speed.py: what the Python module costs over the C it calls.

Prints (never part of ctest; no timed assertions anywhere):

(a) The target (lmc.target, the Cornell box, pt states: a path tracer's
    numbers) evaluated from Python: time per evaluation of t.f and t.grad
      - over a batch of 10^4 states in one call: the module's C loop (the
        target's eval per state, the same call the chains make), run
        without the GIL; the C-side figure;
      - one state per call, the same 10^4 states: Python's call, the argument's
        conversion and the result's object on top of one evaluation;
      - two threads, each with its own target, each a batch of 10^4: the
        batches run in parallel (no GIL), throughput against one thread.
    bench/bench_grad.c times path_eval_pt on ring-caustics at fixed path
    lengths (a lower layer, other paths), so it is not the C figure here:
    the batched call is.
    In C: bench/bench_target.c, the same target's f and grad in a C loop
    in a process without Python (one thread, its own states), beside the
    batched figures: run with OMP_NUM_THREADS=1 for one thread on both
    sides.
(b) lmc.render against the `lmc render` binary (subprocess) at equal spp
    on a small scene, alternating, 3 runs each: the wall time of each
    (Python: load + render + save the EXR and the PNG in this process;
    binary: the whole process, which does the same), the renders' own seconds
    (stats["seconds"] and the binary's statistics line), and the ratios.

usage: PYTHONPATH=build/python /usr/bin/python3 bench/python_speed.py [--lmc build/lmc]
                    [--width 128] [--spp 64] [--bench-target build/bench/bench_target]
"""
import argparse
import os
import re
import subprocess
import sys
import tempfile
import threading
import time

import numpy as np

import lmc

SOURCE = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
CORNELL = os.path.join(SOURCE, "scenes", "cornell-box", "scene.xml")


def best(fn, reps=3):
    """The least wall time of reps calls of fn (seconds) and its last result."""
    t, out = float("inf"), None
    for _ in range(reps):
        t0 = time.perf_counter()
        out = fn()
        t = min(t, time.perf_counter() - t0)
    return t, out


def bench_target(width, height):
    scene = lmc.load(CORNELL, width=width, height=height)
    t = lmc.target(scene, space="pt")
    rng = np.random.default_rng(1)
    U = rng.random((10_000, t.dim))
    F = t.f(U)
    # States with f > 0 (the gradient is defined there; the chains' states).
    P = rng.random((200_000, t.dim))
    P = P[t.f(P) > 0][:10_000]
    P = np.resize(P, (10_000, t.dim)) if len(P) < 10_000 else P
    print(f"(a) target: Cornell box {width}x{height}, space pt, dim {t.dim}, "
          f"P(f > 0) = {(F > 0).mean():.2f}")
    rows = []
    for name, fn, X in (("f, uniform u", t.f, U), ("f, states f > 0", t.f, P),
                        ("grad, states f > 0", t.grad, P)):
        tb, _ = best(lambda: fn(X), reps=5)
        singles = list(X)  # the same states, one call each

        def one_by_one():
            for u in singles:
                fn(u)

        t1, _ = best(one_by_one, reps=5)
        per_b, per_1 = tb / len(X) * 1e6, t1 / len(singles) * 1e6
        rows.append((name, per_b, per_1))
    print(f"  {'':22}{'batch 10^4 [us/eval]':>22}{'batch 1 [us/eval]':>20}{'ratio':>8}")
    for name, per_b, per_1 in rows:
        print(f"  {name:22}{per_b:22.2f}{per_1:20.2f}{per_1 / per_b:8.2f}")
    return rows

    # Two threads, a target each: the batches run without the GIL.
    t2 = lmc.target(scene, space="pt")

    cpu = [0.0, 0.0]

    def grad_timed(i, tt):
        c0 = time.thread_time()
        tt.grad(P)
        cpu[i] = time.thread_time() - c0

    def pair():
        ths = [threading.Thread(target=grad_timed, args=(i, tt)) for i, tt in enumerate((t, t2))]
        for th in ths:
            th.start()
        for th in ths:
            th.join()
        return sum(cpu)

    t_one, _ = best(lambda: t.grad(P), reps=5)
    t_two, cpu_two = best(pair, reps=5)
    # CPU seconds of the two threads over the wall time: at most 1 if the
    # batches held the GIL, up to 2 on two free cores.
    print(f"  grad, 2 threads x 10^4 (own targets): {t_two / (2 * len(P)) * 1e6:.2f} us/eval; "
          f"throughput {2 * t_one / t_two:.2f}x one thread's; "
          f"CPU/wall {cpu_two / t_two:.2f} (GIL held: <= 1)")


def bench_c(bench_bin, rows, width, height):
    """bench/bench_target.c (the same target in a C loop, one thread, no
    Python in the process) beside the batched figures of (a)."""
    if not os.access(bench_bin, os.X_OK):
        print(f"\n(a) in C: {bench_bin} is not built (cmake --build build --target "
              "bench_target): no C figure")
        return
    p = subprocess.run([bench_bin, "--width", str(width), "--height", str(height)],
                       capture_output=True, text=True, timeout=600)
    if p.returncode != 0:
        sys.exit(f"bench_target failed: {p.stderr}")
    c = {m.group(1).strip(): float(m.group(2))
         for m in re.finditer(r"^  (.+?)\s+([0-9.]+) us/eval$", p.stdout, re.M)}
    threads = os.environ.get("OMP_NUM_THREADS", "every core")
    print(f"\n(a) in C: the same quantities by bench_target (one thread) against the batches "
          f"(OpenMP threads: {threads})")
    print(f"  {'':22}{'C [us/eval]':>14}{'batch 10^4 [us/eval]':>22}{'batch / C':>11}")
    for name, per_b, _ in rows:
        if name in c:
            print(f"  {name:22}{c[name]:14.2f}{per_b:22.2f}{per_b / c[name]:11.2f}")


def bench_render(binary, width, spp, runs=3):
    height = width * 3 // 4
    integrators = (("pt", spp), ("lmc", max(1, spp // 8)))
    print(f"\n(b) render: Cornell box {width}x{height}, threads 2, {runs} alternating runs each")
    print(f"  {'integrator':12}{'spp':>5}{'python wall [s]':>17}{'binary wall [s]':>17}"
          f"{'ratio':>7}{'python render [s]':>19}{'binary render [s]':>19}{'ratio':>7}")
    with tempfile.TemporaryDirectory() as tmp:
        out_py, out_cli = os.path.join(tmp, "py.exr"), os.path.join(tmp, "cli.exr")
        for integ, n in integrators:
            flags = dict(integrator=integ, spp=n, seed=1, threads=2)
            cmd = [binary, "render", CORNELL, "-D", f"width={width}", "-D", f"height={height}",
                   "--integrator", integ, "--spp", str(n), "--seed", "1", "--threads", "2",
                   "-q", "-o", out_cli]
            py_wall, py_sec, cli_wall, cli_sec = [], [], [], []
            for _ in range(runs):
                t0 = time.perf_counter()
                scene = lmc.load(CORNELL, width=width, height=height)
                r = lmc.render(scene, **flags)
                r.save(out_py)
                r.save(out_py[:-4] + ".png", exposure="auto")  # the binary writes both
                py_wall.append(time.perf_counter() - t0)
                py_sec.append(r.stats["seconds"])
                t0 = time.perf_counter()
                p = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
                cli_wall.append(time.perf_counter() - t0)
                if p.returncode != 0:
                    sys.exit(f"lmc render failed: {p.stderr}")
                m = re.findall(r" in ([0-9.]+) s \(load", p.stderr + p.stdout)
                cli_sec.append(float(m[-1]) if m else float("nan"))
            same = np.array_equal(lmc.read(out_py), lmc.read(out_cli))
            pw, cw = np.median(py_wall), np.median(cli_wall)
            ps, cs = np.median(py_sec), np.median(cli_sec)
            print(f"  {integ:12}{n:5d}{pw:17.3f}{cw:17.3f}{pw / cw:7.2f}{ps:19.3f}{cs:19.3f}"
                  f"{ps / cs:7.2f}   (medians; images {'equal' if same else 'DIFFER'})")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    default_bin = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(lmc.__file__))),
                               "lmc")
    ap.add_argument("--lmc", default=os.environ.get("LMC_BINARY", default_bin))
    ap.add_argument("--width", type=int, default=128, help="(b)'s image width (height 3/4 of it)")
    ap.add_argument("--spp", type=int, default=64, help="(b)'s pt spp (lmc: an eighth)")
    ap.add_argument("--bench-target", default=None,
                    help="bench/bench_target.c's binary (default: bench/ beside --lmc)")
    args = ap.parse_args()
    if args.bench_target is None:
        args.bench_target = os.path.join(os.path.dirname(args.lmc), "bench", "bench_target")
    print(f"lmc {lmc.__version__}, python {sys.version.split()[0]}, numpy {np.__version__}, "
          f"{os.cpu_count()} cores, load average {os.getloadavg()[0]:.2f}")
    rows = bench_target(64, 48)
    bench_c(args.bench_target, rows, 64, 48)
    bench_render(args.lmc, args.width, args.spp)


if __name__ == "__main__":
    main()
