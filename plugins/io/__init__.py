"""Images in: named sample images and image files, as graph inputs and as nodes.

Sources (values of graph inputs):

* ``sample:NAME`` — an image shipped with scikit-image (no download);
* a path — PNG, JPEG, TIFF, BMP, ... as imageio reads them (PNG, JPEG, BMP
  and WebP opened once, with Pillow: :mod:`._image_file`), or ``.npy``.

The sources return arrays as stored; the graph input's port type applies the
one dtype policy (:mod:`graphvision.values.dtype_policy`): an ``Image`` input gets
``float32`` in [0, 1], gray ``H×W`` or RGB ``H×W×3``, a ``BinaryImage`` input
a bool mask. :func:`read_file` and :func:`read_sample` apply the image policy
for scripts.
"""

from ._read import SAMPLES, read_array, read_file, read_sample, sample, sample_array

__all__ = ["SAMPLES", "read_array", "read_file", "read_sample", "sample", "sample_array"]
