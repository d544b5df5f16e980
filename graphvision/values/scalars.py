"""Scalar and table port types: float, int, bool, text, and column tables."""

from __future__ import annotations

import csv
import json
from itertools import repeat
from pathlib import Path
from typing import Any, ClassVar

import numpy as np

from graphvision.errors import PortValueError
from graphvision.values.ports import Arrays, Meta, PortType, _fail, codes_as, describe_value

__all__ = [
    "BoolPort",
    "FloatPort",
    "IntPort",
    "TablePort",
    "TextPort",
    "_ScalarPort",
    "is_plain_table_port",
]


class _ScalarPort(PortType):
    python_type: ClassVar[type] = object

    @classmethod
    def validate(cls, value: Any) -> Any:
        if type(value) is cls.python_type:  # the common case, decided at once
            return value
        if isinstance(value, np.generic):
            value = value.item()
        if not isinstance(value, cls.python_type) or (
            cls.python_type is not bool and isinstance(value, bool)
        ):
            raise _fail(cls, cls.python_type.__name__, value)
        return value

    @classmethod
    def encode(cls, value: Any) -> tuple[Arrays, Meta]:
        return {}, {"value": value}

    @classmethod
    def decode(cls, arrays: Arrays, meta: Meta) -> Any:
        return meta["value"]

    @classmethod
    def summary(cls, value: Any) -> str:
        return f"{cls._type_name} {value!r:.40}"  # (the name without a call: one per output)

    @classmethod
    def write(cls, value: Any, stem: Path) -> list[Path]:
        path = stem.with_suffix(".json")
        path.write_text(json.dumps(value) + "\n")
        return [path]

    @classmethod
    def read(cls, files: list[Path]) -> Any:
        return json.loads(files[0].read_text())


class FloatPort(_ScalarPort):
    """A real number (an ``Int`` is accepted where a ``Float`` is expected)."""

    python_type: ClassVar[type] = float

    @classmethod
    def validate(cls, value: Any) -> Any:
        if type(value) is cls.python_type:  # the common case, decided at once
            return value
        if isinstance(value, np.generic):
            value = value.item()
        if isinstance(value, int) and not isinstance(value, bool) and cls is FloatPort:
            value = float(value)
        return super().validate(value)


class IntPort(FloatPort):
    """An integer."""

    python_type = int


class BoolPort(_ScalarPort):
    """True or False."""

    python_type = bool


class TextPort(_ScalarPort):
    """A string."""

    python_type = str


class TablePort(PortType):
    """Columns of equal length: ``dict[str, 1-D ndarray]``; written as CSV and JSON."""

    @classmethod
    def validate(cls, value: Any) -> dict[str, np.ndarray]:
        if not isinstance(value, dict) or not all(map(isinstance, value, repeat(str))):
            raise _fail(cls, "dict of column name to 1-D array", value)
        lengths = set()
        for name, column in value.items():
            if not isinstance(column, np.ndarray) or column.ndim != 1 or column.dtype.hasobject:
                raise PortValueError(
                    f"expected Table column '{name}' to be a 1-D numeric array, "
                    f"got {describe_value(column)}"
                )
            lengths.add(len(column))
        if len(lengths) > 1:
            raise PortValueError(f"expected Table columns of equal length, got {sorted(lengths)}")
        return value

    @classmethod
    def encode(cls, value: dict[str, np.ndarray]) -> tuple[Arrays, Meta]:
        return dict(value), {"columns": list(value)}

    @classmethod
    def decode(cls, arrays: Arrays, meta: Meta) -> dict[str, np.ndarray]:
        return {name: arrays[name] for name in meta["columns"]}

    @classmethod
    def summary(cls, value: dict[str, np.ndarray]) -> str:
        rows = len(next(iter(value.values()))) if value else 0
        return f"Table {rows} rows × {len(value)} columns"

    @classmethod
    def write(cls, value: dict[str, np.ndarray], stem: Path) -> list[Path]:
        csv_path, json_path = stem.with_suffix(".csv"), stem.with_suffix(".json")
        columns = list(value)
        rows = zip(*(value[c].tolist() for c in columns), strict=True)
        with csv_path.open("w", newline="") as handle:
            writer = csv.writer(handle)
            writer.writerow(columns)
            writer.writerows(rows)
        json_path.write_text(json.dumps({c: value[c].tolist() for c in columns}) + "\n")
        return [csv_path, json_path]

    @classmethod
    def read(cls, files: list[Path]) -> dict[str, np.ndarray]:
        (table,) = [path for path in files if path.suffix == ".json"]
        return {name: np.asarray(column) for name, column in json.loads(table.read_text()).items()}


def is_plain_table_port(kind: type[PortType]) -> bool:
    """Whether a value of ``kind`` is its arrays as they are: a :class:`TablePort` that encodes
    and decodes a table as ``TablePort`` does (its columns are frozen in the dict's order,
    without the encoding's copy of the dict and the decoding's)."""
    return codes_as(kind, TablePort)
