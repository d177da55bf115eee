"""Optional dependencies: a feature that needs one says which extra to install.

open3d brings about 1 GiB of packages (dash, flask, jupyter...) that nothing else needs, so it is
the `open3d` extra (`pip install 'leafstudio[open3d]'`): ball pivoting (mesher "bpa"), the screened
Poisson comparison, reading .pcd scans and the levels of detail. `./dev setup` installs it.
usd-core (module pxr, about 160 MB) is the `usd` extra: .usda, .usdc and .usdz meshes.
"""

from __future__ import annotations

import importlib
import importlib.util
from types import ModuleType
from typing import Any

from leafstudio.errors import LeafError

EXTRAS = {"open3d": "open3d", "pxr": "usd"}  # module -> the extra that installs it


def needs(module: str, feature: str) -> str:
    """The sentence saying that `feature` needs `module` and which extra installs it."""
    extra = EXTRAS.get(module, module)
    return f"{feature} needs {module}, which is not installed: pip install 'leafstudio[{extra}]'"


def require(module: str, feature: str) -> ModuleType:
    """Import `module`, or raise LeafError saying that `feature` needs its extra."""
    try:
        return importlib.import_module(module)
    except ImportError:
        raise LeafError(needs(module, feature)) from None


def missing(module: str, feature: str) -> str:
    """`needs(module, feature)` when `module` cannot be found, else "": found, not imported
    (importing open3d takes seconds), so a window can disable what needs it at start."""
    try:
        found = importlib.util.find_spec(module) is not None
    except (ImportError, ValueError):
        found = False
    return "" if found else needs(module, feature)


class LazyModule:
    """A module imported on first use (a module-level `o3d = LazyModule(...)` costs nothing at
    import, and a missing extra is a LeafError when the feature is used)."""

    def __init__(self, module: str, feature: str) -> None:
        self._module, self._feature = module, feature
        self._loaded: ModuleType | None = None

    def __getattr__(self, name: str) -> Any:
        if self._loaded is None:
            self._loaded = require(self._module, self._feature)
        return getattr(self._loaded, name)
