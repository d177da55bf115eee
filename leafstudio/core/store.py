"""The pipeline's one cache: stage outputs keyed by the leaf's fingerprint and the parameters each
stage reads. No step of the paper; the table of stages that use it is stages.py's.
"""

from __future__ import annotations

import hashlib
from collections import OrderedDict
from collections.abc import Callable
from typing import Any

from leafstudio.model import Leaf


class StageStore:
    """The one cache of stage outputs, keyed by the leaf's fingerprint and the parameters the
    stage reads (its own and those of every stage before it, STAGE_KEYS).

    As in trimesh's caching.py, an entry holds only while what it was computed from is the same:
    the key names the leaf by a digest of its coordinates (Leaf.fingerprint), so a store may be
    shared between Pipelines and a different leaf with the same parameters misses. Each stage
    keeps its `per_stage` most recent outputs (1: the last run's, as a Pipeline needs to rerun
    only what a parameter change invalidates).

    Besides the stages (stages.STAGE_TABLE) it keeps what is made from a run's mesh on first use,
    under the mesh stage's key: "metrics" (result.Measuring, measured in steps) and "polydata"
    (result.Later, the VTK mesh). A value that must not live longer than its inputs belongs here,
    not in a cache of its own (a cached property, a memoised function, a dict keyed by id()).
    """

    def __init__(self, per_stage: int = 1) -> None:
        self.per_stage = per_stage
        self._entries: dict[str, OrderedDict[tuple[Any, ...], Any]] = {}

    def get(self, stage: str, key: tuple[Any, ...]) -> Any:
        """The output stored for `stage` under `key`, or MISSING."""
        entries = self._entries.get(stage)
        if entries is None or key not in entries:
            return MISSING
        entries.move_to_end(key)
        return entries[key]

    def put(self, stage: str, key: tuple[Any, ...], value: Any) -> None:
        """Keep `value` as `stage`'s output under `key` (the oldest beyond per_stage goes)."""
        entries = self._entries.setdefault(stage, OrderedDict())
        entries[key] = value
        entries.move_to_end(key)
        while len(entries) > self.per_stage:
            entries.popitem(last=False)

    def setdefault(self, stage: str, key: tuple[Any, ...], make: Callable[[], Any]) -> Any:
        """The output stored for `stage` under `key`, or `make()` stored there and returned."""
        value = self.get(stage, key)
        if value is MISSING:
            value = make()
            self.put(stage, key, value)
        return value

    def stages(self) -> tuple[str, ...]:
        """The stages with an output kept."""
        return tuple(name for name, entries in self._entries.items() if entries)


MISSING = object()  # StageStore.get: no output kept under that key


def leaf_key(leaf: Leaf) -> bytes:
    """A 16-byte digest of the leaf's coordinates (Leaf.fingerprint): the store's leaf key."""
    return hashlib.blake2b(leaf.fingerprint(), digest_size=16).digest()
