"""The first run's compile, in parallel and ahead of the run (issue 24, What to build 2).

A flat leaf's reconstruction calls 41 compiled kernels, a bent leaf's 6 more (BENT_KERNELS). On a
cold cache numba compiles each at its first call, one after another, in the calling thread and
holding the GIL: 25.6 s of CPU for the flat demo (benchmarks/bench_first_run.py --kernels, session
30, under load; 16 s when this was first written; 20.6 s before they were written in scalar loops,
without array expressions, slices, np.full, np.floor or a literal flag, each of which compiles code
of its own, and before bounds, _nearer_than and _prediction_misses became numpy; 24 s before their
LAPACK, BLAS and sort calls became loops), during which an app's window would not repaint. Here each
kernel is compiled for the one signature a run uses (`KERNELS`, explicit) by worker processes (one
per core: fresh interpreters that import only the kernels' modules, each taking the costliest kernel
left) into numba's on-disk cache. The calling thread loads each from there as soon as its worker
has written it (about 12 ms each: the run loaded all 41 after the compile, 0.4 s of its wall
time), and says how many are done, so the app's window stays responsive and its status counts them.
A run asked to stop (the app's Cancel, its window closing) ends the workers at once (`should_stop`,
polled every POLL_S; at exit, any still running): the kernels they had compiled stay in the cache
(numba writes each file whole, by renaming), the next run compiles the rest.

Compiled only where a loop beats numpy at grid 512 (139,000 points): curvature's and the
mixture's per-point loops are 5-10 times faster than numpy's whole-array expressions there
(temporaries of (n, 2, 2)); the ring loops 10 times at a million-point cloud.

The kernels a run calls on some inputs only (a cloud's projection) and those of measuring
(distances to a mesh: the metrics, a scan's fidelity; edge counts) are a second table,
`MEASURING`, compiled the same way when first needed (`ensure_compiled`: in the app, after the
first result is on screen, its status saying so), so that the first reconstruction does not
wait for them and the app's process never compiles them holding the GIL (its window stalled
while they compiled on the worker thread). Set-up compiles both tables (`./dev setup`).

Where the flat demo's compile goes (session 31; serial CPU on the 2-core machine, which other
jobs loaded): 19-20 s for KERNELS in one process, of which the 41 kernels' own bodies 11.3 s
(compiled again, warm), the kernels they call 4.4 s and numba's own overloads they use
(np.empty, np.zeros, max, ...) 1.8 s; each worker adds 0.5 s of imports and 0.3 s warming
numba at its first compile, and compiles numba's overloads again (they are not cached), so the
two workers spend 21 s in all. Measured and left out: numba's O1 (0.8 s less, a warm run 1 ms
slower), LLVM's per-function pre-pass skipped in the workers but for fastmath code (0.8-1.5 s
less, the same bits, but the warm run's kernels 0.1-0.4 ms slower), no CFunc wrappers (0.2 s)
or CPython wrappers for the kernels only kernels call (0.1-0.2 s), numpy's error model (none),
single-caller kernels inlined (0.2 s), one OpenBLAS thread in the workers (none measured).

tests/core/test_first_compile.py checks that the tables name every kernel core calls from
Python, with the signature it is called with. A kernel they missed would still work: the
caller would compile it, as before.
"""

from __future__ import annotations

import atexit
import contextlib
import importlib
import os
import queue
import subprocess
import sys
import threading
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor

from numba import types
from numba.core.dispatcher import Dispatcher

from leafstudio._shared import kernelcache
from leafstudio.core.buckets import Buckets
from leafstudio.core.mpu import Cells, Lattice

POLL_S = 0.1  # how often the compile looks whether it should stop
STAGE = "kernels"  # the name on_stage is called with while compiling ("kernels 3/41" after each)

f8, i8 = types.float64, types.int64
F1, F2, F3 = f8[::1], f8[:, ::1], f8[:, :, ::1]
I1, I2, B1, B2 = i8[::1], i8[:, ::1], types.boolean[::1], types.boolean[:, ::1]
J1, S1, S2 = types.int32[::1], types.float32[::1], types.float32[:, ::1]  # scipy's sparse D
RF1, RF2, RF3 = (types.Array(f8, n, "C", readonly=True) for n in (1, 2, 3))
BUCKETS = types.NamedTuple([F1, f8, i8, i8, I1, I1], Buckets)
CELLS = types.NamedTuple([F2, F1, F2], Cells)
LATTICE = types.NamedTuple([f8, f8, f8, i8, i8], Lattice)
# pose_jet.posed_jet's: a pose's terms and relief, then the units' offset and scale
POSED = (F2, F3, f8, F1, F2, i8, f8, f8, f8, f8, f8, F1, F2, f8, f8, f8, f8, F1, f8)

# "module:function" -> its argument types; costliest first (compile CPU seconds on the development
# machine, callees included), so that the workers, each taking the next when free, end together
KERNELS: dict[str, tuple[types.Type, ...]] = {
    "surface:_levenberg_marquardt": (F2, F1, F1, F1, i8, f8),
    "height:_nearest_groups": (F2, F2, I1, F1, i8, BUCKETS, F1, F2, F1, F1),
    "gmm:_em": (F2, I1, i8, f8, f8, i8),
    "mpu:_grid_sums": (LATTICE, I1, i8, CELLS, i8),
    "mesher:_split_cells": (B2, B2, i8),
    "mpu:_ball_fits": (F2, F2, F2, F1, BUCKETS),
    "prepare.polygon:_file_edges": (F2, f8, f8, i8),
    "gmm:_kmeans": (F2, F2, f8),
    "gmm:_search_right": (F1, F1),
    "gmm:_column_variances": (F2,),
    "mesher:_grid_inside": (F2, F1, f8, i8, i8),
    "mesher:_crossed_cells": (F2, F1, f8, i8, i8),
    "mesher:_outside_cells": (F2, I2, B2, F1, f8),
    "mesher:_long_edges": (F2, I2, i8, f8),
    "prepare.polygon:_inside": (F2, F2, f8, f8, i8, f8, I1, I1),
    "curvature:_taper": (RF1, RF2, RF3, f8, B1),
    "mpu:_quotient_rule": (F1, F1, F2, F2, F2, F2, i8),
    "buckets:_neighbour_distances": (F2, I1, BUCKETS),
    "gmm:_weighted_derivatives": (F2, F2, F3, F1),
    "mpu:_blend_sums": (F2, CELLS, BUCKETS, i8),
    "kelvin:spline_derivatives": (F2, F2, F1, f8, f8, F2, f8),
    "kelvin:spline_gradient": (F2, F2, F1, f8, F2, f8),
    "vein_centers:_clear_of_earlier": (F2, F1, I1, F1, f8),
    "node_derivatives:_differences": (F1, I1, i8, f8, f8, f8),
    "bending:_rows": (I1, I1, i8, types.UniTuple(B1, 2), I1, F1, I2, F1, I1),
    "gmm:_gaussians": (F2, F2, F3),
    "buckets:_mark_near_edges": (F2, F2, f8, BUCKETS, B1),
    "curvature:_product": (F1, F2, F3, F1, F2, F3),
    "buckets:_counting_sort": (F2, F1, f8, i8, i8),
    "buckets:_bounds": (F2,),
    "curvature:_graph": (F2, F3),
    "mpu:_ball_radii": (F2, F2, f8, BUCKETS),
    "kelvin:spline_value": (F2, F2, F1, f8, F2, f8),
    "kelvin:phi_matrix": (F2, F2, f8, F2, f8, F1),
    "bending:_bend_twice": (J1, J1, S1, S2),
    "bending:_rows_times": (J1, J1, S1, I1, S2, S1),
    "bending:_lattice_cells": (I1, i8, i8, F1),
    "bending:_projected_steps": (F2, F1, F1, F1, F1, i8),
    "prepare.polygon:_thin_ring": (F2, I1, f8),
    "prepare.polygon:_hull": (F2, I1),
    "prepare.polygon:_apart_each": (F2, I1, f8),
    "prepare.vein_order:_in_order": (F2, I1, f8),
    "prepare.outline:_orientation": (F2, I1),
    "prepare.outline:_ring_length": (F2, I1),
}
# what a bent leaf's run calls besides (its pose's jets, the bent mesh's halved edges and
# curvatures), costliest first; compiled with KERNELS ahead of a bent leaf's first run
# (Pipeline.run), not of a flat one's, which does not wait for them (nor for the edge table,
# which measuring compiles too: a kernel in two tables is loaded from the cache by the second)
BENT_KERNELS: dict[str, tuple[types.Type, ...]] = {
    "pose_jet:posed_jet": POSED,
    "bent_mesh:_halvings": (I2, I1, B1, i8),
    "bent_curvature:_curvatures": (F3,),
    "bent_mesh:_sagging": (F2, F2, I2, f8),
    "bent_mesh:_middles": (F2, I2),
    "edges:_edge_table": (I2, i8),  # measuring's too (a mesh's edge counts)
}
# what measuring calls (a mesh's distances and edges), a run on some inputs (a cloud's
# projection onto its outline) and a texture's edge padding (raster), costliest first;
# compiled when first needed (ensure_compiled)
MEASURING: dict[str, tuple[types.Type, ...]] = {
    "distance:_distances": (F2, F2, I2, I1, I1, I1, I1, F2, F2),
    "distance:_build": (F2, I2, I1),
    "prepare.cloud:_project_kernel": (F2, I1, F2, F2, F1, F1, i8, F1),
    "distance:_morton": (F2,),
    "distance:_centroids": (F2, I2),
    "edges:_edge_table": (I2, i8),  # a bent leaf's run's too (its sagging edges)
    "raster:_feature_transform": (B2,),
}
MEASURE = "measuring"  # MEASURING's name (its stamp's: kernelcache.kernels_cached)
BENT = "bent"  # BENT_KERNELS' name
TABLES = (STAGE, BENT, MEASURE)  # every table, by name
SIGNATURES = {**KERNELS, **BENT_KERNELS, **MEASURING}  # what a worker compiles each kernel for
_COMPILING = threading.Lock()  # one compile at a time: a second caller waits for the first's
# (table, cache folder) this process compiles in workers no more: cached, or tried to the end
_READY: set[tuple[str, str]] = set()


def table(name: str) -> dict[str, tuple[types.Type, ...]]:
    """The kernels of table `name`: STAGE, KERNELS; BENT, BENT_KERNELS; MEASURE, MEASURING."""
    return {STAGE: KERNELS, BENT: BENT_KERNELS, MEASURE: MEASURING}[name]


def compiling_notice(stage: str) -> str | None:
    """The app's status while a pipeline's on_stage says `stage`: the CLI's line (NOTICE) while
    compiling, with the kernels compiled so far ("… 3/41"); None for any other stage."""
    if stage == STAGE:
        return kernelcache.NOTICE
    if stage.startswith(f"{STAGE} "):
        return f"{kernelcache.NOTICE} {stage[len(STAGE) + 1 :]}"
    return None


def dispatcher(name: str) -> Dispatcher:
    """The compiled kernel `name` ("module:function", module under leafstudio.core)."""
    module, function = name.split(":")
    return getattr(importlib.import_module(f"leafstudio.core.{module}"), function)


# A worker: a fresh interpreter that imports leafstudio as a bare package (its __init__ would
# import the whole library, ~0.4 s of CPU in each worker, on the critical path) and only the
# kernels' modules, then compiles each kernel named on its standard input, answering with its
# CPU seconds so far. sys.argv[1] is the package's folder.
WORKER = """
import sys, time, types
package = types.ModuleType("leafstudio")
package.__path__ = [sys.argv[1]]
sys.modules["leafstudio"] = package
from leafstudio._shared import kernelcache
kernelcache.configure()
from leafstudio.core.kernels import SIGNATURES, dispatcher
for line in sys.stdin:
    dispatcher(line.strip()).compile(SIGNATURES[line.strip()])
    print(time.process_time(), flush=True)
"""


class _Crew:
    """One compile's worker processes: a stop ends them, and any started after it, and only
    them; those still running at exit are ended too (a window closed while compiling)."""

    def __init__(self) -> None:
        self.processes: set[subprocess.Popen] = set()
        self.stopped = False
        self.lock = threading.Lock()

    def join(self, process: subprocess.Popen) -> None:
        with self.lock:
            self.processes.add(process)
            if self.stopped:
                process.kill()

    def leave(self, process: subprocess.Popen) -> None:
        with self.lock:
            self.processes.discard(process)

    def end(self) -> None:
        with self.lock:
            self.stopped = True
            for process in self.processes:
                process.kill()


_CREWS: set[_Crew] = set()  # the compiles under way


@atexit.register
def _end_all() -> None:
    for crew in list(_CREWS):
        crew.end()


def _worker(todo: queue.SimpleQueue, done: queue.SimpleQueue, crew: _Crew) -> tuple[int, float]:
    """Start a worker and hand it kernels from `todo` until none are left, putting each compiled
    one's name on `done`; its process id and CPU seconds. A worker that cannot start, dies, is
    ended (a stopped run) or fails to compile a kernel stops: the run compiles what is left, as
    it would without this."""
    command = [sys.executable, "-c", WORKER, str(kernelcache.CORE.parent)]
    seconds = 0.0
    try:
        process = subprocess.Popen(
            command,
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=subprocess.DEVNULL,  # a failure is the run's to report, as without this
            text=True,
        )
    except OSError:
        return 0, seconds
    crew.join(process)
    with process:
        assert process.stdin is not None and process.stdout is not None
        try:
            while (name := _next(todo)) is not None:
                process.stdin.write(name + "\n")
                process.stdin.flush()
                answer = process.stdout.readline()
                if not answer:
                    break
                seconds = float(answer)
                done.put(name)
        except OSError:  # a broken pipe: the worker died
            pass
        # closed here, where a broken pipe is expected: Popen's exit flushed a name left in the
        # buffer into the ended worker and raised (a stopped run's test, once in a full suite)
        with contextlib.suppress(OSError):
            process.stdin.close()
    crew.leave(process)
    return process.pid, seconds


def _next(todo: queue.SimpleQueue) -> str | None:
    try:
        return todo.get_nowait()
    except queue.Empty:
        return None


def compile_kernels(
    on_stage: Callable[[str], None] | None = None,
    workers: int | None = None,
    should_stop: Callable[[], bool] | None = None,
    tables: tuple[str, ...] = (STAGE,),
) -> dict[int, float]:
    """Compile the kernels of `tables` this installation has not compiled yet, in worker
    processes.

    Parameters
    ----------
    on_stage : callable, optional
        Called with STAGE before compiling (not when the cache holds the kernels), then with
        "kernels 1/41", ... as each is compiled, in the calling thread: a pipeline's on_stage,
        for the app to say so (compiling_notice).
    workers : int, optional
        Processes to compile in; default one per core (at most one per kernel). Each takes the
        costliest kernel left when it is free.
    should_stop : callable, optional
        Polled every POLL_S while the workers compile (or while another thread's compile runs);
        when it returns True they are ended and this returns at once, the cache not marked (the
        run that called it then raises Cancelled at its first stage).
    tables : tuple of str, default: ("kernels",)
        Which tables (TABLES): the run's kernels (a pipeline's first run), with BENT's for a
        bent leaf's, MEASURE (what measuring calls: ensure_compiled), or all (set-up, a batch).

    Returns
    -------
    dict
        Each worker's CPU seconds by its process id (benchmarks/bench_first_run.py: the longest
        is the compile's wall time on an idle machine); empty when the cache held the kernels.
    """
    if all(compiled(t) for t in tables):
        return {}
    while not _COMPILING.acquire(timeout=POLL_S):  # another thread compiles: wait for it
        if should_stop is not None and should_stop():
            return {}
    try:
        todo_tables = [t for t in tables if not compiled(t)]  # the other thread's may be done
        names = [name for t in todo_tables for name in table(t)]
        spent = _compile(names, on_stage, workers, should_stop) if names else {}
        if should_stop is None or not should_stop():
            # tried to the end: not again in this process, marked or not (a stamp that cannot
            # be written, a full disk, or a worker that died: the callers compile the rest
            # themselves), as ensure_compiled runs at every distance and edge count
            folder = str(kernelcache.cache_folder())
            _READY.update((t, folder) for t in todo_tables)
        return spent
    finally:
        _COMPILING.release()


def ensure_compiled(tables: tuple[str, ...] = (MEASURE,)) -> None:
    """Compile `tables` in worker processes if this installation has not (compile_kernels);
    a set look-up once they are. Called before the first use of a MEASURING kernel."""
    compile_kernels(tables=tables)


def compiled(name: str) -> bool:
    """Whether table `name` is compiled into the cache in use (remembered once it is: then a
    set look-up)."""
    key = (name, str(kernelcache.cache_folder()))
    if key in _READY:
        return True
    if kernelcache.kernels_cached(name):
        _READY.add(key)
        return True
    return False


def _compile(
    names: list[str],
    on_stage: Callable[[str], None] | None,
    workers: int | None,
    should_stop: Callable[[], bool] | None,
) -> dict[int, float]:
    """Compile `names` (of SIGNATURES) in worker processes; each worker's CPU seconds. Marks the
    tables whose kernels are all compiled (kernelcache.mark_cached)."""
    if on_stage is not None:
        on_stage(STAGE)
    workers = max(1, min(workers or os.cpu_count() or 1, len(names)))
    todo: queue.SimpleQueue = queue.SimpleQueue()
    for name in names:
        todo.put(name)
    done: queue.SimpleQueue = queue.SimpleQueue()
    compiled: set[str] = set()
    crew = _Crew()
    _CREWS.add(crew)
    try:
        with ThreadPoolExecutor(workers) as pool:
            running = [pool.submit(_worker, todo, done, crew) for _ in range(workers)]
            try:
                while len(compiled) < len(names):
                    if should_stop is not None and should_stop():
                        break
                    try:
                        name = done.get(timeout=POLL_S)
                    except queue.Empty:
                        if all(f.done() for f in running) and done.empty():
                            break  # a worker died: the callers compile what is left
                        continue
                    compiled.add(name)
                    # loaded from the cache now, while the workers compile the rest: the run
                    # loaded the 41 after the compile (bench_first_run's wall_s - compile_s,
                    # 0.53 -> 0.15 s; a kernel missing from the cache compiles here instead)
                    dispatcher(name).compile(SIGNATURES[name])
                    if on_stage is not None:
                        on_stage(f"{STAGE} {len(compiled)}/{len(names)}")
            finally:  # stopped, or on_stage raised: no worker compiles on
                if len(compiled) < len(names):
                    while _next(todo) is not None:  # none handed out any more
                        pass
                    crew.end()
            spent = dict(f.result() for f in running)
    finally:
        _CREWS.discard(crew)
    for name in TABLES:
        kernels = table(name).keys()
        if kernels & set(names) and kernels <= compiled:
            kernelcache.mark_cached(name)
    return spent
