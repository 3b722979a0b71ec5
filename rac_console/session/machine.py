"""The session's protocol logic without I/O: what to send, and what bytes received mean.

A driver owns the socket; it asks :meth:`SessionMachine.begin` for the bytes of a
request, hands every read to :meth:`feed`, and acts on the :class:`Verdict`: return
the reply, or drop the connection. The rules (one request in flight; a line nobody
asked for, a line too long or a reply that cannot answer its request ends the
connection) live here once, and tests drive them without sockets.
"""

from __future__ import annotations

from dataclasses import dataclass

from ..protocol import FrameTooLong, LineDecoder, ProtocolError, Response
from ..protocol.messages import decode_frame, parse_response
from ..protocol.request import ReplyCheck, Request
from ..protocol.text import escape_bytes
from .types import BadReply, Disconnected, TransportError

#: Bytes of a bad reply quoted in a message; the whole reply is in the log and --record.
QUOTED_BYTES = 120
#: Judged replies kept per connection (then forgotten all at once).
JUDGED_KEPT = 512

Judgement = tuple[Response | None, str | None]

TWO_LINES = "more than one line came for one request: which one answered cannot be told"


@dataclass(slots=True)
class Verdict:
    """What one read meant.

    ``answer`` is the reply line (no CR) to the request in flight, when it came;
    ``response`` its parse, or ``problem`` why it cannot answer the request.
    ``strays`` are lines (with CR) or fragments nobody asked for; ``too_long`` the
    tail of a line that never ended. ``drop``: the connection cannot be trusted now.
    """

    answer: bytes | None = None
    response: Response | None = None
    problem: str | None = None
    strays: tuple[bytes, ...] = ()
    too_long: bytes | None = None
    drop: bool = False
    #: The usual read: one good reply line, nothing else (strays, tail, drop, problem).
    usual: bool = False


class SessionMachine:
    """One connection's protocol state: the request in flight and the bytes held."""

    __slots__ = ("_after_cr", "_decoder", "_judged", "_request", "_usual")

    def __init__(self, max_line: int) -> None:
        self._decoder = LineDecoder(max_line)
        self._request: Request | None = None
        self._after_cr = False
        # Polled replies repeat: a line already judged for the same check is not parsed
        # again (responses are immutable).
        self._judged: dict[tuple[bytes, ReplyCheck | None], Judgement] = {}
        #: The usual read's verdicts (the reply line whole, and good), made once: a
        #: verdict is only read, never changed, once the machine returned it.
        self._usual: dict[tuple[bytes, ReplyCheck | None], Verdict] = {}

    @property
    def in_flight(self) -> Request | None:
        return self._request

    @property
    def pending(self) -> bytes:
        """Bytes of a line begun but not ended."""
        return self._decoder.pending

    def reset(self) -> None:
        """A new connection: nothing in flight, nothing held."""
        self._decoder.clear()
        self._request = None
        self._after_cr = False

    def begin(self, request: Request) -> bytes:
        """The bytes to send for ``request``, now in flight."""
        self._request = request
        return request.data

    def abandon(self) -> None:
        """The request in flight will get no answer (timeout, closed connection)."""
        self._request = None

    def holds_stray(self) -> bool:
        """True when bytes of a line nobody asked for are held (an LF after a CR is not)."""
        pending = self._decoder.pending
        return bool(pending) and pending != b"\n"

    def feed(self, data: bytes) -> Verdict:
        """Take one read; the verdict says whether the request was answered."""
        request = self._request
        if (
            request is not None
            and data.find(b"\r") == len(data) - 1
            and not self._decoder.pending
            and data[0] != 0x0A  # not an LF: a CRLF peer's, held over from the last
        ):
            # The usual read: exactly the reply line, whole. (The rules below, done fast.)
            self._after_cr = True
            self._request = None
            key = (data, request.check)
            verdict = self._usual.get(key)
            if verdict is None:
                line = data[:-1]
                response, problem = self._judge(request, line)
                verdict = Verdict(line, response, problem, drop=problem is not None)
                verdict.usual = problem is None
                if len(self._usual) >= JUDGED_KEPT:
                    self._usual.clear()
                self._usual[key] = verdict
            return verdict
        return self._feed(data)

    def _feed(self, data: bytes) -> Verdict:
        verdict = Verdict()
        strays: list[bytes] = []
        if data == b"\n" and self._after_cr:
            return verdict  # the LF of a CRLF peer's reply, read on its own
        self._after_cr = data.endswith(b"\r")
        try:
            lines = self._decoder.feed(data)
        except FrameTooLong as exc:
            lines = exc.lines
            verdict.too_long = data[-256:]
            verdict.drop = True
        for line in lines:
            request = self._request
            if request is not None and verdict.answer is None:
                self._request = None
                verdict.answer = line
                verdict.response, verdict.problem = self._judge(request, line)
                verdict.drop = verdict.drop or verdict.problem is not None
            else:
                strays.append(line + b"\r")
                verdict.drop = True
        if verdict.too_long is not None and verdict.answer is None and self._request is not None:
            self._request = None
            verdict.problem = f"reply too long: no CR within {self._decoder.max_line} bytes"
        if self._request is None and self.holds_stray() and not verdict.drop:
            # Bytes of a line nobody asked for: never let them prefix the next reply.
            strays.append(self._decoder.pending)
            verdict.drop = True
        verdict.strays = tuple(strays)
        if verdict.answer is not None and verdict.problem is None and strays:
            # More than one line for one request: with no request ids, either may be the
            # answer (a late stray, then the reply), so neither is taken.
            verdict.problem = TWO_LINES
        return verdict

    def _judge(self, request: Request, line: bytes) -> Judgement:
        key = (line, request.check)
        judged = self._judged.get(key)
        if judged is None:
            judged = judge(request, line)
            if len(self._judged) >= JUDGED_KEPT:
                self._judged.clear()
            self._judged[key] = judged
        return judged

    def waiting_verdict(self, data: bytes, still_open: bool) -> Verdict:
        """What waited unread before a request went out (``data``, with what is held):
        nothing harmful only when it is the LF of a CRLF reply on an open connection."""
        waiting = self._decoder.pending + data
        if waiting == b"\n" and still_open:
            self._decoder.clear()
            self._after_cr = False
            return Verdict()
        return Verdict(strays=tuple(as_lines(waiting)), drop=True)


def judge(request: Request, line: bytes) -> Judgement:
    """Parse a reply once and check that it can answer ``request``: the response (None
    when it cannot be parsed) and the problem (None when it can answer)."""
    try:
        response = parse_response(decode_frame(line))
    except ProtocolError as exc:
        return None, str(exc)
    problem = request.check(response) if request.check is not None else None
    return response, problem or None


def bad_reply_message(line: bytes, problem: str) -> str:
    if len(problem) > QUOTED_BYTES:  # a parser's message may quote the reply too
        problem = problem[:QUOTED_BYTES] + "…"
    return f"bad reply '{quoted(line)}': {problem}"


def no_reply(verdict: Verdict) -> TransportError:
    """Why the read that ended a request's wait gives it no reply: the answer failed its
    check, a line grew too long (its tail is in the log), or a line nobody asked for
    dropped the connection."""
    if verdict.problem is None:
        return Disconnected("the connection was dropped: a line nobody asked for came")
    if verdict.answer is None:  # too long: the tail is in the log
        return BadReply(verdict.problem, verdict.too_long)
    return BadReply(bad_reply_message(verdict.answer, verdict.problem), verdict.answer)


def quoted(frame: bytes) -> str:
    """A reply as a message quotes it: escaped, and cut when long (a 64 KiB line of
    garbage must not fill a screen)."""
    if len(frame) <= QUOTED_BYTES:
        return escape_bytes(frame)
    return f"{escape_bytes(frame[:QUOTED_BYTES])}… ({len(frame)} bytes)"


def as_lines(data: bytes) -> list[bytes]:
    r"""``a\rb\rc`` -> ``[a\r, b\r, c]``: waiting bytes as frames, as the log shows lines."""
    *lines, rest = data.split(b"\r")
    frames = [line[1:] + b"\r" if line[:1] == b"\n" else line + b"\r" for line in lines]
    if rest and rest != b"\n":
        frames.append(rest)
    return frames
