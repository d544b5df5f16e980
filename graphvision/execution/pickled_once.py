"""A value sent with many tasks of a process pool, pickled once in the client and
unpickled once in each worker.

A batch on processes sends its job (the graph, the shared values, the options: 4.8 kB
for coins.yaml) with every task. ``ProcessPoolExecutor`` pickles each task's arguments
afresh, 0.28 ms of the client's CPU for that job, and the worker unpickles it afresh,
0.16 ms, per task. :class:`PickledOnce` keeps its pickled bytes, which the pool then copies as
they are, and a worker keeps the value it last unpickled by its token.
"""

from __future__ import annotations

import pickle
import threading
import uuid
from typing import Any

__all__ = ["PickledOnce"]

_LOCK = threading.Lock()
_LAST: dict[str, Any] = {}  # in a worker: the last value unpickled, by its token


class PickledOnce:
    """``value``, pickled once (its bytes kept) and unpickled as ``value`` itself: a task's
    function receives the value, never this wrapper."""

    def __init__(self, value: Any) -> None:
        self.value = value
        self._token = uuid.uuid4().hex
        self._pickled: bytes | None = None

    def __reduce__(self) -> tuple[Any, tuple[str, bytes]]:
        if self._pickled is None:
            self._pickled = pickle.dumps(self.value, protocol=pickle.HIGHEST_PROTOCOL)
        return _unpickled, (self._token, self._pickled)


def _unpickled(token: str, pickled: bytes) -> Any:
    """The value of ``token``: unpickled from ``pickled`` the first time this process sees
    the token, then the same object (only the last token's value is kept)."""
    with _LOCK:
        if token not in _LAST:
            _LAST.clear()
            _LAST[token] = pickle.loads(pickled)
        return _LAST[token]
