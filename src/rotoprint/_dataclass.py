"""``dataclass`` for the classes on the start-up path of a short job: the same classes as
:func:`dataclasses.dataclass` makes, made without compiling code.

:func:`dataclasses.dataclass` writes each generated method (``__init__``, ``__repr__``,
``__eq__``, ``__hash__``, and a frozen class's ``__setattr__`` and ``__delattr__``) as source
text and ``exec``-s it: about 0.3 ms per plain class and 0.55 ms per frozen one on the
project's 2-core VM (Python 3.11), which for the 29 classes that ``rotoprint dlp`` imports was
about 15 ms of a 10-layer job's 0.2 s. This module lets :mod:`dataclasses` do the rest (the
fields, defaults as class attributes, ``__match_args__``, ``__dataclass_fields__``, so that
:func:`dataclasses.fields`, :func:`~dataclasses.replace`, :func:`~dataclasses.asdict` and
:func:`~dataclasses.is_dataclass` work as ever) and gives the class methods that read a table of
its fields instead: the same behaviour (the same values set in the same order, the same
``repr``, equality, hash and :class:`dataclasses.FrozenInstanceError`), a few microseconds more
per instance.

Only ``frozen`` and ``eq`` are taken; a class this does not cover as :mod:`dataclasses` would
(a method of its own that a dataclass would keep or refuse, a dataclass base, ``InitVar`` or
``ClassVar`` pseudo-fields, keyword-only fields, no docstring) is handed to
:func:`dataclasses.dataclass` whole. ``tests/test_dataclass.py`` holds the two to the same
behaviour.
"""

from __future__ import annotations

import copy
import dataclasses
import reprlib
from operator import attrgetter

__all__ = ["dataclass", "field"]

field = dataclasses.field
_MISSING = dataclasses.MISSING
_std_dataclass = dataclasses.dataclass
_OWN = ("__init__", "__repr__", "__eq__", "__hash__", "__setattr__", "__delattr__")


def dataclass(cls=None, /, *, frozen: bool = False, eq: bool = True):
    """As :func:`dataclasses.dataclass` with ``frozen`` and ``eq`` (every other option at its
    default); usable bare (``@dataclass``) or called (``@dataclass(frozen=True)``).

    Returns
    -------
    type
        ``cls`` itself, made a dataclass.
    """

    def wrap(c: type) -> type:
        return _process(c, frozen, eq)

    return wrap if cls is None else wrap(cls)


def _process(cls: type, frozen: bool, eq: bool) -> type:
    if not _covered(cls):
        return _std_dataclass(cls, frozen=frozen, eq=eq)
    _std_dataclass(cls, init=False, repr=False, eq=False)  # fields, defaults, __match_args__
    flds = dataclasses.fields(cls)
    _check_order(flds)
    qual = cls.__qualname__
    methods = {"__init__": _init(cls, flds), "__repr__": _repr(flds)}
    if eq:
        methods["__eq__"] = _eq([f.name for f in flds if f.compare])
        if frozen:
            methods["__hash__"] = _hash([f.name for f in flds if (f.compare if f.hash is None else f.hash)])
    if frozen:
        methods["__setattr__"], methods["__delattr__"] = _frozen(cls, tuple(f.name for f in flds))
    for name, fn in methods.items():
        fn.__name__ = name
        fn.__qualname__ = f"{qual}.{name}"
        setattr(cls, name, fn)
    if eq and not frozen:
        cls.__hash__ = None  # as a dataclass: equal by value, so not hashable
    params = copy.copy(cls.__dataclass_params__)
    params.init, params.repr, params.eq, params.frozen = True, True, eq, frozen
    cls.__dataclass_params__ = params
    return cls


def _covered(cls: type) -> bool:
    """Whether this module makes ``cls`` as :func:`dataclasses.dataclass` would: no method of
    its own among those made, a docstring, no dataclass base, no ``ClassVar`` / ``InitVar`` /
    ``KW_ONLY`` annotation, no keyword-only field."""
    own = cls.__dict__
    if any(name in own for name in _OWN) or "__slots__" in own or not own.get("__doc__"):
        return False
    if any(hasattr(b, "__dataclass_fields__") for b in cls.__mro__[1:]):
        return False
    for name, ann in own.get("__annotations__", {}).items():
        text = ann if isinstance(ann, str) else repr(ann)
        if "ClassVar" in text or "InitVar" in text or "KW_ONLY" in text:
            return False
        value = own.get(name)
        if isinstance(value, dataclasses.Field) and value.kw_only is True:
            return False
    return True


def _check_order(flds) -> None:
    """A field without a default after one with: refused, as :func:`dataclasses.dataclass` does."""
    seen_default = False
    for f in flds:
        if not f.init:
            continue
        if f.default is _MISSING and f.default_factory is _MISSING:
            if seen_default:
                raise TypeError(f"non-default argument {f.name!r} follows default argument")
        else:
            seen_default = True


def _init(cls: type, flds):
    qual = cls.__qualname__
    init_names = tuple(f.name for f in flds if f.init)
    n_pos = len(init_names)
    accepted = frozenset(init_names)
    # per field, in order: (name, index among the arguments or -1, default, factory)
    plan = []
    k = 0
    for f in flds:
        if f.init:
            plan.append((f.name, k, f.default, f.default_factory))
            k += 1
        elif f.default_factory is not _MISSING:
            plan.append((f.name, -1, _MISSING, f.default_factory))
        # (init=False with a plain default: the class attribute, as a dataclass leaves it)
    plan = tuple(plan)
    post_init = getattr(cls, "__post_init__", None) is not None
    n_required = sum(1 for f in flds if f.init and f.default is _MISSING and f.default_factory is _MISSING)
    takes = f"{n_pos + 1} positional argument{'s' if n_pos else ''}" if n_required == n_pos else \
        f"from {n_required + 1} to {n_pos + 1} positional arguments"

    def __init__(self, *args, **kwargs):
        n = len(args)
        if n > n_pos:
            raise TypeError(f"{qual}.__init__() takes {takes} but {n + 1} were given")
        if kwargs:
            for key in kwargs:
                if key not in accepted:
                    raise TypeError(f"{qual}.__init__() got an unexpected keyword argument {key!r}")
            for name in init_names[:n]:
                if name in kwargs:
                    raise TypeError(f"{qual}.__init__() got multiple values for argument {name!r}")
        d = self.__dict__
        missing = None
        for name, i, default, factory in plan:
            if 0 <= i < n:
                d[name] = args[i]
            elif i >= 0 and name in kwargs:
                d[name] = kwargs[name]
            elif default is not _MISSING:
                d[name] = default
            elif factory is not _MISSING:
                d[name] = factory()
            else:
                missing = [*(missing or ()), name]
        if missing:
            raise TypeError(f"{qual}.__init__() missing {len(missing)} required positional "
                            f"argument{'s' if len(missing) > 1 else ''}: {_names(missing)}")
        if post_init:
            self.__post_init__()

    return __init__


def _names(names: list[str]) -> str:
    """``'a'``, ``'a' and 'b'``, ``'a', 'b', and 'c'``: as Python names missing arguments."""
    q = [repr(n) for n in names]
    if len(q) == 1:
        return q[0]
    if len(q) == 2:
        return f"{q[0]} and {q[1]}"
    return ", ".join(q[:-1]) + f", and {q[-1]}"


def _repr(flds):
    names = tuple(f.name for f in flds if f.repr)

    @reprlib.recursive_repr()
    def __repr__(self):
        return f"{self.__class__.__qualname__}(" + ", ".join(f"{n}={getattr(self, n)!r}" for n in names) + ")"

    return __repr__


def _values(names):
    """``obj -> tuple`` of the attributes ``names``."""
    if len(names) > 1:
        return attrgetter(*names)
    if names:
        get = attrgetter(names[0])
        return lambda obj: (get(obj),)
    return lambda obj: ()


def _eq(names):
    values = _values(tuple(names))

    def __eq__(self, other):
        if other.__class__ is self.__class__:
            return values(self) == values(other)
        return NotImplemented

    return __eq__


def _hash(names):
    values = _values(tuple(names))

    def __hash__(self):
        return hash(values(self))

    return __hash__


def _frozen(cls: type, names: tuple[str, ...]):
    def __setattr__(self, name, value):
        if type(self) is cls or name in names:
            raise dataclasses.FrozenInstanceError(f"cannot assign to field {name!r}")
        super(cls, self).__setattr__(name, value)

    def __delattr__(self, name):
        if type(self) is cls or name in names:
            raise dataclasses.FrozenInstanceError(f"cannot delete field {name!r}")
        super(cls, self).__delattr__(name)

    return __setattr__, __delattr__
