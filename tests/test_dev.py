"""`./dev app` without a display: whatever would open the window saves its picture and exits
(issue 24, finding 3: a window nobody can see kept the command waiting for ever)."""

from __future__ import annotations

import os
import shutil
import subprocess
import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def _fake(folder: Path, name: str, body: str) -> None:
    path = folder / name
    path.write_text(f"#!/bin/sh\n{body}\n")
    path.chmod(0o755)


def _dev_app(tmp_path: Path, *args: str) -> list[str]:
    """The arguments `./dev app ARGS` gives leafstudio with no display, set up already: a copy
    of `dev` beside a fake .venv (its leafstudio prints them), and xvfb-run, dpkg and npm faked
    so nothing is installed."""
    shutil.copy(ROOT / "dev", tmp_path / "dev")
    (tmp_path / "pyproject.toml").write_text("")
    bin_ = tmp_path / ".venv" / "bin"
    bin_.mkdir(parents=True)
    _fake(bin_, "python", "exit 0")
    _fake(bin_, "leafstudio", 'for a in "$@"; do echo "$a"; done')
    (tmp_path / ".venv" / "node" / "node_modules" / "gltf-validator").mkdir(parents=True)
    (tmp_path / ".venv" / ".installed").touch()
    os.utime(tmp_path / "pyproject.toml", (0, 0))  # older than .installed: no pip
    fakes = tmp_path / "fakes"
    fakes.mkdir()
    _fake(fakes, "dpkg", "exit 0")
    _fake(fakes, "npm", "exit 0")
    _fake(fakes, "xvfb-run", 'while [ "${1#-}" != "$1" ]; do shift; [ "$1" = "-s" ] && shift; '
          'done; exec "$@"')  # fmt: skip
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    env["PATH"] = f"{fakes}{os.pathsep}{env['PATH']}"
    done = subprocess.run(["bash", str(tmp_path / "dev"), "app", *args], env=env,
                          capture_output=True, text=True, timeout=60, check=True)  # fmt: skip
    return done.stdout.splitlines()


@pytest.mark.parametrize(
    "args", [(), ("gui",), ("--debug",), ("-v",), ("-q", "gui", "leaf.csv"), ("--debug", "gui")]
)
def test_without_a_display_the_app_saves_its_picture_and_exits(tmp_path, args):
    """`./dev app --debug` (or -v, -q: the app with a global option) ran the window invisibly
    and never returned; only no arguments, or `gui` first, were seen as the app."""
    given = _dev_app(tmp_path, *args)
    assert "gui" in given and given[-2:] == ["--screenshot", "leafstudio-screenshot.png"]
    assert given.count("gui") == 1


@pytest.mark.parametrize(
    "args",
    [("demo", "nested", "-o", "x.csv"), ("--version",), ("-h",), ("gui", "--screenshot", "a.png")],
)
def test_without_a_display_other_commands_run_as_given(tmp_path, args):
    assert _dev_app(tmp_path, *args) == list(args)


def test_the_packages_metadata_is_whole():
    """Issue 24, finding 7: three generic classifiers and no project URLs. The licence is an
    SPDX string, the classifiers name the audiences and topics, and a URL leads to the method's
    paper (the project has no public home of its own yet)."""
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    assert project["license"] == "MIT"
    assert len(project["classifiers"]) >= 10
    assert any(c.startswith("Intended Audience :: Education") for c in project["classifiers"])
    urls = project["urls"]
    assert urls["Paper"] == "https://doi.org/10.20965/ijat.2024.p0287"
    assert "10.20965/ijat.2024.p0287" in (ROOT / "README.md").read_text()
