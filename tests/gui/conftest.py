"""Fixtures for the app's tests, without Qt: demo results reconstructed once per test run for
the tests that only read them (the Qt views' own fixtures are in qt/conftest.py)."""

from __future__ import annotations

from collections.abc import Callable

import pytest

from leafstudio.core.pipeline import Pipeline, Result
from leafstudio.model import Params
from leafstudio.sources.demos import demo
from tests.gui.builders import FAST


@pytest.fixture(scope="session")
def demo_result() -> Callable[..., Result]:
    """`demo_result(name, params=FAST)`: the demo's Result, reconstructed once per run. Shared:
    a test that edits or measures a result makes its own."""
    made: dict[tuple[str, Params], Result] = {}

    def get(name: str, params: Params = FAST) -> Result:
        if (name, params) not in made:
            made[name, params] = Pipeline(demo(name)).run(params)
        return made[name, params]

    return get
