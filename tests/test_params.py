"""Each parameter declared once (model.PARAMS), and the places derived from it agree: validation,
the command line's flags, the stage cache's keys and the pipeline's stage table. (The panel's
controls are checked in tests/gui/qt/test_controls.py.)"""

from __future__ import annotations

import argparse
import re
from dataclasses import fields
from pathlib import Path

import numpy as np
import pytest

import leafstudio as ls
from leafstudio.cli import build_parser, main
from leafstudio.cli.options import params_for as _params_for
from leafstudio.core import stages
from leafstudio.core.pipeline import Pipeline
from leafstudio.core.stages import STAGE_INPUTS, STAGE_KEYS, STAGES
from leafstudio.errors import LeafError
from leafstudio.model import K_AUTO_MAX, PARAMS, Params
from leafstudio.paramspec import Choice, Ranged, Real, Switch, Whole

RANGED = [n for n, p in PARAMS.items() if isinstance(p, Ranged)]
COMMANDS = {  # every command that takes the parameters, with the rest of a valid line
    "reconstruct": ["LEAF.csv", "-o", "m.ply"],
    "measure": ["LEAF.csv"],
    "compare": ["LEAF.csv"],
    "batch": ["LEAVES", "-o", "OUT"],
}


def _other(name: str, base: Params) -> object:
    """A valid value of `name` other than base's (the far end of its range, another word)."""
    p, now = PARAMS[name], getattr(base, name)
    if isinstance(p, Switch):
        return not now
    if isinstance(p, Choice):
        return next(c for c in p.choices if c != now)
    return p.high if now != p.high else p.low


CHANGES = {  # for the stage test: a change of each parameter that a small run can take
    "k": 4,
    "grid": 32,
    "mpu_tolerance": 2e-3,
    "samples": 900,
    "seed": 1,
    "mesher": "conforming",
    "radius_factor": 1.5,
    "taper": 0.5,
    "refine": False,
    "through_veins": False,
    "margin": "smooth",
}


def _text(value: object) -> str:
    return f"{value!r}" if isinstance(value, float) else str(value)


# --- the declarations ---------------------------------------------------------------------------


def test_every_field_is_declared_once_with_a_valid_default_stage_and_flag():
    assert list(PARAMS) == [f.name for f in fields(Params)]
    defaults = Params()
    flags = [p.flag for p in PARAMS.values()]
    assert len(set(flags)) == len(flags) and all(f.startswith("--") for f in flags)
    for name, p in PARAMS.items():
        assert getattr(defaults, name) == p.default
        assert p.stage in STAGES
        assert len(p.help) > 30 and p.what and p.label
        if isinstance(p, Ranged):  # the panel's range sits inside the valid one
            low, high = p.panel_range
            assert p.low <= low <= p.default <= high <= p.high


def test_k_slider_covers_what_auto_chooses_from():
    assert PARAMS["k"].panel_range == (1, K_AUTO_MAX)
    assert f"1 to {K_AUTO_MAX}" in PARAMS["k"].help


def test_a_slider_range_outside_the_valid_one_is_refused_on_declaration():
    with pytest.raises(ValueError, match="not inside the range"):
        Whole(default=5, low=1, high=10, slider=(0, 8), what="x", label="x", help="", stage="",
              flag="--x")  # fmt: skip
    with pytest.raises(ValueError, match="default"):
        Real(default=20.0, low=1, high=50, slider=(1, 10), what="x", label="x", help="", stage="",
             flag="--x")  # fmt: skip


def test_the_readme_names_every_flag():
    readme = (Path(__file__).parents[1] / "README.md").read_text(encoding="utf-8")
    for p in PARAMS.values():
        assert f"`{p.flag}`" in readme or f"`{p.flag}/" in readme, p.flag


# --- validation ---------------------------------------------------------------------------------


@pytest.mark.parametrize("name", RANGED)
def test_validation_takes_each_end_of_the_range_and_refuses_past_it(name):
    p = PARAMS[name]
    assert getattr(Params(**{name: p.low}), name) == p.low
    assert getattr(Params(**{name: p.high}), name) == p.high
    if isinstance(p, Whole):
        below, above = p.low - 1, p.high + 1
    else:
        below, above = np.nextafter(p.low, -np.inf), np.nextafter(p.high, np.inf)
    for bad in (below, above, 10**400, -(10**400)):  # ints beyond any float overflowed before
        with pytest.raises(LeafError, match=f"^{p.what} must be between"):
            Params(**{name: bad})


@pytest.mark.parametrize("name", [n for n in PARAMS if n not in RANGED])
def test_words_and_switches_refuse_anything_else(name):
    p = PARAMS[name]
    message = "must be true or false" if isinstance(p, Switch) else "must be one of"
    for bad in ("maybe", 1, None):
        with pytest.raises(LeafError, match=f"^{p.what} {message}"):
            Params(**{name: bad})


# --- the command line ---------------------------------------------------------------------------


def _subparser(command: str) -> argparse.ArgumentParser:
    sub = next(a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction))
    return sub.choices[command]


@pytest.mark.parametrize("command", COMMANDS)
def test_every_command_with_parameters_has_each_flag_with_its_declared_help(command):
    actions = {a.dest: a for a in _subparser(command)._actions}
    for name, p in PARAMS.items():
        action = actions[name]
        assert p.flag in action.option_strings
        assert action.default is None  # unset unless given: a project's value stands
        assert action.help.replace("%%", "%") == p.help_text()
        if isinstance(p, Choice):
            assert tuple(action.choices) == p.choices


@pytest.mark.parametrize("command", COMMANDS)
def test_every_flag_reaches_params(command):
    base = Params()
    wanted = {name: _other(name, base) for name in PARAMS}
    argv = [command, *COMMANDS[command]]
    for name, value in wanted.items():
        p = PARAMS[name]
        if isinstance(p, Switch):
            argv.append(p.flag if value else f"--no-{p.flag[2:]}")
        else:
            argv += [p.flag, _text(value)]
    args = build_parser().parse_args(argv)
    assert _params_for(args, None) == Params(**wanted)
    assert _params_for(build_parser().parse_args([command, *COMMANDS[command]]), None) == base


@pytest.mark.parametrize("command", COMMANDS)
@pytest.mark.parametrize("name", RANGED)
def test_a_flag_out_of_range_is_one_line_and_exit_2(command, name, capsys):
    p = PARAMS[name]
    above = p.high + 1 if isinstance(p, Whole) else p.high * 2
    assert main([command, *COMMANDS[command], p.flag, _text(above)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    assert f"argument {p.flag}: {p.what} must be between" in err[0]
    assert main([command, *COMMANDS[command], p.flag, "nonsense"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and f"argument {p.flag}: {p.what} must be " in err[0]


# --- the stage cache ----------------------------------------------------------------------------


def _downstream(stage: str) -> set[str]:
    """`stage` and every stage that reads its output, directly or not."""
    found = {stage}
    for s, inputs in STAGE_INPUTS.items():  # in order: a stage's inputs come before it
        if found & set(inputs):
            found.add(s)
    return found


def test_the_stage_table_in_the_stages_docstring_says_what_the_keys_are():
    rows = re.findall(r"^\| (\w+) +\| ([^|]+)\|", stages.__doc__, re.MULTILINE)
    table = {stage: {w.strip() for w in deps.split(",")} for stage, deps in rows if stage in STAGES}
    assert list(table) == list(STAGES)
    for stage, deps in table.items():
        named = {d for d in deps if d != "the leaf"}
        inputs = set(STAGE_INPUTS[stage])
        assert named == inputs | {n for n, p in PARAMS.items() if p.stage == stage}, stage


@pytest.mark.parametrize("name", list(PARAMS))
def test_a_parameter_change_reruns_its_stage_and_those_after_it_and_gives_a_fresh_runs_result(
    name,
):
    """The cache keys follow the declarations, and a declared stage is right: a cached run after
    the change gives what a fresh pipeline gives (a stage declared too late would reuse an
    earlier stage's stale output)."""
    bpa = name in ("mesher", "radius_factor")  # ball pivoting: where radius_factor counts
    if bpa:
        pytest.importorskip("open3d")
    base = Params(k=3, grid=24, samples=600, mesher="bpa" if bpa else "conforming")
    changed = base.with_(**{name: CHANGES[name]})  # a new parameter: add a change for it here
    expected = _downstream(PARAMS[name].stage)
    keys = {s for s in STAGES if _key(s, base) != _key(s, changed)}
    assert keys == expected
    leaf = ls.demo("nested")
    pipe = Pipeline(leaf)
    first = pipe.run(base)
    cached = pipe.run(changed)
    # a lazy stage runs when first asked for (the layout: for the conforming mesher only)
    lazy = {s for s in STAGES if stages.STAGE_TABLE[s].lazy}
    assert expected - lazy <= set(cached.ran) <= expected | (lazy - set(first.ran))
    fresh = Pipeline(leaf).run(changed)
    np.testing.assert_array_equal(cached.triangle_mesh.points, fresh.triangle_mesh.points)
    np.testing.assert_array_equal(
        cached.triangle_mesh.regular_faces, fresh.triangle_mesh.regular_faces
    )


def _key(stage: str, params: Params) -> tuple:
    return tuple(getattr(params, n) for n in STAGE_KEYS[stage])
