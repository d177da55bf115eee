"""LeafStudio: smooth 3D leaf surfaces from leaf boundaries and veins.

An implementation of Nagai & Tanaya, "Leaf Reconstruction Based on Gaussian Mixture Model from
Point Clouds of Leaf Boundaries and Veins".

The public API is imported on first use (PEP 562, through lazy_loader): `import leafstudio`
loads only the types (numpy), and `ls.reconstruct`, `ls.save_mesh`, `ls.batch`, ... load the
pipeline (numba, scipy), the writers and batch when first asked for, so that the command line's
`--help` does not wait for what it never uses (issue 20: `import leafstudio` took 0.7 s).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import lazy_loader

from leafstudio._shared import kernelcache

kernelcache.configure()  # before numba is imported: its cache must go to a writable folder

from leafstudio.errors import LeafError  # noqa: E402
from leafstudio.model import Leaf, Params  # noqa: E402

if TYPE_CHECKING:  # what the lazy names below are, for type checkers and editors
    from leafstudio.assets.export import save_mesh
    from leafstudio.batch.run import batch
    from leafstudio.core.pipeline import Pipeline, Result, reconstruct
    from leafstudio.sources.demos import demo
    from leafstudio.sources.files import load_leaf, save_leaf

# `leafstudio.forms` and the other subpackages after a bare `import leafstudio`, and the public
# names, each imported on first use. `batch` the function stays `ls.batch` even once the
# subpackage leafstudio.batch is imported (lazy_loader guards a name its submodule would shadow).
__getattr__, _lazy_dir = lazy_loader.attach(
    __name__,
    submodules=[
        "analysis",
        "assets",
        "cli",
        "core",
        "forms",
        "gui",
        "render",
        "sources",
        "workflows",
    ],
    submod_attrs={
        "assets.export": ["save_mesh"],
        "batch.run": ["batch"],
        "core.pipeline": ["Pipeline", "Result", "reconstruct"],
        "sources.demos": ["demo"],
        "sources.files": ["load_leaf", "save_leaf"],
    },
)[:2]

__all__ = [
    "Leaf",
    "LeafError",
    "Params",
    "Pipeline",
    "Result",
    "batch",
    "demo",
    "load_leaf",
    "reconstruct",
    "save_leaf",
    "save_mesh",
]


def __dir__() -> list[str]:
    """The module's names, the ones not imported yet included."""
    return sorted({*globals(), *_lazy_dir()})
