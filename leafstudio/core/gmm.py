"""Step 4 (section 3.4): a K-component Gaussian mixture fitted by EM to the height guide (eqs. 6-9).

The paper draws points with density following p(x) and fits π_k, μ_k, Σ_k by EM. A mixture is a
density that integrates to 1, not a height, so we scale it: z(x) = Σ_k a_k N(x | μ_k, Σ_k), with
the amplitudes a_k fitted to p by least squares (see surface.py). With a_k = A π_k this is the
paper's scaled GMM; letting each a_k free (and signed) follows veins of different heights, and
veins below the boundary's plane, that a single scale cannot.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from leafstudio.core.buckets import kernel_array
from leafstudio.core.jit import njit
from leafstudio.errors import LeafError

REG_COVAR = 1e-6  # added to each covariance's diagonal, as scikit-learn does, so Σ stays invertible
EM_TOL = 1e-3  # EM stops when the mean log-likelihood per sample changes less than this
EM_MAX_ITER = 200
UNDERFLOW = 600.0  # exp(-q) for q beyond this is taken as exactly 0 (no subnormals)
KMEANS_ITER = 300  # Lloyd iterations of the k-means start at most (it stops once labels settle)
KMEANS_TOL = 1e-4  # ...or once the centres move less than this times the samples' mean variance
NK_FLOOR = 10 * np.finfo(np.float64).eps  # each component's responsibility sum starts here


@dataclass(frozen=True)
class Mixture:
    """K Gaussians in the plane with amplitudes.

    Attributes
    ----------
    weights : (K,) float array
        π_k from EM (eq. 9: non-negative, sum 1).
    means : (K, 2) float array
        μ_k (eq. 7).
    covariances : (K, 2, 2) float array
        Σ_k (eq. 7).
    amplitudes : (K,) float array
        a_k; z(x) = Σ a_k N(x | μ_k, Σ_k). Defaults to the weights.
    """

    weights: np.ndarray
    means: np.ndarray
    covariances: np.ndarray
    amplitudes: np.ndarray

    @property
    def precisions(self) -> np.ndarray:
        """(K, 2, 2) Σ_k⁻¹."""
        return np.linalg.inv(self.covariances)

    def components(self, xy: np.ndarray) -> np.ndarray:
        """(n, K) values of each Gaussian N(x | μ_k, Σ_k) (eq. 6), without weights."""
        xy = kernel_array(np.atleast_2d(xy))
        return _gaussians(xy, self.means, self.precisions)

    def density(self, xy: np.ndarray) -> np.ndarray:
        """The GMM of eq. 8, Σ π_k N_k(x): a probability density."""
        return self.components(xy) @ self.weights

    def value(self, xy: np.ndarray) -> np.ndarray:
        """Σ a_k N_k(x) at (n, 2) points."""
        return self.components(xy) @ self.amplitudes

    def owners(self, xy: np.ndarray) -> np.ndarray:
        """(n,) the Gaussian that owns each of (n, 2) points: the largest π_k N_k(x) (the
        responsibility of eq. 7's E step)."""
        if len(xy) == 0:
            return np.zeros(0, dtype=int)
        return np.argmax(self.components(xy) * self.weights[None, :], axis=1)

    def scaled(self, scale: float) -> Mixture:
        """EM's mixture on plane points multiplied by `scale` (a unit-size run's in the input's
        units): means × s, covariances × s² (inf past about 1e154: such a leaf is measured, not
        drawn); the weights, and EM's amplitudes (its weights), as they are."""
        with np.errstate(over="ignore"):
            covariances = scale * (scale * self.covariances)
        return Mixture(self.weights, scale * self.means, covariances, self.amplitudes)

    def derivatives(self, xy: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Value (n,), gradient (n, 2) and Hessian (n, 2, 2) of Σ a_k N_k(x), in closed form.

        ∇N = −N P d and ∇²N = N (P d dᵀ P − P), with d = x − μ and P = Σ⁻¹.
        """
        xy = kernel_array(np.atleast_2d(xy))
        return _weighted_derivatives(xy, self.means, self.precisions, self.amplitudes)


@njit(cache=True, nogil=True)
def _gaussian(x, y, mean, prec, k):
    """N(x | μ_k, Σ_k) (eq. 6) from the precision P = Σ⁻¹, and P d with d = x − μ_k."""
    dx, dy = x - mean[k, 0], y - mean[k, 1]
    p00, p01, p11 = prec[k, 0, 0], prec[k, 0, 1], prec[k, 1, 1]
    pdx, pdy = p00 * dx + p01 * dy, p01 * dx + p11 * dy
    det = p00 * p11 - p01 * p01  # det P = 1 / det Σ
    q = 0.5 * (dx * pdx + dy * pdy)
    if q > UNDERFLOW:  # exactly 0, not a subnormal (arithmetic on those is very slow)
        return 0.0, pdx, pdy
    return np.sqrt(det) / (2 * np.pi) * np.exp(-q), pdx, pdy


@njit(cache=True, nogil=True)
def _gaussians(xy, means, prec):
    out = np.empty((len(xy), len(means)))
    for i in range(len(xy)):
        for k in range(len(means)):
            out[i, k] = _gaussian(xy[i, 0], xy[i, 1], means, prec, k)[0]
    return out


@njit(cache=True, nogil=True)
def _weighted_derivatives(xy, means, prec, amplitudes):
    n, m = len(xy), len(means)
    value, grad, hess = np.zeros(n), np.zeros((n, 2)), np.zeros((n, 2, 2))
    scale = np.empty(m)  # a_k / (2π √det Σ_k), once per component
    for k in range(m):
        det = prec[k, 0, 0] * prec[k, 1, 1] - prec[k, 0, 1] * prec[k, 0, 1]
        scale[k] = amplitudes[k] * np.sqrt(det) / (2 * np.pi)
    for i in range(n):
        for k in range(m):
            dx, dy = xy[i, 0] - means[k, 0], xy[i, 1] - means[k, 1]
            pdx = prec[k, 0, 0] * dx + prec[k, 0, 1] * dy
            pdy = prec[k, 0, 1] * dx + prec[k, 1, 1] * dy
            q = 0.5 * (dx * pdx + dy * pdy)
            if q > UNDERFLOW:
                continue
            g = scale[k] * np.exp(-q)
            value[i] += g
            grad[i, 0] -= g * pdx
            grad[i, 1] -= g * pdy
            hess[i, 0, 0] += g * (pdx * pdx - prec[k, 0, 0])
            hess[i, 0, 1] += g * (pdx * pdy - prec[k, 0, 1])
            hess[i, 1, 1] += g * (pdy * pdy - prec[k, 1, 1])
        hess[i, 1, 0] = hess[i, 0, 1]
    return value, grad, hess


def sample_guide(
    xy: np.ndarray, p: np.ndarray, count: int, spacing: float, seed: int
) -> np.ndarray:
    """Draw `count` points with density proportional to |p| (the guide as an existence probability).

    Each draw picks a grid node with probability |p| / Σ|p| and jitters it uniformly within its
    cell, so the samples cover the plane rather than stacking on nodes.
    """
    rng = np.random.default_rng(seed)
    mass = np.abs(p)
    total = mass.sum()
    if total <= 0:
        raise LeafError("the height guide is zero everywhere: nothing to fit")
    if np.isfinite(total):  # as rng.choice(len(xy), size=count, p=mass / total) draws them
        cdf = (mass / total).cumsum()
        cdf /= cdf[-1]
        picks = _search_right(cdf, rng.random(count))
    else:  # its error for NaN
        picks = rng.choice(len(xy), size=count, p=mass / total)
    # take: numpy's fancy index of the (n, 2) nodes took 0.09 ms for 4000 picks, take 0.004
    return xy.take(picks, axis=0) + rng.uniform(-0.5, 0.5, size=(count, 2)) * spacing


@njit(cache=True, nogil=True)
def _search_right(cdf, u):
    """np.searchsorted(cdf, u, side="right") for a non-decreasing (n,) cdf and (m,) u in [0, 1),
    as numpy's Generator.choice picks by it: each search starts from the answers at the ends
    of u's 1/m-wide bin, by one merge of the bins' edges into the cdf (numpy's binary search
    over the whole cdf took 0.32 ms for 4000 draws from a flat ovate's 6895 nodes at grid 128,
    this 0.09, best of 40; the same picks). Where rounding puts u outside its bin's answers,
    the search takes the whole cdf."""
    n, m = len(cdf), len(u)
    bins = max(m, 1)
    first = np.empty(bins + 1, np.int64)  # first[b]: how many cdf values are <= b / bins
    i = 0
    for b in range(bins + 1):
        edge = b / bins
        while i < n and cdf[i] <= edge:
            i += 1
        first[b] = i
    out = np.empty(m, np.int64)
    for q in range(m):
        x = u[q]
        b = min(max(int(x * bins), 0), bins - 1)
        lo, hi = first[b], first[b + 1]
        if lo > 0 and cdf[lo - 1] > x:
            lo = 0
        if hi < n and cdf[hi] <= x:
            hi = n
        while lo < hi:  # the first index in [lo, hi) whose cdf is > x
            mid = (lo + hi) // 2
            if cdf[mid] <= x:
                lo = mid + 1
            else:
                hi = mid
        out[q] = lo
    return out


def fit_mixture(samples: np.ndarray, k: int, seed: int) -> Mixture:
    """EM fit of a K-component full-covariance GMM (eqs. 6-9) to (n, 2) samples, fixed seed.

    Started like scikit-learn's GaussianMixture: k-means++ seeds (drawn with `seed`), Lloyd's
    k-means, then hard responsibilities; EM then runs until the mean log-likelihood per sample
    changes by less than EM_TOL. Compiled (numba) loops over the samples: a few milliseconds,
    where scikit-learn took tens and was erratic with several BLAS threads.
    """
    samples = kernel_array(samples)
    distinct = _distinct_count(samples[: 5 * k])  # enough when the first 5 K already differ
    if distinct < 5 * k:
        distinct = _distinct_count(samples)
    if k > distinct // 5:
        raise LeafError(
            f"K = {k} is more than the data supports: the guide has only {distinct} distinct "
            f"samples (need at least 5 per component); lower K or raise the grid resolution"
        )
    seeds = _kmeans_plus_plus(samples, k, _seeded(seed))
    labels = _kmeans(samples, seeds, KMEANS_TOL * float(_column_variances(samples).mean()))
    weights, means, covariances = _em(samples, labels, k, REG_COVAR, EM_TOL, EM_MAX_ITER)
    return Mixture(weights=weights, means=means, covariances=covariances, amplitudes=weights.copy())


MIN_SIGN_SHARE = 0.05  # a sign of the guide with less of its mass than this gets no component


def split_components(positive_share: float, k: int) -> tuple[int, int]:
    """Components for the guide's positive and negative parts, in proportion to their mass.

    A part holding at least MIN_SIGN_SHARE of the mass gets at least one component when k >= 2.
    """
    if positive_share >= 1 - MIN_SIGN_SHARE:
        return k, 0
    if positive_share <= MIN_SIGN_SHARE:
        return 0, k
    if k == 1:
        return (1, 0) if positive_share >= 0.5 else (0, 1)
    k_pos = int(np.clip(round(k * positive_share), 1, k - 1))
    return k_pos, k - k_pos


def fit_signed_mixture(
    samples: np.ndarray,
    positive: np.ndarray,
    fit: Callable[[np.ndarray, int], Mixture],
    k: int,
) -> Mixture:
    """One K-component mixture for a guide that may be positive in places and negative in others.

    A density cannot be negative, so the samples drawn from |p| where p > 0 and those where p < 0
    are fitted apart (`fit(part, k_part)`, the K split by `split_components`) and joined, each
    part's weights scaled by its share of the samples. The signed amplitudes fitted afterwards
    (surface.py) then raise one part and lower the other.
    """
    counts = split_components(float(positive.mean()), k)
    parts = [
        (fit(samples.compress(mask, axis=0), count), mask.mean())  # [mask]: 7 times as long
        for mask, count in zip((positive, ~positive), counts, strict=True)
        if count != 0
    ]
    return Mixture(
        weights=np.concatenate([m.weights * frac for m, frac in parts]),
        means=np.concatenate([m.means for m, _ in parts]),
        covariances=np.concatenate([m.covariances for m, _ in parts]),
        amplitudes=np.concatenate([m.weights * frac for m, frac in parts]),
    )


def _distinct_count(samples: np.ndarray) -> int:
    """Number of distinct (n, 2) samples, to 9 decimals."""
    rounded = np.round(samples, 9)
    return len(np.unique(rounded[:, 0] + 1j * rounded[:, 1]))


@njit(cache=True, nogil=True)
def _column_variances(x):
    """np.var(x, axis=0) of the (n, d) `x`, as numpy adds it: over axis 0 of a C-ordered array
    numpy's sums go row after row (not pairwise), the mean each sum over n, then the squared
    differences' sums over n (numpy's reductions over 2-wide rows, and .mean(): 0.31-0.35 ms at
    a flat ovate's 4000 samples at grid 128, this 0.06, best of 9 x 300 on a busy host; the same
    bits on 3000 random sets, /work/notes/cpu39/micro_var.py)."""
    n, d = x.shape
    mean, out = np.zeros(d), np.zeros(d)
    for i in range(n):
        for k in range(d):
            mean[k] += x[i, k]
    for k in range(d):
        mean[k] = mean[k] / n
    for i in range(n):
        for k in range(d):
            deviation = x[i, k] - mean[k]
            out[k] += deviation * deviation
    for k in range(d):
        out[k] = out[k] / n
    return out


_STATES = threading.local()  # one RandomState per thread, seeded again at each fit (_seeded)


def _seeded(seed: int) -> np.random.RandomState:
    """np.random.RandomState(seed)'s generator, in the same state (RandomState.seed: the same legacy
    seeding of the same MT19937, its normal's cache cleared), one per thread made once: a new
    RandomState first seeds its MT19937 from the system's entropy (92 µs, this 1.5 µs, best of
    5 x 1000; 0.09 ms of a flat ovate's 25 at grid 128)."""
    state = getattr(_STATES, "state", None)
    if state is None:
        state = _STATES.state = np.random.RandomState()
    state.seed(seed)
    return state


def _kmeans_plus_plus(x: np.ndarray, k: int, rng: np.random.RandomState) -> np.ndarray:
    """(k, 2) greedy k-means++ seeds, drawn as scikit-learn draws them: each next seed is the
    best, by summed squared distance, of 2 + log k candidates drawn ∝ squared distance."""
    trials = 2 + int(np.log(k))
    # rng.choice(n, p=uniform) as RandomState draws it, without its checks of p
    cdf = np.cumsum(np.full(len(x), 1 / len(x)))
    first = int(np.searchsorted(cdf / cdf[-1], rng.random_sample(), side="right"))
    seeds = [x[first]]
    closest = (x[:, 0] - x[first, 0]) ** 2 + (x[:, 1] - x[first, 1]) ** 2
    for _ in range(1, k):
        draws = rng.uniform(size=trials) * closest.sum()
        picks = np.minimum(np.searchsorted(np.cumsum(closest), draws), len(x) - 1)
        dx, dy = x[None, :, 0] - x[picks, 0, None], x[None, :, 1] - x[picks, 1, None]
        dist = np.minimum(closest, dx**2 + dy**2)  # (trials, n); not np.sum(axis=2): slow
        best = int(np.argmin(dist.sum(axis=1)))
        seeds.append(x[picks[best]])
        closest = dist[best]
    return np.array(seeds)


@njit(cache=True, nogil=True)
def _kmeans(x, centers, tol):
    """Lloyd's k-means from the given (k, 2) centres; returns (n,) labels.

    Stops as scikit-learn's does: when the labels settle, or when the centres' summed squared
    shift is at most `tol`, and then labels the samples by the last centres.
    """
    n, k = len(x), len(centers)
    labels = np.empty(n, np.int64)
    for i in range(n):  # not np.full: its own compile at the first run
        labels[i] = -1
    centers = centers.copy()
    for _ in range(KMEANS_ITER):
        if not _assign(x, centers, labels):
            return labels
        sums, counts = np.zeros((k, 2)), np.zeros(k)
        for i in range(n):
            c = labels[i]
            sums[c, 0] += x[i, 0]
            sums[c, 1] += x[i, 1]
            counts[c] += 1
        shift = 0.0
        for c in range(k):
            if counts[c] > 0:
                cx, cy = sums[c, 0] / counts[c], sums[c, 1] / counts[c]
                shift += (cx - centers[c, 0]) ** 2 + (cy - centers[c, 1]) ** 2
                centers[c, 0], centers[c, 1] = cx, cy
        if shift <= tol:
            break
    _assign(x, centers, labels)
    return labels


@njit(cache=True, nogil=True)
def _assign(x, centers, labels):
    """Label each sample by its nearest centre, in place; True if any label changed."""
    changed = False
    for i in range(len(x)):
        best, arg = np.inf, 0
        for c in range(len(centers)):
            d = (x[i, 0] - centers[c, 0]) ** 2 + (x[i, 1] - centers[c, 1]) ** 2
            if d < best:
                best, arg = d, c
        if labels[i] != arg:
            labels[i], changed = arg, True
    return changed


@njit(cache=True, nogil=True)
def _m_step(x, resp, reg):
    """Weights (k,), means (k, 2) and covariances (k, 2, 2) from (n, k) responsibilities (eq. 7)."""
    n, k = resp.shape
    nk, weights = np.empty(k), np.empty(k)  # loops, not np.full or nk / n: each compiles code of
    for c in range(k):  # its own (~0.4 s of the first run's compile)
        nk[c] = NK_FLOOR
    means = np.zeros((k, 2))
    for i in range(n):
        for c in range(k):
            nk[c] += resp[i, c]
            means[c, 0] += resp[i, c] * x[i, 0]
            means[c, 1] += resp[i, c] * x[i, 1]
    cov = np.zeros((k, 2, 2))
    for c in range(k):  # element by element: a row's slice assignment compiles numba's
        means[c, 0] /= nk[c]  # shape-error message, seconds of the first run's compile
        means[c, 1] /= nk[c]
    for i in range(n):
        for c in range(k):
            dx, dy = x[i, 0] - means[c, 0], x[i, 1] - means[c, 1]
            r = resp[i, c]
            cov[c, 0, 0] += r * dx * dx
            cov[c, 0, 1] += r * dx * dy
            cov[c, 1, 1] += r * dy * dy
    for c in range(k):
        cov[c, 0, 0] /= nk[c]
        cov[c, 0, 1] /= nk[c]
        cov[c, 1, 1] /= nk[c]
        cov[c, 1, 0] = cov[c, 0, 1]
        cov[c, 0, 0] += reg
        cov[c, 1, 1] += reg
        weights[c] = nk[c] / n
    return weights, means, cov


@njit(cache=True, nogil=True)
def _e_step(x, weights, means, cov, resp):
    """Fill (n, k) responsibilities (eq. 9's E-step); return the mean log-likelihood."""
    n, k = resp.shape
    log_norm = np.empty(k)
    inv = np.empty((k, 3))
    for c in range(k):
        det = cov[c, 0, 0] * cov[c, 1, 1] - cov[c, 0, 1] ** 2
        inv[c, 0], inv[c, 1] = cov[c, 1, 1] / det, -cov[c, 0, 1] / det
        inv[c, 2] = cov[c, 0, 0] / det
        log_norm[c] = np.log(weights[c]) - np.log(2 * np.pi) - 0.5 * np.log(det)
    total = 0.0
    for i in range(n):
        top = -np.inf
        for c in range(k):
            dx, dy = x[i, 0] - means[c, 0], x[i, 1] - means[c, 1]
            maha = inv[c, 0] * dx * dx + 2 * inv[c, 1] * dx * dy + inv[c, 2] * dy * dy
            resp[i, c] = log_norm[c] - 0.5 * maha
            top = max(top, resp[i, c])
        s = 0.0
        for c in range(k):
            diff = resp[i, c] - top
            resp[i, c] = np.exp(diff) if diff > -UNDERFLOW else 0.0
            s += resp[i, c]
        for c in range(k):
            resp[i, c] /= s
        total += top + np.log(s)
    return total / n


@njit(cache=True, nogil=True)
def _em(x, labels, k, reg, tol, max_iter):
    """EM from hard k-means labels until the mean log-likelihood settles."""
    resp = np.zeros((len(x), k))
    for i in range(len(x)):
        resp[i, labels[i]] = 1.0
    weights, means, cov = _m_step(x, resp, reg)
    previous = -np.inf
    for _ in range(max_iter):
        current = _e_step(x, weights, means, cov, resp)
        weights, means, cov = _m_step(x, resp, reg)
        if abs(current - previous) < tol:
            break
        previous = current
    return weights, means, cov
