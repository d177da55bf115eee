"""Suite-wide: an internal error of the command line (exit 1, "internal error") fails the test.

Bad input must end as one line and exit 2 (LeafError), by design; the catch-all in cli.main is the
last resort. Here it re-raises, so the test fails with the bug's own traceback. A test of the
catch-all itself is marked `@pytest.mark.internal_error`.
"""

from __future__ import annotations

import pytest


def pytest_configure(config: pytest.Config) -> None:
    config.addinivalue_line(
        "markers", "internal_error: the test exercises cli's catch-all for bugs on purpose"
    )


@pytest.fixture(autouse=True)
def _internal_error_fails(request: pytest.FixtureRequest, monkeypatch: pytest.MonkeyPatch):
    if request.node.get_closest_marker("internal_error") is not None:
        yield
        return
    import leafstudio.cli as cli

    def fail(exc: Exception, debug: bool) -> int:
        raise AssertionError(f"internal error in the command line: {exc!r}") from exc

    monkeypatch.setattr(cli, "_internal_error", fail)
    yield
