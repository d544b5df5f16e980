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

import dataclasses
import json
from operator import attrgetter
from pathlib import Path
from typing import Any, BinaryIO, ClassVar

import numpy as np

from graphvision.errors import PortValueError
from graphvision.values.budget import check_array_file
from graphvision.values.dtype_policy import dtype_name, to_dtype
from graphvision.values.memory import (
    alignment_offset,
    frozen_copies,
    frozen_copy,
    is_frozen_window,
)

__all__ = [
    "ArrayPort",
    "Arrays",
    "Meta",
    "Placed",
    "PortType",
    "RecordPort",
    "codes_as",
    "describe_value",
    "freeze",
    "freeze_all",
    "is_frozen",
    "is_plain_array_port",
]


Arrays = dict[str, np.ndarray]
Meta = dict[str, Any]


def freeze(array: np.ndarray, offset: int = 0) -> np.ndarray:
    """``array`` in immutable memory, aligned for its dtype (see :mod:`.memory`).

    A flag is not enough: ``flags.writeable = True`` succeeds again on an
    array that owns its memory (or on a view of a writable base). An array
    over a ``bytes`` object cannot be made writable at all, so the value is
    copied once into one, ``offset`` bytes past a multiple of 64 (where it lay when
    it was computed: :class:`Placed`), unless it already lies over immutable
    memory (a value read from the disk cache does).
    """
    return array if is_frozen(array) else frozen_copy(array, offset)


class Placed(dict[str, np.ndarray]):
    """A value's arrays (as its port type encodes them) that remember where each lay,
    its address modulo 64 (``offsets``), for the process that receives them to freeze
    them at the same offsets (:func:`freeze_all`): a node there then sees the value laid
    out as where it was computed or read from the cache. Pickled with its offsets."""

    offsets: dict[str, int]

    @classmethod
    def of(cls, arrays: Arrays) -> Placed:
        placed = cls(arrays)
        placed.offsets = {name: alignment_offset(array) for name, array in arrays.items()}
        return placed


def freeze_all(arrays: Arrays) -> Arrays:
    """:func:`freeze` of each array, at the offsets :class:`Placed` arrays remember; those
    to copy share one buffer (one allocation for a table's columns instead of one each)."""
    offsets = getattr(arrays, "offsets", None) or {}
    if not offsets and len(arrays) > 1 and all(map(_WRITEABLE, arrays.values())):
        return dict(zip(arrays, frozen_copies(list(arrays.values())), strict=True))  # (fresh)
    thawed = [name for name, array in arrays.items() if not is_frozen(array)]
    if len(thawed) < 2:
        return {name: freeze(array, offsets.get(name, 0)) for name, array in arrays.items()}
    if not offsets and len(thawed) == len(arrays):  # a node's fresh value: all, as they lie
        return dict(zip(thawed, frozen_copies(list(arrays.values())), strict=True))
    made = frozen_copies([arrays[n] for n in thawed], [offsets.get(n, 0) for n in thawed])
    copies = dict(zip(thawed, made, strict=True))
    return {name: copies.get(name, array) for name, array in arrays.items()}


_WRITEABLE = attrgetter("flags.writeable")  # (a writable array is not frozen: no call more)


def is_frozen(array: np.ndarray) -> bool:
    """Whether ``array`` lies, aligned for its dtype and read-only, over immutable memory
    already."""
    if array.flags.writeable:  # (a node's fresh array: no walk to its root)
        return False
    root: object = array
    while isinstance(root, np.ndarray | memoryview):
        if isinstance(root, memoryview):
            if is_frozen_window(root):  # a node's own array, frozen where it lies
                return bool(array.flags.aligned)
            root = root.obj
        elif root.base is None:
            break
        else:
            root = root.base
    # (an array unpickled over bytes can be writable: it is copied)
    return isinstance(root, bytes) and bool(array.flags.aligned)


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
        policy of :mod:`graphvision.values.dtype_policy` (a ``uint8`` array becomes
        a ``float32`` image as a PNG file does). The default changes nothing.
        Raises :class:`PortValueError` naming ``source``.
        """
        return value

    @classmethod
    def admit(cls, value: Any, source: str) -> Any:
        """A value from outside, in this type's convention and checked:
        ``validate(coerce(value, source))``, which a port type may do in fewer passes
        over the data (an image already in the convention is checked once, not by the
        policy and again by :meth:`validate`). Raises what those two raise."""
        return cls.validate(cls.coerce(value, source))

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
            _save_npy(path, arrays["data"])
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
        for path in files:  # what each array declares, within the budget, before inflating
            check_array_file(path)
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
        shape, dtype = value.shape, value.dtype
        known = _SUMMARIES.get((cls, shape, dtype))
        if known is None:
            known = f"{cls._type_name} {'×'.join(map(str, shape))} {dtype_name(dtype)}"
            if len(_SUMMARIES) > 256:
                _SUMMARIES.clear()
            _SUMMARIES[(cls, shape, dtype)] = known
        return known


_SUMMARIES: dict[tuple[type[PortType], tuple[int, ...], np.dtype], str] = {}
""":meth:`ArrayPort.summary` by port type, shape and dtype, all it depends on (a run of one
graph summarises arrays of the same shapes each time)."""


_PLAIN: dict[tuple[type[PortType], type[PortType]], bool] = {}


def codes_as(kind: type[PortType], base: type[PortType]) -> bool:
    """Whether ``kind`` is a ``base`` that encodes and decodes its values as ``base`` does
    (its values are then what ``base`` takes them for). Worked out once per pair."""
    plain = _PLAIN.get((kind, base))
    if plain is None:
        plain = _PLAIN[(kind, base)] = (
            issubclass(kind, base)
            and kind.encode.__func__ is base.encode.__func__  # type: ignore[attr-defined]
            and kind.decode.__func__ is base.decode.__func__  # type: ignore[attr-defined]
        )
    return plain


def is_plain_array_port(kind: type[PortType]) -> bool:
    """Whether a value of ``kind`` is its one array as it is: an :class:`ArrayPort` that
    encodes and decodes it as ``ArrayPort`` does (it may be frozen in place, its size is its
    ``nbytes``)."""
    return codes_as(kind, ArrayPort)


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


class _Writes:
    """A file's ``write`` alone: ``np.save`` writes through it with Python's I/O, whose
    errors carry their cause, where it writes a real file with C's ``fwrite``, whose
    short count it reports as ``OSError('116352 requested and 39904 written')``."""

    def __init__(self, handle: BinaryIO) -> None:
        self.write = handle.write


def _save_npy(path: Path, array: np.ndarray) -> None:
    """``np.save(path, array)``, or the error that stopped it, naming ``path`` and its cause
    (``No space left on device``, ``File too large``): a write C cut short is made again
    through Python's I/O, which says why (or, the cause gone, writes the file whole).

    Raises
    ------
    OSError
        With ``errno``, ``strerror`` and ``filename`` (``path``) set.
    """
    try:
        np.save(path, array, allow_pickle=False)
    except OSError as error:
        if error.errno is not None:
            raise OSError(error.errno, error.strerror, str(path)) from None
        try:
            with path.open("wb") as handle:
                np.lib.format.write_array(_Writes(handle), array, allow_pickle=False)
        except OSError as again:
            raise OSError(again.errno, again.strerror or str(again), str(path)) from None
