"""Port types: what flows along an edge, how it is checked and how it is stored.

A port type is a class used only through its class methods (``GrayImagePort``);
values themselves are plain numpy arrays, Python scalars, column tables or
frozen dataclasses of arrays. Node signatures do not name these classes: they
use the aliases of :mod:`graphvision.types` (``GrayImage = Annotated[
NDArray[np.float32], GrayImagePort]``), which a type checker reads as the
value's type and the registry reads as the port type. A class's name without
its ``Port`` suffix is the type's name in pipeline files and messages.

Subclassing draws the lattice: a ``GrayImage`` is an ``Image``, so an
edge from a ``GrayImage`` output into an ``Image`` input type-checks, the
reverse does not. ``BinaryImage`` and ``LabelImage`` are *not* images: a mask
is not an intensity, and feeding one to a filter is a mistake to report.

::

    Array ─┬─ FloatImage ── Image ─┬─ GrayImage
           │                       └─ ColorImage
           ├─ BinaryImage
           ├─ LabelImage
           ├─ Kernel
           ├─ Points2D, Points3D, Descriptors, Homography
    Float ── Int        Bool        Text        Table        Record (dataclasses)

Each type encodes a value as named arrays plus a small JSON header, and back.
That encoding is the disk cache's format and the process executor's transport:
pickle is never written nor loaded.

Conventions (tested in ``tests/test_ports.py``): images are ``float32`` in
[0, 1], gray ``H×W``, colour ``H×W×3`` RGB; masks are ``bool``; labels
``int32`` with 0 as background; kernels ``float64``.
"""

from __future__ import annotations

import csv
import dataclasses
import json
from pathlib import Path
from typing import Any, ClassVar

import numpy as np

from ._dtype_policy import to_dtype, to_float_image, to_labels, to_mask
from ._errors import PortValueError
from ._memory import frozen_copy, is_aligned

__all__ = [
    "ArrayPort",
    "BinaryImagePort",
    "BoolPort",
    "ColorImagePort",
    "DescriptorsPort",
    "FloatImagePort",
    "FloatPort",
    "GrayImagePort",
    "HomographyPort",
    "ImagePort",
    "IntPort",
    "KernelPort",
    "LabelImagePort",
    "Points2DPort",
    "Points3DPort",
    "PortType",
    "RecordPort",
    "TablePort",
    "TextPort",
    "builtin_port_types",
    "freeze",
]

Arrays = dict[str, np.ndarray]
Meta = dict[str, Any]


def freeze(array: np.ndarray) -> np.ndarray:
    """``array`` in immutable memory at a 64-byte aligned address (see :mod:`._memory`).

    A flag is not enough: ``flags.writeable = True`` succeeds again on an
    array that owns its memory (or on a view of a writable base). An array
    over a ``bytes`` object cannot be made writable at all, so the value is
    copied once into one, unless it already lies, aligned, over immutable
    memory (a value read from the disk cache does).
    """
    root: object = array
    while isinstance(root, np.ndarray | memoryview):
        if isinstance(root, memoryview):
            root = root.obj
        elif root.base is None:
            break
        else:
            root = root.base
    if isinstance(root, bytes) and is_aligned(array) and not array.flags.writeable:
        return array  # (an array unpickled over bytes can be writable: it is copied)
    return frozen_copy(array)


class PortType:
    """Base class of port types. Subclass it to add a type (a plugin may)."""

    description: ClassVar[str] = ""
    _type_name: ClassVar[str] = "PortType"

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        name = cls.__name__  # named once: records and summaries ask for it per value
        cls._type_name = name[: -len("Port")] if name.endswith("Port") and name != "Port" else name

    @classmethod
    def type_name(cls) -> str:
        """The name used in pipeline files and messages: the class name without ``Port``."""
        return cls._type_name

    @classmethod
    def is_a(cls, other: type[PortType]) -> bool:
        """True when a value of this type may flow into a port of type ``other``."""
        return issubclass(cls, other)

    @classmethod
    def validate(cls, value: Any) -> Any:
        """Return ``value`` (normalised) or raise :class:`PortValueError`."""
        raise NotImplementedError

    @classmethod
    def coerce(cls, value: Any, source: str) -> Any:
        """A value from outside (a file, a caller's array) in this type's convention.

        Applied to graph inputs before :meth:`validate`, following the dtype
        policy of :mod:`graphvision._dtype_policy` (a ``uint8`` array becomes
        a ``float32`` image as a PNG file does). The default changes nothing.
        Raises :class:`PortValueError` naming ``source``.
        """
        return value

    @classmethod
    def encode(cls, value: Any) -> tuple[Arrays, Meta]:
        """Named arrays and a JSON-able header that :meth:`decode` turns back into ``value``."""
        raise NotImplementedError

    @classmethod
    def decode(cls, arrays: Arrays, meta: Meta) -> Any:
        raise NotImplementedError

    @classmethod
    def summary(cls, value: Any) -> str:
        """A one-line description for error messages and reports."""
        return f"{cls.type_name()}"

    @classmethod
    def preview(cls, value: Any) -> np.ndarray | None:
        """A picture of ``value`` for reports and notebooks, or None when it has none.

        The picture is ``float32`` in [0, 1], ``H×W`` or ``H×W×3``. A plugin's
        port type overrides this to show its values (lines drawn, boxes drawn).
        """
        return None

    @classmethod
    def write(cls, value: Any, stem: Path) -> list[Path]:
        """Write ``value`` next to ``stem`` (no suffix) and return the files written."""
        arrays, meta = cls.encode(value)
        if list(arrays) == ["data"] and not meta:
            path = stem.with_suffix(".npy")
            np.save(path, arrays["data"], allow_pickle=False)
            return [path]
        path = stem.with_suffix(".npz")
        np.savez(path, **arrays)  # type: ignore[arg-type]  # numpy's stub types **kwds as bool
        if not meta:
            return [path]
        meta_path = stem.with_suffix(".json")
        meta_path.write_text(json.dumps(meta, indent=2))
        return [path, meta_path]

    @classmethod
    def read(cls, files: list[Path]) -> Any:
        """The value :meth:`write` wrote to ``files`` (for a report made again from them).

        Raises
        ------
        ValueError
            When the files are not what this port type writes.
        """
        by_suffix = {path.suffix: path for path in files}
        if ".npy" in by_suffix:
            return cls.decode({"data": np.load(by_suffix[".npy"], allow_pickle=False)}, {})
        if ".npz" not in by_suffix:
            raise ValueError(f"{cls.type_name()} is written as .npy or .npz, got {files}")
        with np.load(by_suffix[".npz"], allow_pickle=False) as archive:
            arrays = {name: archive[name] for name in archive.files}
        meta = json.loads(by_suffix[".json"].read_text()) if ".json" in by_suffix else {}
        return cls.decode(arrays, meta)


def _fail(cls: type[PortType], expected: str, value: Any) -> PortValueError:
    return PortValueError(f"expected {cls.type_name()} ({expected}), got {describe_value(value)}")


def describe_value(value: Any) -> str:
    """Shape and dtype of an array, or the type of anything else."""
    if isinstance(value, np.ndarray):
        return f"array shape={value.shape} dtype={value.dtype}"
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return type(value).__name__
    return f"{type(value).__name__} {value!r:.60}"


class ArrayPort(PortType):
    """Any numeric or boolean numpy array (never an object array)."""

    ndims: ClassVar[tuple[int, ...]] = ()
    dtypes: ClassVar[tuple[type, ...]] = ()
    expected: ClassVar[str] = "a numeric numpy array"
    # Array itself and sets of things (points, descriptors) may be empty; images may not
    allow_empty: ClassVar[bool] = False

    @classmethod
    def validate(cls, value: Any) -> np.ndarray:
        if not isinstance(value, np.ndarray) or value.dtype.hasobject:
            raise _fail(cls, cls.expected, value)
        if cls.ndims and value.ndim not in cls.ndims:
            raise _fail(cls, cls.expected, value)
        if cls.dtypes and value.dtype.type not in cls.dtypes:
            raise _fail(cls, cls.expected, value)
        if value.size == 0 and cls is not ArrayPort and not cls.allow_empty:
            raise PortValueError(f"expected {cls.type_name()}, got an empty array {value.shape}")
        return value

    @classmethod
    def coerce(cls, value: Any, source: str) -> Any:
        """Cast to the one declared dtype when no value can change (int points to float64)."""
        return to_dtype(value, cls.dtypes[0]) if len(cls.dtypes) == 1 else value

    @classmethod
    def encode(cls, value: np.ndarray) -> tuple[Arrays, Meta]:
        return {"data": value}, {}

    @classmethod
    def decode(cls, arrays: Arrays, meta: Meta) -> np.ndarray:
        return arrays["data"]

    @classmethod
    def summary(cls, value: np.ndarray) -> str:
        return f"{cls.type_name()} {'×'.join(map(str, value.shape))} {value.dtype}"


class FloatImagePort(ArrayPort):
    """A filter response: finite ``float32``, ``H×W`` or ``H×W×3``, any range."""

    ndims: ClassVar[tuple[int, ...]] = (2, 3)
    dtypes = (np.float32,)
    expected = "finite float32, H×W or H×W×3"

    @classmethod
    def coerce(cls, value: Any, source: str) -> Any:
        """The image dtype policy, keeping a float array's range."""
        if not isinstance(value, np.ndarray):
            return value
        return to_float_image(value, source=source, check_range=False)

    @classmethod
    def validate(cls, value: Any) -> np.ndarray:
        value = super().validate(value)
        if value.ndim == 3 and value.shape[2] != 3:
            raise _fail(cls, cls.expected, value)
        if cls is FloatImagePort and not np.isfinite(value.min() + value.max()):
            raise PortValueError(f"expected {cls.type_name()} with finite values, got NaN or inf")
        return value

    @classmethod
    def preview(cls, value: np.ndarray) -> np.ndarray | None:
        from ._pictures import stretch

        return stretch(value)


class ImagePort(FloatImagePort):
    """An intensity image: ``float32`` in [0, 1], gray ``H×W`` or RGB ``H×W×3``."""

    expected = "float32 in [0, 1], H×W or H×W×3"

    @classmethod
    def coerce(cls, value: Any, source: str) -> Any:
        """The image dtype policy (:func:`~graphvision.to_float_image`)."""
        return to_float_image(value, source=source) if isinstance(value, np.ndarray) else value

    @classmethod
    def validate(cls, value: Any) -> np.ndarray:
        value = super().validate(value)
        low, high = float(value.min()), float(value.max())
        if not (low >= 0.0 and high <= 1.0):  # also rejects NaN
            raise PortValueError(
                f"expected {cls.type_name()} values in [0, 1], got range [{low:g}, {high:g}]"
            )
        return value

    @classmethod
    def write(cls, value: np.ndarray, stem: Path) -> list[Path]:
        import imageio.v3 as iio

        path = stem.with_suffix(".png")
        iio.imwrite(path, np.round(value * 255.0).astype(np.uint8))
        return [path]

    @classmethod
    def read(cls, files: list[Path]) -> np.ndarray:
        """The PNG back (to 8 bits, as it was written)."""
        import imageio.v3 as iio

        return (iio.imread(files[0]).astype(np.float32) / np.float32(255.0)).astype(np.float32)

    @classmethod
    def preview(cls, value: np.ndarray) -> np.ndarray | None:
        return value


class GrayImagePort(ImagePort):
    """A gray image: ``float32`` ``H×W`` in [0, 1]."""

    ndims = (2,)
    expected = "float32 in [0, 1], H×W"


class ColorImagePort(ImagePort):
    """An RGB image: ``float32`` ``H×W×3`` in [0, 1]."""

    ndims = (3,)
    expected = "float32 in [0, 1], H×W×3"


class BinaryImagePort(ArrayPort):
    """A mask: ``bool`` ``H×W``; True is foreground."""

    ndims = (2,)
    dtypes = (np.bool_,)
    expected = "bool H×W"

    @classmethod
    def coerce(cls, value: Any, source: str) -> Any:
        """bool, or 0 and one other value (a 0/255 PNG), as a mask."""
        return to_mask(value, source=source) if isinstance(value, np.ndarray) else value

    @classmethod
    def write(cls, value: np.ndarray, stem: Path) -> list[Path]:
        import imageio.v3 as iio

        path = stem.with_suffix(".png")
        iio.imwrite(path, value.astype(np.uint8) * 255)
        return [path]

    @classmethod
    def read(cls, files: list[Path]) -> np.ndarray:
        import imageio.v3 as iio

        mask: np.ndarray = iio.imread(files[0]) > 0
        return mask

    @classmethod
    def preview(cls, value: np.ndarray) -> np.ndarray | None:
        return value.astype(np.float32)


class LabelImagePort(ArrayPort):
    """A label image: ``int32`` ``H×W``, 0 is background, regions 1..N."""

    ndims = (2,)
    dtypes = (np.int32,)
    expected = "int32 H×W, 0 = background"

    @classmethod
    def coerce(cls, value: Any, source: str) -> Any:
        """Any non-negative integer labels as int32 (scikit-image's are int64)."""
        return to_labels(value, source=source) if isinstance(value, np.ndarray) else value

    @classmethod
    def validate(cls, value: Any) -> np.ndarray:
        value = super().validate(value)
        if value.min() < 0:
            raise PortValueError(f"expected LabelImage labels >= 0, got {int(value.min())}")
        return value

    @classmethod
    def preview(cls, value: np.ndarray) -> np.ndarray | None:
        from ._pictures import label_colours

        return label_colours(value)


class KernelPort(ArrayPort):
    """A filter kernel: ``float64`` 2-D array, centred at ``(rows // 2, cols // 2)``."""

    ndims = (2,)
    dtypes = (np.float64,)
    expected = "float64 2-D array"

    @classmethod
    def preview(cls, value: np.ndarray) -> np.ndarray | None:
        from ._pictures import stretch

        return stretch(value)


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
        return f"{cls.type_name()} {value!r:.40}"

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
        if not isinstance(value, dict) or not all(isinstance(k, str) for k in value):
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


class RecordPort(PortType):
    """Base for frozen dataclasses whose fields are arrays or JSON scalars.

    Subclasses set ``value_class``; encoding stores array fields as arrays and
    the other fields in the header.
    """

    value_class: ClassVar[type] = object

    @classmethod
    def validate(cls, value: Any) -> Any:
        if not isinstance(value, cls.value_class):
            raise _fail(cls, cls.value_class.__name__, value)
        return value

    @classmethod
    def encode(cls, value: Any) -> tuple[Arrays, Meta]:
        arrays: Arrays = {}
        meta: Meta = {}
        for field in dataclasses.fields(value):
            item = getattr(value, field.name)
            if isinstance(item, np.ndarray):
                arrays[field.name] = item
            else:
                meta[field.name] = item
        return arrays, meta

    @classmethod
    def decode(cls, arrays: Arrays, meta: Meta) -> Any:
        return cls.value_class(**arrays, **meta)


class Points2DPort(ArrayPort):
    """Points ``(x, y)`` = (column, row): ``float64`` ``N×2`` (N may be 0), finite."""

    ndims = (2,)
    dtypes = (np.float64,)
    expected = "float64 N×2 (x, y)"
    allow_empty = True

    @classmethod
    def validate(cls, value: Any) -> np.ndarray:
        value = super().validate(value)
        if value.shape[1] != 2:
            raise _fail(cls, cls.expected, value)
        if not np.isfinite(value).all():
            raise PortValueError("expected Points2D with finite coordinates, got NaN or inf")
        return value

    @classmethod
    def preview(cls, value: np.ndarray) -> np.ndarray | None:
        from ._pictures import scatter

        return scatter(value)


class DescriptorsPort(ArrayPort):
    """Feature descriptors: ``float32`` ``N×D``, one row per keypoint (N may be 0)."""

    ndims = (2,)
    dtypes = (np.float32,)
    expected = "float32 N×D"
    allow_empty = True


class Points3DPort(ArrayPort):
    """3-D points ``(X, Y, Z)``: ``float64`` ``N×3`` (N may be 0), finite; written as PLY."""

    ndims = (2,)
    dtypes = (np.float64,)
    expected = "float64 N×3 (X, Y, Z)"
    allow_empty = True

    @classmethod
    def validate(cls, value: Any) -> np.ndarray:
        value = super().validate(value)
        if value.shape[1] != 3:
            raise _fail(cls, cls.expected, value)
        if not np.isfinite(value).all():
            raise PortValueError("expected Points3D with finite coordinates, got NaN or inf")
        return value

    @classmethod
    def write(cls, value: np.ndarray, stem: Path) -> list[Path]:
        """A binary little-endian PLY file of ``double`` x, y, z vertices (MeshLab,
        CloudCompare, Open3D and Blender read it)."""
        path = stem.with_suffix(".ply")
        header = (
            f"ply\nformat binary_little_endian 1.0\nelement vertex {len(value)}\n"
            "property double x\nproperty double y\nproperty double z\nend_header\n"
        )
        path.write_bytes(header.encode("ascii") + value.astype("<f8").tobytes())
        return [path]

    @classmethod
    def read(cls, files: list[Path]) -> np.ndarray:
        header, _, body = files[0].read_bytes().partition(b"end_header\n")
        if b"binary_little_endian" not in header:
            raise ValueError(f"{files[0]} is not a PLY file graphvision wrote")
        return np.frombuffer(body, "<f8").reshape(-1, 3).copy()

    @classmethod
    def preview(cls, value: np.ndarray) -> np.ndarray | None:
        from ._pictures import scatter

        return scatter(value[:, :2])  # seen along the z axis


class HomographyPort(ArrayPort):
    """A plane-to-plane projective map: ``float64`` 3×3, finite, ``x' ~ H x``."""

    ndims = (2,)
    dtypes = (np.float64,)
    expected = "float64 3×3"

    @classmethod
    def validate(cls, value: Any) -> np.ndarray:
        value = super().validate(value)
        if value.shape != (3, 3) or not np.isfinite(value).all():
            raise _fail(cls, "finite float64 3×3", value)
        return value


def builtin_port_types() -> list[type[PortType]]:
    """The port types the engine defines (plugins may register more)."""
    from ._records import BoxesPort, CameraPort, KeypointsPort, MatchesPort

    return [
        ArrayPort,
        FloatImagePort,
        ImagePort,
        GrayImagePort,
        ColorImagePort,
        BinaryImagePort,
        LabelImagePort,
        KernelPort,
        Points2DPort,
        Points3DPort,
        DescriptorsPort,
        HomographyPort,
        KeypointsPort,
        MatchesPort,
        CameraPort,
        BoxesPort,
        FloatPort,
        IntPort,
        BoolPort,
        TextPort,
        TablePort,
    ]
