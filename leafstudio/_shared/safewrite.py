"""Writing files so that a failed run loses nothing: every output goes through one path.

A writer fills a temporary file beside its target (hidden, and named after the target and this
process, so a later write to the same target removes what a killed run left); the file is checked
(it exists and is not empty), flushed to disk, then renamed over the target. Inside `staged()`
the renames wait until the whole run has succeeded: a run that fails half-way replaces nothing.
Temporary files are removed on errors, on Ctrl-C and on SIGTERM (see `install_signal_cleanup`).
"""

from __future__ import annotations

import contextlib
import contextvars
import logging
import os
import re
import secrets
import signal
import stat
import threading
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path

from leafstudio._shared.inputs import special_file
from leafstudio.errors import LeafError

PART_MARK = "leafstudio-part"  # in every temporary file's name
_NAME_LIMIT = 120  # characters of the target's name kept in its temporary file's name

_live: set[str] = set()  # temporary files of this process not yet renamed or removed
_live_lock = threading.Lock()
_signals_installed = False


def _extension(name: str) -> str:
    """The target's suffix as writers that go by it see it (".leaf.json" counts as one)."""
    lower = name.lower()
    if lower.endswith(".leaf.json"):
        return name[-len(".leaf.json") :]
    return Path(name).suffix


def _temp_name(target: Path) -> str:
    stem = target.name[:_NAME_LIMIT]
    return f".{stem}.{os.getpid()}-{secrets.token_hex(4)}.{PART_MARK}{_extension(target.name)}"


def _pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OverflowError):
        return True
    return True


# a temporary file's name: ".TARGET.PID-HEX.leafstudio-part[.EXT]" (see _temp_name)
_PART = re.compile(rf"^\.(.*)\.(\d+)-[0-9a-f]+\.{re.escape(PART_MARK)}(\..+)?$", re.DOTALL)


def stale_part(name: str) -> str | None:
    """The target's name (cut to _NAME_LIMIT characters) if `name` is one of our temporary files
    left by a process no longer alive (a killed run's, safe to delete); None if it is not a
    temporary file, or its process still runs."""
    found = _PART.match(name)
    if found is None or _pid_alive(int(found.group(2))):
        return None
    return found.group(1)


def remove_stale(target: Path) -> list[Path]:
    """Remove temporary files beside `target` left by runs that are no longer alive."""
    removed = []
    try:
        entries = list(os.scandir(target.parent))
    except OSError:
        return removed
    for entry in entries:
        if stale_part(entry.name) != target.name[:_NAME_LIMIT]:
            continue
        with contextlib.suppress(OSError):
            os.unlink(entry.path)
            removed.append(Path(entry.path))
    return removed


def _register(tmp: str) -> None:
    with _live_lock:
        _live.add(tmp)


def _forget(tmp: str, remove: bool) -> None:
    with _live_lock:
        _live.discard(tmp)
    if remove:
        with contextlib.suppress(OSError):
            os.unlink(tmp)


def remove_all_temporaries() -> None:
    """Remove every temporary file this process still holds (on a signal or at exit)."""
    with _live_lock:
        pending = list(_live)
        _live.clear()
    for tmp in pending:
        with contextlib.suppress(OSError):
            os.unlink(tmp)


def check_target(path: str | os.PathLike) -> Path:
    """`path` as an output: refused (LeafError) if it is a folder or a special file (a device, a
    FIFO), or if a file stands where its folder belongs. Checked before any work. A folder that
    does not exist yet is created when the output is written (make_folder), as `batch -o OUTDIR`
    creates OUTDIR."""
    path = Path(path)
    try:
        info = path.stat()
    except FileNotFoundError:
        info = None
    except OSError as exc:
        raise LeafError(f"cannot be written ({exc.strerror})", str(path)) from None
    if info is not None:
        if stat.S_ISDIR(info.st_mode):
            raise LeafError("is a folder, not a file", str(path))
        if (said := special_file(info.st_mode)) is not None:
            raise LeafError(said, str(path))
    parent = path.parent
    if parent.exists() and not parent.is_dir():
        raise LeafError(f"cannot be written: {parent} is not a folder", str(path))
    return path


def _same_file(a: Path, b: Path) -> bool:
    """The same path (after resolving links and '..') or, for files that exist, the same inode."""
    try:
        if a.exists() and b.exists():
            return os.path.samefile(a, b)
        return a.resolve() == b.resolve()
    except (OSError, RuntimeError):
        return os.path.abspath(a) == os.path.abspath(b)


def refuse_overlap(
    inputs: Sequence[str | os.PathLike | None], outputs: Sequence[str | os.PathLike | None]
) -> None:
    """Refuse, before any work, an output that is also an input or another output of the run."""
    ins = [Path(p) for p in inputs if p]
    outs = [Path(p) for p in outputs if p]
    for i, out in enumerate(outs):
        for src in ins:
            if _same_file(out, src):
                raise LeafError(
                    f"is also an input ({src}); write the output to another file", str(out)
                )
        for other in outs[:i]:
            if _same_file(out, other):
                raise LeafError(f"is given as two outputs ({other} and {out})", str(out))


def check_outputs(
    inputs: Sequence[str | os.PathLike | None], outputs: Sequence[str | os.PathLike | None]
) -> None:
    """Refuse, before any work, every output of a run that is also an input or another output
    (refuse_overlap) or that cannot be written (check_target); None entries are left out."""
    refuse_overlap(inputs, outputs)
    for path in outputs:
        if path:
            check_target(path)


def _usual_permissions(path: str, target: Path) -> None:
    """Give the temporary file (created 0600) the target's permissions, or those a plain new file
    would get."""
    try:
        mode = stat.S_IMODE(target.stat().st_mode)
    except OSError:
        umask = os.umask(0)
        os.umask(umask)
        mode = 0o666 & ~umask
    os.chmod(path, mode)


def _fsync_file(path: str) -> None:
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def _fsync_folder(folder: Path) -> None:
    with contextlib.suppress(OSError):
        fd = os.open(folder, os.O_RDONLY)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)


def _failed(exc: OSError, target: Path) -> LeafError:
    reason = exc.strerror or str(exc)
    return LeafError(f"cannot be written ({reason}); any old file is unchanged", str(target))


class Staging:
    """Outputs written to temporary files, renamed over their targets together by `commit`."""

    def __init__(self) -> None:
        self._pending: list[tuple[str, Path]] = []

    @property
    def targets(self) -> list[Path]:
        """The outputs staged so far."""
        return [target for _, target in self._pending]

    def add(self, tmp: str, target: Path) -> None:
        """Keep `tmp` to be renamed over `target` at commit; a target staged twice is a bug."""
        if any(os.path.abspath(t) == os.path.abspath(target) for t in self.targets):
            _forget(tmp, remove=True)
            raise LeafError("is written twice by one run", str(target))
        self._pending.append((tmp, target))

    def commit(self) -> None:
        """Rename every staged file over its target (each rename is atomic)."""
        pending, self._pending = self._pending, []
        for i, (tmp, target) in enumerate(pending):
            try:
                os.replace(tmp, target)
            except OSError as exc:
                for later, _ in pending[i:]:
                    _forget(later, remove=True)
                raise _failed(exc, target) from None
            _forget(tmp, remove=False)
            _fsync_folder(target.parent)

    def discard(self) -> None:
        """Remove every staged file; the targets stay as they were."""
        pending, self._pending = self._pending, []
        for tmp, _ in pending:
            _forget(tmp, remove=True)


_staging: contextvars.ContextVar[Staging | None] = contextvars.ContextVar(
    "leafstudio_staging", default=None
)


@contextlib.contextmanager
def staged() -> Iterator[Staging]:
    """Within this block, `replace_atomically` writes but does not rename; the renames happen
    together when the block ends without an error, and none happen if it raises.

    Example: ``with staged(): save_mesh(result, out); write_text(metrics, text)``.
    """
    staging = Staging()
    token = _staging.set(staging)
    try:
        yield staging
    except BaseException:
        _staging.reset(token)
        staging.discard()
        raise
    _staging.reset(token)
    try:
        staging.commit()
    except BaseException:
        staging.discard()
        raise


def make_folder(target: Path) -> None:
    """Create the missing folders of an output's path, saying so in one line on the leafstudio
    log (a mistyped folder is not made without a word); nothing when the folder exists."""
    folder = target.parent
    if folder.is_dir():
        return
    top = folder
    while not top.parent.exists() and top.parent != top:
        top = top.parent  # the first folder that did not exist
    folder.mkdir(parents=True, exist_ok=True)
    logging.getLogger("leafstudio").info(f"created the folder {top} for {target}")


def replace_atomically(path: str | os.PathLike, write: Callable[[str], object]) -> None:
    """Run `write` on a temporary file beside `path`, check it, flush it to disk and rename it
    over `path` (or, inside `staged()`, keep it for the block's end).

    The temporary file ends with the target's suffix, so writers that go by it still work. Any
    failure leaves `path` as it was, removes the temporary file and raises a LeafError naming
    `path` (an OSError from `write`) or lets `write`'s own LeafError through.
    """
    target = check_target(path)
    try:
        make_folder(target)
    except OSError as exc:
        raise _failed(exc, target) from None
    remove_stale(target)
    tmp = str(target.parent / _temp_name(target))
    try:
        fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
    except OSError as exc:
        raise _failed(exc, target) from None
    os.close(fd)
    _register(tmp)
    try:
        write(tmp)
        if not os.path.isfile(tmp) or os.path.getsize(tmp) == 0:
            raise LeafError("cannot be written (the writer produced no data)", str(target))
        _usual_permissions(tmp, target)
        _fsync_file(tmp)
        staging = _staging.get()
        if staging is not None:
            staging.add(tmp, target)
            return
        os.replace(tmp, target)
        _forget(tmp, remove=False)
        _fsync_folder(target.parent)
    except OSError as exc:
        _forget(tmp, remove=True)
        raise _failed(exc, target) from None
    except BaseException:
        _forget(tmp, remove=True)
        raise


def write_bytes(path: str | os.PathLike, data: bytes | str) -> None:
    """Write bytes (or UTF-8 text) to `path` safely."""
    payload = data.encode("utf-8") if isinstance(data, str) else data

    def write(tmp: str) -> None:
        with open(tmp, "wb") as handle:
            handle.write(payload)
            handle.flush()

    replace_atomically(path, write)


def install_signal_cleanup() -> None:
    """On SIGTERM or SIGHUP, unwind as Ctrl-C does, so temporary files are removed; call from the
    main thread (the command line does)."""
    global _signals_installed
    if _signals_installed or threading.current_thread() is not threading.main_thread():
        return
    _signals_installed = True

    def stop(signum: int, _frame: object) -> None:
        remove_all_temporaries()
        raise SystemExit(128 + signum)

    for name in ("SIGTERM", "SIGHUP"):
        sig = getattr(signal, name, None)
        if sig is not None:
            with contextlib.suppress(ValueError, OSError):
                signal.signal(sig, stop)
    import atexit

    atexit.register(remove_all_temporaries)


__all__ = [
    "PART_MARK",
    "Staging",
    "check_outputs",
    "check_target",
    "install_signal_cleanup",
    "refuse_overlap",
    "remove_all_temporaries",
    "remove_stale",
    "replace_atomically",
    "staged",
    "stale_part",
    "write_bytes",
]
