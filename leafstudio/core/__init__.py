"""The reconstruction itself: numpy, scipy, scikit-learn and open3d only, never Qt."""
