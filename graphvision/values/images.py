"""Image port types: float responses, images (gray and colour), masks, labels, kernels."""

from __future__ import annotations

from pathlib import Path
from typing import Any, ClassVar

import numpy as np

from graphvision.errors import PortValueError
from graphvision.values.dtype_policy import in_unit_range, to_float_image, to_labels, to_mask
from graphvision.values.ports import ArrayPort, _fail

PNG_LEVEL = 1
"""zlib level of written image and mask PNGs: the fastest, 3-4× less CPU than Pillow's
default 6 on the coins overlay, and no larger on photographs (149 against 154 KB); the
pixels are the same at every level."""

__all__ = [
    "BinaryImagePort",
    "ColorImagePort",
    "FloatImagePort",
    "GrayImagePort",
    "ImagePort",
    "KernelPort",
    "LabelImagePort",
]


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
    def admit(cls, value: Any, source: str) -> Any:
        """A ``float32`` array is checked once, by :meth:`validate`: the dtype policy
        would return it as it is after checking its values the same way. When that check
        fails, the policy's own message (naming ``source``) is the one raised."""
        if type(value) is np.ndarray and value.dtype == np.float32:  # not a masked array
            try:
                return cls.validate(value)
            except PortValueError:
                pass
        return cls.validate(cls.coerce(value, source))

    @classmethod
    def validate(cls, value: Any) -> np.ndarray:
        value = super().validate(value)
        if value.ndim == 3 and value.shape[2] != 3:
            raise _fail(cls, cls.expected, value)
        # Each end apart: their sum overflows float32 for finite values beyond 1.7e38.
        if cls is FloatImagePort and not (np.isfinite(value.min()) and np.isfinite(value.max())):
            raise PortValueError(f"expected {cls.type_name()} with finite values, got NaN or inf")
        return value

    @classmethod
    def preview(cls, value: np.ndarray) -> np.ndarray | None:
        from graphvision.values.pictures import stretch

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
        if in_unit_range(value):  # one pass; else the minimum and maximum say what is wrong
            return value
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
        iio.imwrite(path, np.round(value * 255.0).astype(np.uint8), compress_level=PNG_LEVEL)
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
        iio.imwrite(path, value.astype(np.uint8) * 255, compress_level=PNG_LEVEL)
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
        from graphvision.values.pictures import label_colours

        return label_colours(value)


class KernelPort(ArrayPort):
    """A filter kernel: ``float64`` 2-D array, centred at ``(rows // 2, cols // 2)``."""

    ndims = (2,)
    dtypes = (np.float64,)
    expected = "float64 2-D array"

    @classmethod
    def preview(cls, value: np.ndarray) -> np.ndarray | None:
        from graphvision.values.pictures import stretch

        return stretch(value)
