"""Parsed JSON records whose missing keys name themselves by their path in the document.

A program or sidecar read from disk is indexed in many places (``prog["heads"][0]["swathes"]``);
a key that a hand-edited or truncated file lacks would surface as a bare ``KeyError: 'clock'``.
:func:`as_record` wraps the parsed document so that such a lookup raises
:class:`MissingKeyError` carrying where the key was looked for (``heads[0].swathes[0]``), which
a reader turns into one line naming the file. Nested tables are wrapped as they are reached
(each once: the wrapper replaces the plain table in its parent, so what is stored on it stays),
lists only when they hold tables (a list of numbers is handed back as it is).

:func:`validation_line` says a pydantic validation failure of such a record in words: the
field's path, what it must be, and what the file gave (``head.nozzles must be a whole number,
got 'many'``), never pydantic's own text (``Input should be a valid integer, unable to parse
string as an integer``).
"""

from __future__ import annotations

from typing import Any

__all__ = ["MissingKeyError", "Record", "Records", "as_record", "missing_key_message", "validation_line",
           "field_problem"]


class MissingKeyError(KeyError):
    """A key a record must have is not in it: ``where`` is the record's path, ``key`` the key."""

    def __init__(self, where: str, key: object) -> None:
        super().__init__(key)
        self.where = where
        self.key = key


def _child(at: str, k: object) -> str:
    if isinstance(k, int):
        return f"{at}[{k}]"
    return f"{at}.{k}" if at else str(k)


def _wrap(v: Any, at: str) -> Any:
    if isinstance(v, Record | Records):
        v._at = at
        return v
    if isinstance(v, dict):
        return Record(v, at)
    if isinstance(v, list) and v and isinstance(v[0], dict):
        return Records(v, at)
    return v


class Record(dict):
    """A ``dict`` that names a missing key by its path (:class:`MissingKeyError`) and wraps the
    tables and lists of tables it hands out."""

    __slots__ = ("_at",)

    def __init__(self, data: dict, at: str = "") -> None:
        super().__init__(data)
        self._at = at

    def __getitem__(self, k):
        try:
            v = dict.__getitem__(self, k)
        except KeyError:
            raise MissingKeyError(self._at, k) from None
        w = _wrap(v, _child(self._at, k))
        if w is not v:
            dict.__setitem__(self, k, w)
        return w


class Records(list):
    """A ``list`` of tables whose items are handed out as :class:`Record` (indexed or iterated)."""

    __slots__ = ("_at",)

    def __init__(self, data: list, at: str = "") -> None:
        super().__init__(data)
        self._at = at

    def __getitem__(self, i):
        v = list.__getitem__(self, i)
        if isinstance(i, slice):
            return v
        j = i + len(self) if i < 0 else i
        w = _wrap(v, _child(self._at, j))
        if w is not v:
            list.__setitem__(self, i, w)
        return w

    def __iter__(self):
        for j in range(len(self)):
            yield self[j]


def as_record(doc: Any, at: str = "") -> Any:
    """``doc`` wrapped (a table as :class:`Record`, a list of tables as :class:`Records`);
    anything else, or an already wrapped one, as it is."""
    return _wrap(doc, at) if not isinstance(doc, Record | Records) else doc


def missing_key_message(exc: MissingKeyError, what: str = "the program") -> str:
    """``heads[0].swathes[0] has no key 'clock'`` (``what`` names the top level)."""
    return f"{exc.where or what} has no key {exc.key!r}: {what} is incomplete"


def _shown(v: object) -> str:
    if isinstance(v, dict):
        return "a table"
    if isinstance(v, list | tuple):
        return f"a list of {len(v)}"
    r = repr(v)
    return r if len(r) <= 60 else r[:57] + "..."


def _kind(v: object) -> str:
    return {bool: "true/false", int: "a whole number", float: "a number", str: "a text string", dict: "a table",
            list: "a list", tuple: "a list"}.get(type(v), type(v).__name__)


def field_problem(err: dict) -> str:
    """What a field must be, in words, from one pydantic error (``err`` of
    ``ValidationError.errors()``), with what came: ``must be at least 1, got 0``."""
    t = err.get("type", "")
    ctx = err.get("ctx") or {}
    got = err.get("input")
    said = f", got {_shown(got)}"
    if t == "missing":
        return "is missing (it is required)"
    if t == "extra_forbidden":
        return "is not a known field (a misspelt name?)"
    if t in ("int_parsing", "int_type", "int_from_float"):
        return "must be a whole number" + said
    if t in ("float_parsing", "float_type"):
        return "must be a number" + said
    if t == "finite_number":
        return "must be a finite number" + said
    if t in ("bool_parsing", "bool_type"):
        return "must be true or false" + said
    if t in ("string_type", "string_unicode"):
        return "must be a text string" + said
    if t in ("dict_type", "model_type", "model_attributes_type", "dataclass_type"):
        return "must be a table" + (f", got {_kind(got)}" if not isinstance(got, dict) else "")
    if t in ("list_type", "tuple_type", "set_type", "iterable_type"):
        return "must be a list" + f", got {_kind(got)}"
    bounds = {"greater_than": ("greater than", "gt"), "greater_than_equal": ("at least", "ge"),
              "less_than": ("less than", "lt"), "less_than_equal": ("at most", "le")}
    if t in bounds:
        words, key = bounds[t]
        return f"must be {words} {ctx.get(key)!s}" + said
    if t == "literal_error":
        return f"must be one of {ctx.get('expected', '?')}" + said
    if t == "too_long":
        return f"must have at most {ctx.get('max_length')} items, got {ctx.get('actual_length')}"
    if t == "too_short":
        return f"must have at least {ctx.get('min_length')} items, got {ctx.get('actual_length')}"
    if t == "union_tag_not_found":
        return f"has no {ctx.get('discriminator', 'kind')} (say which kind it is)"
    if t == "union_tag_invalid":
        return f"{ctx.get('discriminator', 'kind')} must be one of {ctx.get('expected_tags', '?')}, got {ctx.get('tag')!r}"
    msg = str(err.get("msg", "is invalid")).removeprefix("Value error, ").removeprefix("Assertion failed, ")
    return ": " + msg + ("" if isinstance(got, dict | list) else said)


def validation_line(exc, prefix: str = "", *, skip: tuple[str, ...] = (), record: str = "the record",
                    field: str = "field") -> str:
    """One line for a pydantic ``ValidationError`` of a record: the first error's field path
    (after ``prefix``; loc parts in ``skip``, such as a tagged union's tag, left out where they
    lead), what it must be and what came (:func:`field_problem`), and how many more there are;
    ``record`` names the whole record (an error at its top level), ``field`` a field of it.

    Examples: ``field 'head.nozzles' must be a whole number, got 'many'``;
    ``field 'machine.encoder_counts_per_rev' is missing (it is required)``; an empty record:
    ``the record has no kind (say which kind it is)``.
    """
    errs = exc.errors()
    err = errs[0]
    loc = list(err.get("loc", ()))
    if loc and loc[0] in skip:
        loc = loc[1:]
    path = prefix
    for part in loc:
        path = _child(path, part)
    problem = field_problem(err)
    more = f" (and {len(errs) - 1} more problem(s))" if len(errs) > 1 else ""
    sep = "" if problem.startswith(":") else " "
    if not path:
        return f"{record}{sep}{problem}{more}"
    return f"{field} '{path}'{sep}{problem}{more}"
