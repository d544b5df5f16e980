"""Connected components and region descriptors (seed: "Labelling regions",
"Region descriptors"): two-pass labelling with an equivalence table, a table
of descriptors per region, filtering by descriptor ranges, and drawings.
"""

from ._draw import colorize, overlay
from ._label import MAX_LABEL, check_label_count, label, label_components, relabel
from ._measure import describe, filter_regions

__all__ = [
    "MAX_LABEL",
    "check_label_count",
    "colorize",
    "describe",
    "filter_regions",
    "label",
    "label_components",
    "overlay",
    "relabel",
]
