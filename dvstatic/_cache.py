"""Explicit, bounded, keyed and clearable caches.

Two kinds, both registered by name so that :func:`clear_caches` empties them all and
:func:`cache_info` reports their sizes:

* :class:`PerObject`: a value computed from one object (a mesh, a model) and kept as
  long as that object lives (weak keys): geometry, sparsity pattern, dof ordering,
  factorisations. Bounded by the objects the user keeps.
* :class:`Bounded`: a value keyed by plain data (numbers, strings), kept in
  least-recently-used order up to ``maxsize`` entries: calibration samples and results.
"""

from __future__ import annotations

import threading
import weakref
from collections import OrderedDict
from collections.abc import Callable, Hashable
from typing import Any

__all__ = ["PerObject", "Bounded", "clear_caches", "cache_info"]

_REGISTRY: dict[str, PerObject | Bounded] = {}


def _register(cache) -> None:
    if cache.name in _REGISTRY:
        raise ValueError(f"a cache named {cache.name!r} exists already")
    _REGISTRY[cache.name] = cache


class PerObject:
    """Values computed from an object, kept while the object lives.

    Parameters
    ----------
    name : str
        Registry name (shown by :func:`cache_info`).
    compute : callable(obj) -> value
    """

    def __init__(self, name: str, compute: Callable[[Any], Any]):
        self.name = name
        self._compute = compute
        self._data: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
        self._lock = threading.Lock()
        _register(self)

    def __call__(self, obj) -> Any:
        """The cached value for ``obj``, computed on first use."""
        value = self._data.get(obj)
        if value is None:
            value = self._compute(obj)
            with self._lock:
                self._data[obj] = value
        return value

    def __contains__(self, obj) -> bool:
        return obj in self._data

    def get(self, obj, default=None):
        return self._data.get(obj, default)

    def put(self, obj, value) -> None:
        with self._lock:
            self._data[obj] = value

    def pop(self, obj, default=None):
        with self._lock:
            return self._data.pop(obj, default)

    def __len__(self) -> int:
        return len(self._data)

    def clear(self) -> None:
        with self._lock:
            self._data.clear()


class Bounded:
    """A least-recently-used mapping of at most ``maxsize`` entries.

    Parameters
    ----------
    name : str
    maxsize : int
    """

    def __init__(self, name: str, maxsize: int):
        if maxsize < 1:
            raise ValueError(f"maxsize must be >= 1, got {maxsize}")
        self.name = name
        self.maxsize = int(maxsize)
        self._data: OrderedDict[Hashable, Any] = OrderedDict()
        self._lock = threading.Lock()
        _register(self)

    def get(self, key: Hashable, default=None):
        with self._lock:
            if key not in self._data:
                return default
            self._data.move_to_end(key)
            return self._data[key]

    def put(self, key: Hashable, value) -> None:
        with self._lock:
            self._data[key] = value
            self._data.move_to_end(key)
            while len(self._data) > self.maxsize:
                self._data.popitem(last=False)

    def __contains__(self, key: Hashable) -> bool:
        return key in self._data

    def __len__(self) -> int:
        return len(self._data)

    def clear(self) -> None:
        with self._lock:
            self._data.clear()


def clear_caches() -> None:
    """Empty every dvstatic cache (geometry, patterns, orderings, calibrations,
    factorisations). Models keep their own assembled stiffness; drop the model to
    free it."""
    for cache in _REGISTRY.values():
        cache.clear()


def cache_info() -> dict[str, int]:
    """Number of entries in every registered cache, by name."""
    return {name: len(cache) for name, cache in _REGISTRY.items()}
