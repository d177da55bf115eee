"""The first reconstruction's time on a cold kernel cache (issue 24, What to build 2).

Runs ``ls.reconstruct(ls.demo("nested"), ls.Params())`` in a fresh interpreter whose numba cache
is an empty temporary folder (``NUMBA_CACHE_DIR``), as a new user's first run, and prints:

- ``compile_s``: the wall time of the workers' compile (core/kernels.py) that the run starts with,
  its loading of each kernel from the cache as its worker finishes it included;
- ``wall_s``: the run's wall time (import excluded), the compile's included;
- ``cpu_s``: the CPU time of the run, its own and that of any process it waited on;
- ``workers_cpu_s``: each compiling worker's CPU time (core/kernels.py); on an idle machine with
  a core per worker, the first run's wall time is about the largest plus the run's own;
- ``warm_s``: the same run again in a new interpreter, the cache now filled.

With ``--kernels`` the kernels are compiled in the run's own process, one after another (as
before core/kernels.py compiled them in parallel), and it prints each compiled function's own
compile time (CPU seconds spent compiling it, its callees excluded), largest first: where the
first run's seconds go.

Wall times depend on the machine's load (the development machine has 2 cores shared by several
jobs): compare ``cpu_s`` between versions, and run it twice.

Usage: ``.venv/bin/python benchmarks/bench_first_run.py [--repeats 2] [--kernels]``
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile

RUN = """
import json, os, sys, time
t0, c0 = time.perf_counter(), time.process_time()
import leafstudio as ls
t1, c1 = time.perf_counter(), time.process_time()
table = None
if {kernels}:
    from collections import defaultdict
    from numba.core import event

    own, stack = defaultdict(float), []

    class Cpu(event.Listener):
        def on_start(self, ev):
            stack.append([time.process_time(), 0.0])

        def on_end(self, ev):
            start, inner = stack.pop()
            spent = time.process_time() - start
            f = ev.data["dispatcher"].py_func
            own[f.__module__ + "." + f.__qualname__] += spent - inner
            if stack:
                stack[-1][1] += spent

    event.register("numba:compile", Cpu())
    import leafstudio.core.pipeline as pipeline

    pipeline.compile_kernels = lambda *args, **kwargs: False  # in this process, serially
workers = {{}}
if not {kernels}:  # as Pipeline.run does first, to see each worker's CPU time
    from leafstudio.core.kernels import compile_kernels

    workers = compile_kernels()
compile_s = time.perf_counter() - t1
ls.reconstruct(ls.demo("nested"), ls.Params())
t2, c2 = time.perf_counter(), time.process_time()
ls._shared.kernelcache.mark_cached()  # compiled serially: the warm run finds them so too
children = os.times()
if {kernels}:
    table = sorted(((round(v, 2), k) for k, v in own.items()), reverse=True)
print(json.dumps({{"import_s": round(t1 - t0, 2), "compile_s": round(compile_s, 2),
                  "wall_s": round(t2 - t1, 2),
                  "cpu_s": round(c2 - c1 + children.children_user + children.children_system, 2),
                  "workers_cpu_s": sorted(round(v, 2) for v in workers.values()),
                  "kernels": table}}))
"""


def run(cache: str, kernels: bool = False) -> dict:
    """One fresh interpreter's first reconstruction with `cache` as numba's cache folder."""
    env = {**os.environ, "NUMBA_CACHE_DIR": cache}
    out = subprocess.run(
        [sys.executable, "-c", RUN.format(kernels=kernels)],
        env=env,
        capture_output=True,
        text=True,
        check=True,
    ).stdout
    return json.loads(out.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=2)
    parser.add_argument("--kernels", action="store_true", help="each kernel's compile time")
    args = parser.parse_args()
    for _ in range(args.repeats):
        with tempfile.TemporaryDirectory() as cache:
            cold = run(cache, args.kernels)
            warm = run(cache)
        table = cold.pop("kernels")
        print(json.dumps({"cold": cold, "warm_s": warm["wall_s"], "warm_cpu_s": warm["cpu_s"]}))
        for seconds, name in table or []:
            print(f"{seconds:7.2f}  {name}")


if __name__ == "__main__":
    main()
