"""What `import leafstudio` and the command line's parser load (issue 20: a quick first start).

`import leafstudio` loaded the pipeline, the writers and batch (numba, scipy: 0.7 s), and
`leafstudio --help` every command's work besides (0.9 s). Each check runs in a fresh
interpreter: this test process has long imported them all.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
HEAVY = ("numba", "scipy", "shapely", "matplotlib", "pyvista", "vtkmodules", "PIL", "trimesh")


def _loaded_after(code: str, since: str = "") -> list[str]:
    """The heavy packages imported by `code` in a new interpreter (after `since` is run)."""
    probe = (
        f"import sys\n{since}\nbefore = set(sys.modules)\n{code}\n"
        "import json\nprint(json.dumps(sorted(set(sys.modules) - before)))"
    )
    out = subprocess.run(
        [sys.executable, "-c", probe], cwd=ROOT, capture_output=True, text=True, check=True
    ).stdout
    modules = json.loads(out.splitlines()[-1])
    return [name for name in HEAVY if name in modules]


@pytest.mark.parametrize(
    "code",
    [
        "import leafstudio",
        "import leafstudio as ls; ls.Leaf([[0, 0, 0], [1, 0, 0], [0, 1, 0]]); ls.Params()",
        "from leafstudio.cli import build_parser; build_parser().format_help()",
    ],
    ids=["import", "types", "help"],
)
def test_the_api_and_the_help_load_no_heavy_package(code):
    assert _loaded_after(code) == []


def test_a_name_loads_its_module_on_first_use():
    code = "import leafstudio as ls; ls.reconstruct"
    assert {"numba", "scipy"} <= set(_loaded_after(code))


def test_the_public_api_is_the_same_whatever_is_imported_first():
    code = (
        "import leafstudio as ls\n"
        "import leafstudio.batch\n"  # the subpackage named as the function: ls.batch stays it
        "from leafstudio.batch import batch, Batch\n"
        "from leafstudio.batch.run import batch as run_batch\n"
        "assert ls.batch is batch is run_batch and callable(ls.batch)\n"
        "import leafstudio.forms, leafstudio.assets\n"
        "assert ls.forms.make_form and ls.assets.save_mesh is ls.save_mesh\n"
        "assert ls.workflows.open_file and ls.Pipeline is ls.core.pipeline.Pipeline\n"
        "assert set(ls.__all__) <= set(dir(ls))\n"
    )
    assert _loaded_after(code)  # ran: check=True raises on a failed assertion


def test_the_app_imports_its_heavy_modules_before_qt():
    """PySide6 replaces `__import__` with a slower hook: run_app imports the window's modules
    that do without Qt first (gui/qt/app.import_before_qt), so none of the heavy packages loads
    after PySide6 but VTK's Qt widget."""
    first = (
        "from leafstudio.gui.qt.app import import_before_qt\n"
        "import_before_qt()\n"
        "assert 'PySide6' not in sys.modules, 'Qt imported before the rest'\n"  # check=True
    )
    late = _loaded_after("import leafstudio.gui.qt.main_window", since=first)
    assert [name for name in late if name != "vtkmodules"] == []
