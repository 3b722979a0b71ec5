"""A frame carries its request: a sent frame the line it sent, a reply the request it
answered (the session knows which exchange it is in), a line nobody asked for none."""

from __future__ import annotations

import contextlib
from collections.abc import Iterator

import pytest

from rac_console.protocol import KINDS, RequestLine, parse_request
from rac_console.protocol.request import raw_request
from rac_console.session import BadReply, Frame, Session
from tests.support.drivers import Front
from tests.support.servers import RecordingServer


def replies_with_their_requests(frames: list[Frame]) -> Iterator[tuple[Frame, Frame]]:
    """Each reply to a request, with the request sent last before it (one in flight)."""
    sent: Frame | None = None
    for frame in frames:
        if frame.direction == "tx":
            sent = frame
        elif not frame.unsolicited and sent is not None:
            yield sent, frame
            sent = None


def test_a_reply_carries_the_request_it_answered_between_polls(front: Front) -> None:
    front.run("watch I 1 I 2")
    front.until(lambda: front.sent().count(b"GET:RC8:2:I:\r") >= 3, "polls of both")
    front.run("put I 10 7")
    front.run("send GET:RC8:10:I:")
    front.run("send FOO")  # malformed: carried all the same
    front.until(lambda: front.sent().count(b"GET:RC8:2:I:\r") >= 6, "polls after them")
    frames = front.frames
    assert any(f.poll for f in frames) and any(not f.poll for f in frames)
    for frame in frames:
        if frame.direction == "tx":
            assert frame.request == parse_request(frame.data)
    pairs = list(replies_with_their_requests(frames))
    assert len(pairs) >= 12
    for request, reply in pairs:
        assert reply.request is not None
        assert reply.request == request.request
        assert reply.poll == request.poll

    def answer_to(data: bytes) -> Frame:
        return next(reply for request, reply in pairs if request.data == data)

    put = answer_to(b"PUT:RC8:10:I:3,7\r").request  # a value as RAC writes it: (vt, value)
    assert put == RequestLine("PUT", (KINDS["I"], 10), "3,7")
    typed = answer_to(b"GET:RC8:10:I:\r")
    assert typed.request is not None and typed.request.is_get and not typed.poll
    assert typed.request.names("I", 10)
    foo = answer_to(b"FOO\r")
    assert foo.request == RequestLine("FOO")
    assert foo.response is not None and not foo.response.ok  # E_INVALIDCOMMAND
    polled = answer_to(b"GET:RC8:1:I:\r")
    assert polled.poll and polled.request is not None and polled.request.names("I", 1)


@pytest.fixture
def two_lines_server() -> Iterator[RecordingServer]:
    """Answers every line with two: the second is a line nobody asked for."""
    server = RecordingServer(lambda line: b"0,3,1\r0,3,2\r")
    try:
        yield server
    finally:
        server.close()


def test_a_line_nobody_asked_for_carries_no_request(two_lines_server: RecordingServer) -> None:
    frames: list[Frame] = []
    with Session("127.0.0.1", two_lines_server.port, timeout=2.0) as session:
        session.add_frame_observer(frames.append)
        for _ in range(2):  # the second line lands with the first, or before the next
            with contextlib.suppress(BadReply):  # two lines for one request: neither taken
                session.exchange(raw_request("GET:RC8:5:I:"))
    asked = parse_request(b"GET:RC8:5:I:\r")
    assert [f.direction for f in frames if not f.unsolicited][:4] == ["tx", "rx", "tx", "rx"]
    for frame in frames:
        assert frame.request == (None if frame.unsolicited else asked)
    assert any(frame.unsolicited for frame in frames)
