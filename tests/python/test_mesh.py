# simit.read_mesh on the TetGen bunny against a plain parse of its text files, and its errors.
import shutil

import numpy as np
import pytest

import simit


def parse_tetgen(path, columns):
    """The records of a TetGen file: the count and the `columns` numbers after each record's
    index (comments and attributes left out), and the first record's index."""
    rows = []
    with open(path) as f:
        lines = [l.split("#")[0].split() for l in f]
    lines = [l for l in lines if l]
    count = int(lines[0][0])
    first_index = int(lines[1][0])
    for fields in lines[1 : 1 + count]:
        rows.append(fields[1 : 1 + columns])
    return count, first_index, rows


@pytest.fixture(scope="module")
def bunny(repo_root):
    """The bunny's TetGen files by extension: bunny["node"] is examples/data/bunny.1.node."""
    return {s: repo_root / "examples" / "data" / f"bunny.1.{s}" for s in ("node", "ele", "edge")}


@pytest.fixture(scope="module")
def mesh(bunny):
    return simit.read_mesh(str(bunny["node"]))


def test_points_match_the_node_file(mesh, bunny):
    count, base, rows = parse_tetgen(bunny["node"], 3)
    points = np.array(rows, dtype=float)
    assert count == 3607 and base == 0
    assert mesh.points.shape == (count, 3) and mesh.points.dtype == np.float64
    np.testing.assert_array_equal(mesh.points, points)
    np.testing.assert_array_equal(mesh.points[0], [-0.895657, -0.131285, 1.40157])


def test_tets_match_the_ele_file(mesh, bunny):
    count, _, rows = parse_tetgen(bunny["ele"], 4)
    tets = np.array(rows, dtype=np.int64)
    assert count == 12687
    assert mesh.tets.shape == (count, 4) and mesh.tets.dtype == np.int32
    # The file's tets are all in TetGen's orientation, so none is swapped on reading.
    p = mesh.points[tets]
    det = np.linalg.det(np.stack([p[:, i] - p[:, 3] for i in range(3)], axis=2))
    assert (det < 0).all()
    np.testing.assert_array_equal(mesh.tets, tets)
    np.testing.assert_array_equal(mesh.tets[0], [2342, 1528, 2323, 3169])


def test_edges_match_the_edge_file(mesh, bunny):
    count, _, rows = parse_tetgen(bunny["edge"], 2)
    assert count == 19233
    assert mesh.edges.shape == (count, 2) and mesh.edges.dtype == np.int32
    np.testing.assert_array_equal(mesh.edges, np.array(rows, dtype=np.int64))
    assert mesh.edges.min() == 0 and mesh.edges.max() == len(mesh.points) - 1


def test_absent_element_kinds_are_none(mesh):
    assert mesh.triangles is None  # the bunny has no .face file


def test_one_based_files_become_zero_based(tmp_path):
    (tmp_path / "tri.node").write_text("3 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1 0\n")
    (tmp_path / "tri.face").write_text("1 0\n1 1 2 3\n")
    m = simit.read_mesh(str(tmp_path / "tri.node"))
    np.testing.assert_array_equal(m.points, [[0, 0, 0], [1, 0, 0], [0, 1, 0]])
    np.testing.assert_array_equal(m.triangles, [[0, 1, 2]])
    assert m.tets is None and m.edges is None


def test_any_file_of_the_family_reads_the_whole_mesh(bunny):
    m = simit.read_mesh(str(bunny["ele"]))
    assert m.points.shape == (3607, 3) and m.tets.shape == (12687, 4)


def test_missing_file_names_it(tmp_path):
    missing = tmp_path / "nothing.node"
    with pytest.raises(simit.Error, match="nothing.node"):
        simit.read_mesh(str(missing))


def test_malformed_file_names_it(tmp_path, bunny):
    for suffix in ("node", "ele"):
        shutil.copy(bunny[suffix], tmp_path / f"broken.{suffix}")
    node = tmp_path / "broken.node"
    lines = node.read_text().splitlines()
    lines[5] = "4    1.0  not-a-number  2.0"
    node.write_text("\n".join(lines) + "\n")
    with pytest.raises(simit.Error, match="broken.node"):
        simit.read_mesh(str(node))
    # A tet naming a vertex past the last one.
    (tmp_path / "broken.node").write_text("4 3 0 0\n0 0 0 0\n1 1 0 0\n2 0 1 0\n3 0 0 1\n")
    (tmp_path / "broken.ele").write_text("1 4 0\n0 0 1 2 9\n")
    with pytest.raises(simit.Error, match="broken.ele"):
        simit.read_mesh(str(tmp_path / "broken.node"))


def test_unknown_extension(tmp_path):
    path = tmp_path / "mesh.xyz"
    path.write_text("1 2 3\n")
    with pytest.raises(simit.Error, match="mesh.xyz"):
        simit.read_mesh(str(path))
