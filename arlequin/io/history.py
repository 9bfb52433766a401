"""Time histories as CSV, one row per record, written and flushed as the run goes."""

from __future__ import annotations

import csv
import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["HistoryCSV", "read_history", "read_rows"]


class HistoryCSV:
    """A CSV file of named columns (the header carries the units: ``name [unit]``).

    Parameters
    ----------
    path : str or Path
    columns : sequence of str
        Column names, in order.
    units : mapping, optional
        Column name -> unit string (SI), shown in the header.
    """

    def __init__(
        self,
        path: str | os.PathLike,
        columns: Sequence[str],
        units: Mapping[str, str] | None = None,
    ) -> None:
        self.path = Path(path)
        self.columns = list(columns)
        units = dict(units or {})
        self._fh = open(self.path, "w", newline="", encoding="utf-8")
        self._csv = csv.writer(self._fh)
        self.header = [f"{c} [{units[c]}]" if units.get(c) else c for c in self.columns]
        self._csv.writerow(self.header)
        self._fh.flush()
        self.n_rows = 0
        # the file's length after the header and after each row: where a truncation cuts
        self._ends = [self._fh.tell()]

    def append(self, row: Mapping[str, float]) -> None:
        """Write one row (missing columns are left empty) and flush it to disk."""
        self._csv.writerow([_text(row[c]) if c in row else "" for c in self.columns])
        self._fh.flush()
        self.n_rows += 1
        self._ends.append(self._fh.tell())

    def append_text(self, cells: Sequence[str]) -> None:
        """Write one row given as the text of its cells, as :func:`read_rows` read it (a
        resumed run's rows written again byte for byte) and flush it to disk."""
        if len(cells) != len(self.columns):
            raise ValueError(f"a row of {len(self.columns)} cells expected, got {len(cells)}")
        self._csv.writerow(list(cells))
        self._fh.flush()
        self.n_rows += 1
        self._ends.append(self._fh.tell())

    def truncate(self, n_rows: int) -> None:
        """Keep the first ``n_rows`` rows on disk, drop the others (an adaptive run's rejected
        interval: its rows are computed again).

        Raises
        ------
        ValueError
            If ``n_rows`` is negative or more than the rows written.
        """
        if not 0 <= n_rows <= self.n_rows:
            raise ValueError(f"n_rows must be in [0, {self.n_rows}], got {n_rows}")
        if n_rows == self.n_rows:
            return
        self._fh.seek(self._ends[n_rows])
        self._fh.truncate()
        self._fh.flush()
        del self._ends[n_rows + 1 :]
        self.n_rows = n_rows

    def close(self) -> None:
        """Close the file (every row is already on disk)."""
        if not self._fh.closed:
            self._fh.close()


def _text(value) -> str:
    """Integers (step counts) as integers, every other number with all its digits, text as
    it is (a list of counts in one cell)."""
    if isinstance(value, str):
        return value
    if isinstance(value, (int, np.integer)) and not isinstance(value, bool):
        return str(int(value))
    return repr(float(value))


def read_history(path: str | os.PathLike) -> dict[str, list[Any]]:
    """Columns of a history file by name (units stripped from the header): numbers as floats,
    empty cells as NaN, a cell that is not a number (a list of counts) as its text."""
    header, rows = read_rows(path)
    names = [h.split(" [")[0] for h in header]
    cols: dict[str, list[Any]] = {h: [] for h in names}
    for row in rows:
        for h, v in zip(names, row):
            cols[h].append(_number(v))
    return cols


def _number(text: str) -> float | str:
    if text == "":
        return float("nan")
    try:
        return float(text)
    except ValueError:
        return text


def read_rows(path: str | os.PathLike) -> tuple[list[str], list[list[str]]]:
    """The header (with units) and the rows of a history file, every cell as its text.

    Returns
    -------
    header : list of str
    rows : list of list of str
    """
    with open(path, newline="", encoding="utf-8") as fh:
        reader = csv.reader(fh)
        header = next(reader)
        return header, [row for row in reader]
