"""The commands of the language and the parsers of their arguments.

Each parser turns the text after a command word into a command object or raises
:class:`InputError` with what is wrong and how to write it; nothing here sends
anything. Each command's registry entry (:mod:`rac_console.engine.commands.builtin`) names
its parser. Every command object sits next to the parser that makes it, and the shared
pieces (variables, ranges, seconds) are used by all; the parsers of the exchanges (get,
put, send: one request each) are apart, in :mod:`.exchange_parsers`.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from dataclasses import dataclass, field
from enum import Enum
from typing import Literal

from ..protocol import (
    KINDS,
    InputError,
    Variant,
    VarKind,
    kind_of,
    parse_index,
)
from ..protocol.request import Request, get_for, put_for, raw_request
from .advice import COMMAND_LINE, Advice
from .plant import Publish


@dataclass(frozen=True)
class VarRef:
    kind: VarKind
    index: int

    def __str__(self) -> str:
        return f"{self.kind.code}{self.index}"


@dataclass(frozen=True)
class Get:
    var: VarRef

    @property
    def request(self) -> Request:
        return get_for(self.var.kind, self.var.index)  # made once per variable

    @property
    def wire(self) -> str:
        return self.request.text


@dataclass(frozen=True)
class Put:
    """A typed write: the value, its RAC text and the request, all made at parse time
    (so a value that cannot be sent is refused before anything goes out)."""

    var: VarRef
    value: Variant
    value_text: str
    request: Request = field(repr=False, compare=False)

    @classmethod
    def of(cls, var: VarRef, value: Variant, value_text: str) -> Put:
        return cls(var, value, value_text, put_for(var.kind, var.index, value_text))

    @property
    def wire(self) -> str:
        return self.request.text


@dataclass(frozen=True)
class Raw:
    """A line sent exactly as typed: ``GET:...``/``PUT:...`` or ``send TEXT``."""

    request: Request

    @classmethod
    def of(cls, text: str) -> Raw:
        return cls(raw_request(text))

    @property
    def wire(self) -> str:
        return self.request.text


Exchange = Get | Put | Raw


@dataclass(frozen=True)
class Watch:
    vars: tuple[VarRef, ...]
    label: str = ""
    every: float | None = None  # ``watch ... every 0.2``: these rows' own poll period


@dataclass(frozen=True)
class Unwatch:
    vars: tuple[VarRef, ...]  # empty: all


@dataclass(frozen=True)
class SetInterval:
    seconds: float


@dataclass(frozen=True)
class Connect:
    """``connect HOST[:PORT]``, ``connect PROFILE`` or ``connect sim`` (host None: the
    built-in simulator). Whether HOST names a profile is the engine's to know."""

    host: str | None
    port: int
    port_given: bool = False  # HOST:PORT: the port wins over a profile's


@dataclass(frozen=True)
class Use:
    """``use NAME``: the cell's current target, where lines without ``@NAME`` run."""

    name: str


def parse_use(text: str) -> Use:
    name = text.strip()
    if not name or " " in name:
        raise InputError("use needs one target's name: use cell4")
    return Use(name)


@dataclass(frozen=True)
class WatchFile:
    action: str  # "save" or "load"
    path: str


@dataclass(frozen=True)
class Help:
    topic: str | None


@dataclass(frozen=True)
class Latency:
    """``latency [COUNT] [TYPE INDEX]``: round trips of repeated GETs."""

    var: VarRef
    count: int = 100
    interval: float = 0.0


@dataclass(frozen=True)
class Frames:
    on: bool


class Op(Enum):
    """How a ``wait`` compares the variable with its value."""

    EQ = "=="
    NE = "!="
    LT = "<"
    LE = "<="
    GT = ">"
    GE = ">="
    ON = "on"
    OFF = "off"
    CHANGES = "changes"


@dataclass(frozen=True)
class After:
    """The condition of another target a cell's ``wait`` waits for first."""

    target: str
    wait: Wait


@dataclass(frozen=True)
class Wait:
    """``wait VAR OP VALUE [within SECONDS]``: read until the condition holds, or time out."""

    var: VarRef
    op: Op
    value: Variant | float | None  # a Variant for == and !=, a number for < <= > >=
    within: float
    value_text: str = ""  # as typed, for messages
    #: ``... after @NAME VAR CONDITION``: waited for only once that target's condition
    #: held (a cell's handshake: robot B's answer after robot A's signal).
    after: After | None = None

    @property
    def condition(self) -> str:
        """``IO128 on``, ``I10 >= 100``, ``P0 changes``."""
        tail = f" {self.value_text}" if self.value_text else ""
        return f"{self.var} {self.op.value}{tail}"

    @property
    def request(self) -> Request:
        return get_for(self.var.kind, self.var.index)


@dataclass(frozen=True)
class CsvLog:
    """``log FILE.csv``: one CSV row per poll cycle; ``log stop``; ``log``: where to."""

    path: str | None
    stop: bool = False


@dataclass(frozen=True)
class FrameFile:
    """``record FILE`` (JSON lines, as ``--record``) or ``transcript FILE`` (plain text,
    as ``--log``) from now on; ``… stop``; alone: where frames go."""

    kind: Literal["record", "transcript"]
    path: str | None
    stop: bool = False


def frame_file_parser(kind: Literal["record", "transcript"]) -> Callable[[str], FrameFile]:
    """The parser of ``record`` or ``transcript``: ``FILE``, ``stop``, or nothing."""

    def parse(rest: str) -> FrameFile:
        text = rest.strip()
        if text.lower() == "stop":
            return FrameFile(kind, None, stop=True)
        return FrameFile(kind, text or None)

    return parse


class Step(Enum):
    """What a command without arguments asks for."""

    PAUSE = "pause"
    RESUME = "resume"
    DISCONNECT = "disconnect"
    CLEAR = "clear"
    QUIT = "quit"


@dataclass(frozen=True)
class Simple:
    """A command with no argument: pause, resume, disconnect, clear, quit."""

    step: Step


Command = (
    Get
    | Put
    | Raw
    | Watch
    | Unwatch
    | SetInterval
    | Connect
    | Use
    | WatchFile
    | Help
    | Frames
    | Latency
    | Wait
    | CsvLog
    | FrameFile
    | Simple
    | Publish
)

#: The command words, in the order ``help`` lists them. Each is the name of one entry in
#: a module of :mod:`rac_console.engine.commands.builtin`; an entry whose word is not here, or a
#: word here with no entry, stops the registry from loading, so a command added is listed
#: where it is declared here, never wherever its module happened to put it.
COMMAND_WORDS = (
    "get", "put", "send",
    "watch", "unwatch", "interval", "pause", "resume",
    "connect", "use", "disconnect",
    "save", "load",
    "frames", "latency", "wait", "log", "publish",
    "record", "transcript",
    "clear", "help", "quit",
)  # fmt: skip

MAX_LATENCY_COUNT = 100_000

MAX_RANGE = 256
MIN_INTERVAL, MAX_INTERVAL = 0.0, 3600.0

_VAR_RE = re.compile(r"\s*([A-Za-z]+)(?:\[\s*([^\]]*?)\s*\]|(\d+))?", re.ASCII)
_RAW_PREFIXES = ("GET:", "PUT:")


def is_raw_line(line: str) -> bool:
    return line.lstrip(" \t")[:4].upper() in _RAW_PREFIXES


def split_word(line: str) -> tuple[str, str]:
    """The first word (lower-cased) and the rest, leading blanks removed."""
    parts = line.strip().split(None, 1)
    if not parts:
        return "", ""
    return parts[0].lower(), parts[1] if len(parts) > 1 else ""


def parse_var(text: str, usage: str) -> tuple[VarRef, str]:
    """``I 10``, ``I10``, ``I[10]`` (any case) and the text after it."""
    match = _VAR_RE.match(text)
    if not match or not match.group(1):
        raise InputError(f"missing variable: {usage}")
    kind = kind_of(match.group(1))
    rest = text[match.end() :]
    index_text = match.group(2) if match.group(2) is not None else match.group(3)
    if index_text is None:
        index_match = re.match(r"\s+(\S+)", rest, re.ASCII)
        if not index_match:
            raise InputError(f"{kind.code} needs an index: {usage}")
        index_text, rest = index_match.group(1), rest[index_match.end() :]
    return VarRef(kind, parse_index(index_text)), rest


UNWATCH_USAGE = "unwatch TYPE INDEX | all"
WATCH_USAGE = "watch TYPE INDEX [LABEL] [every SECONDS], e.g. watch IO 128-135"


def parse_unwatch(rest: str) -> Unwatch:
    if rest.lower() == "all":
        return Unwatch(())
    variables, extra, _ = parse_var_list(rest, UNWATCH_USAGE)
    if extra.strip():
        raise InputError(f"unwatch takes variables only, not {extra.strip()!r}: {UNWATCH_USAGE}")
    return Unwatch(variables)


def parse_interval(rest: str) -> SetInterval:
    return SetInterval(parse_seconds(rest))


def parse_save(rest: str) -> WatchFile:
    if not rest:
        raise InputError("save needs a file name: save cell3.toml")
    return WatchFile("save", rest)


def parse_load(rest: str) -> WatchFile:
    if not rest:
        raise InputError("load needs a file name: load cell3.toml")
    return WatchFile("load", rest)


def parse_help(rest: str) -> Help:
    return Help(rest.lower() or None)


def parse_frames(rest: str) -> Frames:
    if rest.lower() not in ("on", "off"):
        raise InputError("frames needs on or off: frames on")
    return Frames(rest.lower() == "on")


def _parse_vars(text: str, usage: str) -> tuple[tuple[VarRef, ...], str]:
    """One variable or a range ``TYPE FIRST-LAST``, and the text after it."""
    match = re.match(
        r"\s*([A-Za-z]+)\s*(?:\[\s*(\d+)\s*-\s*(\d+)\s*\]|(\d+)\s*-\s*(\d+))", text, re.ASCII
    )
    if match is None or match.group(1).upper() not in KINDS:
        var, rest = parse_var(text, usage)
        return (var,), rest
    kind = kind_of(match.group(1))
    first_text, last_text = (
        (match.group(2), match.group(3)) if match.group(2) else match.group(4, 5)
    )
    first, last = parse_index(first_text), parse_index(last_text)
    if last < first:
        raise InputError(f"a range runs upwards: {kind.code} {last}-{first}")
    if last - first + 1 > MAX_RANGE:
        raise InputError(f"a range holds at most {MAX_RANGE} variables")
    return tuple(VarRef(kind, i) for i in range(first, last + 1)), text[match.end() :]


_TYPE_CODES = "|".join(sorted(KINDS, key=len, reverse=True))  # IO before I
_NEXT_VAR_RE = re.compile(rf"\s*(?:{_TYPE_CODES})\s*\[?\s*\d", re.ASCII | re.IGNORECASE)


def parse_var_list(
    text: str, usage: str, counted: bool = False
) -> tuple[tuple[VarRef, ...], str, int]:
    """Variables and ranges one after another (``P 0 J 0 IO 128-135``), the text after
    them, and how many were written (a label may name one only)."""
    variables, rest = _parse_vars(text, usage)
    specs = 1
    while _NEXT_VAR_RE.match(rest):
        more, rest = _parse_vars(rest, usage)
        variables += more
        specs += 1
    if len(variables) > MAX_RANGE:
        raise InputError(f"at most {MAX_RANGE} variables at once")
    return tuple(dict.fromkeys(variables)), rest, specs


def parse_watch(text: str) -> Watch:
    """``watch P 0``, ``watch IO 128-135 gripper``, ``watch P 0 J 0``, ``... every 0.2``.

    Several variables are all watched; a label (quoted to keep it from being read
    as a variable) names one variable or range, never a list.
    """
    variables, rest, specs = parse_var_list(text, WATCH_USAGE, counted=True)
    label, every, rest = "", None, rest.strip()
    if rest[:1] in ("'", '"'):  # a quoted label is taken whole, "every" inside it too
        close = rest.find(rest[0], 1)
        if close < 0:
            raise InputError(f'the label\'s closing {rest[0]} is missing: watch P 0 "pick"')
        label, rest = rest[1:close], rest[close + 1 :].strip()
    match = re.fullmatch(r"(.*?)\s*\bevery\s+(\S+?)s?", rest, re.ASCII | re.DOTALL)
    if match:
        rest, every = match.group(1).strip(), parse_seconds(match.group(2), "every")
    if label and rest:
        raise InputError(f"after a quoted label only every SECONDS may follow, not {rest!r}")
    label = label or rest
    if label and specs > 1:
        raise InputError(
            "a label names one variable or range: watch P 0 pick, then watch J 0 home "
            '(quote a label that starts like a variable: watch P 0 "J 0 side")'
        )
    return Watch(variables, label, every)


def parse_latency(text: str) -> Latency:
    count_text, _, var_text = text.partition(" ")
    if count_text and not (count_text.isascii() and count_text.isdigit()):
        count_text, var_text = "", text
    count = int(count_text) if count_text else 100
    if not 1 <= count <= MAX_LATENCY_COUNT:
        raise InputError(f"latency takes 1 to {MAX_LATENCY_COUNT} samples, got {count}")
    var = VarRef(kind_of("I"), 0)
    if var_text.strip():
        var, extra = parse_var(var_text, "latency [COUNT] [TYPE INDEX], e.g. latency 1000 I 0")
        if extra.strip():
            raise InputError(f"latency takes a count and a variable, not {extra.strip()!r}")
    return Latency(var, count)


def parse_seconds(text: str, word: str = "interval") -> float:
    """``text`` as a number of seconds (0 to MAX_INTERVAL), ``word`` naming it in the
    refusal: ``interval``, ``every``, ``within``."""
    try:
        seconds = float(text)
    except ValueError:
        raise InputError(
            f"{word} needs a number of seconds, e.g. {word} 0.5, got {text!r}"
        ) from None
    if not MIN_INTERVAL <= seconds <= MAX_INTERVAL:  # also refuses nan and inf
        raise InputError(f"{word} must be from 0 to {MAX_INTERVAL:g} seconds, got {text}")
    return seconds


def parse_connect(text: str, advice: Advice = COMMAND_LINE) -> Connect:
    """``HOST``, ``HOST:PORT``, ``[IPv6]:PORT`` or ``sim``; InputError saying how to
    write one as ``advice``'s front end takes it."""
    if not text or " " in text:
        raise InputError(
            f"connect needs one address: {advice.address} "
            "(or a profile's name, or sim for the built-in simulator)"
        )
    if text == "sim":
        return Connect(None, 5006)
    if text.startswith("["):  # [IPv6]:PORT
        host, closed, port_part = text[1:].partition("]")
        if not closed or (port_part and not port_part.startswith(":")):
            raise InputError(f"write an IPv6 address in brackets: {advice.ipv6}")
        sep, port_text = (":", port_part[1:]) if port_part.startswith(":") else ("", "")
    elif text.count(":") == 1:
        host, sep, port_text = text.partition(":")
    else:
        host, sep, port_text = text, "", ""
    if not host:
        raise InputError(f"connect needs a host: {advice.address}")
    if not sep:
        return Connect(host, 5006)
    if not (port_text.isascii() and port_text.isdigit()) or not 0 < int(port_text) < 65536:
        raise InputError(f"port must be a number from 1 to 65535, got {port_text!r}")
    return Connect(host, int(port_text), port_given=True)
