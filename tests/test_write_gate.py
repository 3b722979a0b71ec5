"""Every write crosses one gate (issue 43): a command declared never to write has its
write refused at the gate with nothing sent, whichever front end runs it; reads cannot
write; the poller sends its rows' GETs alone; and no code but the gate's hands the
session a request that may write (a structural check, so the next handler cannot go
around it). Judged from the controller's side: a fake controller records every line.
"""

from __future__ import annotations

import ast
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import pytest

from rac_console.cli.main import main
from rac_console.commands.exchange_parsers import parse_put
from rac_console.commands.language import Exchange, Raw, VarRef
from rac_console.commands.outcome import ExitStatus, Outcome
from rac_console.commands.target import Target
from rac_console.engine import Engine, Feedback, Message
from rac_console.engine.commands.builtin import BUILTIN
from rac_console.engine.commands.context import JobContext
from rac_console.engine.commands.registry import EVERYWHERE, CommandSpec
from rac_console.engine.commands.session_context import SessionContext
from rac_console.engine.exchange.execute import execute
from rac_console.engine.watch import rows
from rac_console.protocol import KINDS, InputError
from rac_console.protocol.request import put_for
from rac_console.protocol.variables import MAX_INDEX
from rac_console.session import Session
from tests.support.drivers import Front
from tests.support.servers import Memory, Recording, RecordingServer

PACKAGE = Path(__file__).parent.parent / "rac_console"
REFUSED_AT_THE_GATE = "refused at the write gate: the command 'poke' is declared never to write"
SPEC_SAYS = "(writes=NEVER in its spec's traits); nothing was sent"


@dataclass(frozen=True)
class Poke:
    """``poke TYPE INDEX VALUE`` or ``poke PUT:...``: a write its command does not declare."""

    write: Exchange


def parse_poke(rest: str) -> Poke:
    if not rest:
        raise InputError("poke TYPE INDEX VALUE, or poke PUT:RC8:<index>:<type>:<value>")
    return Poke(Raw.of(rest) if rest.upper().startswith("PUT:") else parse_put(rest))


def run_poke(context: JobContext, command: Poke, line: str | None) -> list[Feedback]:
    """A handler that writes, though its spec declares (by default) that it never does:
    the mistake the gate is there to catch."""
    controller = context.controller
    if controller is None:
        return [Message("not connected", "error")]
    return [controller.exchange(command.write, line)]


#: Declared with the default traits: writes=NEVER.
POKE = CommandSpec(
    "poke",
    "TYPE INDEX VALUE",
    "a write undeclared",
    parse_poke,
    run_poke,
    where=EVERYWHERE,
    types=(Poke,),
)


@pytest.fixture
def poke() -> Iterator[CommandSpec]:
    BUILTIN.register(POKE)
    try:
        yield POKE
    finally:
        BUILTIN.unregister(POKE.name)


@pytest.fixture
def controller(recording: Recording) -> RecordingServer:
    """A fake controller that keeps what is PUT and records every line it receives."""
    return recording(Memory())


def puts(server: RecordingServer) -> list[bytes]:
    return [line for line in server.lines if line.upper().lstrip().startswith(b"PUT")]


def test_the_console_engine_refuses_an_undeclared_write_at_the_gate(
    poke: CommandSpec, controller: RecordingServer
) -> None:
    """The engine behind the console, the REPL, a served console and a CLI watch: the
    handler's PUT (typed, or a raw line) never leaves; a declared put still does."""
    engine = Engine("127.0.0.1", controller.port, interval=0.05, timeout=1.0)
    engine.start()
    front = Front(engine)
    try:
        for line, what in (("poke I 10 5", "PUT I10"), ("poke PUT:RC8:10:I:3,5", "PUT")):
            outcome = front.outcome(line)
            assert outcome.status is ExitStatus.REFUSED
            assert outcome.error == f"{what} {REFUSED_AT_THE_GATE} {SPEC_SAYS}"
        front.run("get I 10")  # answered: every line sent before it has arrived
        assert controller.lines == [b"GET:RC8:10:I:"]
        front.run("put I 10 7")  # put is declared to write: it goes out, read back
        assert puts(controller) == [b"PUT:RC8:10:I:3,7"]
    finally:
        engine.stop()


def test_run_refuses_an_undeclared_write_at_the_gate(
    poke: CommandSpec,
    controller: RecordingServer,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """``rac-console run`` (and the one-shot commands, on the same plain session's
    context): refused, exit 2, nothing on the wire."""
    script = tmp_path / "steps.txt"
    script.write_text("poke I 10 5\npoke PUT:RC8:10:I:3,5\nget I 10\n", encoding="utf-8")
    status = main(
        ["-H", "127.0.0.1", "-p", str(controller.port), "run", "--keep-going", str(script)]
    )
    assert status == ExitStatus.REFUSED
    err = capsys.readouterr().err
    assert err.count(REFUSED_AT_THE_GATE) == 2, err
    assert controller.lines == [b"GET:RC8:10:I:"]


def test_a_context_no_command_declared_lets_no_write_out(controller: RecordingServer) -> None:
    """A context handed out without its command's declaration (a mistake too) fails
    safe: it reads, and refuses every write."""
    session = Session("127.0.0.1", controller.port, timeout=1.0)
    try:
        context = SessionContext(session, Target("127.0.0.1", controller.port))
        target = context.controller
        assert target is not None
        outcome = target.exchange(parse_put("I 3 4"))
        assert outcome.status is ExitStatus.REFUSED
        assert (
            outcome.error is not None and "its caller is declared never to write" in outcome.error
        )
        assert target.get(VarRef(KINDS["I"], 3)).ok
        assert controller.lines == [b"GET:RC8:3:I:"]
    finally:
        session.close()


@pytest.mark.parametrize(
    "write", ["PUT:RC8:1:I:5", " put:rc8:1:i:5", "SET:RC8:1:I:5", "GET:RC8:1:I:x"]
)
def test_the_read_path_sends_nothing_but_a_well_formed_get(
    controller: RecordingServer, write: str
) -> None:
    session = Session("127.0.0.1", controller.port, timeout=1.0)
    try:
        for command in (Raw.of(write), parse_put("I 1 5")):
            outcome: Outcome = execute(session, command)
            assert outcome.status is ExitStatus.REFUSED
            assert outcome.error is not None and "only through the write gate" in outcome.error
        assert execute(session, Raw.of("GET:RC8:1:I:")).ok
        assert controller.lines == [b"GET:RC8:1:I:"]
    finally:
        session.close()


def test_a_watched_row_is_polled_with_a_get_and_nothing_else(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The poller hands the session a row's request alone (held below): every row's is
    a well-formed GET, checked once when the row is first polled, not per poll."""
    for kind in KINDS.values():
        for index in (0, MAX_INDEX):
            assert rows.WatchRow(VarRef(kind, index)).request.read_only_safe
    monkeypatch.setattr(rows, "get_for", lambda kind, index: put_for(kind, index, "5"))
    with pytest.raises(AssertionError, match="must be a GET"):
        _ = rows.WatchRow(VarRef(KINDS["I"], 1)).request


# ------------------------------------------------------------ the structure

#: The session's methods that send a request (``get`` aside: a GET by construction).
SENDS = {"exchange", "put", "send_raw", "_exchange_once"}
#: Where the session is handed a request, and in which functions: the gate's one send
#: of a write, the read path's (a GET, checked so), the poller's rows' GETs, and the
#: agent's relay of a script's request (let out by the gate in the script, and held to
#: the agent's rules again there: ``test_agent_library.py``).
SENDERS = {
    "engine/exchange/gate.py": {"_send"},
    "engine/exchange/execute.py": {"execute", "measure_latency"},
    "engine/polling/poller.py": {"_poll_row"},
    "agent/server.py": {"_request"},
}


def session_sends(tree: ast.Module) -> list[tuple[str, ast.Attribute]]:
    """Each use of a session's sending method in a module (by a name that says session:
    ``session.exchange``, ``self._session.put``, ``link.session.send_raw``), with the
    function it is in."""
    found: list[tuple[str, ast.Attribute]] = []

    def visit(node: ast.AST, function: str) -> None:
        for child in ast.iter_child_nodes(node):
            inside = child.name if isinstance(child, ast.FunctionDef) else function
            if (
                isinstance(child, ast.Attribute)
                and child.attr in SENDS
                and "session" in ast.unparse(child.value).lower()
            ):
                found.append((function, child))
            visit(child, inside)

    visit(tree, "")
    return found


def test_only_the_gate_hands_the_session_a_request_that_may_write() -> None:
    """Outside the session itself (and the simulator's own sessions), only the gate, the
    read path and the poller hand a session a request, each in the functions named."""
    places: dict[str, set[str]] = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        name = path.relative_to(PACKAGE).as_posix()
        if name.startswith(("session/", "sim/")):
            continue
        for function, _ in session_sends(ast.parse(path.read_text(encoding="utf-8"))):
            places.setdefault(name, set()).add(function)
    assert places == SENDERS


def test_the_poller_hands_the_session_its_rows_requests_alone() -> None:
    tree = ast.parse((PACKAGE / "engine/polling/poller.py").read_text(encoding="utf-8"))
    sends = session_sends(tree)
    calls = [
        node
        for node in ast.walk(tree)
        if isinstance(node, ast.Call) and any(node.func is attr for _, attr in sends)
    ]
    assert len(calls) == len(sends) == 1
    assert [ast.unparse(arg) for arg in calls[0].args] == ["row.request"]


def test_no_handler_holds_a_session() -> None:
    """The commands' handlers and their contexts' protocol name no session: they get a
    controller, which reads, and writes through the job's gate."""
    handlers = PACKAGE / "engine/commands"
    for path in [*handlers.glob("builtin/*.py"), handlers / "context.py", handlers / "jobs.py"]:
        tree = ast.parse(path.read_text(encoding="utf-8"))
        names = {n.id for n in ast.walk(tree) if isinstance(n, ast.Name)}
        names |= {n.attr for n in ast.walk(tree) if isinstance(n, ast.Attribute)}
        names |= {
            a.asname or a.name
            for n in ast.walk(tree)
            if isinstance(n, ast.ImportFrom)
            for a in n.names
        }
        assert not {n for n in names if "session" in n.lower()}, path.name
