"""A parameter declared once: its kind and range, default, help, the pipeline stage it
invalidates, its command-line flag and the panel's slider range.

`Params` (model.py) declares each of its fields with one of these (as dataclass field metadata,
`Whole(...).field()`); everything else is derived from that declaration:

- validation: `Params.__post_init__` calls each declaration's `check`;
- the stage cache's keys: `core/stages.STAGE_KEYS` from each declaration's `stage`;
- the parameter panel (gui/qt/controls.py): widget, range, label and tooltip;
- the command line (cli/): the flag, its metavar and help, and `parse` for its text.

The panel's range is `panel_range`: a slider needs a range a hand can use, so a wide validation
range may name a smaller `slider` range inside it (checked here, on declaration). The panel
widens a slider to show a value outside it that a loaded project holds, so it never refuses or
changes a valid value, and never offers an invalid one.

Plain Python: no Qt, no argparse.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

import numpy as np

from leafstudio.errors import LeafError, shorten

LONGEST_DIGITS = 30  # int() of 5,000 digits is slow, and fails: such a text is out of range


def short(value: Any) -> str:
    """`value`'s repr, cut so that a long one cannot flood a one-line message."""
    text = repr(value)
    return text if len(text) <= 40 else f"{text[:30]}… ({len(text)} characters)"


def read_whole(text: str) -> int | None:
    """A command line's whole number: plain digits with an optional sign (no "1_0", no "1.0"),
    else None. Over LONGEST_DIGITS digits it is ±10**LONGEST_DIGITS: out of any range."""
    body = text.strip()
    digits = body[1:] if body[:1] in "+-" else body
    if not digits.isascii() or not digits.isdigit():
        return None
    if len(digits) > LONGEST_DIGITS:
        return -(10**LONGEST_DIGITS) if body[0] == "-" else 10**LONGEST_DIGITS
    return int(body)


def _number(value: float) -> str:
    return f"{value:g}" if isinstance(value, float) else str(value)


@dataclass(frozen=True, kw_only=True)
class Param:
    """What every parameter declares.

    Parameters
    ----------
    default : the value when none is given
    what : str
        Its name in messages ("K", "EM sample count").
    label : str
        Its label in the parameter panel.
    help : str
        Plain words: the panel's tooltip and the flag's --help (range and default added).
    stage : str
        The pipeline stage that reads it (core/stages.STAGES): that stage, and every stage
        that reads its output, reruns when it changes (core/stages.STAGE_KEYS).
    flag : str
        The command-line flag (`--k`); reconstruct, measure, compare and batch take it.
    metavar : str, optional
        The flag's value in --help.
    """

    default: Any
    what: str
    label: str
    help: str
    stage: str
    flag: str
    metavar: str | None = None

    def __post_init__(self) -> None:
        if self.check(self.default) != self.default:
            raise ValueError(f"{self.what}: the default {self.default!r} is not a valid value")

    def field(self) -> Any:
        """The dataclass field that carries this declaration (`fields(Params)[i].metadata`)."""
        return dataclasses.field(default=self.default, metadata={"param": self})

    def check(self, value: Any) -> Any:
        """`value` as a plain Python value, or a LeafError in the words of `what`."""
        raise NotImplementedError

    def parse(self, text: str) -> Any:
        """A command-line value: `text` read as this kind and checked."""
        return self.check(text)

    def describe(self) -> str:
        """The values taken, in words ("8 to 2048")."""
        raise NotImplementedError

    def help_text(self) -> str:
        """`help` with the values taken and the default: the tooltip and the flag's --help."""
        default = self.default
        if isinstance(default, bool):
            default = "on" if default else "off"
        return f"{self.help} ({self.describe()}; default {default})"


@dataclass(frozen=True, kw_only=True)
class Ranged(Param):
    """A number in [low, high]; the panel's slider covers `slider`, inside that range."""

    low: float
    high: float
    slider: tuple[float, float] | None = None  # None: the whole range (a spin box for Whole)

    def __post_init__(self) -> None:
        low, high = self.panel_range
        if not self.low <= low < high <= self.high:
            raise ValueError(f"{self.what}: slider {self.slider} is not inside the range")
        if not low <= self.default <= high:
            raise ValueError(f"{self.what}: the default is outside the slider's range")
        super().__post_init__()

    @property
    def panel_range(self) -> tuple[float, float]:
        """The range the panel's slider offers (a sub-range of the valid one)."""
        return self.slider if self.slider is not None else (self.low, self.high)

    def out_of_range(self, shown: str) -> LeafError:
        return LeafError(
            f"{self.what} must be between {_number(self.low)} and {_number(self.high)}, got {shown}"
        )

    def describe(self) -> str:
        return f"{_number(self.low)} to {_number(self.high)}"


@dataclass(frozen=True, kw_only=True)
class Whole(Ranged):
    """A whole number (a bool, a float such as 100.0 or a string is refused); `special` is a word
    taken as well (K's "auto"); `step` is the slider's single step."""

    low: int
    high: int
    special: str | None = None
    step: int = 1

    def check(self, value: Any) -> Any:
        if self.special is not None and isinstance(value, str) and value == self.special:
            return value
        if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)):
            also = f" or {self.special!r}" if self.special else ""
            raise LeafError(f"{self.what} must be a whole number{also}, got {short(value)}")
        if not self.low <= value <= self.high:
            raise self.out_of_range(short(value))
        return int(value)

    def parse(self, text: str) -> Any:
        """Plain digits with an optional sign (read_whole)."""
        value = read_whole(text)
        if value is None:
            return self.check(text)  # the special word, or "must be a whole number"
        if not self.low <= value <= self.high:
            raise self.out_of_range(shorten(text))
        return self.check(value)

    def describe(self) -> str:
        also = f", or {self.special}" if self.special else ""
        return super().describe() + also


@dataclass(frozen=True, kw_only=True)
class Real(Ranged):
    """A finite real number (a bool, a string or a complex number is refused); the panel shows
    `decimals` places."""

    decimals: int = 2

    def __post_init__(self) -> None:
        if round(self.panel_range[0], self.decimals) <= 0 < self.panel_range[0]:
            raise ValueError(f"{self.what}: {self.decimals} decimals cannot show the slider's low")
        super().__post_init__()

    def check(self, value: Any) -> Any:
        if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, float, np.number)):
            raise LeafError(f"{self.what} must be a number, got {short(value)}")
        if isinstance(value, (complex, np.complexfloating)):
            raise LeafError(f"{self.what} must be a real number, got {short(value)}")
        try:
            number = float(value)
        except OverflowError:  # a Python int beyond any float, e.g. 10**400
            raise self.out_of_range(short(value)) from None
        if not self.low <= number <= self.high:  # NaN fails this too
            raise self.out_of_range(short(value))
        return number

    def parse(self, text: str) -> Any:
        try:
            value = float(text)
        except ValueError:
            return self.check(text)  # "must be a number"
        return self.check(value)


@dataclass(frozen=True, kw_only=True)
class Choice(Param):
    """One of a few words."""

    choices: tuple[str, ...]

    def check(self, value: Any) -> Any:
        if not isinstance(value, str) or value not in self.choices:
            raise LeafError(
                f"{self.what} must be one of {', '.join(self.choices)}, got {short(value)}"
            )
        return value

    def describe(self) -> str:
        return f"{', '.join(self.choices[:-1])} or {self.choices[-1]}"


@dataclass(frozen=True, kw_only=True)
class Switch(Param):
    """On or off; the command line has `--flag` and `--no-flag`."""

    def check(self, value: Any) -> Any:
        if not isinstance(value, (bool, np.bool_)):
            raise LeafError(f"{self.what} must be true or false, got {short(value)}")
        return bool(value)

    def describe(self) -> str:
        return "on or off"


def declared(cls: type) -> dict[str, Param]:
    """The declarations of a dataclass's fields, by field name, in field order."""
    return {f.name: f.metadata["param"] for f in dataclasses.fields(cls)}


def numpy_doc(params: dict[str, Param]) -> str:
    """A NumPy-style "Parameters" section written from the declarations (for a class's doc)."""
    lines = ["", "    Parameters", "    ----------"]
    for name, p in params.items():
        lines.append(f"    {name} : {p.describe()}, default: {p.default!r}")
        lines.append(f"        {p.help}. Stage: {p.stage}; flag: {p.flag}.")
    return "\n".join(lines) + "\n"
