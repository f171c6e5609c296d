"""rotoprint._dataclass makes the same classes as dataclasses.dataclass (without exec): the
same fields, values, repr, equality, hash, frozen errors, replace / asdict, pickling, and
errors for bad arguments."""

from __future__ import annotations

import dataclasses
import pickle
import sys
from functools import cached_property
from typing import ClassVar

import numpy as np
import pytest

from rotoprint import _dataclass
from rotoprint._dataclass import dataclass, field


def _pair(frozen: bool, eq: bool, body: dict, bases: tuple = ()):
    """The same class body made by dataclasses and by ours."""
    made = []
    for deco in (dataclasses.dataclass, dataclass):
        ns = dict(body)
        ns["__annotations__"] = dict(body["__annotations__"])
        ns["__module__"] = __name__
        ns["__qualname__"] = "Rec"
        cls = type("Rec", bases, ns)
        made.append(deco(frozen=frozen, eq=eq)(cls))
    return made


def _body():
    return {
        "__doc__": "A record.",
        "__annotations__": {"a": "int", "b": "str", "c": "list", "d": "float", "e": "dict"},
        "b": "bee",
        "c": field(default_factory=list),
        "d": field(default=1.5, compare=False, repr=False),
        "e": field(default_factory=dict, init=False),
    }


def _mine(cls) -> bool:
    return cls.__init__.__code__.co_filename == _dataclass.__file__


@pytest.mark.parametrize("frozen", [False, True])
@pytest.mark.parametrize("eq", [False, True])
def test_same_behaviour_as_dataclasses(frozen, eq):
    std, ours = _pair(frozen, eq, _body())
    assert _mine(ours) and not _mine(std)
    assert dataclasses.is_dataclass(ours)
    assert [(f.name, f.type, f.default, f.default_factory, f.init, f.repr, f.compare) for f in dataclasses.fields(std)] == \
           [(f.name, f.type, f.default, f.default_factory, f.init, f.repr, f.compare) for f in dataclasses.fields(ours)]
    assert ours.__match_args__ == std.__match_args__
    for name in ("init", "repr", "eq", "frozen", "order", "unsafe_hash"):
        assert getattr(ours.__dataclass_params__, name) == getattr(std.__dataclass_params__, name), name
    for args, kw in [((1,), {}), ((1, "x"), {"c": [2], "d": 3.0}), ((), {"a": 4, "d": 9.0}), ((5, "y", [1], 2.0), {})]:
        s, o = std(*args, **kw), ours(*args, **kw)
        assert list(vars(s).items()) == list(vars(o).items())  # the same values in the same order
        assert repr(s).replace("Rec(", "") == repr(o).replace("Rec(", "")
        assert (s == std(*args, **kw)) == (o == ours(*args, **kw))
        assert (o == dataclasses.replace(o, d=-1.0)) == eq  # d is not compared
        assert o != ours(99)
        assert o.__eq__(s) is NotImplemented or not eq  # another class: not equal
        assert (std.__hash__ is None) == (ours.__hash__ is None)
        if std.__hash__ is not None:
            def h(x):
                try:
                    return hash(x)
                except TypeError as exc:  # a list field
                    return str(exc)

            if eq and frozen:  # by value: the same as dataclasses' hash
                assert h(o) == h(s) and h(o) == h(ours(*args, **kw))
            else:  # by identity
                assert h(o) == object.__hash__(o)
        if frozen:
            for obj in (s, o):
                with pytest.raises(dataclasses.FrozenInstanceError, match="cannot assign to field 'a'"):
                    obj.a = 2
                with pytest.raises(dataclasses.FrozenInstanceError, match="cannot delete field 'b'"):
                    del obj.b
                with pytest.raises(dataclasses.FrozenInstanceError, match="cannot assign to field 'zz'"):
                    obj.zz = 1
        else:
            o.a = 7
            assert o.a == 7
        r = dataclasses.replace(o, a=11)
        assert r.a == 11 and r.b == o.b and type(r) is ours
        assert dataclasses.asdict(o) == {k: getattr(o, k) for k in "abcde"}
    assert ours(1).c is not ours(1).c  # a fresh default each time


def test_post_init_plain_base_and_cached_property():
    class Base:
        @property
        def double(self):
            return 2 * self.x

    calls = []

    @dataclass(frozen=True, eq=False)
    class P(Base):
        """A part."""

        x: int
        arr: np.ndarray | None = None

        def __post_init__(self):
            calls.append(self.x)
            if self.x < 0:
                raise ValueError("negative")

        @cached_property
        def square(self):
            return self.x * self.x

    p = P(3)
    assert calls == [3] and p.double == 6 and p.square == 9 and p.square == 9
    assert p != P(3) and p == p and hash(p) == object.__hash__(p)
    object.__setattr__(p, "_cache", 1)  # as the code does for lazily built parts
    with pytest.raises(ValueError, match="negative"):
        P(-1)


def test_pickled_as_to_a_worker():
    from rotoprint.pipeline.producer import RunOptions
    from rotoprint.pipeline.tasks import MaskLayer
    from rotoprint.ranges import Range

    for obj in (MaskLayer({"mode": "coverage"}, 3), RunOptions(workers=2, inputs=("a",)), Range(0, 1, "mm", lo_open=True)):
        back = pickle.loads(pickle.dumps(obj))
        assert back == obj and type(back) is type(obj) and repr(back) == repr(obj)
        assert isinstance(obj, MaskLayer) or hash(back) == hash(obj)  # (MaskLayer: a dict field, unhashable)


def test_subclass_by_a_real_dataclass():
    @dataclass(frozen=True)
    class A:
        """A."""

        x: int
        y: int = 2

    @dataclasses.dataclass(frozen=True)
    class B(A):
        z: int = 3

    b = B(1, z=5)
    assert (b.x, b.y, b.z) == (1, 2, 5) and b == B(1, 2, 5) and hash(b) == hash(B(1, 2, 5))

    @dataclass(frozen=True)  # a dataclass base: handed to dataclasses whole
    class C(A):
        """C."""

        w: int = 0

    assert not _mine(C) and C(1, 2, 3).w == 3


@pytest.mark.parametrize("call, message", [
    (lambda R: R(), r"missing 1 required positional argument: 'a'"),
    (lambda R: R(1, "b", [], 1.0, 2), r"takes from 2 to 5 positional arguments but 6 were given"),
    (lambda R: R(1, a=2), r"got multiple values for argument 'a'"),
    (lambda R: R(1, q=2), r"got an unexpected keyword argument 'q'"),
    (lambda R: R(1, e={}), r"got an unexpected keyword argument 'e'"),  # init=False
])
def test_bad_arguments_are_type_errors(call, message):
    std, ours = _pair(True, True, _body())
    for cls in (std, ours):
        with pytest.raises(TypeError, match=message):
            call(cls)


def test_missing_several():
    @dataclass
    class T:
        """T."""

        a: int
        b: int
        c: int

    with pytest.raises(TypeError, match=r"missing 2 required positional arguments: 'b' and 'c'"):
        T(1)
    with pytest.raises(TypeError, match=r"missing 3 required positional arguments: 'a', 'b', and 'c'"):
        T()
    with pytest.raises(TypeError, match=r"T.__init__\(\) takes 4 positional arguments but 5 were given"):
        T(1, 2, 3, 4)


def test_class_errors_as_dataclasses():
    with pytest.raises(TypeError, match="non-default argument 'b' follows default argument"):
        @dataclass
        class Bad:
            """Bad."""

            a: int = 1
            b: int

    with pytest.raises(ValueError, match="mutable default"):
        @dataclass
        class Mutable:
            """Mutable."""

            a: list = []  # noqa: RUF012


def test_not_covered_goes_to_dataclasses():
    @dataclass(frozen=True)
    class Own:
        """Has its own repr."""

        a: int

        def __repr__(self):
            return "own"

    @dataclass
    class Var:
        """With a ClassVar."""

        a: int
        k: ClassVar[int] = 3

    @dataclass
    class NoDoc:
        a: int

    for cls in (Own, Var, NoDoc):
        assert not _mine(cls)
    assert repr(Own(1)) == "own" and Var(1).k == 3 and [f.name for f in dataclasses.fields(Var)] == ["a"]


#: The modules the fast ``dlp`` entry imports that define dataclasses.
DLP_PATH_MODULES = (
    "rotoprint.ranges", "rotoprint.cli._base", "rotoprint._plain_device", "rotoprint.io.formats._common",
    "rotoprint.io.archives", "rotoprint.pipeline.producer", "rotoprint.pipeline.journal", "rotoprint.pipeline.tasks",
    "rotoprint.masks.exposure", "rotoprint.masks.pipeline", "rotoprint._holes", "rotoprint.mesh",
    "rotoprint.slicing._sections", "rotoprint.slicing._gaps", "rotoprint.slicing.grid", "rotoprint.slicing.layers",
    "rotoprint.slicing.options", "rotoprint.slicing.fibres",
)


def test_the_dlp_path_classes_are_made_here():
    """Every dataclass of the modules the fast ``dlp`` entry imports is made by
    rotoprint._dataclass (its point): 29 of them."""
    import importlib

    found = []
    for name in DLP_PATH_MODULES:
        mod = importlib.import_module(name)
        found += [v for v in vars(mod).values() if isinstance(v, type) and v.__module__ == name and dataclasses.is_dataclass(v)]
    assert len(found) == 29
    assert [f"{c.__module__}.{c.__qualname__}" for c in found if not _mine(c)] == []
