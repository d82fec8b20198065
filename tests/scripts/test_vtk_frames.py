"""hapfluid.vtk_frames, the reader of haptic-sim's frames that tests and benchmarks share: a file
in another layout, or a broken series index, is a ValueError naming the file."""
import json

import pytest


@pytest.fixture(scope="module")
def vtk_frames():
    from hapfluid import vtk_frames
    return vtk_frames


def test_a_file_that_is_not_binary_polydata_is_refused_naming_it(vtk_frames, tmp_path):
    ascii_grid = tmp_path / "grid.vtk"
    ascii_grid.write_text("# vtk DataFile Version 3.0\nx\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 0 float\n")
    with pytest.raises(ValueError, match=r"grid\.vtk: not a binary legacy VTK POLYDATA file"):
        vtk_frames.read_vtk(ascii_grid)


def test_series_gives_times_and_paths_in_order(vtk_frames, tmp_path):
    (tmp_path / "particles.vtk.series").write_text(json.dumps(
        {"file-series-version": "1.0", "files": [{"name": "frame_000000.vtk", "time": 0},
                                                 {"name": "frame_000001.vtk", "time": 0.25}]}))
    assert vtk_frames.read_series(tmp_path) == [(0.0, tmp_path / "frame_000000.vtk"), (0.25, tmp_path / "frame_000001.vtk")]


def test_a_broken_series_index_is_refused_naming_it(vtk_frames, tmp_path):
    (tmp_path / "particles.vtk.series").write_text('{"files": [{"name": "frame_000000.vtk"}]}')
    with pytest.raises(ValueError, match=r"particles\.vtk\.series: not a readable \.vtk\.series index"):
        vtk_frames.read_series(tmp_path)
    with pytest.raises(ValueError, match=r"bodies\.vtk\.series"):
        vtk_frames.read_series(tmp_path, "bodies.vtk.series")
