"""Where numba keeps the compiled kernels, and whether this run will compile them.

numba caches beside the sources (core/__pycache__ and its subfolders) when they can be
written. In an installation whose package folder is read-only, the kernels go to the user's
cache folder (XDG_CACHE_HOME, ~/.cache, ~/Library/Caches or LOCALAPPDATA), or to a private
temporary folder as a last resort, instead of failing at import. `configure()` must run before
numba is imported (leafstudio/__init__.py calls it first); it does not import numba itself
(about 0.2 s), so `import leafstudio` stays light: `guard_cache_writes()` runs when the first
kernel module imports numba's njit through core/jit.py. A stamp in the cache folder for each
table of kernels (core/kernels.TABLES), written once the table is compiled (after a compile or a
first run), lets the command line say "compiling" on a first run instead of 20 s of silence.
"""

from __future__ import annotations

import contextlib
import hashlib
import os
import sys
import tempfile
from pathlib import Path

CORE = Path(__file__).resolve().parents[1] / "core"


def _writable(folder: Path) -> bool:
    """`folder` exists (or can be made) and a file can be created in it."""
    try:
        folder.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryFile(dir=folder):
            pass
    except OSError:
        return False
    return True


def user_cache_folder() -> Path:
    """This platform's per-user cache folder for LeafStudio."""
    if sys.platform == "win32":
        base = Path(os.environ.get("LOCALAPPDATA") or Path.home() / "AppData" / "Local")
    elif sys.platform == "darwin":
        base = Path.home() / "Library" / "Caches"
    else:
        base = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache")
    return base / "leafstudio"


def configure() -> Path | None:
    """Point numba's cache at a writable folder when the package's own cannot be written, and
    make a failed cache write (a full disk) harmless once numba is imported; returns the folder
    chosen (None: numba's default beside the sources, or the user's NUMBA_CACHE_DIR)."""
    folder = _choose_folder()
    # numba not imported yet: core/jit.py guards the writes when a kernel module imports it
    if "numba" in sys.modules:
        guard_cache_writes()
    return folder


def guard_cache_writes() -> None:
    """A kernel whose cache file cannot be written (disk full, quota) still runs: it is compiled
    in memory; numba would raise the OSError out of the user's run instead."""
    from numba.core import caching  # heavy (numba, 0.2 s): only where the kernels are

    save = caching.Cache.save_overload
    if getattr(save, "_leafstudio_guard", False):
        return

    def save_overload(self, sig, data):
        with contextlib.suppress(OSError):  # the kernel is compiled; its on-disk copy is lost
            save(self, sig, data)

    save_overload._leafstudio_guard = True  # type: ignore[attr-defined]
    caching.Cache.save_overload = save_overload


def _choose_folder() -> Path | None:
    if os.environ.get("NUMBA_CACHE_DIR") or _writable(CORE / "__pycache__"):
        return None
    uid = os.getuid() if hasattr(os, "getuid") else 0
    for folder in (
        user_cache_folder() / "numba",
        Path(tempfile.gettempdir()) / f"leafstudio-{uid}-numba",
    ):
        if _writable(folder):
            os.environ["NUMBA_CACHE_DIR"] = str(folder)
            if "numba" in sys.modules:  # already imported: its config read the variable then
                from numba.core import config

                config.CACHE_DIR = str(folder)
            return folder
    return None


def cache_folder() -> Path:
    """Where numba keeps the kernels now (NUMBA_CACHE_DIR, or beside the sources)."""
    folder = os.environ.get("NUMBA_CACHE_DIR")
    return Path(folder) if folder else CORE / "__pycache__"


def _stamp(table: str = "kernels") -> Path:
    """A file named after a table of kernels (core/kernels.TABLES), their sources (every module
    under core/, by its path there, size and time) and numba's version."""
    import numba

    digest = hashlib.sha256(numba.__version__.encode())
    digest.update(sys.version.encode())
    for source in sorted(CORE.rglob("*.py")):
        info = source.stat()
        name = source.relative_to(CORE).as_posix()  # core/prepare's modules by their folder too
        digest.update(f"{name}:{info.st_size}:{info.st_mtime_ns}".encode())
    return cache_folder() / f"leafstudio-{table}-{digest.hexdigest()[:16]}.stamp"


def kernels_cached(table: str = "kernels") -> bool:
    """Whether the current kernels of `table` (a run's by default) are compiled and cached."""
    try:
        return _stamp(table).exists()
    except OSError:
        return True  # cannot tell: say nothing rather than something wrong


def mark_cached(table: str = "kernels") -> None:
    """Record that the kernels of `table` are compiled (after a successful run); best effort."""
    with contextlib.suppress(OSError):
        stamp = _stamp(table)
        if not stamp.exists():
            stamp.parent.mkdir(parents=True, exist_ok=True)
            stamp.touch()


NOTICE = "Compiling the numerical kernels (first run only)…"  # the CLI's line, the app's status
