"""The reconstruction itself: numpy, scipy, numba, shapely, Triangle and open3d; never Qt."""
