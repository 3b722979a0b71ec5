"""The agent's one connection per controller, shared by its engines (one per client),
judged from the controller's side: the connections it accepted and the lines it read."""

from __future__ import annotations

from collections.abc import Callable

from rac_console.engine import Engine
from rac_console.protocol import kind_of
from rac_console.session import Frame, Session
from rac_console.session.shared import SharedConnection, SharedSession
from tests.support.drivers import Front
from tests.support.servers import Memory, RecordingServer

INTEGER = kind_of("I")


def shared_to(server: RecordingServer) -> SharedConnection:
    return SharedConnection(Session("127.0.0.1", server.port, timeout=5.0))


def test_a_poll_is_answered_by_a_read_made_for_another_since_its_last_answer(recording) -> None:
    server = recording(Memory())
    connection = shared_to(server)
    a = connection.attach("a", lambda frame: None, 5.0)
    b = connection.attach("b", lambda frame: None, 5.0)
    gets = [
        a.get(INTEGER, 1, poll=True),  # read
        b.get(INTEGER, 1, poll=True),  # a's read is newer than anything b had: no request
        b.get(INTEGER, 1, poll=True),  # nothing read since b's last answer: read
        a.get(INTEGER, 1, poll=True),  # b's read is newer than a's last answer: no request
        a.get(INTEGER, 1),  # typed, not polled: always read
    ]
    connection.close()
    assert [g.response.variant for g in gets] == [gets[0].response.variant] * 5
    assert server.lines == [b"GET:RC8:1:I:"] * 3
    assert server.accepted == 1


def test_engines_share_one_connection_and_see_each_others_writes_tagged(recording) -> None:
    server = recording(Memory())
    connection = shared_to(server)
    foreign: dict[str, list[Frame]] = {"a": [], "b": []}

    def maker(name: str) -> Callable[[str, int, float], Session]:
        def make(host: str, port: int, timeout: float) -> SharedSession:
            return connection.attach(name, foreign[name].append, timeout)

        return make

    engines = {
        name: Engine("127.0.0.1", server.port, interval=0.05, timeout=5.0, sessions=maker(name))
        for name in ("a", "b")
    }
    for engine in engines.values():
        engine.start()
    try:
        a, b = Front(engines["a"]), Front(engines["b"])
        a.run("watch I 7")
        b.run("watch I 7")
        assert b.run("put I 7 42")
        a.until(lambda: a.rows["I7"].variant is not None and a.rows["I7"].variant.value == 42, "42")
        assert any(f.data == b"PUT:RC8:7:I:3,42\r" and f.source == "b" for f in foreign["a"])
        assert not any(f.data.startswith(b"PUT") for f in foreign["b"])  # its own: not foreign
    finally:
        for engine in engines.values():
            engine.stop()
        connection.close()
    assert server.accepted == 1
    assert server.lines.count(b"PUT:RC8:7:I:3,42") == 1


def test_a_poll_after_a_write_is_read_again(recording) -> None:
    """b's poll after b's PUT is not answered by a's read made before the PUT."""
    server = recording(Memory())
    connection = shared_to(server)
    a = connection.attach("a", lambda frame: None, 5.0)
    b = connection.attach("b", lambda frame: None, 5.0)
    a.get(INTEGER, 7, poll=True)  # read: 7
    b.send_raw("PUT:RC8:7:I:3,42")
    after = b.get(INTEGER, 7, poll=True)
    connection.close()
    assert after.response.variant is not None and after.response.variant.value == 42
    assert server.lines == [b"GET:RC8:7:I:", b"PUT:RC8:7:I:3,42", b"GET:RC8:7:I:"]
