"""A bounded, thread-safe memo of the most recently used values by key (plans by content,
optimised routines by content): a long run does not keep every value alive."""

from __future__ import annotations

import threading
from collections import OrderedDict
from collections.abc import Callable, Hashable
from typing import Generic, TypeVar

_K = TypeVar("_K", bound=Hashable)
_V = TypeVar("_V")


class Recent(Generic[_K, _V]):
    """The last `size` values kept, most recent last. A value kept under a key already there is
    the one already there, so two threads that derived the same thing share one."""

    def __init__(self, size: int) -> None:
        self.size = size
        self._items: OrderedDict[_K, _V] = OrderedDict()
        self._lock = threading.Lock()

    def get(self, key: _K) -> _V | None:
        """The value under `key` (now the most recent), or None."""
        with self._lock:
            found = self._items.get(key)
            if found is not None:
                self._items.move_to_end(key)
            return found

    def keep(self, key: _K, value: _V) -> _V:
        """`value` kept under `key` (the one already there wins); the least recent dropped
        beyond `size`."""
        with self._lock:
            value = self._items.setdefault(key, value)
            self._items.move_to_end(key)
            while len(self._items) > self.size:
                self._items.popitem(last=False)
            return value

    def get_or_make(self, key: _K, make: Callable[[], _V]) -> _V:
        """The value under `key`, else `make()` kept under it (made outside the lock: two
        threads may both make it, and share the one kept first)."""
        found = self.get(key)
        return found if found is not None else self.keep(key, make())
