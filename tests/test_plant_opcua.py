"""``--opcua``: the watched values served over OPC UA, read with asyncua's own client.

The CLI runs as a subprocess (``watch``, ``agent``) on the built-in simulator, the
simulator as a process of its own, or a fake controller of the test's that records
what reaches it: a write is judged from the controller's side.
"""

from __future__ import annotations

import asyncio
import re
import shutil
import sys
import time
from collections.abc import Awaitable, Callable, Iterator
from datetime import UTC, datetime, timedelta
from pathlib import Path
from typing import Any

import pytest

from tests.support.drivers import Running, cli, one_error_line
from tests.support.servers import Memory, Recording
from tests.support.serving import start_sim

asyncua = pytest.importorskip("asyncua", exc_type=ImportError)  # Wine 8: cryptography cannot load
from asyncua import Client, ua  # noqa: E402

pytestmark = pytest.mark.slow

NAMESPACE = "urn:rac-console:watched"
DEADLINE = 30.0
SERVING = re.compile(r"over OPC UA at (opc\.tcp://\S+)")


@pytest.fixture
def running() -> Iterator[list[Running]]:
    started: list[Running] = []
    yield started
    for run in started:
        if sys.platform == "win32":  # no SIGINT to send there: its server's process sees
            run.process.kill()  # its pipe close and ends too
            run.process.wait(20)
        else:
            run.stop()


def serve(env: dict[str, str], running: list[Running], *args: str) -> tuple[Running, str]:
    """``rac-console ARGS --opcua opc.tcp://127.0.0.1:0``; the endpoint it serves."""
    run = Running(env, *args, "--opcua", "opc.tcp://127.0.0.1:0")
    running.append(run)
    found: list[str] = []

    def serving() -> bool:
        for line in run.err + run.out:  # the agent says it on stdout
            if match := SERVING.search(line):
                found.append(match.group(1))
                return True
        return False

    run.wait_for("the OPC UA server", serving)
    return run, found[0]


async def until(what: str, holds: Callable[[], Any], deadline: float = DEADLINE) -> None:
    end = time.monotonic() + deadline
    while not await holds():
        assert time.monotonic() < end, f"timed out waiting for {what}"
        await asyncio.sleep(0.05)


async def variable(client: Client, target: str, name: str) -> Any:
    ns = await client.get_namespace_index(NAMESPACE)
    return client.get_node(ua.NodeId(f"{target}/{name}", ns))


async def data_value(node: Any) -> Any:
    """The node's value and status, Bad ones included (a node not made yet: BadNodeIdUnknown)."""
    return await node.read_data_value(raise_on_bad_status=False)


async def served(node: Any) -> bool:
    """The node is there (made at its variable's first read, Good or not)."""
    status = (await data_value(node)).StatusCode.value
    return bool(status != ua.StatusCodes.BadNodeIdUnknown)


async def good(node: Any) -> bool:
    return bool((await data_value(node)).StatusCode.is_good())


def is_good(node: Any) -> Callable[[], Awaitable[bool]]:
    return lambda: good(node)


# ------------------------------------------------------------------------- reading


@pytest.mark.windows  # the server's own process, started from Windows too
async def test_a_client_browses_the_watched_variables_typed_with_the_polls_time(
    env: dict[str, str], running: list[Running]
) -> None:
    started = datetime.now(UTC) - timedelta(seconds=1)
    run, url = serve(env, running, "watch", "I", "1", "F", "1", "D", "1", "S", "1", "IO", "128",
                     "V", "1", "P", "1", "J", "1", "T", "1")  # fmt: skip
    run.wait_for("a line of values", lambda: any("I1=" in line for line in run.out))
    printed = dict(item.split("=", 1) for item in run.out[0].split("\t")[1:])
    async with Client(url) as client:
        ns = await client.get_namespace_index(NAMESPACE)
        folder = await client.nodes.objects.get_child([f"{ns}:RacConsole", f"{ns}:sim"])
        names = [(await child.read_browse_name()).Name for child in await folder.get_children()]
        assert names == ["I1", "F1", "D1", "S1", "IO128", "V1", "P1", "J1", "T1"]
        types = {"I1": "Int32", "F1": "Float", "D1": "Double", "S1": "String", "IO128": "Boolean"}
        for name, kind in [*types.items(), ("V1", "Float"), ("P1", "Float"), ("J1", "Float")]:
            node = await variable(client, "sim", name)
            await until(f"{name} Good", is_good(node))
            data_type = await client.get_node(await node.read_data_type()).read_browse_name()
            assert data_type.Name == kind, name
            rank = await node.read_value_rank()
            assert rank == (1 if name[0] in "VPJT" else -1), name
            value = await node.read_data_value()
            assert started <= value.SourceTimestamp <= datetime.now(UTC) + timedelta(seconds=1)
        i1 = await (await variable(client, "sim", "I1")).read_value()
        s1 = await (await variable(client, "sim", "S1")).read_value()
        io = await (await variable(client, "sim", "IO128")).read_value()
        p1 = await (await variable(client, "sim", "P1")).read_value()
        assert (str(i1), s1, "ON" if io else "OFF") == (
            printed["I1"],
            printed["S1"],
            printed["IO128"],
        )
        assert [f"{x:g}" for x in p1] == printed["P1"].split(",")
        status = await (await variable(client, "sim", "I1")).get_child([f"{ns}:Status"])
        assert await status.read_value() == "OK"


async def test_a_subscription_sees_a_value_changed_at_the_controller(
    env: dict[str, str], running: list[Running]
) -> None:
    port = start_sim(env, running)
    _, url = serve(env, running, "watch", "I", "1", "-H", "127.0.0.1", "-p", str(port),
                   "--interval", "0.1")  # fmt: skip
    seen: list[Any] = []

    class Handler:
        def datachange_notification(self, node: Any, value: Any, data: Any) -> None:
            seen.append(value)

    async with Client(url) as client:
        node = await variable(client, f"127.0.0.1:{port}", "I1")
        await until("I1 Good", lambda: good(node))
        subscription = await client.create_subscription(50, Handler())
        await subscription.subscribe_data_change(node)

        async def first() -> bool:
            return bool(seen)

        await until("the first notification", first)
        assert 77 not in seen
        put = await asyncio.to_thread(
            cli, env, "put", "I", "1", "77", "-H", "127.0.0.1", "-p", str(port), "--direct"
        )
        assert put.returncode == 0, put.stderr

        async def changed() -> bool:
            return 77 in seen

        await until("the change seen", changed)


async def test_values_go_bad_once_the_controllers_port_is_closed(
    env: dict[str, str], running: list[Running]
) -> None:
    port = start_sim(env, running)
    simulator = running[0]
    _, url = serve(env, running, "watch", "I", "1", "S", "1", "-H", "127.0.0.1",
                   "-p", str(port), "--interval", "0.2")  # fmt: skip
    async with Client(url) as client:
        nodes = [await variable(client, f"127.0.0.1:{port}", name) for name in ("I1", "S1")]
        for node in nodes:
            await until("Good", is_good(node))
        simulator.stop()  # its port closes: the next poll is refused

        async def bad() -> bool:
            values = [await data_value(node) for node in nodes]
            return all(v.StatusCode.value == ua.StatusCodes.BadCommunicationError for v in values)

        await until("every value Bad", bad)
        for node in nodes:
            value = await data_value(node)
            assert value.Value is None or value.Value.Value is None  # no stale value served


# ------------------------------------------------------------------------- writing


async def write_status(node: Any, value: ua.Variant) -> str:
    """How the server answered a write: Good, or the Bad status's name."""
    try:
        await node.write_value(ua.DataValue(value))
    except ua.UaStatusCodeError as exc:
        return str(ua.StatusCode(exc.code).name)
    return "Good"


def puts(server: Any) -> list[bytes]:
    return [line for line in server.lines if line.startswith(b"PUT")]


@pytest.mark.windows  # the server's own process, started from Windows too
async def test_a_write_is_refused_by_default_with_nothing_on_the_wire(
    env: dict[str, str], running: list[Running], recording: Recording
) -> None:
    controller = recording(Memory())
    _, url = serve(env, running, "watch", "I", "1", *controller.args)
    async with Client(url) as client:
        node = await variable(client, f"127.0.0.1:{controller.port}", "I1")
        await until("I1 Good", lambda: good(node))
        answer = await write_status(node, ua.Variant(42, ua.VariantType.Int32))
        assert answer in ("BadNotWritable", "BadUserAccessDenied")
        assert await node.read_value() == 1
    # Refused before any job is made for it (answered by the server's process): nothing
    # can still be on its way to the controller once the answer is in.
    assert puts(controller) == []


@pytest.mark.windows  # the server's own process, started from Windows too
async def test_with_writes_a_write_lands_read_back_and_logged_as_from_opc_ua(
    env: dict[str, str], running: list[Running], recording: Recording, tmp_path: Path
) -> None:
    controller = recording(Memory())
    log = tmp_path / "frames.log"
    _, url = serve(env, running, "watch", "I", "1", *controller.args, "--opcua-writes",
                   "--log", str(log))  # fmt: skip
    async with Client(url) as client:
        node = await variable(client, f"127.0.0.1:{controller.port}", "I1")
        await until("I1 Good", lambda: good(node))
        assert await write_status(node, ua.Variant(42, ua.VariantType.Int32)) == "Good"
    assert puts(controller) == [b"PUT:RC8:1:I:3,42"]
    put_at = controller.lines.index(b"PUT:RC8:1:I:3,42")
    assert b"GET:RC8:1:I:" in controller.lines[put_at + 1 :], "read back"
    logged = [line for line in log.read_text().splitlines() if "PUT:RC8:1:I:3,42" in line]
    assert logged and all("[OPC UA]" in line for line in logged)


async def test_a_write_not_read_back_as_written_is_bad(
    env: dict[str, str], running: list[Running], recording: Recording
) -> None:
    controller = recording(Memory(puts="ignore"))  # S_OK, and the old value kept
    _, url = serve(env, running, "watch", "I", "1", *controller.args, "--opcua-writes")
    async with Client(url) as client:
        node = await variable(client, f"127.0.0.1:{controller.port}", "I1")
        await until("I1 Good", lambda: good(node))
        assert await write_status(node, ua.Variant(42, ua.VariantType.Int32)) == "BadDeviceFailure"
    assert puts(controller) == [b"PUT:RC8:1:I:3,42"]


@pytest.mark.parametrize(
    ("args", "name", "value", "expected"),
    [
        (("--read-only",), "I1", ua.Variant(42, ua.VariantType.Int32), "BadUserAccessDenied"),
        ((), "S1", ua.Variant("two\rlines", ua.VariantType.String), "BadTypeMismatch"),
        ((), "I1", ua.Variant("42", ua.VariantType.String), "BadTypeMismatch"),
        ((), "P1", ua.Variant([1.0, 2.0], ua.VariantType.Float), "BadTypeMismatch"),
    ],
    ids=["read-only", "CR in a string", "a string to an I", "two fields of a P"],
)
async def test_a_write_that_cannot_go_is_refused_with_nothing_on_the_wire(
    env: dict[str, str],
    running: list[Running],
    recording: Recording,
    args: tuple[str, ...],
    name: str,
    value: ua.Variant,
    expected: str,
) -> None:
    controller = recording(Memory())
    _, url = serve(env, running, "watch", "I", "1", "S", "1", "P", "1", *controller.args,
                   "--opcua-writes", *args)  # fmt: skip
    async with Client(url) as client:
        node = await variable(client, f"127.0.0.1:{controller.port}", name)
        await until(f"{name} served", lambda: served(node))
        assert await write_status(node, value) == expected
    # Refused before the engine runs anything for it (the value, then the rules, are
    # checked as the write arrives): nothing can still be on its way once answered.
    assert puts(controller) == []


# ------------------------------------------------------------------------- security


async def secured_client(url: str, uri: str, cert: Path, key: Path, folder: Path) -> Client:
    """A client with its own certificate, Basic256Sha256 SignAndEncrypt, trusting the
    server's certificate in ``folder``."""
    from asyncua.crypto.security_policies import SecurityPolicyBasic256Sha256

    client = Client(url)
    client.application_uri = uri
    await client.set_security(
        SecurityPolicyBasic256Sha256,
        str(cert),
        str(key),
        server_certificate=str(folder / "server-cert.der"),
        mode=ua.MessageSecurityMode.SignAndEncrypt,
    )
    return client


@pytest.mark.parametrize("address", ["opc.tcp://0.0.0.0:4840", "opc.tcp://192.0.2.7:4840"])
def test_an_endpoint_off_loopback_without_security_is_refused(
    env: dict[str, str], address: str
) -> None:
    result = cli(env, "watch", "I", "1", "--opcua", address)
    assert result.returncode == 2
    line = one_error_line(result)
    assert "not a loopback address and needs a security policy" in line
    assert "--opcua-security" in line


async def test_a_secured_endpoint_lets_in_only_a_client_whose_certificate_is_trusted(
    env: dict[str, str], running: list[Running], tmp_path: Path
) -> None:
    from asyncua.crypto.cert_gen import setup_self_signed_certificate
    from cryptography.x509.oid import ExtendedKeyUsageOID

    folder = tmp_path / "opcua"
    env = env | {"RAC_CONSOLE_OPCUA_DIR": str(folder)}
    run = Running(env, "watch", "I", "1", "--opcua", "opc.tcp://127.0.0.1:0",
                  "--opcua-security", "encrypt")  # fmt: skip
    running.append(run)
    made = str(folder / "server-cert.der")
    run.wait_for("the certificate said", lambda: any(made in line for line in run.err))
    url = next(m.group(1) for line in run.err if (m := SERVING.search(line)))
    key, cert = tmp_path / "client-key.pem", tmp_path / "client-cert.der"
    uri = "urn:rac-console:tests:client"
    await setup_self_signed_certificate(
        key, cert, uri, "localhost", [ExtendedKeyUsageOID.CLIENT_AUTH], {"commonName": "tests"}
    )

    async def read_with_certificate() -> Any:
        client = await secured_client(url, uri, cert, key, folder)
        async with client:
            return await (await variable(client, "sim", "I1")).read_data_value()

    with pytest.raises(Exception):  # noqa: B017 - refused, however asyncua says it
        await read_with_certificate()
    run.wait_for("where to move it", lambda: any("was refused" in line for line in run.err))
    rejected = list((folder / "rejected").iterdir())
    assert len(rejected) == 1
    shutil.move(str(rejected[0]), folder / "trusted" / rejected[0].name)
    value = await read_with_certificate()
    assert value.StatusCode.is_good() or value.StatusCode.value in (
        ua.StatusCodes.BadWaitingForInitialData,
    )
    with pytest.raises(Exception):  # noqa: B017 - no unsecured endpoint is offered
        async with Client(url) as client:
            await (await variable(client, "sim", "I1")).read_value()


async def test_a_secured_endpoint_takes_no_session_on_an_unsecured_channel(
    env: dict[str, str], running: list[Running], tmp_path: Path
) -> None:
    """A client may ask for the endpoints on a channel with no security (that is how it
    learns the server's certificate), but a session there would read and write in the
    clear without any certificate checked: asyncua takes one unless told not to."""
    env = env | {"RAC_CONSOLE_OPCUA_DIR": str(tmp_path / "opcua")}
    run = Running(env, "watch", "I", "1", "--opcua", "opc.tcp://127.0.0.1:0",
                  "--opcua-security", "encrypt", "--opcua-writes")  # fmt: skip
    running.append(run)
    run.wait_for("the server", lambda: any(SERVING.search(line) for line in run.err))
    url = next(m.group(1) for line in run.err if (m := SERVING.search(line)))
    client = Client(url)
    await client.connect_socket()
    try:
        await client.send_hello()
        await client.open_secure_channel()  # SecurityPolicy#None
        endpoints = await client.uaclient.get_endpoints(ua.GetEndpointsParameters(EndpointUrl=url))
        assert endpoints, "the endpoints are given on it"
        params = ua.CreateSessionParameters()
        params.ClientDescription = ua.ApplicationDescription(ApplicationUri="urn:tests:raw")
        params.ClientNonce = b"n" * 32
        params.EndpointUrl = url
        params.SessionName = "raw"
        params.RequestedSessionTimeout = 60_000
        with pytest.raises(ua.UaStatusCodeError) as refused:
            await client.uaclient.create_session(params)
        assert "SecurityPolicyRejected" in type(refused.value).__name__
    finally:
        client.disconnect_socket()


# ------------------------------------------------------------------------- the agent


@pytest.mark.skipif(sys.platform == "win32", reason="the agent's tests run it on POSIX here")
async def test_the_agent_serves_its_watch_lists_rows_labelled(
    env: dict[str, str], running: list[Running], tmp_path: Path
) -> None:
    watch = tmp_path / "watch.toml"
    watch.write_text('[[watch]]\ntype = "I"\nindex = 1\nlabel = "parts made"\n', encoding="utf-8")
    _, url = serve(env, running, "agent", "--watch", str(watch))
    async with Client(url) as client:
        ns = await client.get_namespace_index(NAMESPACE)
        root = await client.nodes.objects.get_child([f"{ns}:RacConsole"])

        async def one_target() -> bool:
            return len(await root.get_children()) == 1

        await until("the target's folder", one_target)
        (folder,) = await root.get_children()  # the agent's simulator, by its address
        node = await variable(client, (await folder.read_browse_name()).Name, "I1")
        await until("I1 Good", lambda: good(node))
        assert (await node.read_display_name()).Text == "parts made"
        assert "parts made" in (await node.read_description()).Text


async def test_with_a_user_only_its_password_lets_a_client_in(
    env: dict[str, str], running: list[Running], tmp_path: Path
) -> None:
    from asyncua.crypto.cert_gen import setup_self_signed_certificate
    from cryptography.x509.oid import ExtendedKeyUsageOID

    folder = tmp_path / "opcua"
    (folder / "trusted").mkdir(parents=True)
    key, cert = tmp_path / "client-key.pem", folder / "trusted" / "client-cert.der"
    uri = "urn:rac-console:tests:client"
    await setup_self_signed_certificate(
        key, cert, uri, "localhost", [ExtendedKeyUsageOID.CLIENT_AUTH], {"commonName": "tests"}
    )
    env = env | {"RAC_CONSOLE_OPCUA_DIR": str(folder), "RAC_OPCUA_PASSWORD": "s3cret"}
    run = Running(env, "watch", "I", "1", "--opcua", "opc.tcp://127.0.0.1:0",
                  "--opcua-security", "encrypt", "--opcua-user", "operator")  # fmt: skip
    running.append(run)
    run.wait_for("the server", lambda: any(SERVING.search(line) for line in run.err))
    url = next(m.group(1) for line in run.err if (m := SERVING.search(line)))
    assert not any("s3cret" in line for line in run.err + run.out)

    async def read_as(user: str, password: str) -> Any:
        client = await secured_client(url, uri, cert, key, folder)
        client.set_user(user)
        client.set_password(password)
        async with client:
            node = await variable(client, "sim", "I1")
            await until("I1 Good", lambda: good(node))
            return await node.read_value()

    for user, password in (("operator", "wrong"), ("admin", "s3cret")):
        with pytest.raises(ua.UaStatusCodeError) as refused:
            await read_as(user, password)
        assert "Identity" in type(refused.value).__name__ or "Denied" in str(refused.value)
    assert await read_as("operator", "s3cret") == 1


def test_a_user_without_security_or_password_is_refused(env: dict[str, str]) -> None:
    no_security = cli(env, "watch", "I", "1", "--opcua", "opc.tcp://127.0.0.1:0",
                      "--opcua-user", "operator")  # fmt: skip
    assert no_security.returncode == 2
    assert "RAC_OPCUA_PASSWORD" in one_error_line(no_security)
    secured = env | {"RAC_OPCUA_PASSWORD": "s3cret"}
    plain = cli(secured, "watch", "I", "1", "--opcua", "opc.tcp://127.0.0.1:0",
                "--opcua-user", "operator")  # fmt: skip
    assert plain.returncode == 2
    assert "unencrypted" in one_error_line(plain)


async def test_while_polling_is_paused_values_are_uncertain_then_good_again(
    env: dict[str, str],
) -> None:
    """F2 (or ``pause``) stops reading: the values served are no longer the controller's
    present ones, so not Good, until polling resumes."""
    from rac_console.commands.opcua import opcua_settings
    from rac_console.engine import Engine
    from rac_console.engine.setup.options import EngineOptions
    from rac_console.plant.opcua_server import OpcUaServer
    from tests.support.drivers import Front

    server = OpcUaServer(opcua_settings("opc.tcp://127.0.0.1:0", None, False, None, None))
    await asyncio.to_thread(server.start)
    engine = Engine(None, options=EngineOptions(interval=0.1, opcua=server))
    try:
        await asyncio.to_thread(engine.start)
        front = Front(engine)
        await asyncio.to_thread(front.run, "watch I 1")
        async with Client(str(server)) as client:
            node = await variable(client, "sim", "I1")
            await until("I1 Good", lambda: good(node))

            async def code() -> int:
                return int((await data_value(node)).StatusCode.value)

            await asyncio.to_thread(front.run, "pause")

            async def uncertain() -> bool:
                return bool(await code() == ua.StatusCodes.UncertainLastUsableValue)

            await until("I1 Uncertain", uncertain)
            assert (await data_value(node)).Value.Value == 1  # the last value, kept
            await asyncio.to_thread(front.run, "resume")
            await until("I1 Good again", lambda: good(node))
    finally:
        await asyncio.to_thread(engine.stop)
        await asyncio.to_thread(server.stop)


async def test_a_write_queued_behind_a_connect_is_sent_to_neither_controller(
    env: dict[str, str], recording: Recording
) -> None:
    """A client's write is meant for the target it was served from: queued behind a
    typed ``connect`` to another controller, it must not run there (nor at the first)."""
    import threading

    from rac_console.commands.opcua import opcua_settings
    from rac_console.engine import Engine
    from rac_console.engine.setup.options import EngineOptions
    from rac_console.plant.opcua_server import OpcUaServer
    from tests.support.drivers import Front

    held = threading.Event()
    first = recording(Memory(hold=(b"GET:RC8:5:I:", held)))
    second = recording(Memory())
    server = OpcUaServer(opcua_settings("opc.tcp://127.0.0.1:0", None, True, None, None))
    await asyncio.to_thread(server.start)
    options = EngineOptions(interval=0.1, opcua=server, plant_name="cell")  # a member's name
    engine = Engine("127.0.0.1", first.port, options=options)
    try:
        await asyncio.to_thread(engine.start)
        front = Front(engine)
        await asyncio.to_thread(front.run, "watch I 1")
        async with Client(str(server)) as client:
            node = await variable(client, "cell", "I1")
            await until("I1 Good", lambda: good(node))
            engine.submit("get I 5")  # held at the first controller: the jobs wait
            engine.submit(f"connect 127.0.0.1:{second.port}")
            await asyncio.to_thread(
                front.until, lambda: b"GET:RC8:5:I:" in first.lines, "the held get"
            )
            submitted = threading.Event()  # the write handed to the engine, behind the connect
            hand = server._write

            def handed(*args: Any) -> None:
                hand(*args)
                submitted.set()

            server._write = handed  # type: ignore[method-assign,assignment]
            writing = asyncio.create_task(write_status(node, ua.Variant(7, ua.VariantType.Int32)))
            assert await asyncio.to_thread(submitted.wait, DEADLINE), "the write handed over"
            held.set()
            assert await writing == "BadResourceUnavailable"
    finally:
        held.set()
        await asyncio.to_thread(engine.stop)
        await asyncio.to_thread(server.stop)
    assert puts(first) == [] and puts(second) == []
