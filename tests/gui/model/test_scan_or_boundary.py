"""The app tells a scan from a boundary as the pipeline does (review finding, session 2): its own
test (12 nearest neighbours) took a dense noisy boundary for a scan, so opening one extracted a
leaf from it instead of reconstructing the boundary given."""

from __future__ import annotations

from pathlib import Path

import pytest

from leafstudio.model import Leaf
from leafstudio.sources.scan import looks_like_scan, read_scan
from tests.leaves import ellipse_cloud as _ellipse
from tests.leaves import random_leaf as _random_leaf

REAL = Path(__file__).resolve().parents[4] / "shared" / "realleaves"


@pytest.mark.parametrize("noise", [1e-3, 1e-2])
def test_a_dense_noisy_boundary_opens_as_a_boundary(noise):
    assert not looks_like_scan(_random_leaf(0, 20000, noise, 1.0)[0])
    assert not looks_like_scan(Leaf(_ellipse(20000, 0.04), []))


@pytest.mark.skipif(not REAL.is_dir(), reason=f"no real scans at {REAL}")
def test_the_real_scans_open_as_scans():
    assert all(looks_like_scan(Leaf(read_scan(p), [])) for p in sorted(REAL.glob("*.txt")))


def test_a_bent_narrow_outline_opens_as_a_boundary_and_a_bent_strip_scan_as_a_scan():
    """Session 3: the app asks the pipeline's question, so a curved grass leaf's outline (aspect
    30, bent 1 rad, noise 0.2%) opened as a scan (0.51) and the scan of a bent strip as a
    boundary (0.17); now the other way round."""
    from tests.leaves import bent_filled_strip, bent_strap

    assert not looks_like_scan(Leaf(bent_strap(5000, 30, 1.0, 0.002), []))
    assert looks_like_scan(Leaf(bent_filled_strip(5000, 25, 2.0), []))


def test_a_sparse_scan_opens_as_a_scan(tmp_path):
    """Fuzzing finding (hunt26): a scan of a few hundred points (a real one subsampled to 300)
    is too sparse for the surface's spread, and the pipeline refuses it as a boundary by the
    share of its points surrounded ("fill an area ... is this a scan?"); the app asked only the
    spread, opened it as a boundary and showed that refusal. It now asks both, as the pipeline."""
    import numpy as np

    from leafstudio.workflows import open_file
    from tests.leaves import synthetic_scan

    blade = synthetic_scan(seed=0, blade_points=150)["blade"]
    assert looks_like_scan(Leaf(blade, []))
    path = tmp_path / "sparse.xyz"
    np.savetxt(path, blade)
    opened = open_file(path)
    assert opened.kind == "scan" and len(opened.leaf.veins) >= 3


def test_a_sparse_noisy_outline_stays_a_boundary():
    """Review finding: a linear form's outline thinned to about 200 points, shuffled, with
    noise of 1% of its length, has up to 0.31 of its points surrounded (cover.FILL_SHARE's
    note): opened as a scan, it was meshed up to 65% too large. It stays a boundary, which the
    pipeline refuses by name."""
    import numpy as np

    from leafstudio.core.prepare.cover import FILL_SHARE, surface_cover
    from leafstudio.forms import Form

    rng = np.random.default_rng(1)
    outline = Form("linear").leaf().boundary
    length = float(np.ptp(outline, axis=0).max())
    shares = []
    for _ in range(6):
        kept = np.sort(rng.choice(len(outline), 220, replace=False))
        points = outline[kept] + rng.normal(0, 0.01 * length, (220, 3)) * [1, 1, 0]
        points = points[rng.permutation(220)]
        shares.append(surface_cover(points)[1])
        assert not looks_like_scan(Leaf(points, []))
    assert max(shares) > FILL_SHARE  # the pipeline's own test would call some of them filled


def _missed_returns(tmp_path: Path, name: str) -> tuple[Path, int]:
    """A synthetic scan written to `name` with a NaN row before every 25th point (an organised
    cloud's pixels without a return, as PCL and Open3D write them), and its finite points."""
    import numpy as np

    from tests.leaves import synthetic_scan

    points = np.vstack(list(synthetic_scan(seed=0).values()))
    where = np.arange(3, len(points), 25)
    path = tmp_path / name
    np.savetxt(path, np.insert(points, where, np.nan, axis=0))
    return path, len(points)


@pytest.mark.parametrize("name", ["scan.xyz", "scan.csv"])
def test_a_scan_with_missed_returns_opens_as_a_scan_by_file_open(tmp_path, name):
    """Review of qa37: `open_scan` leaves a scan's NaN points out with a note, but File > Open
    (open_file) read an x y z list as a leaf file first, which refused it ("line 4: NaN or
    infinite value") before the scan reader was asked: the lenient reading reached .pcd files,
    meshes and lists with extra columns only."""
    from leafstudio.workflows import open_file

    path, finite = _missed_returns(tmp_path, name)
    opened = open_file(path)
    assert opened.kind == "scan" and len(opened.scan) <= finite
    assert opened.notes[0].startswith("left out ")


def test_an_outline_with_a_nan_point_is_still_refused_by_its_line(tmp_path):
    """A leaf file's boundary (not a scan) with a NaN point is refused as before, naming the
    line: only a file whose finite points look like a scan opens as one."""
    import numpy as np

    from leafstudio.errors import LeafError
    from leafstudio.workflows import open_file

    t = np.linspace(0, 2 * np.pi, 200, endpoint=False)
    outline = np.column_stack([np.cos(t), 0.4 * np.sin(t), np.zeros_like(t)])
    outline[7] = np.nan
    path = tmp_path / "leaf.xyz"
    np.savetxt(path, outline)
    with pytest.raises(LeafError, match="line 8: NaN or infinite value"):
        open_file(path)


def test_the_app_says_which_points_a_scan_left_out(tmp_path):
    """Review of qa37: the note of a scan's left-out NaN points reached extract, reconstruct
    and batch but not the app: the Document kept the scan's points and no note."""
    from leafstudio.gui.model.opening import read_document

    path, _ = _missed_returns(tmp_path, "scan.xyz")
    document = read_document(str(path), as_scan=True)
    assert document.scan is not None and "left out " in document.notice
