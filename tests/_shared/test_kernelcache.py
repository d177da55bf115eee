"""The compiled-kernel cache (issue 11): a user cache folder when the package's folder cannot be
written, a failed cache write that does not fail the run, and a notice on a first run."""

from __future__ import annotations

import logging

import pytest

from leafstudio._shared import kernelcache


def test_a_read_only_package_folder_sends_the_cache_to_the_user_cache_folder(tmp_path, monkeypatch):
    monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    package_cache = kernelcache.CORE / "__pycache__"
    real = kernelcache._writable
    monkeypatch.setattr(kernelcache, "_writable", lambda f: f != package_cache and real(f))
    from numba.core import config

    monkeypatch.setattr(config, "CACHE_DIR", config.CACHE_DIR)
    folder = kernelcache.configure()
    assert folder == tmp_path / "cache" / "leafstudio" / "numba"
    assert kernelcache.os.environ["NUMBA_CACHE_DIR"] == str(folder) == config.CACHE_DIR
    monkeypatch.delenv("NUMBA_CACHE_DIR")


def test_a_writable_package_folder_or_a_users_choice_is_left_alone(monkeypatch, tmp_path):
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))
    assert kernelcache.configure() is None
    monkeypatch.delenv("NUMBA_CACHE_DIR")
    monkeypatch.setattr(kernelcache, "_writable", lambda f: True)
    assert kernelcache.configure() is None


def test_a_failed_cache_write_does_not_fail_the_run(monkeypatch):
    from numba import njit
    from numba.core import caching

    kernelcache.configure()  # the guard is installed once
    assert getattr(caching.Cache.save_overload, "_leafstudio_guard", False)

    def full(self, filepath):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(caching.IndexDataCacheFile, "_open_for_write", full)

    @njit(cache=True)
    def twice(x):  # pragma: no cover - compiled
        return 2 * x

    assert twice(21) == 42


def test_a_first_run_says_it_compiles(monkeypatch, tmp_path, caplog):
    from leafstudio.cli import options

    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))
    assert not kernelcache.kernels_cached()
    logger = logging.getLogger("leafstudio")
    monkeypatch.setattr(logger, "propagate", True)
    with caplog.at_level(logging.INFO, logger="leafstudio"):
        options.compiling_notice()
    assert kernelcache.NOTICE in caplog.text
    kernelcache.mark_cached()
    assert kernelcache.kernels_cached()
    caplog.clear()
    with caplog.at_level(logging.INFO, logger="leafstudio"):
        options.compiling_notice()
    assert "ompiling" not in caplog.text


@pytest.fixture(autouse=True)
def _restore_environment(monkeypatch):
    """configure() sets NUMBA_CACHE_DIR itself: recorded first here, so it is restored last."""
    monkeypatch.setenv("NUMBA_CACHE_DIR", kernelcache.os.environ.get("NUMBA_CACHE_DIR", ""))
    yield
