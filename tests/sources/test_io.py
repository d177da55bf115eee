"""Leaf files in and out: every format round-trips, and every malformed file says what is wrong."""

import codecs
from pathlib import Path

import numpy as np
import pytest
from plyfile import PlyData

import leafstudio as ls
from leafstudio.sources.files import load_project, save_leaf


def _same(a: ls.Leaf, b: ls.Leaf, atol: float = 1e-8) -> None:
    np.testing.assert_allclose(a.boundary, b.boundary, atol=atol)
    assert len(a.veins) == len(b.veins)
    for va, vb in zip(a.veins, b.veins, strict=True):
        np.testing.assert_allclose(va, vb, atol=atol)


@pytest.mark.parametrize("suffix", [".csv", ".txt", ".xyz", ".ply", ".leaf.json"])
def test_leaf_round_trips(tmp_path: Path, suffix: str):
    leaf = ls.demo("nested")
    path = tmp_path / f"leaf{suffix}"
    save_leaf(leaf, path)
    _same(leaf, ls.load_leaf(path))


def test_project_keeps_params_and_sketch(tmp_path: Path):
    path = tmp_path / "p.leaf.json"
    params = ls.Params(k=5, grid=64, mesher="bpa")
    save_leaf(ls.demo("parallel"), path, params=params, sketch={"boundary": [[0, 0], [1, 0]]})
    _, loaded, sketch = load_project(path)
    assert loaded == params
    assert sketch == {"boundary": [[0, 0], [1, 0]]}
    assert [p.name for p in tmp_path.iterdir()] == ["p.leaf.json"]  # no temporary file left


def test_whitespace_and_header_and_unlabelled_boundary_with_vein_files(tmp_path: Path):
    leaf = ls.demo("nested")
    boundary = tmp_path / "b.xyz"
    boundary.write_text("X Y Z\n" + "\n".join("  ".join(map(str, p)) for p in leaf.boundary))
    vein = tmp_path / "v.csv"
    vein.write_text("\n".join(",".join(map(str, p)) for p in leaf.veins[0]))
    loaded = ls.load_leaf(boundary, veins=[vein])
    np.testing.assert_allclose(loaded.boundary, leaf.boundary)
    np.testing.assert_allclose(loaded.veins[0], leaf.veins[0])


@pytest.mark.parametrize("header", ["", "x,y\n", "X, Y\n"], ids=["bare", "x,y", "X, Y"])
def test_an_xy_outline_reads_as_a_flat_boundary(tmp_path: Path, header: str):
    """A two-column `x,y` outline (a spreadsheet's or a digitiser's, with or without a header
    row) was refused ("expected 3 or 4 columns"): it is now a boundary at z = 0, and a vein file
    of two columns a vein at z = 0."""
    outline = ls.demo("parallel").boundary[:, :2]
    path = tmp_path / "outline.csv"
    path.write_text(header + "\n".join(f"{x},{y}" for x, y in outline) + "\n")
    vein = tmp_path / "vein.txt"
    vein.write_text("0.1 0.0\n0.5 0.01\n0.9 0.0\n")
    leaf = ls.load_leaf(path, veins=[vein])
    np.testing.assert_allclose(leaf.boundary, np.column_stack([outline, np.zeros(len(outline))]))
    np.testing.assert_allclose(leaf.veins[0][:, 2], 0.0)
    assert leaf.veins[0].shape == (3, 3)


@pytest.mark.parametrize("header", ["", "x;y;z\n"], ids=["bare", "header"])
def test_a_european_spreadsheets_decimal_commas_read_as_numbers(tmp_path: Path, header: str):
    """A CSV saved by a European Excel (`1,5;2,25;0`: `;` between fields, a comma for the
    decimal mark) was refused as five columns, or opened as a scan; it now reads as the numbers
    it holds, as a leaf and as a scan, and a file mixing both marks says so in one line."""
    from leafstudio.sources.scan import read_scan
    from leafstudio.workflows import open_file

    leaf = ls.demo("parallel")
    rows = [f"{x:.6f};{y:.6f};{z:.6f}".replace(".", ",") for x, y, z in leaf.boundary]
    path = tmp_path / "outline.csv"
    path.write_text(header + "\n".join(rows) + "\n")
    np.testing.assert_allclose(ls.load_leaf(path).boundary, leaf.boundary, atol=1e-6)
    opened = open_file(path)
    assert opened.kind == "leaf"
    np.testing.assert_allclose(opened.leaf.boundary, leaf.boundary, atol=1e-6)
    np.testing.assert_allclose(read_scan(path), leaf.boundary, atol=1e-6)
    mixed = tmp_path / "mixed.csv"
    mixed.write_text("1,5;2,25;0\n1.000,5;2;0\n0;1;0\n")
    for read in (ls.load_leaf, read_scan):
        with pytest.raises(ls.LeafError, match=r"line 2: .*both decimal commas and points"):
            read(mixed)


@pytest.mark.parametrize(
    "separator, header", [("\t", ""), ("\t", "x\ty\tz\n"), (" ", ""), ("  ", "# mm\n")]
)
def test_tab_or_space_separated_decimal_commas_read_as_numbers(
    tmp_path: Path, separator: str, header: str
):
    """A European spreadsheet's tab-separated text (`1,5<tab>2,25<tab>0`) read each comma as a
    separator: (0,0 0 0) became four numbers, every row shifted, and a triangle of area 0.94
    measured 63.7, without a word. Numbers separated by tabs or spaces, with no comma between
    them, now have decimal commas; both marks in one file are refused, naming the line."""
    from leafstudio.sources.scan import read_scan

    leaf = ls.demo("parallel")
    rows = [separator.join(f"{v:.6f}" for v in p).replace(".", ",") for p in leaf.boundary]
    path = tmp_path / "outline.txt"
    path.write_text(header + "\n".join(rows) + "\n")
    np.testing.assert_allclose(ls.load_leaf(path).boundary, leaf.boundary, atol=1e-6)
    np.testing.assert_allclose(read_scan(path), leaf.boundary, atol=1e-6)
    mixed = tmp_path / "mixed.txt"
    mixed.write_text(f"1,5{separator}2,25{separator}0\n1.5{separator}2{separator}0\n")
    with pytest.raises(ls.LeafError, match=r"line 2: .*tabs or spaces with both decimal commas"):
        ls.load_leaf(mixed)


@pytest.mark.parametrize("text", ["0, 0, 0\n1, 0, 0\n0, 1, 0\n", "0,0,0\n1,0,0\n0 ,1,0\n"])
def test_commas_with_spaces_beside_them_stay_separators(tmp_path: Path, text: str):
    path = tmp_path / "b.csv"
    path.write_text(text)
    np.testing.assert_allclose(ls.load_leaf(path).boundary, np.eye(3)[[2, 0, 1]] * [1, 1, 0])


def test_commas_between_fields_stay_separators_beside_a_semicolon_in_a_comment(tmp_path: Path):
    """Only a file whose fields are `;`-separated has decimal commas."""
    path = tmp_path / "b.csv"
    path.write_text("# exported; by hand\n0,0,0\n1,0,0\n0,1,0\n")
    np.testing.assert_allclose(ls.load_leaf(path).boundary, np.eye(3)[[2, 0, 1]] * [1, 1, 0])


def test_commas_between_fields_stay_separators_before_a_semicolon_ending_each_row(
    tmp_path: Path,
):
    """A comma-separated file whose rows end in `;` (a matrix copied from MATLAB, `1,2,0;`) was
    read before decimal commas were; the `;` ending one row and the next row's number are not
    `;`-separated fields, so its commas stay separators (it was refused, 'not a number in
    '3.1.0;'')."""
    path = tmp_path / "rows.csv"
    path.write_text("0,0,0;\n1,0,0;\n0,1,0;\n")
    np.testing.assert_allclose(ls.load_leaf(path).boundary, np.eye(3)[[2, 0, 1]] * [1, 1, 0])


@pytest.mark.parametrize(
    "header, row",
    [
        (",x,y,z,label", "{i},{x},{y},{z},{label}"),  # pandas' to_csv: its index first, unnamed
        ("id;X;Y;Z;label", "{i};{x};{y};{z};{label}"),
        ("label,x,y,z", "{label},{x},{y},{z}"),
        ("y x z label", "{y} {x} {z} {label}"),
        ("x [mm],y [mm],z [mm],label", "{x},{y},{z},{label}"),
    ],
    ids=["pandas index", "id column", "label first", "y before x", "units"],
)
def test_a_header_naming_the_columns_says_which_is_which(tmp_path: Path, header: str, row: str):
    """A header was skipped unread and the columns taken in order: pandas' default to_csv (an
    index column first) made every point (index, x, y) with label z, a leaf 800 times the area
    with no veins and no error; 'label,x,y,z' was refused. Columns named x, y, z (and label)
    are now taken by name, others ignored."""
    leaf = ls.demo("nested")
    points = [(p, 0) for p in leaf.boundary] + [
        (p, k + 1) for k, vein in enumerate(leaf.veins) for p in vein
    ]
    lines = [
        row.format(i=i, x=p[0], y=p[1], z=p[2], label=label) for i, (p, label) in enumerate(points)
    ]
    path = tmp_path / "leaf.csv"
    path.write_text(header + "\n" + "\n".join(lines) + "\n")
    _same(leaf, ls.load_leaf(path))


def test_a_header_wider_than_its_rows_is_skipped_as_before(tmp_path: Path):
    """Names that do not fit the rows (a scan's header over its x, y, z alone) are not taken."""
    leaf = ls.demo("nested")
    path = tmp_path / "b.csv"
    rows = "\n".join(",".join(map(str, p)) for p in leaf.boundary)
    path.write_text("x,y,z,nx,ny,nz\n" + rows + "\n")
    np.testing.assert_allclose(ls.load_leaf(path).boundary, leaf.boundary)


def test_ply_labels_survive(tmp_path: Path):
    """pyvista's PLY reader drops extra vertex properties; ours keeps the label."""
    path = tmp_path / "leaf.ply"
    save_leaf(ls.demo("parallel"), path)
    assert len(ls.load_leaf(path).veins) == len(ls.demo("parallel").veins)


@pytest.mark.parametrize(
    "content, message",
    [
        ("", "holds no points"),
        ("x,y,z\n", "holds no points"),
        ("0 0 0\n1 0\n", "line 2: 2 columns where earlier lines have 3"),
        ("0 0\n1 0 0\n", "line 2: 3 columns where earlier lines have 2"),
        ("0\n", "line 1: expected 2, 3 or 4 columns"),
        ("0 0 0 0 0\n", "line 1: expected 2, 3 or 4 columns"),
        ("0 0 0\n1 0 nan\n0 1 0\n", "line 2: NaN or infinite"),
        ("0 0 0\n1 0 inf\n0 1 0\n", "line 2: NaN or infinite"),
        ("0 0 0\n1 0 zero\n", "line 2: not a number"),
        ("0 0 0 0\n1 0 0 0\n0 1 0 1.5\n", "labels must be whole numbers"),
        ("0 0 0 0\n1 0 0 0\n0 1 0 1\n", "at least 3 boundary points"),
        ("0 0 0\n1 0 0 0\n", "line 2: 4 columns where earlier lines have 3"),
        ("x,y,z\n1,2\n", "line 2: 2 columns where the header line names 3"),  # not x, y
    ],
)
def test_bad_point_files_say_what_is_wrong(tmp_path: Path, content: str, message: str):
    path = tmp_path / "bad.csv"
    path.write_text(content)
    with pytest.raises(ls.LeafError, match=message) as err:
        ls.load_leaf(path)
    assert str(path) in str(err.value)


def test_missing_unknown_and_binary_files(tmp_path: Path):
    with pytest.raises(ls.LeafError, match="no such file"):
        ls.load_leaf(tmp_path / "none.csv")
    with pytest.raises(ls.LeafError, match=r"unknown file type '\.dat'"):
        ls.load_leaf(tmp_path / "leaf.dat")
    binary = tmp_path / "bin.txt"
    binary.write_bytes(b"\xff\xfe\x00\x81")
    with pytest.raises(ls.LeafError, match="not a text file"):
        ls.load_leaf(binary)
    broken = tmp_path / "broken.ply"
    broken.write_text("not a ply at all")
    with pytest.raises(ls.LeafError, match="not a readable PLY"):
        ls.load_leaf(broken)


def test_bad_projects(tmp_path: Path):
    path = tmp_path / "bad.leaf.json"
    path.write_text("{oops")
    with pytest.raises(ls.LeafError, match="not valid JSON"):
        ls.load_leaf(path)
    path.write_text('{"boundary": []}')
    with pytest.raises(ls.LeafError, match="not a LeafStudio project"):
        ls.load_leaf(path)


@pytest.mark.parametrize("suffix", [".ply", ".obj", ".stl", ".vtp", ".vtk"])
def test_mesh_export_by_extension(tmp_path: Path, suffix: str):
    import pyvista as pv

    from leafstudio.assets.placement import result_placement

    result = ls.reconstruct(ls.demo("nested"), ls.Params(grid=32))
    path = tmp_path / f"leaf{suffix}"
    ls.save_mesh(result, path)
    back = pv.read(path)
    assert back.n_cells == result.mesh.n_cells
    turn, offset = result_placement(result).transform(None, suffix)  # OBJ: Y-up (placement.py)
    points = np.asarray(result.mesh.points) @ turn.T + offset
    np.testing.assert_allclose(back.bounds, pv.PolyData(points).bounds, atol=1e-5)
    if suffix != ".stl":  # STL stores each triangle's corners apart
        np.testing.assert_allclose(back.points, points, atol=1e-5)


def test_a_triangle_mesh_exports_as_vtp_and_ply_without_a_polydata(tmp_path: Path):
    import pyvista as pv

    result = ls.reconstruct(ls.demo("nested"), ls.Params(grid=32))
    for suffix in (".vtp", ".ply"):
        ls.save_mesh(result.triangle_mesh, tmp_path / f"leaf{suffix}")
        back = pv.read(tmp_path / f"leaf{suffix}")
        np.testing.assert_allclose(back.points, result.triangle_mesh.points, atol=1e-6)
        assert back.n_cells == len(result.triangle_mesh.regular_faces)
    vertex = PlyData.read(tmp_path / "leaf.ply")["vertex"]  # VTK's reader drops the arrays
    np.testing.assert_allclose(vertex["height"], result.triangle_mesh.point_data["height"])
    assert "mesh" not in result.__dict__  # no PolyData of the result was made


def test_unknown_mesh_type(tmp_path: Path):
    result = ls.reconstruct(ls.demo("nested"), ls.Params(grid=32))
    with pytest.raises(ls.LeafError, match="unknown mesh type"):
        ls.save_mesh(result, tmp_path / "leaf.dae")


@pytest.mark.parametrize(
    "header, row",
    [
        ("id,x,y,label", "{i},{x},{y},{label}"),
        ("x,y,label", "{x},{y},{label}"),
        ("x;y;point;label", "{x};{y};{i};{label}"),
        ("label x y", "{label} {x} {y}"),
    ],
    ids=["index first", "labels", "index between", "label first"],
)
def test_a_header_naming_x_and_y_but_no_z_reads_a_flat_leaf_by_name(
    tmp_path: Path, header: str, row: str
):
    """A header naming x and y without z was skipped unread and the columns taken in order:
    'id,x,y' made every point (index, x, y), a leaf 40 times as long, and 'x,y,label' took the
    labels for heights (no veins): both without a word. Now read by name, z = 0."""
    nested = ls.demo("nested")
    leaf = ls.Leaf(nested.boundary * [1, 1, 0], [v * [1, 1, 0] for v in nested.veins])
    points = [(p, 0) for p in leaf.boundary] + [
        (p, k + 1) for k, vein in enumerate(leaf.veins) for p in vein
    ]
    lines = [row.format(i=i, x=p[0], y=p[1], label=label) for i, (p, label) in enumerate(points)]
    path = tmp_path / "leaf.csv"
    path.write_text(header + "\n" + "\n".join(lines) + "\n")
    _same(leaf, ls.load_leaf(path))


def test_a_vein_file_with_an_index_column_reads_by_name(tmp_path: Path):
    path = tmp_path / "vein.csv"
    path.write_text("n,x,y\n0,0.1,0.0\n1,0.5,0.05\n2,0.9,0.1\n")
    boundary = tmp_path / "b.csv"
    boundary.write_text("\n".join(",".join(map(str, p)) for p in ls.demo("nested").boundary))
    vein = ls.load_leaf(boundary, veins=[path]).veins[0]
    np.testing.assert_allclose(vein, [[0.1, 0, 0], [0.5, 0.05, 0], [0.9, 0.1, 0]])


@pytest.mark.parametrize("encoding", ["utf-16", "utf-16-be"])
def test_a_spreadsheets_unicode_text_reads_as_its_numbers(tmp_path: Path, encoding: str):
    """Excel's "Unicode Text" (UTF-16 after a byte-order mark, tab-separated; decimal commas in
    much of Europe) was refused as binary data; it reads as a leaf, a scan and an opened file."""
    import codecs

    from leafstudio.sources.scan import read_scan
    from leafstudio.workflows import open_file

    leaf = ls.demo("parallel")
    rows = ["\t".join(f"{v:.6f}" for v in p).replace(".", ",") for p in leaf.boundary]
    text = "x\ty\tz\r\n" + "\r\n".join(rows) + "\r\n"
    bom = b"" if encoding == "utf-16" else codecs.BOM_UTF16_BE
    path = tmp_path / "outline.txt"
    path.write_bytes(bom + text.encode(encoding))
    np.testing.assert_allclose(ls.load_leaf(path).boundary, leaf.boundary, atol=1e-6)
    np.testing.assert_allclose(read_scan(path), leaf.boundary, atol=1e-6)
    np.testing.assert_allclose(open_file(path).leaf.boundary, leaf.boundary, atol=1e-6)


def test_a_scans_unicode_text_with_normals_opens_as_a_scan(tmp_path: Path):
    """A scan with normals saved as "Unicode Text" was taken for a leaf (its six columns
    refused) because the scan test read the file as UTF-8."""
    from leafstudio.workflows import open_file

    rng = np.random.default_rng(3)
    xy = rng.uniform(-1, 1, (400, 2)) * [1.0, 0.5]
    points = np.column_stack([xy, 0.05 * xy[:, 0] ** 2, np.tile([0.0, 0.0, 1.0], (400, 1))])
    text = "\r\n".join("\t".join(f"{v:.6f}" for v in p) for p in points) + "\r\n"
    path = tmp_path / "scan.txt"
    path.write_bytes(text.encode("utf-16"))
    opened = open_file(path, force=True)
    assert opened.kind == "scan"
    np.testing.assert_allclose(opened.scan, points[:, :3], atol=1e-6)


def test_a_header_naming_x_y_and_another_word_keeps_reading_the_third_column_as_heights(
    tmp_path: Path,
):
    """`x,y,height` (or `x,y,z_mm`) was read in order, x, y, z: naming x and y without z must
    not make such a leaf flat; only an index or labels beside x and y do."""
    boundary = ls.demo("nested").boundary * [1, 1, 0]
    boundary[:, 2] = 0.1 * boundary[:, 0] ** 2  # heights: a curled margin
    for header in ("x,y,height", "x,y,z_mm"):
        path = tmp_path / "leaf.csv"
        rows = "\n".join(",".join(map(str, p)) for p in boundary)
        path.write_text(header + "\n" + rows + "\n")
        np.testing.assert_allclose(ls.load_leaf(path).boundary, boundary)


def test_a_csv_under_a_title_with_spaced_numbers_keeps_its_decimal_points(tmp_path: Path):
    """A comma-separated file with decimal points under one title line whose words hold numbers
    apart ('exported 2024 05 01') was read as written until the tab- or space-separated decimal
    commas were told from the file's start: the title's '4 0' made its commas decimal marks, and
    the file was refused for holding both marks. Only lines of numbers tell the separator."""
    boundary = ls.demo("nested").boundary
    path = tmp_path / "leaf.csv"
    rows = "\n".join(",".join(f"{v:.6f}" for v in p) for p in boundary)
    path.write_text("exported 2024 05 01\n" + rows + "\n")
    np.testing.assert_allclose(ls.load_leaf(path).boundary, boundary, atol=1e-6)


@pytest.mark.parametrize("header", [" \tX\tY", "\tx\ty"], ids=["ImageJ", "pandas"])
def test_a_tab_separated_header_with_an_unnamed_index_reads_by_name(tmp_path: Path, header: str):
    """ImageJ's Results table (` <tab>X<tab>Y`, a row number first) and pandas' to_csv with tabs
    (`<tab>x<tab>y`) name their index column with nothing: the line's leading tab was stripped,
    the header named fewer columns than the rows hold, and the row numbers were read as x (a
    leaf 40 times as long, without a word), as 'id,x,y' was before the header was read by name."""
    boundary = ls.demo("nested").boundary * [1, 1, 0]
    rows = "\n".join(f"{i + 1}\t{x:.6f}\t{y:.6f}" for i, (x, y, _) in enumerate(boundary))
    path = tmp_path / "Results.txt"
    path.write_text(header + "\n" + rows + "\n")
    np.testing.assert_allclose(ls.load_leaf(path).boundary, boundary, atol=1e-6)


def test_a_utf8_byte_order_mark_is_not_read_as_a_header(tmp_path: Path):
    """Excel's "CSV UTF-8" starts with a byte-order mark: glued to the first number, it made the
    first row a header, and the leaf lost its first point without a word."""
    boundary = ls.demo("nested").boundary
    path = tmp_path / "leaf.csv"
    rows = "\n".join(",".join(f"{v:.6f}" for v in p) for p in boundary)
    path.write_bytes(codecs.BOM_UTF8 + rows.encode())
    np.testing.assert_allclose(ls.load_leaf(path).boundary, boundary, atol=1e-6)


def test_a_two_column_header_with_units_reads_as_a_flat_outline(tmp_path: Path):
    """`x [mm],y [mm]` over rows of two numbers was refused, "2 columns where the header line
    names 4": the header's names were counted at every space."""
    path = tmp_path / "outline.csv"
    path.write_text("x [mm],y [mm]\n0,0\n1,0\n0,1\n")
    np.testing.assert_allclose(ls.load_leaf(path).boundary, [[0, 0, 0], [1, 0, 0], [0, 1, 0]])


def test_the_scan_test_does_not_count_a_european_rows_decimal_commas_as_columns(tmp_path: Path):
    """A `;`-separated row of a labelled leaf (`1,5;2,25;0;1`) counted 8 fields, so the app's
    fallback after a failed leaf read took it for a scan with normals."""
    from leafstudio.sources.scan import is_scan_file

    leaf, scan = tmp_path / "leaf.csv", tmp_path / "scan.csv"
    leaf.write_text("1,5;2,25;0;1\n2,5;1,25;0;0\n")
    scan.write_text("1,5;2,25;0;0;0;1\n")
    assert not is_scan_file(str(leaf)) and is_scan_file(str(scan))


@pytest.mark.parametrize("names", [("x", "y", "z", "label"), ("id", "x", "y", "z", "label")])
def test_numbers_in_quotes_read_as_numbers(tmp_path: Path, names: tuple[str, ...]):
    """Python's csv.QUOTE_ALL, and a spreadsheet's cells stored as text, quote every field:
    "not a number in '"0.1","0.2",...'" refused such a leaf (and the app took its scans for
    leaves). Quoted numbers read as numbers; the quoted header names the columns."""
    import csv

    nested = ls.demo("nested")
    path = tmp_path / "quoted.csv"
    with path.open("w", newline="") as handle:
        table = csv.writer(handle, quoting=csv.QUOTE_ALL)
        table.writerow(names)
        rows = [(*p, 0) for p in nested.boundary]
        rows += [(*p, k + 1) for k, vein in enumerate(nested.veins) for p in vein]
        table.writerows([(i, *row) if "id" in names else row for i, row in enumerate(rows)])
    _same(nested, ls.load_leaf(path))
    scan = tmp_path / "scan.csv"
    with scan.open("w", newline="") as handle:
        points = np.random.default_rng(0).uniform(size=(80, 6))
        csv.writer(handle, quoting=csv.QUOTE_ALL).writerows(points.tolist())
    from leafstudio.sources.scan import is_scan_file, read_scan

    assert is_scan_file(str(scan))  # six columns: normals beside x, y, z
    np.testing.assert_allclose(read_scan(scan), points[:, :3])
