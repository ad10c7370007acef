"""The one reading path for files a user hands to nfarm: parameter files (YAML), saved models
and data-set descriptions (JSON).

Every reader here checks, before parsing, that the path is a **regular file** (a FIFO would
block forever, ``/dev/zero`` never ends) of at most ``max_bytes``; it parses with bounds on
nesting depth and on the number of nodes after alias expansion (a 1 KB "billion laughs"
document otherwise expands to 10⁹ items), and reports every failure as one
:class:`ParamsError` line naming the file, the field and the rule broken::

    params/robots/x.yaml:12:3: duplicate key 'mass' (first at line 9)
    params/robots/x.yaml: joints[2].mass: must be >= 0, got -1.0

YAML is read with the YAML 1.2 core schema's *decimal* numbers only, and ``true``/``false`` as
booleans: ``5e-4`` is a number (YAML 1.1 reads it as text), while YAML 1.1's base-60
``1:30`` (= 90), hexadecimal ``0x10``, octal ``010``, ``yes``/``no``/``on``/``off`` and dates
stay text, so the schema check rejects them instead of accepting a number the author did not
mean. Duplicate keys are errors (PyYAML silently keeps the last).

:class:`Validator` holds the per-field checks the robot, study and model schemas share.
"""

from __future__ import annotations

import difflib
import hashlib
import json
import math
import os
import re
import reprlib
import stat
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from .arguments import is_integer, is_number

__all__ = ["ParamsError", "ParamsWarning", "read_bytes", "load_yaml", "load_json", "Validator",
           "show", "json_ready", "with_content_digest", "checked_content", "MAX_BYTES", "MAX_DEPTH",
           "MAX_NODES", "MAX_DIGITS", "listed", "MAX_LISTED"]

MAX_BYTES = 1 << 20        # 1 MiB: a robot file is ~2 KB, a saved 128-rule model ~100 KB
MAX_DEPTH = 32             # nesting levels (a robot file uses 4)
MAX_NODES = 200_000        # scalars, lists and mappings after alias expansion


class ParamsError(ValueError):
    """A file breaks a rule; the message names the file, the field and the rule."""


class ParamsWarning(UserWarning):
    """A file is accepted but something in it is physically suspicious."""


_repr = reprlib.Repr()
_repr.maxlevel, _repr.maxlist, _repr.maxtuple, _repr.maxdict = 2, 4, 4, 4
_repr.maxstring, _repr.maxother, _repr.maxlong = 40, 40, 40


def show(value: Any) -> str:
    """A short repr of a value read from a file, for error messages (bounded work and length,
    whatever the value: a nested or shared structure is cut at two levels and four items)."""
    text = _repr.repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


#: Names a message lists before it counts the rest (a list in a message stays one short line).
MAX_LISTED = 8


def listed(names, limit: int = MAX_LISTED) -> str:
    """``names`` joined by commas for a message, each shortened (:func:`show` of a long one), at
    most ``limit`` of them and then how many more: a file of 40 000 roots is one short line.

    Example:
        >>> listed(["a", "b"]), listed(f"l{k}" for k in range(40_001))
        ('a, b', 'l0, l1, l2, l3, l4, l5, l6, l7 and 39,993 more')
    """
    items = list(names)
    shown_items = [x if isinstance(x, str) and len(x) <= 40 and x.isprintable() else show(x)
                   for x in items[:limit]]
    more = f" and {len(items) - limit:,} more" if len(items) > limit else ""
    return ", ".join(shown_items) + more


# --------------------------------------------------------------------------------------------
# Bytes


def read_bytes(path: str | os.PathLike, *, max_bytes: int = MAX_BYTES, what: str = "file") -> bytes:
    """The bytes of a regular file of at most ``max_bytes``.

    The file is opened non-blocking and checked with ``fstat`` on the open descriptor, so a
    FIFO, a device or a directory is refused without reading it (and without a race between
    checking and opening).
    """
    path = Path(path)
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_CLOEXEC", 0))
    except FileNotFoundError:
        raise ParamsError(f"{path}: file not found") from None
    except OSError as exc:
        raise ParamsError(f"{path}: cannot open: {exc.strerror}") from None
    try:
        info = os.fstat(fd)
        if not stat.S_ISREG(info.st_mode):
            kind = "a directory" if stat.S_ISDIR(info.st_mode) else "a FIFO" \
                if stat.S_ISFIFO(info.st_mode) else "a device or special file"
            raise ParamsError(f"{path}: must be a regular file, got {kind}")
        if info.st_size > max_bytes:
            raise ParamsError(f"{path}: file is {info.st_size} bytes, over the limit of "
                              f"{max_bytes} for a {what}")
        with os.fdopen(fd, "rb", closefd=True) as stream:
            fd = -1
            data = stream.read(max_bytes + 1)
    except OSError as exc:
        raise ParamsError(f"{path}: cannot read: {exc.strerror or exc}") from None
    finally:
        if fd >= 0:
            os.close(fd)
    if len(data) > max_bytes:   # grew while we read
        raise ParamsError(f"{path}: file is over the limit of {max_bytes} bytes for a {what}")
    return data


def _text(path: Path, data: bytes) -> str:
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise ParamsError(f"{path}: not UTF-8 text (byte {exc.start}: "
                          f"{data[exc.start:exc.start + 1]!r}); is it a binary file?") from None


# --------------------------------------------------------------------------------------------
# YAML


_INT = re.compile(r"^[-+]?(?:0|[1-9][0-9]*)$")      # no leading zeros: YAML 1.1 reads 010 as 8
_FLOAT = re.compile(r"""^(?:[-+]?(?:[0-9]+\.[0-9]*|\.[0-9]+)(?:[eE][-+]?[0-9]+)?
                        |[-+]?[0-9]+[eE][-+]?[0-9]+
                        |[-+]?\.(?:inf|Inf|INF)
                        |\.(?:nan|NaN|NAN))$""", re.X)
_BOOL = re.compile(r"^(?:true|True|TRUE|false|False|FALSE)$")
_NULL = re.compile(r"^(?:~|null|Null|NULL|)$")


class _Loader(yaml.SafeLoader):
    """SafeLoader with YAML 1.2 decimal numbers and booleans, duplicate keys refused, and
    bounded nesting and alias expansion."""

    max_depth = MAX_DEPTH
    max_nodes = MAX_NODES

    def __init__(self, stream):
        super().__init__(stream)
        self._depth = 0
        self._sizes: dict[int, int] = {}   # expanded size of each anchored node
        self._total = 0

    def compose_node(self, parent, index):
        if self.check_event(yaml.AliasEvent):
            event = self.peek_event()
            anchor = event.anchor
            if anchor in self.anchors and id(self.anchors[anchor]) not in self._sizes:
                # its anchor's node is still being composed: the alias is inside it
                raise yaml.composer.ComposerError(
                    None, None, f"a recursive alias *{anchor} (inside the value it names)",
                    event.start_mark)
            if anchor in self.anchors:
                self._count(self._sizes.get(id(self.anchors[anchor]), 1), event.start_mark)
            return super().compose_node(parent, index)
        self._depth += 1
        if self._depth > self.max_depth:
            mark = self.peek_event().start_mark
            raise yaml.composer.ComposerError(
                None, None, f"nested deeper than {self.max_depth} levels", mark)
        before = self._total
        try:
            node = super().compose_node(parent, index)
        finally:
            self._depth -= 1
        self._count(1, node.start_mark)
        self._sizes[id(node)] = self._total - before
        return node

    def _count(self, size: int, mark) -> None:
        self._total += size
        if self._total > self.max_nodes:
            raise yaml.composer.ComposerError(
                None, None, f"more than {self.max_nodes} values once aliases are expanded "
                            f"(an alias bomb?)", mark)

    def construct_mapping(self, node, deep=False):
        if isinstance(node, yaml.MappingNode):
            seen: dict[Any, Any] = {}
            for key_node, _ in node.value:
                if key_node.tag == "tag:yaml.org,2002:merge":
                    raise yaml.constructor.ConstructorError(
                        None, None, "merge keys '<<' are not supported", key_node.start_mark)
                key = self.construct_object(key_node, deep=True)
                try:
                    hash(key)
                except TypeError:
                    raise yaml.constructor.ConstructorError(
                        None, None, "a key must be a plain value", key_node.start_mark) from None
                if key in seen:
                    raise yaml.constructor.ConstructorError(
                        None, None, f"duplicate key {show(key)} (first at line "
                                    f"{seen[key].start_mark.line + 1})", key_node.start_mark)
                seen[key] = key_node
        return super().construct_mapping(node, deep=deep)


# Replace the YAML 1.1 implicit resolvers for numbers, booleans, null and dates by YAML 1.2
# decimal ones: other scalars stay strings.
_REPLACED = {"tag:yaml.org,2002:int", "tag:yaml.org,2002:float", "tag:yaml.org,2002:bool",
             "tag:yaml.org,2002:null", "tag:yaml.org,2002:timestamp"}
_Loader.yaml_implicit_resolvers = {
    first: [(tag, regexp) for tag, regexp in resolvers if tag not in _REPLACED]
    for first, resolvers in yaml.SafeLoader.yaml_implicit_resolvers.items()}
_Loader.add_implicit_resolver("tag:yaml.org,2002:bool", _BOOL, list("tTfF"))
_Loader.add_implicit_resolver("tag:yaml.org,2002:int", _INT, list("-+0123456789"))
_Loader.add_implicit_resolver("tag:yaml.org,2002:float", _FLOAT, list("-+0123456789."))
_Loader.add_implicit_resolver("tag:yaml.org,2002:null", _NULL, ["~", "n", "N", ""])


#: Digits a number in a parameter file or a saved model may have: every plausible value has far
#: fewer, and Python refuses to convert integers of more than 4 300 digits with a long message.
MAX_DIGITS = 100


class _Unbuildable(yaml.constructor.ConstructorError):
    """A value whose tag the loader cannot build (``!!int 0x10``, ``!!bool maybe``, a date): one
    line naming the tag and the text, from :func:`load_yaml`."""


def _refuse(node, rule: str):
    value = show(node.value) if isinstance(node, yaml.ScalarNode) else \
        "a list" if isinstance(node, yaml.SequenceNode) else "a mapping"
    raise _Unbuildable(None, None, f"{node.tag.rsplit(':', 1)[-1]} {value}: {rule}", node.start_mark)


def _tagged_text(loader, node, pattern: re.Pattern, rule: str) -> str:
    """The text of a scalar tagged explicitly (``!!int …``), which must read as that tag's plain
    values do (the same grammar as an untagged value): otherwise one line naming the tag."""
    if not isinstance(node, yaml.ScalarNode):
        _refuse(node, f"must be a single value ({rule})")
    text = loader.construct_scalar(node)
    if not pattern.match(text):
        _refuse(node, rule)
    return text


def _construct_int(loader, node):
    text = _tagged_text(loader, node, _INT, "a whole number is plain decimal digits (no 0x, 0o, "
                                             "leading zeros, '_' or ':')")
    if len(text.lstrip("+-")) > MAX_DIGITS:
        raise yaml.constructor.ConstructorError(
            None, None, f"an integer of {len(text.lstrip('+-')):,} digits (at most {MAX_DIGITS})",
            node.start_mark)
    return int(text)


#: What ``!!float`` accepts: a plain float or a plain whole number (``!!float 3`` is 3.0).
_TAGGED_FLOAT = re.compile(rf"(?:{_FLOAT.pattern})|^[-+]?(?:0|[1-9][0-9]*)$", re.X)


def _construct_float(loader, node):
    text = _tagged_text(loader, node, _TAGGED_FLOAT, "a number is plain decimal (1, -0.25, 1.5e-3, .inf)").lower()
    if text.lstrip("+-") == ".inf":
        return -math.inf if text.startswith("-") else math.inf
    if text == ".nan":
        return math.nan
    return float(text)


def _construct_bool(loader, node):
    return _tagged_text(loader, node, _BOOL, "a truth value is true or false").lower() == "true"


def _construct_null(loader, node):
    _tagged_text(loader, node, _NULL, "null is null, ~ or nothing")
    return None


def _not_read(rule: str):
    def construct(loader, node):
        _refuse(node, rule)
    return construct


_Loader.add_constructor("tag:yaml.org,2002:int", _construct_int)
_Loader.add_constructor("tag:yaml.org,2002:float", _construct_float)
_Loader.add_constructor("tag:yaml.org,2002:bool", _construct_bool)
_Loader.add_constructor("tag:yaml.org,2002:null", _construct_null)
# Tags of YAML 1.1 no parameter file has a use for: refused by name rather than built.
for _tag, _what in (("timestamp", "dates are not read (write the value as text or a number)"),
                    ("binary", "binary data is not read"), ("set", "sets are not read (write a list)"),
                    ("omap", "ordered maps are not read (write a mapping)"),
                    ("pairs", "pairs are not read (write a mapping)")):
    _Loader.add_constructor(f"tag:yaml.org,2002:{_tag}", _not_read(_what))


def load_yaml(path: str | os.PathLike, *, max_bytes: int = MAX_BYTES, what: str = "parameter file"
              ) -> Any:
    """Parse a YAML file through the checks of this module (module docstring)."""
    path = Path(path)
    text = _text(path, read_bytes(path, max_bytes=max_bytes, what=what))
    try:
        return yaml.load(text, Loader=_Loader)  # noqa: S506 — a SafeLoader subclass
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f"{path}:{mark.line + 1}:{mark.column + 1}" if mark else str(path)
        problem = getattr(exc, "problem", None) or str(exc).splitlines()[0]
        if isinstance(exc, _Unbuildable):
            raise ParamsError(f"{where}: a value tagged !!{problem}") from None
        if problem.startswith(("duplicate key", "nested deeper", "more than", "merge keys",
                               "a key must", "an integer of", "a recursive alias")):
            raise ParamsError(f"{where}: {problem}") from None
        raise ParamsError(f"{where}: YAML syntax error: {problem}") from None
    except RecursionError:  # a recursive alias (&a [*a]) the composer cannot close
        raise ParamsError(f"{path}: nested too deeply (a recursive alias?)") from None
    except (ValueError, TypeError, KeyError, AttributeError, OverflowError) as exc:   # pragma: no cover
        # a constructor PyYAML ships that met a value it cannot build: still one line
        raise ParamsError(f"{path}: a value the YAML loader cannot build ({type(exc).__name__}: "
                          f"{show(str(exc))})") from None


# --------------------------------------------------------------------------------------------
# JSON


def _json_constant(name: str):
    raise ValueError(f"{name} is not a number JSON allows")


def _json_int(text: str) -> int:
    if len(text.lstrip("-")) > MAX_DIGITS:
        raise ValueError(f"an integer of {len(text.lstrip('-')):,} digits (at most {MAX_DIGITS})")
    return int(text)


def _json_float(text: str) -> float:
    value = float(text)
    if not math.isfinite(value):
        raise ValueError(f"{text[:24]}{'…' if len(text) > 24 else ''} overflows a floating-point number")
    return value


def _json_object(pairs: list) -> dict:
    """A JSON object whose keys are distinct (``json`` keeps the last of a duplicate key)."""
    out: dict = {}
    for key, value in pairs:
        if key in out:
            raise ValueError(f"duplicate key {show(key)} in one object")
        out[key] = value
    return out


def _json_depth(value: Any, limit: int) -> None:
    stack = [(value, 1)]
    while stack:
        item, depth = stack.pop()
        if depth > limit:
            raise ValueError(f"nested deeper than {limit} levels")
        if isinstance(item, dict):
            stack.extend((v, depth + 1) for v in item.values())
        elif isinstance(item, list):
            stack.extend((v, depth + 1) for v in item)


def load_json(path: str | os.PathLike, *, max_bytes: int = 64 << 20, max_depth: int = MAX_DEPTH,
              what: str = "JSON file") -> Any:
    """Parse a JSON file (regular, at most ``max_bytes``, nesting at most ``max_depth``;
    ``NaN``/``Infinity``, numbers that overflow a float, duplicate keys in an object and
    integers of more than :data:`MAX_DIGITS` digits refused)."""
    path = Path(path)
    text = _text(path, read_bytes(path, max_bytes=max_bytes, what=what))
    try:
        data = json.loads(text, parse_constant=_json_constant, parse_int=_json_int, parse_float=_json_float,
                          object_pairs_hook=_json_object)
        _json_depth(data, max_depth)
    except json.JSONDecodeError as exc:
        raise ParamsError(f"{path}:{exc.lineno}:{exc.colno}: not valid JSON: {exc.msg}") from None
    except RecursionError:
        raise ParamsError(f"{path}: nested deeper than {max_depth} levels") from None
    except ValueError as exc:
        raise ParamsError(f"{path}: {exc}") from None
    return data


#: The field of a saved model that holds the SHA-256 of the rest of its content.
CONTENT_FIELD = "content_sha256"


def _content_digest(data: Mapping) -> str:
    body = {k: v for k, v in data.items() if k != CONTENT_FIELD}
    text = json.dumps(body, sort_keys=True, separators=(",", ":"), allow_nan=False)
    return hashlib.sha256(text.encode()).hexdigest()


def with_content_digest(data: Mapping) -> dict:
    """``data`` with :data:`CONTENT_FIELD`: the SHA-256 of its canonical JSON (sorted keys,
    no spaces) without that field. JSON floats round-trip exactly, so a file written from it
    and read back hashes the same; any edit of a value, a key or the structure does not."""
    return {**data, CONTENT_FIELD: _content_digest(data)}


def checked_content(data: Any, source: str) -> dict:
    """``data`` read from a saved model, without :data:`CONTENT_FIELD`, once the field's hash
    matches the content.

    Raises:
        ParamsError: not a JSON object, no hash (not written by nfarm's ``save``), or a hash
            that does not match: an edited or damaged file, named in one line.
    """
    v = Validator(source)
    if not isinstance(data, dict):
        v.fail("", f"must be a JSON object (a saved nfarm model), got {show(data)}")
    stored = data.get(CONTENT_FIELD)
    if not isinstance(stored, str):
        v.fail(CONTENT_FIELD, "missing: the file was not written by this version of nfarm's save (models "
                              "carry a hash of their content since 0.1.0): train the model again")
    if stored != _content_digest(data):
        v.fail(CONTENT_FIELD, "does not match the file's content: the model was edited or damaged after it "
                              "was saved; train it again or restore the saved file")
    return {k: val for k, val in data.items() if k != CONTENT_FIELD}


# --------------------------------------------------------------------------------------------
# Field checks


class Validator:
    """Checks one field at a time; every failure names the source, the field and the rule."""

    def __init__(self, source: str):
        self.source = source

    def fail(self, field: str, rule: str):
        prefix = f"{self.source}: {field}: " if field else f"{self.source}: "
        raise ParamsError(prefix + rule)

    def mapping(self, data: Any, at: str, keys: Mapping[str, bool]) -> Mapping:
        """``data`` is a mapping with only the ``keys`` (``True``: required)."""
        if not isinstance(data, Mapping):
            self.fail(at, f"must be a mapping of fields, got {show(data)}")
        for key in data:
            if key not in keys:
                close = difflib.get_close_matches(str(key), list(keys), n=1)
                hint = f" (did you mean {close[0]!r}?)" if close else \
                    f" (allowed: {', '.join(keys)})"
                self.fail(f"{at}.{key}" if at else str(key), f"unknown field{hint}")
        for key, required in keys.items():
            if required and key not in data:
                self.fail(f"{at}.{key}" if at else key, "required field is missing")
        return data

    def string(self, value: Any, at: str, allow_empty: bool = False) -> str:
        if not isinstance(value, str) or not (value.strip() or allow_empty):
            self.fail(at, f"must be a non-empty string, got {show(value)}")
        return value

    def choice(self, value: Any, at: str, choices: Sequence[str]) -> str:
        if not isinstance(value, str) or value not in choices:
            self.fail(at, f"must be one of {', '.join(choices)}, got {show(value)}")
        return value

    def boolean(self, value: Any, at: str) -> bool:
        if not isinstance(value, bool):
            self.fail(at, f"must be true or false, got {show(value)}")
        return value

    def number(self, value: Any, at: str, *, lo: float | None = None, hi: float | None = None,
               lo_open: bool = False) -> float:
        """A finite number (``lo <= value <= hi``, or ``lo < value`` with ``lo_open``)."""
        if not is_number(value, numpy=False):
            self.fail(at, f"must be a number, got {show(value)}")
        try:
            x = float(value)
        except OverflowError:
            x = math.inf
        if not math.isfinite(x):
            self.fail(at, f"must be finite, got {show(value)}")
        if lo is not None and (x <= lo if lo_open else x < lo):
            self.fail(at, f"must be {'>' if lo_open else '>='} {lo:g}, got {x!r}")
        if hi is not None and x > hi:
            self.fail(at, f"must be <= {hi:g}, got {x!r}")
        return x

    def integer(self, value: Any, at: str, *, lo: int | None = None, hi: int | None = None) -> int:
        if not is_integer(value, numpy=False):
            self.fail(at, f"must be a whole number, got {show(value)}")
        if lo is not None and value < lo:
            self.fail(at, f"must be >= {lo}, got {value}")
        if hi is not None and value > hi:
            self.fail(at, f"must be <= {hi}, got {show(value)}")
        return value

    def vector(self, value: Any, at: str, length: int) -> list[float]:
        if not isinstance(value, Sequence) or isinstance(value, str) or len(value) != length:
            self.fail(at, f"must be a list of {length} numbers, got {show(value)}")
        return [self.number(x, f"{at}[{k}]") for k, x in enumerate(value)]

    def sequence(self, value: Any, at: str, *, min_len: int = 0, max_len: int | None = None
                 ) -> Sequence:
        if not isinstance(value, Sequence) or isinstance(value, str):
            self.fail(at, f"must be a list, got {show(value)}")
        if len(value) < min_len or (max_len is not None and len(value) > max_len):
            bound = f"{min_len}" if max_len == min_len else \
                f"at least {min_len}" if max_len is None else f"{min_len} to {max_len}"
            self.fail(at, f"must be a list of {bound} items, got {len(value)}")
        return value

    def array(self, value: Any, at: str, shape: Sequence[int | None], *, integer: bool = False
              ) -> np.ndarray:
        """A nested list of finite numbers (whole numbers if ``integer``) of ``shape``
        (``None``: any length) as an array."""
        kind = "whole numbers" if integer else "numbers"
        try:
            a = np.asarray(value)
        except (ValueError, TypeError):
            a = None
        if a is None or a.dtype.kind not in ("iu" if integer else "iuf") or a.ndim != len(shape) \
                or any(want is not None and got != want for got, want in zip(a.shape, shape)):
            if len(shape) == 1:
                count = "" if shape[0] is None else f"{shape[0]} "
                self.fail(at, f"must be a list of {count}{kind}, got {show(value)}")
            dims = " × ".join("N" if k is None else str(k) for k in shape)
            self.fail(at, f"must be a {dims} array of {kind}, got {show(value)}")
        if not integer:
            a = a.astype(float)
            if not np.isfinite(a).all():
                self.fail(at, "must hold finite numbers, got NaN or inf")
        return a


def json_ready(value: Any) -> Any:
    """``value`` as JSON types for saving: tuples and arrays become lists, numpy numbers Python
    numbers; a NaN or infinite float is a ``ValueError`` (JSON has none, and
    :func:`load_json` refuses them)."""
    if isinstance(value, Mapping):
        return {k: json_ready(v) for k, v in value.items()}
    if isinstance(value, np.ndarray) and value.ndim and value.dtype.kind in "biuf":
        # numbers at C speed (a saved kernel model holds millions): the same lists element by element
        if value.dtype.kind == "f" and not np.isfinite(value).all():
            raise ValueError(f"value {float(value[~np.isfinite(value)].flat[0])!r} cannot be saved as JSON")
        return value.tolist()
    if isinstance(value, (list, tuple, np.ndarray)):
        return [json_ready(v) for v in value]
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        raise ValueError(f"value {value!r} cannot be saved as JSON")
    return value
