"""LeafStudio: smooth 3D leaf surfaces from leaf boundaries and veins.

An implementation of Nagai & Tanaya, "Leaf Reconstruction Based on Gaussian Mixture Model from
Point Clouds of Leaf Boundaries and Veins".
"""

from leafstudio.core.pipeline import Pipeline, Result, reconstruct
from leafstudio.demos import demo
from leafstudio.errors import LeafError
from leafstudio.io import load_leaf, save_leaf, save_mesh
from leafstudio.model import Leaf, Params

__all__ = [
    "Leaf",
    "LeafError",
    "Params",
    "Pipeline",
    "Result",
    "demo",
    "load_leaf",
    "reconstruct",
    "save_leaf",
    "save_mesh",
]
