"""An executor shut down in the background while the batch that made it finishes."""

from __future__ import annotations

import threading
from typing import Any

__all__ = ["Closing"]


class Closing(threading.Thread):
    """An executor shut down from a thread (a forked worker's exit took 20-50 ms, a Dask
    cluster's close longer), while the batch writes its summary: :meth:`wait` joins it and
    raises what the shutdown raised."""

    def __init__(self, pool: Any) -> None:
        super().__init__(name="graphvision-pool-shutdown")
        self.pool = pool
        self.error: BaseException | None = None
        self.start()

    def run(self) -> None:
        try:
            self.pool.shutdown()
        except BaseException as error:  # raised in the batch's thread, by wait()
            self.error = error

    def wait(self) -> None:
        self.join()
        if self.error is not None:
            raise self.error
