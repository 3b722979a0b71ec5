"""The first line on a live target, shared by the console's welcome and the REPL's
banner: which controller this is, under which profile and write rules, before anything
is typed, so a robot is never taken for the simulator."""

from __future__ import annotations

from collections.abc import Sequence

from rich.text import Text

from ..engine.published.events import Status
from ..protocol.text import terminal_safe
from .status import label_text


def live_banner(status: Status) -> Text:
    """``LIVE controller 192.168.0.1:5006, profile cell3 (Cell 3 — welding): writes
    confirm.`` (``LIVE controller HOST:PORT.`` without a profile)."""
    return Text.assemble(
        ("LIVE", "bold white on red"),
        f" controller {terminal_safe(f'{status.host}:{status.port}')}",
        profile_words(status),
        ".",
    )


def profile_words(status: Status) -> str:
    """``, profile cell3 (Cell 3 — welding): writes confirm`` for a profile, else ''."""
    if status.profile is None:
        return ""
    label = f" ({label_text(status.label)})" if status.label else ""
    return f", profile {terminal_safe(status.profile)}{label}: writes {status.writes}"


def cell_banner(names: Sequence[str], next_key: str) -> Text:
    """A cell's welcome: its targets, and how a line reaches each."""
    return Text(
        f"A cell of {len(names)} targets ({terminal_safe(', '.join(names))}): lines go to "
        f"the one the prompt names; @NAME LINE runs a line on another; use NAME (or "
        f"{next_key}) changes the current one.",
        style="bold",
    )


def simulated_banner(names: Sequence[str]) -> Text:
    """Targets that are simulators this program started (``--cell demo``): said under
    the cell's banner, so that no one takes their values for a robot's."""
    shown = terminal_safe(" and ".join(names))
    verb = "is a simulator" if len(names) == 1 else "are simulators"
    return Text.assemble(
        ("SIMULATOR", "bold black on yellow"),
        f" {shown} {verb} playing a handshake, not controllers (--cell demo).",
    )


def welcome_lines(
    names: Sequence[str],
    status: Status | None,
    simulated: Sequence[str],
    version: str,
    next_key: str = "F8",
) -> list[Text]:
    """What the console says first: the cell and its simulated targets, or the one
    target (the simulator marked, a controller's banner), then how to begin."""
    from ..engine import SIMULATOR_NOTICE

    lines: list[Text] = []
    if len(names) > 1:
        lines.append(cell_banner(names, next_key))
        if simulated:
            lines.append(simulated_banner(simulated))
    elif status is not None and status.is_simulator:
        lines.append(Text.assemble(("SIMULATOR", "bold black on yellow"), f" {SIMULATOR_NOTICE}."))
    elif status is not None:
        lines.append(live_banner(status))
    begin = f"rac-console {version}: type help, or try watch P 0, watch IO 0-7, get S 1"
    lines.append(Text(begin, style="dim"))
    return lines


def repl_banner(names: Sequence[str], status: Status | None) -> Text | None:
    """The REPL's first line: the cell, the simulator, or the live controller with its
    profile and write rules; then how to get help and out (None: no session yet)."""
    from ..engine import SIMULATOR_NOTICE

    if len(names) > 1:
        return Text.assemble(
            ("cell", "bold"),
            f" of {len(names)} targets: {', '.join(names)}. Lines run "
            "on the one the prompt names; @NAME LINE runs one elsewhere, use NAME changes "
            "it. help lists the commands; Ctrl-D leaves.",
        )
    if status is None or not status.has_session:
        return None
    if status.is_simulator:
        return Text.assemble(
            ("sim", "bold yellow"),
            f": {SIMULATOR_NOTICE}. help lists the commands; Ctrl-D leaves.",
        )
    return Text.assemble(live_banner(status), " help lists the commands; Ctrl-D leaves.")
