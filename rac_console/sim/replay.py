"""``rac-console sim --replay FILE``: a ``--record`` file's answers, served again in order.

A session recorded at a cell can be watched again at the desk: the Nth GET of a
variable gets the Nth answer the controller gave to a GET of it, byte for byte (an
error HRESULT included), so the console is tried against real data with no robot.

Only what the controller said is served, never an invented value:

- Pairs only: a request and the reply that answered it. A reply the session refused,
  a partial or unsolicited line, and a request that got no answer are left out.
- Requests are keyed as the controller reads them (:func:`read_request`), by type and
  index, so ``get:rc8:010:i:`` replays the answers recorded for ``GET:RC8:10:I:``.
- A GET of a variable the file never answered gets E_NOTIMPL: a controller answers no
  well-formed GET with it, so it cannot be mistaken for a recorded error (a recorded
  E_INVALIDARG, say, for an index out of range, is replayed as it was).
- A PUT gets E_ACCESSDENIED: the replay is read-only, so every value it answers is one
  the controller gave. (Accepting writes would mix values nobody recorded into it.)
- Past a variable's last answer it holds that answer (``hold``, the default: it never
  shows a change that did not happen) or starts again from its first (``cycle``).

The order is the replay's, shared by every connection, like one controller's values.

A cell's recording (every line naming its ``target``) is one recording per target, each
paired on its own (:func:`load_recordings`): the targets' lines interleave, and a reply
answers the request of its own target. A file mixing lines with and without a target
is refused: it is two recordings appended to one file.

Pure: no I/O but reading the file; what the user should hear goes to ``notify``. The
file is read a line at a time, never a line longer than :data:`MAX_LINE_BYTES` nor more
than :data:`MAX_FILE_BYTES` in all: a bigger one is refused, said in one line.
"""

from __future__ import annotations

import itertools
import json
import os
import re
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass, field
from typing import BinaryIO

from ..commands.cells import MOST_TARGETS
from ..protocol.hresult import (
    E_ACCESSDENIED,
    E_INVALIDCOMMAND,
    E_INVALIDRCVPACKET,
    E_NOTIMPL,
    E_UNEXPECTED,
)
from ..protocol.text import terminal_safe
from .controller import MAX_REQUEST, code_reply, read_request

END_MODES = ("hold", "cycle")
DEFAULT_END = "hold"
NOT_RECORDED = E_NOTIMPL
READ_ONLY = E_ACCESSDENIED
QUOTED = 40  # characters of a file's value quoted in an error
MAX_TOLD = 4096  # variables told about once each; past that, the notices' rate limit only
#: The longest line a replay reads, in bytes. A --record line holds one frame of at most
#: 64 KiB (the longest reply a session takes), each byte at most 5 characters once
#: escaped and put in JSON (``\\x1b``): about 320 KiB. Longer is no --record line.
MAX_LINE_BYTES = 512 * 1024
#: The largest file a replay loads, in bytes (about half a million answers of a number):
#: every answer is held in memory, so a bigger file is refused, not read.
MAX_FILE_BYTES = 64 * 1024 * 1024
#: A target's name as a cell writes it: a profile's name, or an address (``[::1]:5006``).
_NAME = re.compile(r"[A-Za-z0-9_.:\[\]-]{1,64}", re.ASCII)

Key = tuple[str, int]  # (type code, index): ("I", 10)
Notify = Callable[[str, str], None]  # (kind, text), as Notices.note takes them


class ReplayError(Exception):
    """A record file that cannot be replayed; its text is one line for the user."""


@dataclass
class Recording:
    """The GET answers of one record file, per variable, in the order they came."""

    path: str
    answers: dict[Key, list[bytes]] = field(default_factory=dict)  # reply frames, CR ended
    target: str | None = None  # the cell's target it was recorded from (None: no cell)
    member: int | None = None  # its place in that cell (1: the first), when recorded
    unanswered: int = 0  # requests with no reply, or whose reply was refused or cut off
    unused_replies: int = 0  # unsolicited lines, and replies that answered no request
    not_gets: int = 0  # answered requests that were not GETs (PUTs, raw lines, SIM:)

    @property
    def count(self) -> int:
        return sum(len(replies) for replies in self.answers.values())

    def describe(self, end: str) -> str:
        """The one line said when the replay starts."""
        ignored = [
            f"{n} {what}"
            for n, what in (
                (self.unanswered, "requests with no answer"),
                (self.unused_replies, "unsolicited or unpaired replies"),
                (self.not_gets, "answered PUTs and other non-GET requests"),
            )
            if n
        ]
        skipped = f" (ignored: {', '.join(ignored)})" if ignored else ""
        then = "hold the last" if end == "hold" else "start again from the first"
        of = "" if self.target is None else f" ({terminal_safe(self.target)})"
        return (
            f"replaying {terminal_safe(self.path)}{of}: {len(self.answers)} variables, "
            f"{self.count} answers{skipped}; after a variable's last answer: {then}"
        )


def unescape_text(text: str) -> bytes:
    """The bytes ``escape_bytes`` wrote as ``text``; ValueError for text it never writes."""
    if not (text.isascii() and text.isprintable()):
        raise ValueError("only printable ASCII is written as it is")
    if "\\" not in text:
        return text.encode("ascii")
    out = bytearray()
    i, size = 0, len(text)
    while i < size:
        ch = text[i]
        if ch != "\\":
            out += ch.encode("ascii")
            i += 1
        elif text.startswith("\\\\", i):
            out.append(0x5C)
            i += 2
        elif text[i + 1 : i + 2] == "x" and _is_hex(text[i + 2 : i + 4]):
            out.append(int(text[i + 2 : i + 4], 16))
            i += 4
        else:
            raise ValueError("a backslash that starts no \\\\ or \\xNN")
    return bytes(out)


def _is_hex(pair: str) -> bool:
    return len(pair) == 2 and all(c in "0123456789abcdefABCDEF" for c in pair)


def load_recording(path: str) -> Recording:
    """Read a ``--record`` file of one target (see :func:`load_recordings`)."""
    recordings = load_recordings(path)
    if len(recordings) > 1:
        names = ", ".join(terminal_safe(r.target or "") for r in recordings)
        raise ReplayError(f"{terminal_safe(path)} holds a cell's targets ({names}), not one")
    return recordings[0]


def load_recordings(path: str) -> list[Recording]:
    """Read a ``--record`` file: one recording, or one per target of a cell's, in the
    order they first appear; a target with no answered GET is left out. ReplayError (one
    line) when it cannot be replayed, or is larger than :data:`MAX_FILE_BYTES` or has a
    line longer than :data:`MAX_LINE_BYTES` (refused before either is read whole)."""
    name = terminal_safe(path)
    try:
        with open(path, "rb") as file:
            if os.fstat(file.fileno()).st_size > MAX_FILE_BYTES:  # a pipe says 0: counted
                raise ReplayError(_too_large(name))
            recordings = read_targets(_bounded_lines(file, name), path)
    except OSError as exc:
        reason = terminal_safe(exc.strerror or str(exc))
        raise ReplayError(f"cannot read the replay file {name}: {reason}") from None
    answered = [recording for recording in recordings if recording.answers]
    if not answered:
        raise ReplayError(
            f"{name} holds no GET answered by a controller: nothing to replay "
            "(record one with --record FILE)"
        )
    return answered


def _too_large(name: str) -> str:
    size = f"{MAX_FILE_BYTES // (1024 * 1024)} MiB"
    return (
        f"{name} is larger than {size}, the most a replay loads: replay it in parts "
        f"(split -l 400000 {name} part-) or record shorter sessions"
    )


def _bounded_lines(file: BinaryIO, name: str) -> Iterator[bytes]:
    """The file's lines, none read past :data:`MAX_LINE_BYTES` and none past
    :data:`MAX_FILE_BYTES` in all (a file that grows, or a pipe, is counted as read)."""
    total = 0
    for number in itertools.count(1):
        raw = file.readline(MAX_LINE_BYTES + 1)
        if not raw:
            return
        total += len(raw)
        if total > MAX_FILE_BYTES:
            raise ReplayError(_too_large(name))
        if len(raw.removesuffix(b"\n")) > MAX_LINE_BYTES:
            raise ReplayError(
                f"{name} line {number} is longer than {MAX_LINE_BYTES // 1024} KiB, "
                "more than any --record line (not a --record file?)"
            )
        yield raw


def read_records(lines: Iterable[bytes], path: str) -> Recording:
    """Pair each request with the reply that answered it, line by line (one target)."""
    recordings = read_targets(lines, path)
    return recordings[0] if recordings else Recording(path)


class _Pairing:
    """One target's requests paired with their replies, as its lines come."""

    def __init__(self, recording: Recording, seen: dict[bytes, bytes]) -> None:
        self.recording = recording
        self.seen = seen  # one bytes object per distinct reply: a still value
        self.pending: bytes | None = None  # the request waiting for its reply

    def add(self, direction: str, data: bytes, unusable: str) -> None:
        recording, pending = self.recording, self.pending
        if direction == "tx":
            recording.unanswered += pending is not None
            self.pending = data
            return
        if pending is None or unusable == "unsolicited":  # a waiting request still waits
            recording.unused_replies += 1
            return
        self.pending = None
        if unusable:  # refused or cut off: the request went unanswered
            recording.unanswered += 1
            return
        key = _get_key(pending)
        if key is None:
            recording.not_gets += 1
            return
        reply = data + b"\r"
        recording.answers.setdefault(key, []).append(self.seen.setdefault(reply, reply))

    def finish(self) -> Recording:
        self.recording.unanswered += self.pending is not None
        return self.recording


def read_targets(lines: Iterable[bytes], path: str) -> list[Recording]:
    """One recording per target (one in all for a file of no cell), paired apart."""
    pairings: dict[str | None, _Pairing] = {}
    seen: dict[bytes, bytes] = {}
    for number, raw in enumerate(lines, 1):
        if not raw.strip():
            continue
        target, direction, data, unusable, member = _record(raw, number, path)
        pairing = pairings.get(target)
        if pairing is None:
            if pairings and (target is None or None in pairings):
                raise ReplayError(
                    f"{terminal_safe(path)} line {number}: lines of a cell's targets and "
                    "lines of no target in one file (two recordings appended?): "
                    "replay them apart"
                )
            if len(pairings) == MOST_TARGETS:
                raise ReplayError(
                    f"{terminal_safe(path)} line {number}: more than {MOST_TARGETS} "
                    "targets, more than a cell holds"
                )
            pairing = pairings[target] = _Pairing(Recording(path, target=target), seen)
        if pairing.recording.member is None:
            pairing.recording.member = member
        pairing.add(direction, data, unusable)
    return in_cell_order([pairing.finish() for pairing in pairings.values()])


def in_cell_order(recordings: list[Recording]) -> list[Recording]:
    """A cell's targets in the cell's order (each line records its place in the cell),
    else by name: never by which target happened to write first, so each target gets
    the same port every run."""
    if all(r.member is not None for r in recordings):
        return sorted(recordings, key=lambda r: (r.member or 0, (r.target or "").casefold()))
    return sorted(recordings, key=lambda r: (r.target or "").casefold())


def _record(raw: bytes, number: int, path: str) -> tuple[str | None, str, bytes, str, int | None]:
    """One line's target, direction, its bytes, why a reply cannot be used ("" when
    it can), and its target's place in the cell (None: not recorded)."""
    where = f"{terminal_safe(path)} line {number}"
    try:
        record = json.loads(raw)
    except (ValueError, RecursionError):  # RecursionError: nesting too deep to read
        raise ReplayError(f"{where} is not JSON (not a --record file?)") from None
    if not isinstance(record, dict):
        raise ReplayError(f"{where} is not a recorded frame (a JSON object)")
    direction, text = record.get("dir"), record.get("text")
    if direction not in ("tx", "rx"):
        raise ReplayError(f'{where}: \'dir\' must be "tx" or "rx", not {_quoted(direction)}')
    if not isinstance(text, str):
        raise ReplayError(f"{where}: 'text' must be a string, not {_quoted(text)}")
    target = record.get("target")
    if target is not None and not (isinstance(target, str) and _NAME.fullmatch(target)):
        raise ReplayError(f"{where}: 'target' is no target's name: {_quoted(target)}")
    try:
        data = unescape_text(text)
    except ValueError:
        raise ReplayError(
            f"{where}: 'text' is not as --record writes it: {_quoted(text)}"
        ) from None
    member = record.get("member")
    place = member if isinstance(member, int) and not isinstance(member, bool) else None
    return target, direction, data, _unusable(record, data), place


def _unusable(record: dict[str, object], data: bytes) -> str:
    if record.get("partial"):
        return "partial"
    if record.get("refused") is not None:
        return "refused"
    if record.get("unsolicited"):
        return "unsolicited"
    if b"\r" in data:  # it could not be sent again as one reply
        return "refused"
    return ""


def _quoted(value: object) -> str:
    text = json.dumps(value)
    if len(text) > QUOTED:
        text = text[: QUOTED - 1] + "…"
    return terminal_safe(text)


def _get_key(request: bytes) -> Key | None:
    """The variable a well-formed GET reads; None for anything else."""
    try:
        parsed = read_request(request.decode("ascii"))
    except UnicodeDecodeError:
        return None
    if parsed is None or parsed[0] != "GET" or parsed[3].strip(" \t"):
        return None
    return parsed[1].code, parsed[2]


class ReplayController:
    """Answers request lines from a :class:`Recording`, as the server's controller.

    It keeps no replies (``known_frames`` stays empty): the same line is answered with
    the next recorded value each time, so the server's fast path never serves it.
    """

    def __init__(
        self, recording: Recording, end: str = DEFAULT_END, notify: Notify | None = None
    ) -> None:
        if end not in END_MODES:
            raise ValueError(f"end must be one of {', '.join(END_MODES)}, not {end!r}")
        self.recording = recording
        self.end = end
        self.notify = notify  # (kind, text) for Notices.note; set once the server has one
        self.requests = 0
        self.known_frames: dict[bytes, bytes] = {}  # the server's fast path: never filled
        self._next: dict[Key, int] = {}
        self._told: set[tuple[str, Key]] = set()

    def forget(self) -> None:
        """Nothing is kept, so nothing to drop (the server calls it after SIM: lines)."""

    def handle(self, line: bytes) -> tuple[bytes, bool]:
        """The reply frame (CR included) to one request line, and whether to close."""
        self.requests += 1
        if len(line) + 1 > MAX_REQUEST:
            return code_reply(E_INVALIDRCVPACKET), True
        try:
            return self._answer(line.decode("ascii")), False
        except UnicodeDecodeError:
            return code_reply(E_INVALIDCOMMAND), False
        except Exception:  # a bug here must cost one answer, never the session
            return code_reply(E_UNEXPECTED), False

    def _answer(self, text: str) -> bytes:
        request = read_request(text)
        if request is None:
            return code_reply(E_INVALIDCOMMAND)
        command, kind, index, parameter = request
        key = (kind.code, index)
        if command == "PUT":
            self._say("put", key, "refused (E_ACCESSDENIED): a replay is read-only")
            return code_reply(READ_ONLY)
        if parameter.strip(" \t"):
            return code_reply(E_INVALIDCOMMAND)
        replies = self.recording.answers.get(key)
        if replies is None:
            self._say("unrecorded", key, "not in the recording: answered E_NOTIMPL")
            return code_reply(NOT_RECORDED)
        n = self._next.get(key, 0)
        if n == len(replies):  # past the last answer
            n = 0 if self.end == "cycle" else n - 1
            then = "holding the last" if self.end == "hold" else "starting again from the first"
            self._say("end", key, f"past its {len(replies)} recorded answers: {then}")
        self._next[key] = n + 1
        return replies[n]

    def _say(self, kind: str, key: Key, text: str) -> None:
        """Tell the user once per variable and kind (the notices rate-limit the rest)."""
        if self.notify is None or (kind, key) in self._told or len(self._told) >= MAX_TOLD:
            return
        self._told.add((kind, key))
        code, index = key
        verb = "PUT" if kind == "put" else "GET"
        self.notify(f"replay-{kind}", f"replay: {verb}:RC8:{index}:{code}: {text}")
