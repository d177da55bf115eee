"""leafstudio batch's rows and tables: what a row warns, the length and units its traits are
in, a flat blade's empty K, and the trait table kept off the inputs. The runs themselves
(failures, resume, one and two workers, Dask, progress) are test_batch.py's; both take their
inputs from conftest.py and read tables with tables.py."""

from __future__ import annotations

import hashlib
import importlib.util
import json
from pathlib import Path

import numpy as np
import pytest

import leafstudio as ls
from leafstudio.batch import Settings, TraitTable, plan, run_job
from leafstudio.batch.settings import RESULTS
from leafstudio.cli import main
from leafstudio.forms import make_form
from leafstudio.sources.extract import OUTLINE_POINTS
from tests.batch.tables import GRID
from tests.batch.tables import failed_line as _message
from tests.batch.tables import read_rows as _rows


def test_the_trait_table_never_replaces_an_input_or_a_users_file(tmp_path, leaves, capsys):
    """Review finding: `batch DIR -o out --traits DIR/a.leaf.json` left that leaf out of the
    inputs, wrote the table over it and exited 0. A --traits path that holds anything but a
    trait table is refused before any work."""
    leaf = sorted(leaves.rglob("*.csv"))[0]
    before = leaf.read_bytes()
    out = tmp_path / "out"
    text = _message(["batch", str(leaves), "-o", str(out), "--traits", str(leaf)], capsys)
    assert str(leaf) in text and "not a trait table" in text
    assert leaf.read_bytes() == before and not out.exists()
    own = tmp_path / "mine.csv"
    own.write_text("x,y,z\n1,2,3\n")
    assert "not a trait table" in _message(
        ["batch", str(leaves), "-o", str(out), "--traits", str(own)], capsys
    )
    assert own.read_text() == "x,y,z\n1,2,3\n"


def _warned(err: str, source: str) -> list[str]:
    """The warnings `leafstudio` printed about `source`, without their prefix."""
    lead = f"leafstudio: warning: {source}: "
    return [line[len(lead) :] for line in err.splitlines() if line.startswith(lead)]


@pytest.mark.usefixtures("warm_pools")
def test_a_scan_row_fails_and_warns_as_extract_and_reconstruct_do(tmp_path, scans, capsys):
    """Issue 15: `batch --scans` did not run extract's plausibility check (check_leaf_like), so
    a cloud of two leaves became an `ok` row. Its row now fails with extract's line, and with
    --force it is reconstructed, its warnings those of `extract --force` then `reconstruct`."""
    inputs = tmp_path / "in"
    inputs.mkdir()
    good = (scans / "scan0.txt").read_bytes()
    (inputs / "good.txt").write_bytes(good)
    xyz = np.loadtxt(scans / "scan1.txt")
    two = inputs / "two.txt"
    np.savetxt(two, np.vstack([xyz, xyz + [3 * np.ptp(xyz[:, 0]), 0.0, 0.0]]), fmt="%.6f")
    leaf = tmp_path / "two.leaf.json"
    refused = _message(["extract", str(two), "-o", str(leaf)], capsys)
    assert "does not look like one leaf" in refused
    argv = ["batch", str(inputs), "--scans", "--grid", GRID, "--jobs", "1", "-o"]
    assert main([*argv, str(tmp_path / "out")]) == 1
    assert refused in capsys.readouterr().err
    rows = {Path(r["input"]).name: r for r in _rows(tmp_path / "out" / "traits.csv")}
    assert rows["good.txt"]["status"] == "ok" and rows["good.txt"]["warnings"] == ""
    assert rows["two.txt"]["status"] == "failed"
    assert f"leafstudio: error: {rows['two.txt']['error']}" == refused
    # --force: the problems become the row's warnings, followed by reconstruct's
    assert main(["extract", str(two), "-o", str(leaf), "--force"]) == 0
    warned = _warned(capsys.readouterr().err, str(two))
    assert main(["reconstruct", str(leaf), "-o", str(tmp_path / "two.ply"), "--grid", GRID]) == 0
    warned += _warned(capsys.readouterr().err, str(leaf))
    assert any("not one leaf" in w for w in warned)
    assert main([*argv, str(tmp_path / "forced"), "--force"]) == 0
    rows = {Path(r["input"]).name: r for r in _rows(tmp_path / "forced" / "traits.csv")}
    assert rows["two.txt"]["status"] == "ok" and rows["two.txt"]["warnings"] == "; ".join(warned)


def test_a_leaf_row_warns_as_reconstruct_does(tmp_path, capsys):
    """A leaf whose vein lies far off the boundary's plane: reconstruct warns about it
    (plausibility.leaf_warnings), and so does the batch row."""
    demo = ls.demo("nested")
    far = demo.veins[0] + [0.0, 0.0, 5 * np.ptp(demo.boundary[:, 0])]
    path = tmp_path / "far.csv"
    ls.save_leaf(ls.Leaf(boundary=demo.boundary, veins=[far, *demo.veins[1:]]), path)
    assert main(["reconstruct", str(path), "-o", str(tmp_path / "far.ply"), "--grid", GRID]) == 0
    warned = _warned(capsys.readouterr().err, str(path))
    assert any("from the boundary's plane" in w for w in warned)
    settings = Settings(ls.Params(grid=int(GRID)))
    row = run_job(plan([path], tmp_path / "out", settings)[0])
    assert row["status"] == "ok" and row["warnings"] == "; ".join(warned)


def test_batch_says_a_rows_warnings_on_stderr_as_reconstruct_does(tmp_path, capsys):
    """qa37: a row's warnings (a scan 1.6% of its length from its surface, a vein far off the
    boundary's plane) went to the table only: the terminal said "1 ok, 0 failed" and nothing
    else, though reconstruct warns of the same leaf. Each warned row is now one warning line
    (hidden by -q -q, as reconstruct's), and the summary counts the rows warned."""
    demo = ls.demo("nested")
    far = demo.veins[0] + [0.0, 0.0, 5 * np.ptp(demo.boundary[:, 0])]
    inputs = tmp_path / "in"
    inputs.mkdir()
    path = inputs / "far.csv"
    ls.save_leaf(ls.Leaf(boundary=demo.boundary, veins=[far, *demo.veins[1:]]), path)
    ls.save_leaf(demo, inputs / "plain.csv")
    argv = ["batch", str(inputs), "--grid", GRID, "--jobs", "1", "-o"]
    assert main([*argv, str(tmp_path / "out")]) == 0
    err = capsys.readouterr().err
    (row,) = [r for r in _rows(tmp_path / "out" / "traits.csv") if r["input"] == str(path)]
    assert "from the boundary's plane" in row["warnings"]
    assert f"leafstudio: warning: {path}: {row['warnings']}" in err.splitlines()
    assert "plain.csv" not in err
    assert "2 inputs: 2 ok (1 with warnings: the table's warnings column), 0 failed" in err
    assert main(["-q", "-q", *argv, str(tmp_path / "quiet")]) == 0
    assert capsys.readouterr().err == ""


def test_a_batch_of_one_says_one_input(tmp_path, capsys):
    """The summary said "1 inputs"."""
    path = tmp_path / "leaf.csv"
    ls.save_leaf(ls.demo("nested"), path)
    assert main(["batch", str(path), "--grid", GRID, "--jobs", "1", "-o", str(tmp_path / "o")]) == 0
    assert "batch: 1 input: 1 ok, 0 failed;" in capsys.readouterr().err


def test_a_job_run_in_the_callers_process_gives_its_threads_back(tmp_path):
    """run_job pins one BLAS and one numba thread while it runs; in the caller's own process it
    gave them back never, so later fits there differed (a scan's far-area 0.02% -> 0.098%)."""
    from threadpoolctl import threadpool_info

    numba = pytest.importorskip("numba")
    path = tmp_path / "nested.csv"
    ls.save_leaf(ls.demo("nested"), path)
    jobs = plan([path], tmp_path / "out", Settings(ls.Params(grid=int(GRID))))
    # numba's threads launched (they load libgomp, whose pool is then in `before` too; a job
    # launches them when no test before it in this process has)
    numba.set_num_threads(numba.get_num_threads())
    before = ([pool["num_threads"] for pool in threadpool_info()], numba.get_num_threads())
    row = run_job(jobs[0])
    assert row["status"] == "ok"
    assert ([pool["num_threads"] for pool in threadpool_info()], numba.get_num_threads()) == before


def test_a_millimetre_leaf_written_to_gltf_without_a_length_is_noted_as_reconstruct_notes_it(
    tmp_path, capsys
):
    """A leaf 60 units long (a photo's or a scan's millimetres) written to glTF, which reads
    units as metres: reconstruct notes it would arrive 60 m long; the batch row did not."""
    demo = ls.demo("nested")
    scale = 60.0 / np.ptp(demo.boundary[:, 0])
    path = tmp_path / "mm.csv"
    ls.save_leaf(ls.Leaf(demo.boundary * scale, [vein * scale for vein in demo.veins]), path)
    out = tmp_path / "mm.glb"
    assert main(["reconstruct", str(path), "-o", str(out), "--grid", GRID]) == 0
    noted = [w for w in _warned(capsys.readouterr().err, str(path)) if "--length" in w]
    assert len(noted) == 1
    params = ls.Params(grid=int(GRID))
    row = run_job(plan([path], tmp_path / "out", Settings(params, format="glb"))[0])
    assert row["status"] == "ok" and noted[0] in (row["warnings"] or "")
    sized = Settings(params, format="glb", length=0.06)  # given its real length: nothing to say
    row = run_job(plan([path], tmp_path / "sized", sized)[0])
    assert row["status"] == "ok" and "--length" not in (row["warnings"] or "")


def test_the_length_a_batch_is_given_is_the_length_its_table_reads(tmp_path):
    """`batch --length 80mm` placed each leaf 80 mm from base to apex but its table measured the
    length along the outline's main axis: 77 mm for a soybean scan, 111 mm for a kidney-shaped
    leaf (wider than long, so its width was read as its length). The table's length is the
    blade's, base to apex, so it reads what was given."""
    form = make_form("reniform")
    path = tmp_path / "kidney.csv"
    ls.save_leaf(form, path)
    settings = Settings(ls.Params(grid=int(GRID)), format="none", length=0.08)
    row = run_job(plan([path], tmp_path / "out", settings)[0])
    assert row["status"] == "ok"
    assert row["length"] == pytest.approx(80, rel=1e-9)
    assert row["width"] == pytest.approx(80 / 0.72, rel=1e-2)


def test_a_batch_given_the_real_length_measures_in_millimetres(tmp_path):
    """`batch --length 8cm` wrote the meshes 80 mm long but kept the traits in the input's units
    (a form 37 units long: length 37, not 80): they are in millimetres now, areas in mm² and
    curvatures in 1/mm and 1/mm²."""
    form = make_form("ovate")
    path = tmp_path / "ovate.csv"
    ls.save_leaf(ls.Leaf(form.boundary * 37, [vein * 37 for vein in form.veins]), path)
    params = ls.Params(grid=int(GRID))
    own, real = (
        run_job(plan([path], tmp_path / name, Settings(params, format="none", length=length))[0])
        for name, length in (("own", None), ("real", 0.08))
    )
    assert own["status"] == real["status"] == "ok"
    assert own["length"] == pytest.approx(37, rel=0.01)
    assert real["length"] == pytest.approx(80, rel=1e-9)
    scale = real["length"] / own["length"]
    for name, power in [("area", 2), ("perimeter", 1), ("height", 1), ("aspect_ratio", 0)]:
        assert real[name] == pytest.approx(own[name] * scale**power, rel=1e-9), name
    for stat in ("mean", "min", "max"):
        assert real[f"mean_curvature_{stat}"] == pytest.approx(
            own[f"mean_curvature_{stat}"] / scale, rel=1e-9
        )
        assert real[f"gaussian_curvature_{stat}"] == pytest.approx(
            own[f"gaussian_curvature_{stat}"] / scale**2, rel=1e-9
        )


def test_a_length_run_does_not_resume_rows_measured_in_the_inputs_units():
    """A --length table written while its traits stayed in the input's units had the same
    settings key: resumed, one table held a length of 37 beside one of 80 (mm)."""
    before = {"format": "none", "force": False, "points": OUTLINE_POINTS, "scans": False}
    before["results"] = RESULTS  # the figures' own version (the key's other part)
    for length in (None, 0.08):
        settings = Settings(ls.Params(grid=64), format="none", length=length)
        text = json.dumps(
            {"params": settings.params.to_dict(), **before}
            | ({"length": length} if length is not None else {}),
            sort_keys=True,
        )
        old_key = hashlib.sha256(text.encode()).hexdigest()[:16]
        assert (settings.key() == old_key) == (length is None)  # without a length: unchanged


def test_a_scan_batch_given_the_real_length_gives_its_distances_in_millimetres(scans, tmp_path):
    """The scan columns scan_mean and scan_p95 are distances (the scan's units): in a --length
    table in millimetres they stayed in the scan's own units beside the traits in mm."""
    params = ls.Params(grid=int(GRID))
    path = scans / "scan0.txt"
    own, real = (
        run_job(plan([path], tmp_path / name, Settings(params, True, "none", length=length))[0])
        for name, length in (("own", None), ("real", 0.08))
    )
    assert own["status"] == real["status"] == "ok"
    scale = real["length"] / own["length"]
    assert scale > 1  # a soybean leaf of about 63 mm given 8 cm
    for name in ("scan_mean", "scan_p95"):
        assert real[name] == pytest.approx(own[name] * scale, rel=1e-9)
    for name in ("scan_points", "scan_beyond_1pct", "scan_beyond_2pct", "scan_folded"):
        assert real[name] == own[name]  # counts and shares
    assert 0 <= own["scan_folded"] < 0.01  # the share of the mesh's edges folded back


def test_a_flat_blades_k_is_empty_in_csv_and_null_in_json_not_its_placeholder_1(tmp_path):
    """A blade with its veins in its plane fits no mixture (Result.fits_no_mixture): its
    placeholder Gaussian's K of 1 was the row's "k", a K that did nothing. The table leaves it
    empty (CSV) or null (JSON lines), as the README says; a relief's K stays."""
    t = np.linspace(0, 2 * np.pi, 80, endpoint=False)
    boundary = np.column_stack([np.cos(t), 0.4 * np.sin(t), 0 * t])
    x = np.linspace(-0.9, 0.9, 20)
    flat = ls.Leaf(boundary, [np.column_stack([x, 0 * x, 0 * x])])
    ls.save_leaf(flat, tmp_path / "flat.csv")
    ls.save_leaf(ls.demo("nested"), tmp_path / "nested.csv")
    settings = Settings(ls.Params(k=3, grid=int(GRID)), format="none")
    jobs = plan([tmp_path / "flat.csv", tmp_path / "nested.csv"], tmp_path / "out", settings)
    rows = {Path(row["input"]).stem: row for row in map(run_job, jobs)}
    assert rows["flat"]["k"] is None and rows["nested"]["k"] == 3
    for name in ("t.csv", "t.json"):
        table = TraitTable(tmp_path / name, scans=False)
        table.start()
        for row in rows.values():
            table.add(row)
        table.close()
    by_input = {Path(r["input"]).stem: r for r in _rows(tmp_path / "t.csv")}
    assert by_input["flat"]["k"] == "" and by_input["nested"]["k"] == "3"
    lines = [json.loads(line) for line in (tmp_path / "t.json").read_text().splitlines()]
    assert {Path(r["input"]).stem: r["k"] for r in lines} == {"flat": None, "nested": 3}


def test_a_parquet_tables_whole_number_columns_read_back_whole_in_pandas(tmp_path):
    """A flat blade's k is null (test above): written as Arrow's int64 with a null, pandas'
    read_parquet took the column for float64 (3.0 and NaN; --resume and Arrow's own readers
    kept ints). The table carries the note pandas itself writes, so k, grid and scan_points
    come back as its nullable Int64."""
    pq = pytest.importorskip("pyarrow.parquet")
    path = tmp_path / "t.parquet"
    table = TraitTable(path, scans=True)
    table.start()
    for name, k in (("flat.csv", None), ("nested.csv", 3)):
        table.add({"input": name, "status": "ok", "k": k, "grid": 32, "scan_points": None})
    table.close()
    note = json.loads(pq.read_schema(path).metadata[b"pandas"])
    whole = {c["name"] for c in note["columns"] if c["numpy_type"] == "Int64"}
    assert whole == {"k", "grid", "scan_points"}
    assert [r["k"] for r in pq.read_table(path).to_pylist()] == [None, 3]
    if importlib.util.find_spec("pandas") is not None:  # not a dependency: read where it is
        import pandas as pd

        frame = pd.read_parquet(path)
        assert str(frame["k"].dtype) == "Int64" and frame["k"].tolist()[1] == 3
