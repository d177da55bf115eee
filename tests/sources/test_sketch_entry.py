"""sources/sketch_entry: a project's sketch plane read as a frame, rounded axes made exact and
degenerate ones refused (review36)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from leafstudio.sources.sketch_entry import sketch_plane
from tests.leaves import clicked_sketch

SLANT = np.sqrt(0.5)


def test_a_plane_written_to_four_decimals_reads_as_the_orthonormal_frame_meant():
    """u and v at 45°, typed as 0.7071 (1e-4 short of unit) and a normal on the lower side:
    read exactly unit and square (main kept 0.7071, 0.99999 long), the side kept."""
    plane = {"origin": [1, 2, 3], "u": [0.7071, 0.7071, 0], "v": [-0.7071, 0.7071, 0.0001]}
    frame = sketch_plane({"plane": {**plane, "normal": [0, 0, -1]}})
    axes = np.array([frame.u, frame.v, frame.normal])
    np.testing.assert_allclose(axes @ axes.T, np.eye(3), atol=1e-15)
    np.testing.assert_allclose(frame.u, [SLANT, SLANT, 0], atol=1e-15)
    np.testing.assert_allclose(frame.normal, [0, 0, -1], atol=2e-4)
    np.testing.assert_array_equal(frame.origin, [1, 2, 3])


def test_a_plane_the_app_wrote_reads_back_bit_for_bit():
    sketch = clicked_sketch()
    turned = np.array([[SLANT, SLANT, 0], [-SLANT, SLANT, 0], [0, 0, 1]])
    data = json.loads(json.dumps(sketch.to_dict()))
    data["plane"].update(u=turned[0].tolist(), v=turned[1].tolist(), normal=turned[2].tolist())
    frame = sketch_plane(data)
    np.testing.assert_array_equal(np.array([frame.u, frame.v, frame.normal]), turned)


@pytest.mark.parametrize("bad", [[0, 0, 0], [1, 0, 0], [0, 0, 1.1], [0, np.nan, 1]])
def test_a_plane_whose_v_is_no_axis_is_refused(bad):
    plane = {"origin": [0, 0, 0], "u": [1, 0, 0], "v": bad, "normal": [0, 0, 1]}
    with pytest.raises(ValueError, match='"plane"'):
        sketch_plane({"plane": plane})
