"""Images in: named sample images and image files, as graph inputs and as nodes.

Sources (values of graph inputs):

* ``sample:NAME`` — an image shipped with scikit-image (no download);
* a path — PNG, JPEG, TIFF, BMP, ... read with imageio, or ``.npy``.

Every image goes through one dtype policy (:func:`to_float_image`): ``float32``
in [0, 1], gray ``H×W`` or RGB ``H×W×3``.
"""

from ._read import SAMPLES, read_file, read_sample, sample

__all__ = ["SAMPLES", "read_file", "read_sample", "sample"]
