"""Property tests of the loaders (issue 11): random bytes and valid files mutated byte by byte or
field by field give a Leaf (or scan) or one LeafError naming the file, never another exception;
and at the command line exit 0 or exit 2 with one line, never a change to any other file."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from leafstudio.cli import main
from leafstudio.errors import LeafError
from leafstudio.model import Leaf
from leafstudio.sources.demos import demo
from leafstudio.sources.files import load_leaf, project_dict, save_leaf
from leafstudio.sources.scan import read_scan

FUZZ = settings(
    max_examples=150,
    deadline=10_000,  # ms per example: a hang or a huge allocation shows as a failure
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
    derandomize=True,  # the same examples on every run: a failure repeats
)
LEAF_TYPES = (".csv", ".xyz", ".ply", ".leaf.json")
SCAN_TYPES = (".ply", ".xyz", ".csv")


def _small_leaf() -> Leaf:
    leaf = demo("nested")
    return Leaf(leaf.boundary[::6], [v[::4] for v in leaf.veins])


@pytest.fixture(scope="module")
def valid(tmp_path_factory) -> dict[str, bytes]:
    """A small valid leaf in every leaf format, as bytes."""
    folder = tmp_path_factory.mktemp("valid")
    files = {}
    for suffix in LEAF_TYPES:
        path = folder / f"leaf{suffix}"
        save_leaf(_small_leaf(), path)
        files[suffix] = path.read_bytes()
    return files


def _load(path: Path, loader) -> object:
    """The loader's result, or None for a LeafError that names the file in one line."""
    try:
        return loader(path)
    except LeafError as exc:
        message = str(exc)
        assert message.startswith(str(path)) and "\n" not in message, message
        assert len(message) < 500, message
        return None


def _mutate(data: bytes, edits: list[tuple[int, int, int]]) -> bytes:
    """Apply (kind, position, byte) edits: 0 replaces, 1 inserts, 2 deletes a byte."""
    out = bytearray(data)
    for kind, position, value in edits:
        if not out:
            out.append(value)
            continue
        at = position % len(out)
        if kind == 0:
            out[at] = value
        elif kind == 1:
            out.insert(at, value)
        else:
            del out[at]
    return bytes(out)


EDITS = st.lists(
    st.tuples(st.integers(0, 2), st.integers(0, 10**6), st.integers(0, 255)), min_size=1, max_size=8
)


@FUZZ
@given(
    data=st.binary(max_size=2000),
    kind=st.sampled_from(
        [(s, load_leaf) for s in LEAF_TYPES] + [(s, read_scan) for s in SCAN_TYPES]
    ),
)
def test_random_bytes_are_a_leaf_or_a_scan_or_one_leaf_error(tmp_path, data, kind):
    suffix, loader = kind
    path = tmp_path / f"random{suffix}"
    path.write_bytes(data)
    _load(path, loader)


@FUZZ
@given(suffix=st.sampled_from(LEAF_TYPES), edits=EDITS)
def test_valid_files_mutated_byte_by_byte(tmp_path, valid, suffix, edits):
    path = tmp_path / f"mutated{suffix}"
    path.write_bytes(_mutate(valid[suffix], edits))
    _load(path, load_leaf)
    if suffix in SCAN_TYPES:
        _load(path, read_scan)


JSON_VALUES = st.recursive(
    st.none()
    | st.booleans()
    | st.integers(min_value=-(10**400), max_value=10**400)
    | st.floats(allow_nan=False)
    | st.text(max_size=20),
    lambda inner: st.lists(inner, max_size=5) | st.dictionaries(st.text(max_size=8), inner),
    max_leaves=30,
)
FIELDS = ("format", "version", "boundary", "veins", "params", "sketch")
PARAM_NAMES = ("k", "grid", "mpu_tolerance", "samples", "seed", "mesher", "taper", "refine")


@FUZZ
@given(
    field=st.sampled_from(FIELDS + tuple(f"params.{p}" for p in PARAM_NAMES)),
    value=JSON_VALUES,
)
def test_projects_mutated_field_by_field(tmp_path, field, value):
    data = project_dict(_small_leaf())
    if field.startswith("params."):
        data["params"] = {field.split(".", 1)[1]: value}
    else:
        data[field] = value
    path = tmp_path / "mutated.leaf.json"
    path.write_text(json.dumps(data))
    _load(path, load_leaf)


@FUZZ
@given(
    point=st.integers(0, 40),
    coordinate=st.integers(0, 2),
    value=st.floats(allow_nan=True, allow_infinity=True) | st.integers(-(10**30), 10**30),
)
def test_projects_with_one_strange_coordinate(tmp_path, point, coordinate, value):
    data = project_dict(_small_leaf())
    data["boundary"][point % len(data["boundary"])][coordinate] = value
    path = tmp_path / "odd.leaf.json"
    path.write_text(json.dumps(data))  # NaN and Infinity as JSON's non-standard words
    _load(path, load_leaf)


CLI = settings(FUZZ, max_examples=12, deadline=60_000)


@CLI
@given(suffix=st.sampled_from(LEAF_TYPES), edits=EDITS)
def test_the_command_line_on_mutated_files_is_exit_0_or_2_and_touches_nothing_else(
    tmp_path_factory, valid, capsys, suffix, edits
):
    folder = tmp_path_factory.mktemp("cli")
    source = folder / f"leaf{suffix}"
    source.write_bytes(_mutate(valid[suffix], edits))
    bystander = folder / "other.ply"
    bystander.write_bytes(b"not to be touched")
    before = {p.name: p.read_bytes() for p in folder.iterdir()}
    out = folder / "out.ply"
    code = main(["reconstruct", str(source), "-o", str(out), "--grid", "16", "--k", "1"])
    err = [line for line in capsys.readouterr().err.splitlines() if "warning" not in line]
    err = [line for line in err if "compiling" not in line]
    assert code in (0, 2), err
    if code == 2:
        assert len(err) == 1 and str(source) in err[0], err
        assert not out.exists()
    after = {p.name: p.read_bytes() for p in folder.iterdir() if p.name != "out.ply"}
    assert after == before  # the input, and any other file, as it was; no temporaries left
    np.testing.assert_equal(code == 0, out.exists())
