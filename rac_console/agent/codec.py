"""The engine's immutable events as bytes for the agent's socket, and back.

The agent runs the engine; its clients draw what it publishes. The events are frozen
dataclasses, enums, named tuples and a few exceptions: each is packed (msgpack) as its
class's name and its fields in order. Decoding makes only the classes listed in
:data:`MODULES`: a name that is not one of them is refused, so bytes from the socket can
never make an object of another kind. Both ends run the same release (the hello checks
it), so a class's fields are the same on both sides.
"""

from __future__ import annotations

import dataclasses
import datetime
import importlib
from decimal import Decimal
from enum import Enum
from functools import cache
from typing import Any

import msgpack

from ..commands.language import VarRef
from ..protocol import RacError
from ..protocol.request import ReplyCheck, Request, get_check, put_for_check
from ..protocol.variables import KINDS, VarKind

#: The modules whose dataclasses, enums, named tuples and exceptions travel.
MODULES = (
    "rac_console.protocol.errors",
    "rac_console.protocol.messages",
    "rac_console.protocol.request",
    "rac_console.protocol.variant",
    "rac_console.protocol.vartypes",
    "rac_console.session.types",
    "rac_console.commands.language",
    "rac_console.commands.latency",
    "rac_console.commands.outcome",
    "rac_console.commands.conditions",
    "rac_console.engine.published.events",
    "rac_console.engine.published.feedback",
    "rac_console.engine.published.status",
)

# The ext codes: what each packed extension holds.
_DATACLASS, _ENUM, _TUPLE, _FROZENSET, _SET, _DECIMAL, _KIND, _ERROR, _NAMED, _DATETIME = range(
    1, 11
)
_VAR = 11  # a watched variable (VarRef): its text, "I10", one leaf (on every row and sample)
#: An exception of a class not listed: travels as a RacError with its text.
_OTHER_ERROR = "Exception"


class DecodeError(RacError):
    """Bytes from the socket that are no message of this release."""


@cache
def _classes() -> dict[str, type]:
    """Every class that may travel, by name (each name once across the modules)."""
    found: dict[str, type] = {}
    for name in MODULES:
        module = importlib.import_module(name)
        for value in vars(module).values():
            if not isinstance(value, type) or value.__module__ != module.__name__:
                continue
            travels = (
                dataclasses.is_dataclass(value)
                or issubclass(value, (Enum, BaseException))
                or (issubclass(value, tuple) and hasattr(value, "_fields"))
            )
            if travels:
                if value.__name__ in found:
                    raise RuntimeError(f"two classes named {value.__name__} in MODULES")
                found[value.__name__] = value
    return found


_FIELD_NAMES: dict[type, tuple[str, ...]] = {}


def _fields(cls: Any) -> tuple[str, ...]:
    """A dataclass's field names, in order (read once per class)."""
    names = _FIELD_NAMES.get(cls)
    if names is None:
        names = _FIELD_NAMES[cls] = tuple(f.name for f in dataclasses.fields(cls))
    return names


def _mark(code: int, name: str = "") -> msgpack.ExtType:
    """The extension that heads a list standing for an object (made once per kind)."""
    mark = _MARKS.get((code, name))
    if mark is None:
        mark = _MARKS[(code, name)] = msgpack.ExtType(code, name.encode())
    return mark


_MARKS: dict[tuple[int, str], msgpack.ExtType] = {}


def _default(obj: Any) -> Any:
    """Called by the packer for what msgpack does not pack itself: a leaf extension,
    or a list headed by a mark that says what it stands for (packed in the same pass:
    no packing within packing, which cost 17 µs a watched value in a cycle)."""
    cls = type(obj)
    if cls is VarRef:
        return msgpack.ExtType(_VAR, f"{obj.kind.code}:{obj.index}".encode())
    if cls is VarKind:
        return msgpack.ExtType(_KIND, obj.code.encode())
    if cls is tuple:
        return [_mark(_TUPLE), *obj]
    if dataclasses.is_dataclass(obj) and cls is not Request:
        return [_mark(_DATACLASS, _listed(cls)), *[getattr(obj, n) for n in _fields(cls)]]
    if isinstance(obj, Enum):
        return [_mark(_ENUM, _listed(cls)), obj.value]
    if isinstance(obj, tuple):
        if hasattr(cls, "_fields"):
            return [_mark(_NAMED, _listed(cls)), *obj]
        return [_mark(_TUPLE), *obj]
    if isinstance(obj, frozenset):
        return [_mark(_FROZENSET), *obj]
    if isinstance(obj, set):
        return [_mark(_SET), *obj]
    if isinstance(obj, Decimal):
        return msgpack.ExtType(_DECIMAL, str(obj).encode())
    if isinstance(obj, datetime.datetime):
        return msgpack.ExtType(_DATETIME, obj.isoformat().encode())
    if isinstance(obj, BaseException):
        name = cls.__name__
        if _classes().get(name) is not cls:
            return [_mark(_ERROR, _OTHER_ERROR), [str(obj)], {}]
        attrs = {k: v for k, v in vars(obj).items() if not k.startswith("__")}
        return [_mark(_ERROR, name), list(obj.args), attrs]
    if isinstance(obj, Request):  # its reply check is a function: said by what it checks
        return [_mark(_DATACLASS, "Request"), obj.text, obj.data, obj.line, _check_name(obj.check)]
    raise TypeError(f"{cls.__name__} does not travel to the agent's clients")


def _check_name(check: ReplyCheck | None) -> str | None:
    """A request's reply check as a word: ``put``, a variable type's code, or None."""
    if check is None:
        return None
    if check is put_for_check():
        return "put"
    for code, kind in KINDS.items():
        if check is get_check(kind):
            return code
    raise TypeError("a request's reply check that does not travel")


def _check_of(name: str | None) -> ReplyCheck | None:
    if name is None:
        return None
    if name == "put":
        return put_for_check()
    kind = KINDS.get(name)
    if kind is None:
        raise DecodeError(f"no reply check {name!r}")
    return get_check(kind)


def _listed(cls: type) -> str:
    if _classes().get(cls.__name__) is not cls:
        raise TypeError(f"{cls.__module__}.{cls.__qualname__} is not in codec.MODULES")
    return cls.__name__


def _class(name: str) -> type:
    cls = _classes().get(name)
    if cls is None:
        raise DecodeError(f"a message names {name!r}, which no message of this release holds")
    return cls


class _Mark:
    """What a mark unpacks to: the head of a list that stands for an object."""

    __slots__ = ("code", "name")

    def __init__(self, code: int, name: str) -> None:
        self.code, self.name = code, name


_HEADS = {_DATACLASS, _ENUM, _TUPLE, _FROZENSET, _SET, _ERROR, _NAMED}


def _ext(code: int, data: bytes) -> Any:
    """Called by the unpacker for each extension: a leaf's object, or a mark."""
    try:
        return _leaf(code, data)
    except DecodeError:
        raise
    except Exception as exc:  # a Decimal, a date or a name that is none
        raise DecodeError(f"an extension {code} that cannot be read: {exc}") from None


def _leaf(code: int, data: bytes) -> Any:
    if code == _VAR:
        return _var(data)
    mark = _MARKS_READ.get((code, data))
    if mark is not None:
        return mark
    if code == _KIND:
        kind = KINDS.get(data.decode())
        if kind is None:
            raise DecodeError(f"no variable type {data!r}")
        return kind
    if code == _DECIMAL:
        return Decimal(data.decode())
    if code == _DATETIME:
        return datetime.datetime.fromisoformat(data.decode())
    if code in _HEADS:
        mark = _Mark(code, data.decode())
        if not data or mark.name in _classes():  # only marks that name what travels
            _MARKS_READ[(code, data)] = mark
        return mark
    raise DecodeError(f"no extension {code}")


#: The marks read so far (a handful: one per class that travels).
_MARKS_READ: dict[tuple[int, bytes], _Mark] = {}
_VARS: dict[bytes, VarRef] = {}


def _var(data: bytes) -> VarRef:
    """A watched variable from its text (each made once)."""
    var = _VARS.get(data)
    if var is None:
        code, _, index = data.decode().partition(":")
        kind = KINDS.get(code)
        if kind is None or not index.isdigit():
            raise DecodeError(f"no variable {data!r}")
        var = VarRef(kind, int(index))
        if len(_VARS) < 100_000:
            _VARS[data] = var
    return var


def _list(items: list[Any]) -> Any:
    """Called by the unpacker for each list, inner ones first: the object a marked list
    stands for, or the list."""
    if not items or type(items[0]) is not _Mark:
        return items
    mark, rest = items[0], items[1:]
    try:
        return _made(mark.code, mark.name, rest)
    except DecodeError:
        raise
    except Exception as exc:  # fields that fit no such object
        raise DecodeError(f"a {mark.name or 'value'} that cannot be made: {exc}") from None


def _made(code: int, name: str, rest: list[Any]) -> Any:
    if code == _TUPLE:
        return tuple(rest)
    if code == _FROZENSET:
        return frozenset(rest)
    if code == _SET:
        return set(rest)
    if code == _ERROR:
        args, attrs = rest
        if name == _OTHER_ERROR:
            return RacError(*args)
        error_class = _class(name)
        if not issubclass(error_class, BaseException):
            raise DecodeError(f"{name} is no exception")
        error = error_class.__new__(error_class)
        error.args = tuple(args)
        vars(error).update(attrs)
        return error
    cls = _class(name)
    if code == _ENUM:
        return cls(rest[0])
    if code == _NAMED:
        return cls(*rest)
    if cls is Request:
        text, data, line, check = rest
        return Request(text, data, line, _check_of(check))
    if not dataclasses.is_dataclass(cls):
        raise DecodeError(f"{name} is no dataclass")
    return cls(*rest)


def pack(obj: Any) -> bytes:
    """The bytes of one message (any of the travelling types, in lists and maps)."""
    return msgpack.packb(obj, default=_default, strict_types=True, use_bin_type=True)  # type: ignore[no-any-return]


def unpack(data: bytes) -> Any:
    """The message ``pack`` made of it; :class:`DecodeError` for anything else."""
    try:
        return msgpack.unpackb(
            data, ext_hook=_ext, list_hook=_list, raw=False, strict_map_key=False
        )
    except DecodeError:
        raise
    except Exception as exc:  # msgpack's own errors, and a class made with wrong fields
        raise DecodeError(f"a message that cannot be read: {exc}") from None


def unpacker(max_message: int) -> msgpack.Unpacker:
    """A stream reader of messages, none over ``max_message`` bytes."""
    return msgpack.Unpacker(
        ext_hook=_ext,
        list_hook=_list,
        raw=False,
        strict_map_key=False,
        max_buffer_size=max_message,
    )
