"""numba's `njit`, for every kernel module of core: importing it from here guards the kernel
cache's writes first (_shared/kernelcache.guard_cache_writes: a full disk must not fail a run).

numba (about 0.2 s to import) then loads with the first module that has a kernel, not with
`import leafstudio` nor with core's modules that have none.
"""

from numba import njit

from leafstudio._shared import kernelcache

kernelcache.guard_cache_writes()

__all__ = ["njit"]
