"""A picture of a network's right and wrong predictions."""

from __future__ import annotations

from typing import Annotated

from pydantic import Field

from graphvision import ColorImage, node

from ..recognition._draw import prediction_mosaic
from ..recognition._types import Samples
from ._network import Network
from ._train import predicted_labels

__all__ = ["draw_predictions"]


@node("cnn.draw_predictions", version=1)
def draw_predictions(
    network: Network, samples: Samples, *, count: Annotated[int, Field(ge=1, le=64)] = 8
) -> ColorImage:
    """A sample of the network's right and wrong predictions on ``samples``, as a picture.

    The top row holds the first ``count`` samples the network classifies as
    their own label, framed green; the bottom row the first ``count`` it gets
    wrong, framed red (as ``recognition.draw_predictions``).

    Parameters
    ----------
    network : Network
        A trained network.
    samples : Samples
        Images of the shape the network was trained on, with their labels.
    count : int
        Samples shown per row.
    """
    predicted, _ = predicted_labels(network, samples)
    return prediction_mosaic(samples.images, samples.labels, predicted, count)
