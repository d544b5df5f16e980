"""A batch's job pickled once in the client and unpickled once per worker
(graphvision.execution.pickled_once)."""

from __future__ import annotations

import os
import pickle

from graphvision.execution.executors import make_executor
from graphvision.execution.pickled_once import PickledOnce


class _Counted:
    """Counts how often it is pickled (in this process) and carries a payload."""

    pickled = 0

    def __init__(self, payload: list[int]) -> None:
        self.payload = payload

    def __reduce__(self):
        type(self).pickled += 1
        return _Counted, (self.payload,)


def test_the_value_is_pickled_once_however_often_it_is_sent():
    _Counted.pickled = 0
    sent = PickledOnce(_Counted([1, 2, 3]))
    first, second = pickle.dumps(sent), pickle.dumps((sent, "another task"))
    assert _Counted.pickled == 1
    value = pickle.loads(first)
    assert isinstance(value, _Counted) and value.payload == [1, 2, 3]  # the value, unwrapped
    assert pickle.loads(second)[0] is value  # the same token: the object unpickled before
    other = pickle.loads(pickle.dumps(PickledOnce(_Counted([4]))))
    assert other.payload == [4]  # another token: its own value


def _identity(value: object) -> tuple[int, int, object]:
    return os.getpid(), id(value), value


def test_a_worker_unpickles_it_once_for_all_its_tasks():
    pool = make_executor("processes", 1)
    try:
        sent = pool.sent_once({"graph": "coins", "seeds": list(range(100))})  # type: ignore[attr-defined]
        results = [pool.submit(_identity, sent).result(timeout=120) for _ in range(3)]
    finally:
        pool.shutdown()
    assert len({pid for pid, _, _ in results}) == 1
    assert len({ident for _, ident, _ in results}) == 1  # one object for the three tasks
    assert results[0][2] == {"graph": "coins", "seeds": list(range(100))}
