"""The session's undo history without Qt: snapshots of the document (State), undoable steps
and the History that moves between them, and the small Event the model reports through."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from leafstudio.gui.model.sketch_model import Sketch
from leafstudio.model import Leaf, Params


class Event:
    """A list of callbacks: `connect(f)`, `disconnect(f)`, `emit(*args)` (no Qt)."""

    def __init__(self) -> None:
        self._callbacks: list[Callable[..., Any]] = []

    def connect(self, callback: Callable[..., Any]) -> None:
        self._callbacks.append(callback)

    def disconnect(self, callback: Callable[..., Any]) -> None:
        self._callbacks.remove(callback)

    def emit(self, *args: Any) -> None:
        for callback in list(self._callbacks):
            callback(*args)


@dataclass(frozen=True, eq=False)
class State:
    """One snapshot of what is edited; undo and redo swap snapshots.

    leaf is None while a sketch has fewer than 3 boundary points; sketch is None for a leaf read
    from points (until it is first edited). `serial` numbers documents: a new one is framed.
    """

    leaf: Leaf | None
    sketch: Sketch | None
    params: Params
    path: str | None = None
    title: str = "untitled"
    scan: Any = None  # gui.scans.ScanData
    serial: int = 0
    photo: Any = None  # assets.leafphoto.LeafPhoto: the photo the leaf was found in
    # a leaf opened in 3D that no pose laid flat: its margin's share off its plane
    # (core/unfolded.unposed_share), kept through its edits so they are not fitted again
    # (bending.keeps_refusal)
    unposed: float | None = None


@dataclass(frozen=True, eq=False)
class Step:
    """One undoable edit."""

    text: str
    before: State
    after: State


class History:
    """Undo and redo over State snapshots, with a clean mark (the saved state)."""

    def __init__(self, moved: Callable[[State], None] | None = None) -> None:
        self.moved = moved  # called with the state that undo or redo makes current
        self.steps: list[Step] = []
        self.index = 0  # steps[:index] are done
        self.clean_index: int | None = 0
        self.changed = Event()

    def push(self, step: Step) -> None:
        if self.clean_index is not None and self.clean_index > self.index:
            self.clean_index = None  # the saved state was undone and is now out of reach
        del self.steps[self.index :]
        self.steps.append(step)
        self.index += 1
        self.changed.emit()

    def undo(self) -> State | None:
        if not self.can_undo():
            return None
        self.index -= 1
        state = self.steps[self.index].before
        if self.moved is not None:
            self.moved(state)
        self.changed.emit()
        return state

    def redo(self) -> State | None:
        if not self.can_redo():
            return None
        self.index += 1
        state = self.steps[self.index - 1].after
        if self.moved is not None:
            self.moved(state)
        self.changed.emit()
        return state

    def can_undo(self) -> bool:
        return self.index > 0

    def can_redo(self) -> bool:
        return self.index < len(self.steps)

    def undo_text(self) -> str:
        return self.steps[self.index - 1].text if self.can_undo() else ""

    def redo_text(self) -> str:
        return self.steps[self.index].text if self.can_redo() else ""

    def count(self) -> int:
        return len(self.steps)

    def is_clean(self) -> bool:
        return self.index == self.clean_index

    def set_clean(self) -> None:
        self.clean_index = self.index
        self.changed.emit()

    def clear(self) -> None:
        self.steps.clear()
        self.index, self.clean_index = 0, 0
        self.changed.emit()
