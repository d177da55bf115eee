"""One BLAS thread while leafstudio computes: its dense solves are small (the vein correction's
180-800 centres, a base surface's 192), and a second OpenBLAS thread only makes them wait.

On two cores with the other one busy (the app's main thread drawing, a second test worker, any
other program), OpenBLAS's helper thread gets no core until the scheduler's next turn, and the
calling thread waits for it: an LU factorisation of a 179 x 179 matrix took 125 ms instead of
0.3 ms. Measured with one core busy (`OPENBLAS_NUM_THREADS=1` against the default, median of 8):
an ovate form's reconstruction at grid 128 312 -> 142 ms, opening a soybean scan 3.3 -> 1.7 s. On
an idle machine one thread is no slower at these sizes (the LU 0.76 -> 0.29 ms).

OpenBLAS's limit is process-wide, and threadpoolctl lets only one thread set it (the first that
does; in other threads a limit does nothing). So the command line, the app's too, runs each
command inside `one_blas_thread` on the main thread, before any lane starts: the lanes compute
under that limit. A reconstruction or a scan's extraction called from a script limits it too,
while it runs, and gives the script's own limit back after. threadpoolctl's controller is made
once (about 5 ms); a limit costs about 0.04 ms.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from functools import cache

from threadpoolctl import ThreadpoolController


@cache
def _controller() -> ThreadpoolController:
    """The loaded BLAS libraries (made on first use, once numpy and scipy have loaded theirs)."""
    import scipy.linalg  # noqa: F401  (loads scipy's own OpenBLAS, for the controller to list)

    return ThreadpoolController()


@contextmanager
def one_blas_thread() -> Iterator[None]:
    """Run the body with BLAS on one thread, then give the earlier limit back."""
    with _controller().limit(limits=1, user_api="blas"):
        yield
