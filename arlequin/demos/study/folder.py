"""A study's folder: ``index.json`` (each case's parameters, status, error and results) and
the table of the completed cases (``results.csv``, and ``results.parquet`` with pandas and
pyarrow)."""

from __future__ import annotations

import csv
import json
import os
from pathlib import Path
from typing import Any

from .spec import StudyError, StudySpec

__all__ = ["StudyIndex", "open_study_folder", "write_table"]


class StudyIndex:
    """``index.json`` of a study folder: each case's parameters, status, error (rewritten
    atomically after every case)."""

    def __init__(self, root: Path, spec: StudySpec) -> None:
        self.path = root / "index.json"
        old = json.loads(self.path.read_text()) if self.path.exists() else {}
        self.cases: dict[str, dict[str, Any]] = old.get("cases", {})
        self.demo = spec.demo
        for c in spec.cases:
            self.cases.setdefault(c.case_id, {"number": c.number, "params": c.params,
                                              "status": "pending"})  # fmt: skip
        self.write()

    def set(self, case_id: str, **entry: Any) -> None:
        """Update a case's entry (status, error, results) and rewrite the index."""
        self.cases[case_id].update(entry)
        self.write()

    def write(self) -> None:
        """Rewrite ``index.json`` atomically (write, then rename)."""
        tmp = self.path.with_suffix(".tmp")
        tmp.write_text(json.dumps({"demo": self.demo, "cases": self.cases}, indent=2,
                                  default=float))  # fmt: skip
        os.replace(tmp, self.path)


def write_table(root: Path, index: StudyIndex, spec: StudySpec) -> list[dict[str, Any]]:
    """``results.csv`` (and ``results.parquet`` with pandas and pyarrow): one row per completed
    case, its parameters and scalar results; returns the table (a DataFrame with pandas)."""
    rows = []
    for c in spec.cases:
        entry = index.cases[c.case_id]
        if entry.get("status") != "complete":
            continue
        rows.append({"case": c.case_id, **{f"param.{k}": json.dumps(v) if isinstance(v, list)
                                           else v for k, v in c.params.items()},
                     **entry.get("results", {})})  # fmt: skip
    columns: list[str] = []
    for r in rows:
        columns += [k for k in r if k not in columns]
    with open(root / "results.csv", "w", newline="", encoding="utf-8") as f:
        writer = csv.DictWriter(f, columns)
        writer.writeheader()
        writer.writerows(rows)
    try:
        import pandas as pd

        table = pd.DataFrame(rows, columns=columns)
        try:
            table.to_parquet(root / "results.parquet")
        except Exception:  # no pyarrow: the CSV is the table
            pass
        return table
    except ImportError:
        return rows


def open_study_folder(root: Path, spec: StudySpec) -> StudyIndex:
    """Create the study folder (or reopen it, refusing one that holds another study) and its
    index."""
    try:
        (root / "cases").mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise StudyError(f"cannot write the study folder {str(root)!r}: {exc}") from exc
    old_index = root / "index.json"
    if old_index.exists():
        old = json.loads(old_index.read_text())
        ours = {c.case_id for c in spec.cases}
        others = sorted(set(old.get("cases", {})) - ours)
        if old.get("demo") != spec.demo or others:
            raise StudyError(
                f"the study folder {str(root)!r} holds another study ({old.get('demo')!r}, "
                f"{len(others)} cases not in this one): give another out, or remove the folder"
            )
    return StudyIndex(root, spec)
