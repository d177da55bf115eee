"""The first run's compile (issue 24, What to build 2): core/kernels.KERNELS names every kernel a
reconstruction calls from Python, with the signature it calls it with, and compile_kernels
compiles them in worker processes into numba's cache."""

from __future__ import annotations

import ast
import os
import re
from pathlib import Path

import numpy as np
import pytest

import leafstudio as ls
from leafstudio._shared import kernelcache
from leafstudio._shared.kernelcache import NOTICE
from leafstudio.core import evaluate, kernels
from leafstudio.core.pipeline import Cancelled

CORE = Path(kernels.__file__).parent
ROOT = CORE.parents[1]


def _compiled(f: ast.FunctionDef) -> bool:
    return any("njit" in ast.unparse(d) for d in f.decorator_list)


def _called_from_python() -> set[str]:
    """Every compiled kernel that a plain function of core calls, as "module:function" (found by
    its name: each kernel's is unique in core, but a plain function of the calling module may
    share it, as bend._split does distance._split's)."""
    trees = {
        path.relative_to(CORE).with_suffix("").as_posix().replace("/", "."): ast.parse(
            path.read_text()
        )
        for path in CORE.rglob("*.py")
    }
    functions = {
        module: [n for n in ast.walk(tree) if isinstance(n, ast.FunctionDef)]
        for module, tree in trees.items()
    }
    kernel = {f.name: m for m, fs in functions.items() for f in fs if _compiled(f)}
    return {
        f"{kernel[name]}:{name}"
        for fs in functions.values()
        for f in fs
        if not _compiled(f)
        for call in ast.walk(f)
        if isinstance(call, ast.Call) and (name := ast.unparse(call.func)) in kernel
        if not any(g.name == name and not _compiled(g) for g in fs)  # the module's own
    }


def test_the_tables_name_each_kernel_called_from_python():
    tables = [kernels.table(name) for name in kernels.TABLES]
    assert set().union(*tables) == _called_from_python()
    assert all(kernels.SIGNATURES[k] == v for t in tables for k, v in t.items())
    assert len(kernels.SIGNATURES) == len(set().union(*tables))


def test_a_flat_leafs_first_run_does_not_wait_for_a_bent_leafs_kernels(monkeypatch):
    """The app's first leaf is a flat demo: the bent leaf's kernels (a pose's jets, its 3.8 s
    of compile the costliest) are compiled ahead of the first bent run, not of a flat one."""
    asked = []
    monkeypatch.setattr(
        "leafstudio.core.pipeline.compile_kernels", lambda *a, **kw: asked.append(kw["tables"])
    )
    from leafstudio.forms.make import Form

    ls.Pipeline(ls.demo("nested")).run(ls.Params(grid=32))
    ls.Pipeline(Form("ovate", fold=30).leaf()).run(ls.Params(grid=32))
    assert asked == [(kernels.STAGE,), (kernels.STAGE, kernels.BENT)]
    bent_modules = ("pose_jet", "bent_mesh", "bent_curvature", "edges")
    assert {n for n in _called_from_python() if n.split(":")[0] in bent_modules} == set(
        kernels.BENT_KERNELS
    )
    assert not set(kernels.BENT_KERNELS) & set(kernels.KERNELS)


def test_each_kernel_of_the_tables_is_the_one_a_run_or_measuring_calls():
    from PIL import Image

    from leafstudio.assets.texture import bleed
    from leafstudio.forms.make import Form
    from tests.leaves import noisy

    assert ls.Pipeline(ls.demo("nested")).run(ls.Params()).metrics
    ls.Pipeline(noisy("nested")).run(ls.Params(grid=32))  # a cloud: its projection
    ls.Pipeline(Form("ovate", roll=0.3).leaf()).run(ls.Params(grid=32))  # a bent one's curvatures
    # a blade large on the grid: the bending gram by Dᵀ D TΦ (bending._bend_twice), which none of
    # the runs above takes (their lattice has fewer rows than nodes): alone, this test failed
    ls.Pipeline(Form("ovate").leaf()).run(ls.Params(grid=128))
    rgba = np.zeros((8, 8, 4), np.uint8)
    rgba[2:5, 3:6] = 200
    bleed(Image.fromarray(rgba, "RGBA"))  # a texture's edge padding
    for name, argtypes in kernels.SIGNATURES.items():
        assert argtypes in kernels.dispatcher(name).signatures, name


def test_measuring_compiles_its_kernels_in_worker_processes(monkeypatch, tmp_path):
    """The metrics' and a scan's distances compile in worker processes when first needed (issue
    24, #5): the app's process compiled them on its worker thread, holding the GIL for seconds
    (its window stalled, the measurements came ~25 s after the leaf)."""
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))  # the workers inherit it
    one = "distance:_morton"
    monkeypatch.setattr(kernels, "MEASURING", {one: kernels.MEASURING[one]})
    assert not kernelcache.kernels_cached(kernels.MEASURE)
    evaluate.edge_counts(np.array([[0, 1, 2], [0, 2, 3]]))  # a mesh's facts: measuring
    assert any(p.name.startswith("distance._morton") for p in tmp_path.rglob("*.nbi"))
    assert kernelcache.kernels_cached(kernels.MEASURE)
    assert not kernelcache.kernels_cached()  # the run's table is its own


def test_set_up_compiles_every_table(monkeypatch):
    """`./dev setup` compiles the run's and measuring's kernels, then runs once."""
    command = re.search(r'^SETUP_RUN="([^"]*)"', (ROOT / "dev").read_text(), re.M).group(1)
    asked = []
    monkeypatch.setattr(kernels, "compile_kernels", lambda **kw: asked.append(kw["tables"]))
    exec(command, {})  # the set-up's own command, compiling nothing here
    assert asked == [kernels.TABLES]


def test_a_cold_cache_is_filled_by_worker_processes(monkeypatch, tmp_path):
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))  # the workers inherit it
    one = "prepare.outline:_ring_length"
    monkeypatch.setattr(kernels, "KERNELS", {one: kernels.KERNELS[one]})
    said = []
    spent = kernels.compile_kernels(said.append, workers=1)
    assert len(spent) == 1 and os.getpid() not in spent  # one worker, not this process
    assert said == [kernels.STAGE, f"{kernels.STAGE} 1/1"]  # the app's status: compiling_notice
    assert [kernels.compiling_notice(s) for s in said] == [NOTICE, f"{NOTICE} 1/1"]
    assert any(p.name.startswith("outline._ring_length") for p in tmp_path.rglob("*.nbi"))
    assert kernelcache.kernels_cached()
    assert not kernels.compile_kernels(said.append)  # cached now: nothing said or done
    assert len(said) == 2
    assert kernels.compiling_notice("guide") is None


def test_a_worker_that_dies_leaves_the_kernels_to_the_run(monkeypatch, tmp_path):
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))
    monkeypatch.setattr(kernels, "WORKER", "import sys; sys.exit(1)")
    assert kernels.compile_kernels(workers=2)  # both workers started, and stopped
    assert not kernelcache.kernels_cached()  # not marked: the next run says it compiles


# a cheap kernel, then one whose compile takes about a second (ten polls, POLL_S): a stop that
# comes after the first kernel comes while the second compiles (the costliest kernel,
# surface:_levenberg_marquardt, took 3.7 s of CPU to compile in full, the next run's)
CHEAP, SLOWER = "prepare.outline:_ring_length", "mpu:_quotient_rule"


def _cached_kernels(folder: Path) -> set[str]:
    """The kernels whose index numba wrote in `folder` ("_ring_length", ...)."""
    return {p.name.split(".")[1].split("-")[0] for p in folder.rglob("*.nbi")}


def test_a_stopped_compile_ends_its_workers_and_the_next_one_compiles_the_rest(
    monkeypatch, tmp_path
):
    """Cancel (or a closed window) during the first run's compile: the workers are ended at
    once, not left to compile on; the kernel compiled stays cached and the next compile does
    the rest (issue 24, first hour)."""
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))
    names = [CHEAP, SLOWER]  # the stop comes while the second compiles
    monkeypatch.setattr(kernels, "KERNELS", {n: kernels.KERNELS[n] for n in names})
    said: list[str] = []
    spent = kernels.compile_kernels(said.append, workers=1, should_stop=lambda: len(said) > 1)
    assert said == [kernels.STAGE, f"{kernels.STAGE} 1/2"]
    (pid,) = spent
    assert not Path(f"/proc/{pid}").exists()  # ended (and reaped), not compiling on
    assert _cached_kernels(tmp_path) == {"_ring_length"}  # the second was cut short
    assert not kernelcache.kernels_cached()
    assert kernels.compile_kernels(said.append, workers=1)  # the next run: no broken cache
    assert said[-1] == f"{kernels.STAGE} 2/2"
    assert {"_ring_length", "_quotient_rule"} <= _cached_kernels(tmp_path)
    assert kernelcache.kernels_cached()


def test_a_compile_whose_progress_callback_raises_ends_its_workers(monkeypatch, tmp_path):
    """A progress callback that raises (a job cancelled through it) ends the workers at once
    too: the pool waited for every kernel before, and the crew stayed registered."""
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))
    names = [CHEAP, SLOWER]
    monkeypatch.setattr(kernels, "KERNELS", {n: kernels.KERNELS[n] for n in names})

    def stop_at_first_kernel(stage: str) -> None:
        if stage.endswith("1/2"):
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        kernels.compile_kernels(stop_at_first_kernel, workers=1)
    assert _cached_kernels(tmp_path) == {"_ring_length"}  # the second was cut short
    assert not kernels._CREWS
    assert not kernelcache.kernels_cached()


def test_a_run_stopped_while_compiling_is_cancelled(monkeypatch, tmp_path):
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))
    one = "surface:_levenberg_marquardt"
    monkeypatch.setattr(kernels, "KERNELS", {one: kernels.KERNELS[one]})
    said: list[str] = []
    with pytest.raises(Cancelled):
        ls.Pipeline(ls.demo("nested")).run(
            ls.Params(), on_stage=said.append, should_stop=lambda: bool(said)
        )
    assert said == [kernels.STAGE]  # stopped while compiling: no stage ran
    assert not _cached_kernels(tmp_path)


@pytest.fixture(autouse=True)
def _restore_environment(monkeypatch):
    monkeypatch.setenv("NUMBA_CACHE_DIR", os.environ.get("NUMBA_CACHE_DIR", ""))
    yield


def test_measurings_compile_is_tried_once_per_process_even_when_its_stamp_is_not_written(
    monkeypatch, tmp_path
):
    """ensure_compiled runs before every distance and edge count: a compile whose stamp could
    not be written (a full disk: kernelcache makes numba's own writes harmless) or whose worker
    died started the worker processes again at each call, seconds of CPU every time. A stopped
    compile is tried again (the next run finishes it)."""
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))
    tried: list[list[str]] = []
    monkeypatch.setattr(kernels, "_compile", lambda names, *_: tried.append(names) or {})
    kernels.compile_kernels(should_stop=lambda: True, tables=(kernels.MEASURE,))  # stopped
    kernels.ensure_compiled()  # tried again, to the end
    kernels.ensure_compiled()
    evaluate.edge_counts(np.array([[0, 1, 2]]))
    assert tried == [list(kernels.MEASURING)] * 2  # nothing marked, and tried to the end once
    assert not kernelcache.kernels_cached(kernels.MEASURE)


def test_the_compile_loads_each_kernel_as_its_worker_ends_it(monkeypatch, tmp_path):
    """Each kernel compiled is loaded from the cache at once, while the workers compile the
    rest: the run loaded all 41 after the compile, 0.4 s of a first run's wall time."""
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))
    monkeypatch.setattr(kernels, "KERNELS", {CHEAP: kernels.KERNELS[CHEAP]})
    loaded = []
    real = kernels.dispatcher
    monkeypatch.setattr(kernels, "dispatcher", lambda name: loaded.append(name) or real(name))
    kernels.compile_kernels(workers=1)
    assert loaded == [CHEAP]
    assert kernels.KERNELS[CHEAP] in real(CHEAP).signatures


def test_a_worker_ended_before_its_first_kernel_leaves_quietly(monkeypatch):
    """A stopped run ends its workers (_Crew.end) at any moment: one ended before it read its
    first kernel's name left that name in its pipe's buffer, and leaving the process flushed
    it into the ended worker and raised BrokenPipeError out of the compile (a full suite's
    test_a_stopped_compile_ends_its_workers_and_the_next_one_compiles_the_rest, once)."""
    import queue
    import subprocess

    started = subprocess.Popen

    def ended_at_once(*args, **kwargs):
        process = started(*args, **kwargs)
        process.kill()
        process.wait()
        return process

    monkeypatch.setattr(kernels.subprocess, "Popen", ended_at_once)
    todo, done = queue.SimpleQueue(), queue.SimpleQueue()
    todo.put(CHEAP)
    crew = kernels._Crew()
    pid, seconds = kernels._worker(todo, done, crew)
    assert pid > 0 and seconds == 0.0 and done.empty()
    assert not crew.processes
