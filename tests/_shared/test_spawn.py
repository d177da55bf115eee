"""Worker processes (_shared/spawn.py): forked from a server that imported leafstudio once, yet
seeing what a spawned worker would see."""

from __future__ import annotations

import os
import sys
from concurrent.futures import ProcessPoolExecutor

import pytest

from leafstudio._shared.spawn import WorkerContext


def _ask(function, *args):
    """function(*args) in a one-worker pool of WorkerContext."""
    with ProcessPoolExecutor(1, mp_context=WorkerContext()) as pool:
        return pool.submit(function, *args).result(timeout=120)


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="a fork server on Linux only")
def test_a_worker_is_forked_from_the_server_not_spawned_by_this_process():
    _ask(os.getpid)  # the server started, with this process's environment
    assert _ask(os.getppid) != os.getpid()  # spawned, it would be this process's child


def test_a_worker_sees_the_environment_and_folder_its_parent_has_now(monkeypatch, tmp_path):
    monkeypatch.setenv("LEAFSTUDIO_SPAWN_TEST", "first")
    assert _ask(os.getenv, "LEAFSTUDIO_SPAWN_TEST") == "first"
    monkeypatch.setenv("LEAFSTUDIO_SPAWN_TEST", "second")  # after the server started
    assert _ask(os.getenv, "LEAFSTUDIO_SPAWN_TEST") == "second"
    monkeypatch.chdir(tmp_path)
    assert os.path.samefile(_ask(os.getcwd), tmp_path)
