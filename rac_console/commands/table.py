"""Every command of the language with its usage and one line of help.

The single source for ``help``, completion candidates and argument hints.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class CommandSpec:
    name: str
    arguments: str
    summary: str
    example: str = ""

    @property
    def usage(self) -> str:
        return f"{self.name} {self.arguments}".strip()


COMMANDS: dict[str, CommandSpec] = {
    spec.name: spec
    for spec in (
        CommandSpec("get", "TYPE INDEX", "read a variable", "get P 10"),
        CommandSpec("put", "TYPE INDEX VALUE...", "write a variable", "put I 10 123"),
        CommandSpec(
            "send",
            "TEXT",
            "send TEXT exactly as typed, even malformed",
            "send GET:RC8:10:I:",
        ),
        CommandSpec(
            "watch",
            "TYPE INDEX [LABEL] [every SECONDS]",
            "add variables to the live table",
            "watch IO 128-135",
        ),
        CommandSpec(
            "unwatch", "TYPE INDEX | all", "remove variables from the live table", "unwatch P 10"
        ),
        CommandSpec("interval", "SECONDS", "time between poll cycles", "interval 0.5"),
        CommandSpec("pause", "", "stop polling the watched variables"),
        CommandSpec("resume", "", "start polling again"),
        CommandSpec(
            "connect",
            "HOST[:PORT]",
            "talk to a controller (port 5006 by default)",
            "connect 192.168.0.1",
        ),
        CommandSpec("disconnect", "", "close the session and stop polling"),
        CommandSpec("save", "FILE", "save the watch list as TOML", "save cell3.toml"),
        CommandSpec("load", "FILE", "add the watch list saved in FILE", "load cell3.toml"),
        CommandSpec("frames", "on|off", "echo every frame sent and received (REPL)", "frames on"),
        CommandSpec(
            "latency",
            "[COUNT] [TYPE INDEX]",
            "measure round trips: COUNT GETs back to back (default 100 of I 0)",
            "latency 1000",
        ),
        CommandSpec("clear", "", "clear the frame log"),
        CommandSpec("help", "[COMMAND]", "list commands, or explain one", "help put"),
        CommandSpec("quit", "", "leave the console"),
    )
}

RAW_HELP = "GET:... / PUT:... lines are sent exactly as typed (raw RAC entry)"


def help_lines(topic: str | None = None) -> list[str]:
    """The text of ``help`` or ``help COMMAND``."""
    if topic:
        spec = COMMANDS.get(topic.lower())
        if spec is None:
            return [f"no command {topic!r}: type help for the list"]
        lines = [f"{spec.usage}  -  {spec.summary}"]
        if spec.example:
            lines.append(f"  e.g. {spec.example}")
        if spec.name in ("get", "put", "watch", "unwatch"):
            lines.append("  TYPE: I F D S V P J T IO; I 10, I10 and I[10] name the same variable")
        if spec.name == "put":
            lines.append("  V/P/J/T take 3/7/8/10 numbers, IO takes on|off, S the rest of the line")
        return lines
    width = max(len(s.usage) for s in COMMANDS.values())
    return [f"{s.usage:<{width}}  {s.summary}" for s in COMMANDS.values()] + [RAW_HELP]
