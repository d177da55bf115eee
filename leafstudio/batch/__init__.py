"""Many leaves at once: one mesh per input and a trait table, on a pool of local worker processes
or on a Dask distributed cluster (`leafstudio batch`, `ls.batch`).

- Inputs are files, folders (searched recursively) or glob patterns. Only their paths are listed
  up front; the workers read the files, and at most a few jobs per worker are in flight, so memory
  stays bounded whatever the number of inputs.
- Each input's mesh is written by the worker, atomically (io.save_mesh), at the input's path
  relative to the inputs' common folder, under the output folder.
- The trait table gets one row per input as results arrive, flushed at once; at the end it is
  rewritten sorted by input path (atomically). A row records the input's content hash and a key of
  the settings, so `resume` keeps exactly the rows (and meshes) that a new run would make again.
- A failing input becomes a `failed` row with the one-line message `leafstudio reconstruct`
  would print; the others go on.
- Every job runs in a worker process with BLAS (and numba) threads pinned to 1, so 1 or n
  workers, and the order results arrive in, give the same meshes and traits.

The package, layer by layer: settings (what every input is run with, the table's columns), plan
(inputs, jobs, resume), worker (one input's row), table (the trait table, one small class per
format), executors (local processes, Dask), run (`Batch`, `batch`). The command line's side is
leafstudio/cli/batch.py.
"""

import lazy_loader

# imported on first use: `leafstudio batch --help` reads the formats (settings) without the
# workers, which load the whole pipeline
__getattr__, __dir__, __all__ = lazy_loader.attach(
    __name__,
    submod_attrs={
        "executors": [
            "INSTALL_CLUSTER",
            "LOCAL_CLUSTER_CONFIG",
            "DaskCluster",
            "LocalPool",
            "check_scheduler",
        ],
        "plan": ["Job", "file_hash", "find_inputs", "plan", "resumable"],
        "run": ["IN_FLIGHT_PER_WORKER", "Batch", "batch", "remove_temporaries"],
        "settings": [
            "CURVATURE_COLUMNS",
            "DEFAULT_TABLE",
            "FLOAT_COLUMNS",
            "FORMATS",
            "INT_COLUMNS",
            "SCAN_COLUMNS",
            "SHAPE_COLUMNS",
            "Settings",
            "columns",
        ],
        "table": ["TABLE_SUFFIXES", "TraitTable"],
        "worker": ["pin_threads", "run_failed", "run_job"],
    },
)
