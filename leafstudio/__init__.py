"""LeafStudio: smooth 3D leaf surfaces from leaf boundaries and veins.

An implementation of Nagai & Tanaya, "Leaf Reconstruction Based on Gaussian Mixture Model from
Point Clouds of Leaf Boundaries and Veins".
"""

from leafstudio._shared import kernelcache

kernelcache.configure()  # before numba is imported: its cache must go to a writable folder

from leafstudio.assets.export import save_mesh  # noqa: E402
from leafstudio.batch import batch  # noqa: E402
from leafstudio.core.pipeline import Pipeline, Result, reconstruct  # noqa: E402
from leafstudio.errors import LeafError  # noqa: E402
from leafstudio.model import Leaf, Params  # noqa: E402
from leafstudio.sources.demos import demo  # noqa: E402
from leafstudio.sources.files import load_leaf, save_leaf  # noqa: E402

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
