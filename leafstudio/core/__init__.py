"""The reconstruction itself, the paper's steps (Leaf + Params -> Result): numpy, scipy, numba,
shapely, Triangle and open3d; never Qt.

| step (paper)                      | stage(s)          | module                              |
|-----------------------------------|-------------------|-------------------------------------|
| before 1: input made ready        | frame             | prepare/ (outline, polygon, cloud,  |
|                                   |                   | units, …)                           |
| 1 plane, heights (3.1, eq. 3)     | frame             | plane, base                         |
| 2 implicit g (3.2, eqs. 1-2)      | implicit          | mpu                                 |
| 3-5 sampling grid                 | grid              | grid                                |
| 3 height guide p (3.3, eqs. 4-5)  | guide             | height                              |
| 4 mixture (3.4, eqs. 6-9)         | samples, gmm      | gmm, autok                          |
| 4-5 surface z (3.4-3.5, eq. 8)    | surface           | surface, base, curvature            |
| 5 mesh (3.5)                      | layout, mesh      | mesher, trianglemesh                |
| the stages in order, one cache    | all               | pipeline, stages, steps, store      |
| results (4, Table 1)              | Result.metrics    | result, evaluate, distance, border  |

Support without a step of its own: buckets (the compiled neighbour searches), raster (the
nearest set pixel of a mask, for the textures' edge padding) and cuts (a mesh cut along level
lines, for bend.py's creases and a scan's holes). The stage table itself, with what
each stage depends on, is in stages.py (each stage's function in steps.py); docs/architecture.md
has the layers around core.
"""
