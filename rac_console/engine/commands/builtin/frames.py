"""frames, record, transcript, clear, help and quit: what the console and the REPL
do with frames and with themselves."""

from __future__ import annotations

from collections.abc import Sequence

from ....commands.language import (
    FrameFile,
    Frames,
    Help,
    Simple,
    Step,
    frame_file_parser,
    parse_frames,
    parse_help,
)
from ....commands.routing import Reach, Traits
from ....protocol import InputError
from ....protocol.text import terminal_safe
from ...published.events import Feedback, Message, UiStep
from ..context import CommandContext
from ..registry import EngineSpec, Option, Sources, no_argument


def run_frames(context: CommandContext, command: Frames, line: str | None) -> list[Feedback]:
    return [UiStep.FRAMES_ON if command.on else UiStep.FRAMES_OFF]


def run_frame_file(context: CommandContext, command: FrameFile, line: str | None) -> list[Feedback]:
    """``record FILE`` / ``transcript FILE`` from now on (the interesting moment is rarely
    foreseen at start), ``… stop``, or where frames go now."""
    word = command.kind
    flag = "--record" if word == "record" else "--log"
    running = context.frame_file(word)
    if command.stop or command.path is None:
        if running is None:
            return [Message(f"no {word} running: {word} FILE starts one (as {flag} FILE)")]
        if not command.stop:
            return [Message(f"{word} to {terminal_safe(running)}: {word} stop ends it")]
        context.stop_frame_file(word)
        return [Message(f"{word} stopped: {terminal_safe(running)}")]
    if running is not None:
        return [
            Message(f"{word} already goes to {terminal_safe(running)}: {word} stop first", "error")
        ]
    try:
        context.start_frame_file(word, command.path)
    except InputError as exc:
        return [Message(str(exc), "error")]
    what = "every frame as JSON lines" if word == "record" else "a transcript of every frame"
    if context.shares_frame_files:
        what += " of every target, each line naming its target,"
    return [Message(f"{word}: {what} to {terminal_safe(command.path)} ({word} stop ends it)")]


def run_help(context: CommandContext, command: Help, line: str | None) -> list[Feedback]:
    return [Message("\n".join(context.help_lines(command.topic)))]


def run_step(context: CommandContext, command: Simple, line: str | None) -> list[Feedback]:
    return [UiStep.CLEAR if command.step is Step.CLEAR else UiStep.QUIT]


def _on_off(args: list[str], sources: Sources) -> Sequence[Option]:
    return [("on", "echo every frame"), ("off", "stop echoing frames")] if not args else ()


def _commands(args: list[str], sources: Sources) -> Sequence[Option]:
    return sources.commands if not args else ()


#: This module's commands (``help`` lists them in the order of the language's
#: COMMAND_WORDS).
SPECS = (
    EngineSpec(
        "frames",
        "on|off",
        "echo every frame sent and received (REPL)",
        parse_frames,
        run_frames,
        "frames on",
        complete=_on_off,
        types=(Frames,),
    ),
    EngineSpec(
        "record",
        "FILE | stop",
        "append every frame to FILE as JSON lines from now on (as --record)",
        frame_file_parser("record"),
        run_frame_file,
        "record cell3.jsonl",
        notes=(
            "record stop ends it; record alone says where frames go; "
            "rac-console sim --replay FILE serves what was recorded",
        ),
        types=(FrameFile,),
        traits=Traits(reaches=Reach.FILES),
    ),
    EngineSpec(
        "transcript",
        "FILE | stop",
        "append every frame to FILE as a plain timestamped transcript (as --log)",
        frame_file_parser("transcript"),
        run_frame_file,
        "transcript cell3.log",
        notes=("transcript stop ends it; transcript alone says where it goes",),
        types=(FrameFile,),
        traits=Traits(reaches=Reach.FILES),
    ),
    EngineSpec(
        "clear",
        "",
        "clear the frame log (the REPL: the screen)",
        no_argument(Step.CLEAR),
        run_step,
        types=(Simple,),
    ),
    EngineSpec(
        "help",
        "[COMMAND]",
        "list commands, or explain one",
        parse_help,
        run_help,
        "help put",
        complete=_commands,
        types=(Help,),
    ),
    EngineSpec(
        "quit",
        "",
        "leave (Ctrl+Q in the console, Ctrl+D in the REPL)",
        no_argument(Step.QUIT),
        run_step,
        types=(Simple,),
    ),
)
