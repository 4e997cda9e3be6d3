"""A base for the typed rows of results files: frozen dataclasses that write and read the JSON layout.

A row class is a frozen dataclass deriving from :class:`Record`; its fields, in order, are the keys of its JSON
object. :meth:`Record.to_dict` gives that object (nested records as objects, tuples as arrays, a field named in
``_OMIT_NONE`` left out where it is None: keys that only some files hold); :meth:`Record.from_dict` reads it back
(nested record classes named in ``_NESTED``: ``{"field": Cls}`` for an object, ``{"field": (tuple, Cls)}`` for an
array of them, ``{"field": (dict, Cls)}`` for an object of them by name), refusing a key it does not know (the
provenance stamp of a results file, :data:`twin.provenance.PROVENANCE_KEY`, aside) rather than losing it. A JSON
key that is no Python name is mapped in ``_KEYS`` (``{"lam": "lambda"}``).

Read access by key (``row["name"]``, ``"name" in row``, ``row.get``, ``row.items()``) gives the dict's values, as
the plain dicts these rows replace did.
"""

from __future__ import annotations

import dataclasses
from typing import Any, ClassVar, Iterator, Mapping

__all__ = ["ByKey", "Record"]

_STAMP = "provenance"  # twin.provenance.PROVENANCE_KEY (not imported: this module imports nothing of the package)


def _plain(v: Any) -> Any:
    if isinstance(v, Record):
        return v.to_dict()
    if isinstance(v, (tuple, list)):
        return [_plain(x) for x in v]
    if isinstance(v, Mapping):
        return {k: _plain(x) for k, x in v.items()}
    return v


def _frozen(v: Any) -> Any:
    """Lists as tuples, at every depth (what a frozen row holds); mappings and scalars as they are."""
    if isinstance(v, (list, tuple)):
        return tuple(_frozen(x) for x in v)
    return v


class ByKey:
    """Read access by key to the dict a ``to_dict()`` gives: what the plain dicts typed values replace allowed."""

    def to_dict(self) -> dict[str, Any]:  # pragma: no cover - each class defines it
        raise NotImplementedError

    def __getitem__(self, key: str) -> Any:
        return self.to_dict()[key]

    def __contains__(self, key: object) -> bool:
        return key in self.to_dict()

    def get(self, key: str, default: Any = None) -> Any:
        return self.to_dict().get(key, default)

    def keys(self) -> Iterator[str]:
        return iter(self.to_dict().keys())

    def items(self):
        return self.to_dict().items()


class Record(ByKey):
    """Mixin of a frozen dataclass row (module docstring)."""

    _OMIT_NONE: ClassVar[tuple[str, ...]] = ()
    _NESTED: ClassVar[dict[str, Any]] = {}
    _KEYS: ClassVar[dict[str, str]] = {}

    def __post_init__(self) -> None:
        """Nested plain values (dicts, lists) as the record classes and tuples the fields hold."""
        for f in dataclasses.fields(self):  # type: ignore[arg-type]
            v = getattr(self, f.name)
            spec = self._NESTED.get(f.name)
            if spec is None:
                new = _frozen(v) if isinstance(v, list) else v
            elif isinstance(spec, tuple) and spec[0] is tuple:
                new = None if v is None else tuple(x if isinstance(x, spec[1]) else spec[1].from_dict(x) for x in v)
            elif isinstance(spec, tuple) and spec[0] is dict:
                new = None if v is None else {k: x if isinstance(x, spec[1]) else spec[1].from_dict(x)
                                              for k, x in v.items()}
            else:
                new = v if v is None or isinstance(v, (spec, str)) else spec.from_dict(v)
            if new is not v:
                object.__setattr__(self, f.name, new)

    def to_dict(self) -> dict[str, Any]:
        """The JSON object: fields in order under their keys; a field of ``_OMIT_NONE`` left out where None."""
        out: dict[str, Any] = {}
        for f in dataclasses.fields(self):  # type: ignore[arg-type]
            v = getattr(self, f.name)
            if v is None and f.name in self._OMIT_NONE:
                continue
            out[self._KEYS.get(f.name, f.name)] = _plain(v)
        return out

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]):
        """The row of a JSON object as :meth:`to_dict` writes it (a results file's stamp ignored); ValueError
        naming a key the row does not know."""
        keys = {cls._KEYS.get(f.name, f.name): f for f in dataclasses.fields(cls)}  # type: ignore[arg-type]
        other = [k for k in d if k not in keys and k != _STAMP]
        if other:
            raise ValueError(f"{cls.__name__}: keys {', '.join(map(repr, other))} unknown; "
                             f"allowed: {', '.join(keys)}")
        missing = [k for k, f in keys.items() if k not in d and f.name not in cls._OMIT_NONE
                   and f.default is dataclasses.MISSING]
        if missing:
            raise ValueError(f"{cls.__name__}: keys {', '.join(map(repr, missing))} missing")
        return cls(**{f.name: d[k] for k, f in keys.items() if k in d})  # type: ignore[call-arg]
