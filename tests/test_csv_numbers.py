"""A recording's plain numbers read by NumPy's parser (issue 39, alpes_dyn.estimation.experiments.csv_numbers): the
same arrays as the cell-by-cell reader; anything else left to that reader, which names the bad cell."""

from __future__ import annotations

import numpy as np
import pytest

import alpes_dyn as ad
from alpes_dyn.errors import RecordingError
from alpes_dyn.estimation.experiments import csv_numbers, recording
from alpes_dyn.estimation.experiments.experiment import ExperimentDesign, experiment
from alpes_dyn.estimation.experiments.recording import read_recording, write_recording


@pytest.fixture(scope="module")
def written(tmp_path_factory):
    """finger3's documented 1 s experiment written as CSV (every cell a number written by repr)."""
    path = tmp_path_factory.mktemp("csv") / "rec.csv"
    write_recording(experiment("finger3", None, ExperimentDesign(duration=1.0), seed=4), path)
    return path, ad.Model.alpes("finger3")


def test_plain_numbers_read_as_the_cell_by_cell_reader_reads_them(written, monkeypatch):
    path, model = written
    text = path.read_text()
    data = csv_numbers.plain_rows(text, text.splitlines()[0].count(",") + 1)
    assert data is not None and data.shape == (1001, text.splitlines()[0].count(",") + 1)
    fast = read_recording(path, model)
    monkeypatch.setattr(recording, "plain_rows", lambda text, columns: None)
    slow = read_recording(path, model)
    for name in ("t", "encoder", "torque", "true_q"):
        assert np.array_equal(getattr(fast, name), getattr(slow, name)), name  # both correctly rounded


@pytest.mark.parametrize("body, why", [
    ("0.0,1\n0.001,\n", "an empty cell"), ('0.0,1\n"0.001",2\n', "a quoted cell"), ("0.0,1\n0.001,1_000\n", "digit separators"),
    ("0.0,1\n0.001,nan\n", "a NaN"), ("0.0,1\n0.001,inf\n", "an infinity"), ("0.0,1\n#0.001,2\n", "a comment sign"),
    ("0.0,1\n0.001,2,3\n", "a longer row"), ("0.0,1\n0.001,1e-320\n", "a subnormal value"),
    ("0.0,1\n0.001," + "1" * 300 + "\n", "a cell over 256 characters"), ("0.0,1\n0.001,0x10\n", "a hexadecimal"),
    ("", "no data row"), ("\n", "a blank data row alone")])
def test_anything_but_plain_numbers_is_left_to_the_cell_by_cell_reader(body, why):
    assert csv_numbers.plain_rows("t,x\n" + body, 2) is None, why
    assert csv_numbers.plain_rows("\nt,x\n0.0,1\n", 2) is None  # a blank first line


@pytest.mark.parametrize("cell, message", [
    ("", "is empty at line 3"), ("1_000", "not a number ('1_000')"), ("nan", "NaN or inf"),
    ("1" * 300, "a cell of 300 characters"), ('"x"', "not a number ('x')")])
def test_the_cell_by_cell_reader_still_names_the_bad_cell(written, tmp_path, cell, message):
    path, model = written
    lines = path.read_text().splitlines()
    cells = lines[2].split(",")
    cells[1] = cell  # line 3's encoder cell
    lines[2] = ",".join(cells)
    bad = tmp_path / "bad.csv"
    bad.write_text("\n".join(lines) + "\n")
    with pytest.raises(RecordingError, match="encoder_finger") as exc:
        read_recording(bad, model)
    assert message in str(exc.value) and "\n" not in str(exc.value)


@pytest.mark.parametrize("row", ["", ",,,,,", "   ", " , ,\r"], ids=["blank", "commas", "spaces", "crlf"])
def test_an_empty_row_between_data_rows_is_refused_naming_its_line(written, tmp_path, row):
    """A row of empty cells (or a blank line) in mid-recording is a lost sample: refused by both readers, naming its
    line (issue 52: it was skipped without a word). Blank lines after the last row (a file's trailing newlines) are
    no sample: the same recording as without them."""
    path, model = written
    lines = path.read_text().splitlines()
    bad = tmp_path / "bad.csv"
    bad.write_text("\n".join(lines[:500] + [row] + lines[500:]) + "\n")
    with pytest.raises(RecordingError, match="line 501 is empty between data rows") as exc:
        read_recording(bad, model)
    assert "\n" not in str(exc.value)
    trailing = tmp_path / "trailing.csv"
    trailing.write_text("\n".join(lines + [row, ""]) + "\n")
    assert np.array_equal(read_recording(trailing, model).encoder, read_recording(path, model).encoder)
    assert csv_numbers.empty_row("\n\n" + "\n".join(lines)) is None  # blank lines before the header: not a sample
