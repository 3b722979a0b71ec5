"""``get``, ``put`` and ``send`` take their words as the shell passed them.

The real CLI runs as a subprocess against a RecordingServer (127.0.0.1, port 0) and
the tests assert on the exact bytes it received (nothing at all for a refusal) and on
the exit status; the rest are unit tests of the pure ``rac_console.commands.argv``.
"""

from __future__ import annotations

import json
import subprocess
from collections.abc import Iterator, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path

import pytest
from hypothesis import given
from hypothesis import strategies as st

from rac_console.commands.argv import (
    Option,
    SplitWords,
    exchange_from_words,
    find_command,
    input_line,
    looks_like_number,
    split_words,
)
from rac_console.commands.language import Get, Put, Raw, VarRef
from rac_console.protocol import KINDS, VT, InputError, Variant
from tests.support.drivers import cli, json_lines, one_error_line
from tests.support.samples import GET_SAMPLES
from tests.support.servers import RecordingServer, sample_reply

PORT = "{port}"  # replaced by the recording server's port
TARGET = ["-H", "127.0.0.1", "-p", PORT]
WORKERS = 3  # CLI subprocesses at once: most of each one's 0.3 s is start-up


def any_index_reply(line: bytes) -> bytes | None:
    """The vendor's sample answer for the type, whatever the index: GET P3 gets P10's."""
    parts = line.split(b":")
    if line.startswith(b"GET:") and len(parts) == 5:
        sample = GET_SAMPLES.get(b":".join([*parts[:2], b"10", *parts[3:]]))
        if sample is not None:
            return sample + b"\r"
    return sample_reply(line)


@dataclass
class Run:
    """One CLI run against its own recording server."""

    args: list[str]
    server: RecordingServer
    result: subprocess.CompletedProcess[str]


class Runner:
    """Runs CLI argument lists, each against a fresh recording server, a few at a time.

    The servers stay up until the test ends, so a test can still probe them.
    """

    def __init__(self, environment: dict[str, str]) -> None:
        self.environment = environment
        self.servers: list[RecordingServer] = []

    def __call__(self, cases: Sequence[Sequence[str]]) -> list[Run]:
        servers = [RecordingServer(any_index_reply) for _ in cases]
        self.servers += servers
        # The recording server keeps no value, so a PUT goes alone (--no-verify): what
        # reaches the wire is the PUT as typed (read-back has tests of its own).
        argvs = [
            ["--no-verify", *(word.replace(PORT, str(server.port)) for word in args)]
            for args, server in zip(cases, servers, strict=True)
        ]
        with ThreadPoolExecutor(WORKERS) as pool:
            results = list(pool.map(lambda argv: cli(self.environment, *argv), argvs))
        return [
            Run(argv, server, result)
            for argv, server, result in zip(argvs, servers, results, strict=True)
        ]

    def close(self) -> None:
        for server in self.servers:
            server.close()


@pytest.fixture
def run_all(env: dict[str, str]) -> Iterator[Runner]:
    runner = Runner(env)
    yield runner
    runner.close()


# ------------------------------------------------ CLI: what reaches the wire

WIRE_CASES: list[tuple[list[str], bytes]] = [
    # global options after the value, in both spellings
    (["put", "S", "10", "hello", "-H", "127.0.0.1", "-p", PORT], b"PUT:RC8:10:S:8,hello\r"),
    (["put", "I", "10", "-5", "--host=127.0.0.1", f"--port={PORT}"], b"PUT:RC8:10:I:3,-5\r"),
    (["put", "-H", "127.0.0.1", "S", "10", "-p", PORT, "x"], b"PUT:RC8:10:S:8,x\r"),
    (["get", "I", "10", "--timeout", "5", *TARGET], b"GET:RC8:10:I:\r"),
    # negative numbers stay values
    ([*TARGET, "put", "I", "10", "-5"], b"PUT:RC8:10:I:3,-5\r"),
    (
        [*TARGET, "put", "P", "10", "-1", "-2.5", "3", "-1e3", ".5", "-.5", "-1"],
        b"PUT:RC8:10:P:8196,-1,-2.5,3,-1000,0.5,-0.5,-1\r",
    ),
    (["put", "F", "1", "-1e-5", *TARGET], b"PUT:RC8:1:F:4,-1e-05\r"),
    ([*TARGET, "put", "S", "10", "-5"], b"PUT:RC8:10:S:8,-5\r"),
    # after -- every word is the value, verbatim
    ([*TARGET, "put", "S", "10", "--", "--read-only"], b"PUT:RC8:10:S:8,--read-only\r"),
    (["put", "S", "10", *TARGET, "--", "-H", "x"], b"PUT:RC8:10:S:8,-H x\r"),
    ([*TARGET, "send", "--", "-weird-text"], b"-weird-text\r"),
    # a string is what the shell passed
    ([*TARGET, "put", "S", "10", "  two  spaces "], b"PUT:RC8:10:S:8,  two  spaces \r"),
    ([*TARGET, "put", "S", "10", '"quoted"'], b'PUT:RC8:10:S:8,"quoted"\r'),
    ([*TARGET, "put", "S", "10", ""], b"PUT:RC8:10:S:8,\r"),
    ([*TARGET, "put", "S", "10", "hello", "world"], b"PUT:RC8:10:S:8,hello world\r"),
    # the index inside the TYPE word
    ([*TARGET, "get", "P3"], b"GET:RC8:3:P:\r"),
    ([*TARGET, "get", "P[3]"], b"GET:RC8:3:P:\r"),
    ([*TARGET, "get", "p[3]"], b"GET:RC8:3:P:\r"),
    ([*TARGET, "get", "IO128"], b"GET:RC8:128:IO:\r"),
    (
        [*TARGET, "put", "P3", "1", "2", "3", "4", "5", "6", "-1"],
        b"PUT:RC8:3:P:8196,1,2,3,4,5,6,-1\r",
    ),
    ([*TARGET, "put", "IO", "20", "on"], b"PUT:RC8:20:IO:11,-1\r"),
]


@pytest.mark.slow
def test_wire_bytes(run_all: Runner) -> None:
    failures = []
    for run, (_, wire) in zip(run_all([c[0] for c in WIRE_CASES]), WIRE_CASES, strict=True):
        # exit 0 means the reply came, so every byte of the request had arrived by then
        received = run.server.wait_received(len(wire)) if run.result.returncode == 0 else b""
        if (run.result.returncode, received) != (0, wire):
            failures.append((run.args, run.result.returncode, received, run.result.stderr))
    assert failures == []


# ------------------------------------------- CLI: refused, nothing on the wire

REFUSED_CASES: list[tuple[list[str], str]] = [
    (["put", "S", "10", "hello", "--read-only", *TARGET], "read-only"),
    (["put", "S", "10", "hello", *TARGET, "--read-only"], "read-only"),
    ([*TARGET, "put", "S", "10", "--bogus"], "put S 10 -- --bogus"),
    ([*TARGET, "put", "S", "10", "--frobnicate"], "put it after --"),
    ([*TARGET, "put", "S", "10", "hello", "-x"], "'-x' looks like an option"),
    ([*TARGET, "put", "P", "10", "1", "2", "3", "4", "5", "6", "-x"], "'-x'"),
    ([*TARGET, "put", "S", "10"], 'S10 needs a value: write "" for an empty string'),
    ([*TARGET, "put", "S10"], 'S10 needs a value: write "" for an empty string'),
    ([*TARGET, "put", "S", "10", "hello", "-H"], "-H needs a value"),
    ([*TARGET, "put", "S", "10", "a\tb"], "control character"),
    ([*TARGET, "put", "S", "10", "é"], "ASCII"),
    ([*TARGET, "get", "P"], "P needs an index"),
    ([*TARGET, "get", "P3", "4"], "get takes only a variable"),
    ([*TARGET, "get", "I", "10", "--frob"], "'--frob'"),
    ([*TARGET, "send", "-weird-text"], "send -- -weird-text"),
]


@pytest.mark.slow
def test_refused_before_sending(run_all: Runner) -> None:
    failures = []
    for run, (_, expected) in zip(
        run_all([c[0] for c in REFUSED_CASES]), REFUSED_CASES, strict=True
    ):
        result = run.result
        problem = None
        if result.returncode != 2:
            problem = f"exit {result.returncode}"
        elif "Traceback" in result.stderr or not result.stderr.startswith("rac-console: "):
            problem = "not one clear line"
        elif len(result.stderr.strip("\n").split("\n")) != 1 or expected not in result.stderr:
            problem = "message"
        elif run.server.connections() or run.server.received:
            problem = "something was sent"
        if problem:
            failures.append((run.args, problem, result.stderr, bytes(run.server.received)))
    assert failures == []


def test_stray_option_says_how_to_write_it(run_all: Runner) -> None:
    """The advice is the whole command line, ready to paste."""
    (run,) = run_all([[*TARGET, "put", "S", "10", "--frobnicate"]])
    assert run.result.returncode == 2
    assert one_error_line(run.result) == (
        "rac-console: '--frobnicate' looks like an option; to write it as the value "
        "put it after --: rac-console --no-verify -H 127.0.0.1 "
        f"-p {run.server.port} put S 10 -- --frobnicate"
    )
    assert run.server.connections() == []


# ------------------------------------------------------------ CLI: --json anywhere


@pytest.mark.slow
def test_json_after_the_value(run_all: Runner) -> None:
    runs = run_all(
        [
            [*TARGET, "put", "S", "10", "two words", "--json"],
            [*TARGET, "send", "GET:RC8:1:I:", "--json"],
            ["get", "P3", *TARGET, "--json"],
            [*TARGET, "put", "S", "10", "--bogus", "--json"],
        ],
    )
    put, send, get, bogus = (json_lines(run.result.stdout) for run in runs)
    assert [run.result.returncode for run in runs] == [0, 0, 0, 2]
    assert put[0]["request"] == "PUT:RC8:10:S:8,two words"
    assert put[0]["input"] == "put S 10 two words"
    assert send[0]["request"] == "GET:RC8:1:I:"
    assert send[0]["response"] == "0,3,123"
    assert get[0]["request"] == "GET:RC8:3:P:"
    assert bogus[0]["ok"] is False
    assert "put it after --" in bogus[0]["error"]
    assert bytes(runs[3].server.received) == b""


def test_record_after_the_value(run_all: Runner, tmp_path: Path) -> None:
    record = tmp_path / "frames.jsonl"
    (run,) = run_all([[*TARGET, "put", "I", "10", "7", "--record", str(record)]])
    assert run.result.returncode == 0, run.result.stderr
    frames = [json.loads(line) for line in record.read_text().splitlines()]
    assert any("PUT:RC8:10:I:3,7" in json.dumps(frame) for frame in frames)


def test_help_explains_the_double_dash(env: dict[str, str]) -> None:
    top = cli(env, "--help")
    put = cli(env, "put", "--help")
    late = cli(env, "put", "S", "10", "--help")
    for result in (top, put, late):
        assert result.returncode == 0, result.stderr
        assert result.stderr == ""
        assert "--" in result.stdout and "rac-console put S 10 -- -" in result.stdout
    assert put.stdout == late.stdout
    assert put.stdout.startswith("usage: rac-console put")


# ------------------------------------------------------ pure: the option words

OPTIONS = {
    "-h": Option("--help", None),
    "--help": Option("--help", None),
    "-H": Option("--host", "HOST"),
    "--host": Option("--host", "HOST"),
    "--cell": Option("--cell", "NAME"),
    "-p": Option("--port", "PORT"),
    "--port": Option("--port", "PORT"),
    "--timeout": Option("--timeout", "SECONDS"),
    "--json": Option("--json", None),
    "--read-only": Option("--read-only", None),
    "--record": Option("--record", "FILE"),
    "--log": Option("--log", "FILE"),
    "--no-verify": Option("--no-verify", None),
    "--yes": Option("--yes", None),
    "--direct": Option("--direct", None),
}
TOP_OPTIONS = OPTIONS | {
    "--version": Option("--version", None),
    "--watch": Option("--watch", "FILE"),
    "--log-csv": Option("--log-csv", "FILE"),
    "--history": Option("--history", "FILE"),
    "--interval": Option("--interval", "SECONDS"),
    "--mqtt": Option("--mqtt", "URL"),
    "--metrics": Option("--metrics", "[HOST:]PORT"),
    "--opcua": Option("--opcua", "ENDPOINT"),
    "--opcua-security": Option("--opcua-security", "POLICY"),
    "--opcua-writes": Option("--opcua-writes", None),
    "--opcua-user": Option("--opcua-user", "NAME"),
}


def test_the_cli_gives_these_options() -> None:
    from rac_console.cli.main import build_cli

    built = build_cli()
    assert built.command_options == OPTIONS
    assert built.top_options == TOP_OPTIONS


@pytest.mark.parametrize(
    ("words", "options", "operands"),
    [
        (["S", "10", "hello", "--read-only"], ["--read-only"], ["S", "10", "hello"]),
        (["S", "10", "hi", "-H", "h", "-p", "5"], ["--host=h", "--port=5"], ["S", "10", "hi"]),
        (["S", "10", "hi", "--host=h", "--port=5"], ["--host=h", "--port=5"], ["S", "10", "hi"]),
        (["S", "10", "hi", "-Hh", "-p5"], ["--host=h", "--port=5"], ["S", "10", "hi"]),
        (
            ["--json", "I", "10", "-5", "--timeout", "0.5"],
            ["--json", "--timeout=0.5"],
            ["I", "10", "-5"],
        ),
        (["S", "10", "--", "--read-only", "-H", "x"], [], ["S", "10", "--read-only", "-H", "x"]),
        (["S", "10", "--", "--"], [], ["S", "10", "--"]),
        (["S", "10", "-"], [], ["S", "10", "-"]),
        (["S", "10", "hi", "-h"], ["--help"], ["S", "10", "hi"]),
        (["--record", "f.jsonl", "S", "1", "v"], ["--record=f.jsonl"], ["S", "1", "v"]),
        (["S", "1", "v", "-p", "-1"], ["--port=-1"], ["S", "1", "v"]),
        (
            ["P", "1", "-1", "-2.5", "3", "-1e3", ".5", "-.5", "-1"],
            [],
            ["P", "1", "-1", "-2.5", "3", "-1e3", ".5", "-.5", "-1"],
        ),
    ],
)
def test_split_words(words: list[str], options: list[str], operands: list[str]) -> None:
    assert split_words("put", words, OPTIONS) == SplitWords(tuple(options), tuple(operands))


@pytest.mark.parametrize(
    ("command", "words", "message"),
    [
        (
            "put",
            ["S", "10", "--bogus"],
            "'--bogus' looks like an option; to write it as the value put it after --: "
            "rac-console put S 10 -- --bogus",
        ),
        (
            "put",
            ["S", "10", "a b", "-x", "-H", "h"],
            "'-x' looks like an option; to write it as the value put it after --: "
            "rac-console put -H h S 10 'a b' -- -x",
        ),
        ("put", ["S", "10", "--jsno"], "(did you mean --json?)"),
        ("put", ["S", "10", "-inf"], "'-inf' looks like an option"),
        ("send", ["-weird"], "to send it as text put it after --: rac-console send -- -weird"),
        ("get", ["I", "10", "--frob"], "get has no option '--frob'"),
        ("put", ["S", "10", "x", "-H"], "-H needs a value: -H HOST"),
        ("put", ["S", "10", "x", "--timeout", "--json"], "--timeout needs a value"),
        ("put", ["S", "10", "x", "--json=yes"], "--json takes no value"),
    ],
)
def test_split_words_problems(command: str, words: list[str], message: str) -> None:
    split = split_words(command, words, OPTIONS)
    assert split.problem is not None
    assert message in split.problem


def test_problem_suggestion_keeps_the_words_before_the_command() -> None:
    split = split_words("put", ["S", "10", "-x"], OPTIONS, before=["-H", "10.0.0.1"])
    assert split.problem is not None
    assert split.problem.endswith("rac-console -H 10.0.0.1 put S 10 -- -x")


@pytest.mark.parametrize(
    "word", ["-5", "5", "-2.5", "-1e3", "-1e-5", ".5", "-.5", "+3", "-5.", "-0x1F", "-1,-2,3"]
)
def test_numbers(word: str) -> None:
    assert looks_like_number(word)


@pytest.mark.parametrize("word", ["-x", "--5", "-inf", "-nan", "-1e", "-", "", "-1,", "1 2"])
def test_not_numbers(word: str) -> None:
    assert not looks_like_number(word)


@pytest.mark.parametrize(
    ("words", "at"),
    [
        (["get", "I", "1"], 0),
        (["-H", "h", "get"], 2),
        (["--host=h", "--json", "put"], 2),
        (["-Hh", "put"], 1),
        (["--tim", "3", "get"], 2),
        (["--record", "put", "get"], 2),
        (["--json"], None),
        ([], None),
        (["--", "get"], None),
    ],
)
def test_find_command(words: list[str], at: int | None) -> None:
    assert find_command(words, TOP_OPTIONS) == at


# ------------------------------------------------------ pure: words to commands

P, S, IO = KINDS["P"], KINDS["S"], KINDS["IO"]


@pytest.mark.parametrize("words", [["P3"], ["P[3]"], ["p[3]"], ["P", "3"], ["p", "3"], ["P[ 3 ]"]])
def test_get_variable_forms(words: list[str]) -> None:
    assert exchange_from_words("get", words) == Get(VarRef(P, 3))


def test_get_io_index_in_the_word() -> None:
    assert exchange_from_words("get", ["IO128"]) == Get(VarRef(IO, 128))


@pytest.mark.parametrize(
    ("value_words", "value"),
    [
        (["  two  spaces "], "  two  spaces "),
        (['"quoted"'], '"quoted"'),
        (["'single'"], "'single'"),
        ([""], ""),
        (["hello", "world"], "hello world"),
        (["a", "", "b"], "a  b"),
        (["Sample,Test"], "Sample,Test"),
        (["-5"], "-5"),
    ],
)
def test_string_value_is_the_words(value_words: list[str], value: str) -> None:
    command = exchange_from_words("put", ["S", "10", *value_words])
    assert command == Put.of(VarRef(S, 10), Variant(VT.BSTR, value), f"8,{value}")
    assert command.wire == f"PUT:RC8:10:S:8,{value}"


@pytest.mark.parametrize(
    ("words", "wire"),
    [
        (["P3", "1", "2", "3", "4", "5", "6", "-1"], "PUT:RC8:3:P:8196,1,2,3,4,5,6,-1"),
        (["P", "3", "1,2,3", "4", "5", "6", "-1"], "PUT:RC8:3:P:8196,1,2,3,4,5,6,-1"),
        (["IO", "20", "on"], "PUT:RC8:20:IO:11,-1"),
        (["I", "10", "-5"], "PUT:RC8:10:I:3,-5"),
        (["F", "1", "-1e-5"], "PUT:RC8:1:F:4,-1e-05"),
        (["I[7]", "0x10"], "PUT:RC8:7:I:3,16"),
    ],
)
def test_put_other_types(words: list[str], wire: str) -> None:
    command = exchange_from_words("put", words)
    assert isinstance(command, Put)
    assert command.wire == wire


def test_send_takes_the_text() -> None:
    assert exchange_from_words("send", ["-weird-text"]) == Raw.of("-weird-text")
    assert exchange_from_words("send", ["  GET:RC8:1:I:"]) == Raw.of("  GET:RC8:1:I:")
    assert exchange_from_words("send", ["GET:RC8:1:I:", "x"]) == Raw.of("GET:RC8:1:I: x")


@pytest.mark.parametrize(
    ("command", "words", "message"),
    [
        ("put", ["S", "10"], 'S10 needs a value: write "" for an empty string'),
        ("put", ["S[10]"], 'S10 needs a value: write "" for an empty string'),
        ("put", ["S", "10", "a\rb"], "CR or LF"),
        ("put", ["S", "10", "a\nb"], "CR or LF"),
        ("put", ["S", "10", "a\tb"], "control character '\\t'"),
        ("put", ["S", "10", "a\x7fb"], "control character '\\x7f'"),
        ("put", ["S", "10", "é"], "ASCII"),
        ("put", ["S", "10", "x" * 300], "at most 256"),
        ("put", ["P", "10", "1", "2", "3"], "P needs 7 values"),
        ("put", ["I", "10"], "I needs a value"),
        ("put", [], "put TYPE INDEX VALUE"),
        ("get", [], "get TYPE INDEX"),
        ("get", ["P"], "P needs an index"),
        ("get", ["P", "3x"], "'3x'"),
        ("get", ["P", "3 4"], "'3 4'"),
        ("get", ["P3x"], "'P3x'"),
        ("get", ["X", "1"], "unknown variable type 'X'"),
        ("get", ["P3", "4"], "get takes only a variable, not '4': get P3"),
        ("get", ["P", "3", "4", "5"], "get takes only a variable, not '4 5': get P3"),
        ("send", [], "send needs the text"),
        ("send", [""], "send needs the text"),
        ("send", ["a\rb"], "CR or LF"),
    ],
)
def test_words_refused(command: str, words: list[str], message: str) -> None:
    with pytest.raises(InputError) as caught:
        exchange_from_words(command, words)
    assert message in str(caught.value)


def test_input_line_is_the_words_joined() -> None:
    assert input_line("put", ["S", "10", "a b"]) == "put S 10 a b"
    assert input_line("get", ["P3"]) == "get P3"


@given(st.text(st.characters(min_codepoint=0x20, max_codepoint=0x7E), max_size=200))
def test_any_printable_string_after_double_dash_is_written_as_given(text: str) -> None:
    split = split_words("put", ["S", "10", "--json", "--", text], OPTIONS)
    assert split == SplitWords(("--json",), ("S", "10", text))
    command = exchange_from_words("put", split.operands)
    assert command == Put.of(VarRef(S, 10), Variant(VT.BSTR, text), f"8,{text}")
