"""``rac-console check``: the steps between this computer and a controller, in words.

Pure: the session's probe (:mod:`rac_console.session.diagnose`) fills these dataclasses
with what happened; here each failure gets its likely cause and what to check, the exit
status is decided, and the text and JSON are made. Hints live here, not in the probe, so
they can be read and tested without a network.
"""

from __future__ import annotations

import shlex
from dataclasses import dataclass
from typing import Any, Literal

from ..protocol.text import endpoint
from .outcome import ExitStatus

DEFAULT_PORT = 5006

StepName = Literal["resolve", "connect", "get", "round_trip", "second_session"]

#: The steps in the order they are tried; each needs the ones before it.
STEPS: tuple[StepName, ...] = ("resolve", "connect", "get", "round_trip", "second_session")

#: How each step is named on its line.
TITLES: dict[StepName, str] = {
    "resolve": "resolve",
    "connect": "connect",
    "get": "RAC GET",
    "round_trip": "round trip",
    "second_session": "second session",
}

#: What went wrong in a step, as the probe saw it (the hint follows from it).
Problem = Literal[
    "unknown host",  # the name does not resolve
    "dns timeout",  # the name server did not answer in time
    "refused",  # the host said no: nothing listens on the port
    "unreachable",  # no route, network unreachable
    "timed out",  # no answer to the TCP connect
    "closed",  # the controller closed the connection
    "no answer",  # connected, but no reply to a GET in time
    "bad reply",  # a reply that is not RAC
    "error",  # RAC answered an error HRESULT
    "displaced",  # a second connection pushed the first one out
    "failed",  # anything else
]

#: Problems that mean the controller answered: exit 1, not 3.
ANSWERED = frozenset({"error"})


@dataclass(frozen=True)
class StepResult:
    """One step: ok (True, False, or None when it was not tried), how long it took, what
    happened (facts, one line) and, when it failed, the kind of failure."""

    name: StepName
    ok: bool | None
    seconds: float | None = None
    detail: str = ""
    problem: Problem | None = None


@dataclass(frozen=True)
class CheckReport:
    """What ``check`` found at ``host:port``: every step in :data:`STEPS` order."""

    host: str
    port: int
    steps: tuple[StepResult, ...]
    timeout: float = 2.0

    @classmethod
    def of(cls, host: str, port: int, done: list[StepResult], timeout: float) -> CheckReport:
        """The steps tried, then every later one as not tried (the check stops at the
        first failure: a step cannot be judged over one that failed)."""
        tried = {step.name for step in done}
        rest = [StepResult(name, None, detail="not tried") for name in STEPS if name not in tried]
        return cls(host, port, (*done, *rest), timeout)

    @property
    def failed(self) -> StepResult | None:
        return next((step for step in self.steps if step.ok is False), None)

    @property
    def status(self) -> ExitStatus:
        """0 all ok; 1 the controller answered the GET with an error; 3 a connection
        step failed (as every command says a connection failure)."""
        failed = self.failed
        if failed is None:
            return ExitStatus.OK
        if failed.problem in ANSWERED:
            return ExitStatus.CONTROLLER_ERROR
        return ExitStatus.TRANSPORT


def check_command(host: str | None, port: int | None = None) -> str:
    """``rac-console check -H HOST [-p PORT]``: the command that checks this target."""
    words = ["rac-console", "check"]
    if host:
        words += ["-H", host]
    if host and port is not None and port != DEFAULT_PORT:
        words += ["-p", str(port)]
    return shlex.join(words)


def check_pointer(host: str | None, port: int | None = None) -> str:
    """``(rac-console check -H HOST says why)``: added where a connection failure is said,
    so the user learns there is a command that finds which step fails."""
    return f"({check_command(host, port)} says why)"


def hint(step: StepResult, report: CheckReport, no_profile: str | None = None) -> str | None:
    """What to check when ``step`` failed: the likely cause in words. ``no_profile``: the
    name was no profile either (said with a name that does not resolve)."""
    if step.ok is not False:
        return None
    port, timeout = report.port, report.timeout
    where = endpoint(report.host, port)
    rac_port = "RAC listens on 5006" + (
        "" if port == DEFAULT_PORT else f", not {port}, unless changed"
    )
    match step.name, step.problem:
        case "resolve", "dns timeout":
            text = (
                "the name server did not answer: check this computer's DNS settings, "
                "or type the controller's IP address"
            )
        case "resolve", _:
            text = (
                f"{report.host} is no name this computer can resolve: check the spelling, "
                "DNS or the hosts file, or type the controller's IP address"
            )
            if no_profile:
                text += f" ({no_profile})"
        case "connect", "refused":
            text = (
                f"the host is there but nothing accepts connections on port {port}: check "
                f"the port ({rac_port}), that RAC is enabled on the controller (the RAC "
                "server option), and that no firewall rejects the port"
            )
        case "connect", "timed out":
            text = (
                "nothing answered the connection: check the cable, the IP address, and that "
                "this computer has an address in the controller's subnet; a firewall dropping "
                f"port {port} looks the same"
            )
        case "connect", "unreachable":
            text = (
                f"this computer has no way to {report.host}: check the cable (link lights), "
                "the IP address, and that this computer has an address in the controller's "
                "subnet"
            )
        case "connect", "closed":
            text = (
                "the controller took the connection and closed it at once: another client "
                "may hold the only RAC session (an HMI, a PLC, a script, another "
                "rac-console): close it and check again"
            )
        case "connect", _:
            text = f"check the address, the cable and any firewall between here and {where}"
        case "get" | "round_trip", "error":
            text = (
                "the connection and RAC work, but the controller refused this read: see the "
                "error, and the controller's RAC settings"
            )
        case "get" | "round_trip", "no answer":
            text = (
                f"connected, but RAC did not answer: check that port {port} is the controller's "
                "RAC server (the RAC server option enabled) and not another service; another "
                "client holding the only session leaves a connection unanswered too; a busy "
                f"controller may need more than --timeout {timeout:g}"
            )
        case "get" | "round_trip", "bad reply":
            text = (
                f"something answers on port {port}, but not in RAC: check the port "
                f"({rac_port}) and that the controller's RAC server option is enabled"
            )
        case "get" | "round_trip", "closed":
            text = (
                "the controller closed the connection instead of answering: RAC may be "
                "disabled on it (the RAC server option), or another client holds the only "
                "session"
            )
        case "get" | "round_trip", _:
            text = "the link drops replies: check the cable and the network in between"
        case "second_session", "displaced":
            text = (
                "a second connection pushed the first one out: the controller keeps one "
                "session, so another client (an HMI, a PLC, a script, another rac-console) "
                "connecting drops this one"
            )
        case "second_session", _:
            text = (
                "the controller serves one session at a time: when rac-console cannot "
                "connect, another client holds it (an HMI, a PLC, a script, another "
                "rac-console); close that client first"
            )
        case _:
            text = "check the address, the cable and any firewall"
    return text


def step_line(step: StepResult, report: CheckReport, no_profile: str | None = None) -> str:
    """One line per step: ``connect         FAILED  <what happened>: <what to check>``."""
    status = {True: "ok", False: "FAILED", None: "not tried"}[step.ok]
    text = f"{TITLES[step.name]:<15} {status:<7}"
    if step.ok is None:
        return text.rstrip()
    advice = hint(step, report, no_profile)
    return f"{text} {step.detail}" + (f" — {advice}" if advice else "")


def heading(report: CheckReport, profile: str | None, simulator: bool) -> str:
    """What is checked: the address, and the profile or the simulator it stands for."""
    what = endpoint(report.host, report.port)
    if simulator:
        return (
            f"checking the built-in simulator at {what} (no -H: give -H HOST to check a controller)"
        )
    if profile:
        return f"checking {what} (profile {profile})"
    return f"checking {what}"


def report_json(
    report: CheckReport, profile: str | None, simulator: bool, no_profile: str | None = None
) -> dict[str, Any]:
    """The one JSON object of ``check --json``."""
    return {
        "host": report.host,
        "port": report.port,
        "profile": profile,
        "simulator": simulator,
        "ok": report.failed is None,
        "status": int(report.status),
        "steps": [
            {
                "name": step.name,
                "ok": step.ok,
                "seconds": None if step.seconds is None else round(step.seconds, 6),
                "detail": step.detail,
                "problem": step.problem,
                "hint": hint(step, report, no_profile),
            }
            for step in report.steps
        ],
    }
