"""Builders shared by the app's tests, without Qt: a stand-in for the worker that runs the
session's requests when asked, the small parameters the window tests run at, and synthetic scans.
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from leafstudio.core.pipeline import Pipeline
from leafstudio.errors import LeafError
from leafstudio.gui.model.session import Session
from leafstudio.model import Leaf, Params

FAST = Params(k=3, grid=48, samples=1500)  # small enough for quick runs, same code paths


class Runner:
    """Stands in for the worker: records requests, runs them when asked."""

    def __init__(self) -> None:
        self.requests: list[tuple[Leaf, Params]] = []

    def __call__(self, leaf: Leaf, params: Params, interrupt: bool) -> int:
        self.requests.append((leaf, params))
        return len(self.requests)

    def finish(self, session: Session, index: int = -1) -> object:
        """Run request `index` and report it to the session as the worker would."""
        request_id = len(self.requests) + 1 + index if index < 0 else index + 1
        leaf, params = self.requests[request_id - 1]
        try:
            result = Pipeline(leaf).run(params)
        except LeafError as exc:
            session.accept_failure(request_id, exc)
            return None
        outcome = SimpleNamespace(request=SimpleNamespace(id=request_id), result=result, layers={})
        session.accept_result(outcome)
        return outcome


def six_column_scan(n: int = 900, seed: int = 0) -> np.ndarray:
    """(m, 6) points of a curved elliptic blade (length 2) with made-up normals: a scan."""
    rng = np.random.default_rng(seed)
    xy = rng.uniform([-1.0, -0.4], [1.0, 0.4], size=(n, 2))
    xy = xy[xy[:, 0] ** 2 + (xy[:, 1] / 0.4) ** 2 < 1]
    z = 0.15 * xy[:, 0] ** 2 - 0.3 * xy[:, 1] ** 2
    return np.column_stack([xy, z, np.tile([0.0, 0.0, 1.0], (len(xy), 1))])


def write_points(path, rows: np.ndarray) -> str:
    path.write_text("\n".join(",".join(f"{v:.6f}" for v in row) for row in rows) + "\n")
    return str(path)
