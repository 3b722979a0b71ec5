"""The status line: target, connection, round trip, poll cycle, badges."""

from __future__ import annotations

import time
from collections.abc import Mapping
from dataclasses import dataclass
from itertools import pairwise

from rich.cells import cell_len, set_cell_size
from rich.color import Color, ColorParseError
from rich.style import Style
from rich.text import Text

from ..commands.policy import TargetProfile
from ..engine.published.status import LABEL_WIDTH, Status, shown_label
from ..protocol.text import terminal_safe

#: A reply is shown as awaited once it is this late (seconds): quicker ones would flicker.
WAITING_SHOWN_AFTER = 0.2
#: A typed line is shown as running once it has run this long (seconds).
RUNNING_SHOWN_AFTER = 0.5
#: Characters of a running line shown.
RUNNING_WIDTH = 24


def profile_colour(colour: str | None) -> Color | None:
    """A profile's colour as Rich knows it; None when it names no colour Rich knows
    (the config file checks only its spelling): the front ends then use their own."""
    if not colour:
        return None
    try:
        return Color.parse(colour)
    except ColorParseError:
        return None


def _luminance(colour: Color) -> float:
    """WCAG relative luminance of ``colour`` (its truecolor: a name by Rich's palette)."""

    def linear(value: int) -> float:
        channel = value / 255
        return channel / 12.92 if channel <= 0.04045 else ((channel + 0.055) / 1.055) ** 2.4

    red, green, blue = colour.get_truecolor()
    return 0.2126 * linear(red) + 0.7152 * linear(green) + 0.0722 * linear(blue)


def contrast(first: Color, second: Color) -> float:
    """The WCAG contrast ratio of two colours: 1 (none) to 21 (black on white)."""
    lighter, darker = sorted((_luminance(first), _luminance(second)), reverse=True)
    return (lighter + 0.05) / (darker + 0.05)


_BLACK = Color.parse("#000000")
_WHITE = Color.parse("#ffffff")


def ink_on(colour: Color) -> str:
    """Black or white, whichever contrasts more with ``colour`` (WCAG)."""
    return "black" if contrast(_BLACK, colour) >= contrast(_WHITE, colour) else "white"


def label_style(colour: str | None) -> Style:
    """The label's block: the profile's colour behind, black or white ink, whichever
    contrasts more; reversed default colours for a profile without a colour (or with one
    nobody knows). Both as truecolor: a theme maps named colours (``red``) to its own,
    and the ink was chosen for this one."""
    parsed = profile_colour(colour)
    if parsed is None:
        return Style(bold=True, reverse=True)
    background = Color.from_rgb(*parsed.get_truecolor())
    ink = _BLACK if ink_on(parsed) == "black" else _WHITE
    return Style(bold=True, color=ink, bgcolor=background)


def target_label(status: Status, width: int = LABEL_WIDTH) -> str | None:
    """The profile's label (or its name) as shown: escaped, cut with ``…`` to ``width``
    cells (:data:`LABEL_WIDTH` by default); None without a profile."""
    text = status.label or status.profile
    if not text:
        return None
    return label_text(text, width)


def label_text(label: str, width: int = LABEL_WIDTH) -> str:
    """A profile's label wherever it is shown: escaped, cut with ``…`` to ``width``
    cells (:data:`LABEL_WIDTH` by default; wide characters count 2)."""
    return _cut(shown_label(label, width), width)


def connect_targets(profiles: Mapping[str, TargetProfile]) -> list[tuple[str, str]]:
    """What ``connect`` completes to besides sim: each profile's name, with its label (or
    its address) cut as a label is shown, as the candidate's help."""
    if not profiles:
        return []  # no config file: the profiles' rules need not load
    from ..commands.profiles import completion_targets

    return [(name, label_text(about)) for name, about in completion_targets(profiles)]


def _cut(text: str, width: int) -> str:
    """``text`` cut to ``width`` cells, ending in ``…`` when cut."""
    if cell_len(text) <= width:
        return text
    return set_cell_size(text, width - 1).rstrip() + "…"


#: The label's share of a line of a given width: a quarter, within these bounds (cells).
LABEL_MIN = 8
#: Styles of the badges; truecolor, so a theme cannot turn them into one another.
LIVE_STYLE = Style.parse("bold #ff5f5f on #262626")  # not a block of red: labels are
SIMULATOR_STYLE = Style.parse("bold #000000 on #ffd700")
NO_SESSION_STYLE = Style.parse("bold #ffffff on #585858")
READ_ONLY_STYLE = Style.parse("bold #ffffff on #005fd7")
CONFIRM_STYLE = Style.parse("bold #ffffff on #8700af")
ALARM_STYLE = Style.parse("bold #ffffff on #d70000")
CSV_STYLE = Style.parse("bold #000000 on #5fd75f")
RUNNING_STYLE = Style.parse("bold #000000 on #ffd700")


@dataclass(slots=True)
class _Field:
    """One field of the status line: its forms, longest first, all whole."""

    forms: list[Text]
    badge_start: bool = False  # begins with a badge: a space before it, not " · "
    badge_end: bool = False  # ends with one: a space after it
    essential: bool = False  # kept (shortened, not dropped) while anything else can go
    droppable: bool = True  # may go once the rest is as short as it gets
    last_resort: int = 0  # how many of the shortest forms wait until the label is short


def _badge(text: str, style: Style | str, **kind: bool) -> _Field:
    return _Field([Text(f" {text} ", style=style)], badge_start=True, badge_end=True, **kind)


def _figure(
    *forms: Text | str, essential: bool = False, droppable: bool = True, last_resort: int = 0
) -> _Field:
    texts = [form if isinstance(form, Text) else Text(form) for form in forms]
    return _Field(texts, essential=essential, droppable=droppable, last_resort=last_resort)


def _fields(
    status: Status,
    waiting_since: float | None,
    frames_per_second: float,
    running: tuple[str, float, int] | None,
    label_width: int,
) -> list[_Field]:
    """Every field of the line, highest priority first (also left to right)."""
    fields: list[_Field] = []
    text = status.label or status.profile
    if text:  # first: two consoles on two robots can't be mixed up
        style = label_style(status.colour)
        safe = shown_label(text)  # at most LABEL_WIDTH characters: cut again below
        widths = range(min(label_width, cell_len(safe)), LABEL_MIN - 1, -1)
        forms: list[Text] = []
        for width in widths:
            form = Text(f" {_cut(safe, width)} ", style=style)
            if form not in forms:
                forms.append(form)
        fields.append(_Field(forms or [Text(f" {safe} ", style=style)], True, True, True))
    if not status.has_session:
        target_style = NO_SESSION_STYLE
    elif status.is_simulator:
        target_style = SIMULATOR_STYLE
    else:
        target_style = LIVE_STYLE
    target = terminal_safe(status.target)
    # On a small screen the simulator is still named one, in a word.
    short = target.removesuffix(" (built-in)")
    forms = [Text(f" {name} ", style=target_style) for name in dict.fromkeys((target, short))]
    fields.append(_Field(forms, True, True, essential=True, droppable=False))
    # The writes mode changes what a command does: never off a narrow screen.
    if status.read_only:
        fields.append(_badge("READ-ONLY", READ_ONLY_STYLE, essential=True, droppable=False))
    elif status.writes == "confirm":
        fields.append(_badge("CONFIRM WRITES", CONFIRM_STYLE, essential=True, droppable=False))
    elif status.writes == "open":
        shown = Text("writes open", style="dim" if status.is_simulator else "")
        fields.append(_figure(shown, essential=True, droppable=False))
    # So are the failures that decide the exit status (README: first, never cut off).
    if status.record_failure is not None:
        fields.append(_badge("RECORDING STOPPED", ALARM_STYLE, essential=True))
    if status.csv_log is None and status.csv_failure is not None:
        fields.append(_badge("CSV LOG STOPPED", ALARM_STYLE, essential=True))
    fields.append(_connection(status))
    if status.via:  # the session is the agent's, shared with its other clients
        fields.append(_figure(terminal_safe(status.via), essential=True))
    if running is not None and running[1] >= RUNNING_SHOWN_AFTER:
        fields.append(_running(*running))
    connected = status.connection == "connected" and status.has_session
    rtt = status.rtt if connected else None
    fields.append(_figure(f"rtt {rtt * 1000:.2f} ms" if rtt is not None else "rtt –"))
    if connected and waiting_since is not None:
        waited = time.perf_counter() - waiting_since
        if waited >= WAITING_SHOWN_AFTER:
            fields.append(
                _figure(
                    Text(
                        f"waiting for a reply {waited:.1f} s of {status.timeout:g} s",
                        style="bold yellow",
                    ),
                    Text(f"waiting {waited:.1f} s", style="bold yellow"),
                )
            )
    if status.csv_log is not None:  # a new log runs: an earlier failure is for the exit
        fields.append(_badge("CSV", CSV_STYLE))
    if status.broker is not None:  # the watched values go to an MQTT broker
        fields.append(_mqtt(status.broker))
    if status.paused:
        fields.append(_figure(Text("POLLING PAUSED", style="bold yellow")))
    elif (
        connected
        and status.watched
        and status.cycle_seconds is not None
        and status.polls_per_second
    ):
        period = status.period
        cycle = Text(f"cycle {status.cycle_seconds * 1000:.0f} ms")
        cycle.append(" back to back" if period == 0 else f"/{period:g} s")
        if not status.interval_met:
            cycle.append(" NOT MET", style="bold yellow")
        fields.append(_figure(cycle))
        fields.append(_figure(f"{status.polls_per_second:.0f} polls/s"))
    if frames_per_second:
        fields.append(_figure(Text(f"{frames_per_second:.0f} frames/s", style="dim")))
    return fields


#: The MQTT badge by the broker's state: publishing must not look healthy when it is not.
MQTT_BADGES = {
    "connected": ("MQTT", CSV_STYLE),
    "connecting": ("MQTT …", CONFIRM_STYLE),
    "away": ("MQTT LOST", ALARM_STYLE),
    "silent": ("MQTT NO BROKER", ALARM_STYLE),
    "refused": ("MQTT REFUSED", ALARM_STYLE),
    "broken": ("MQTT BROKEN", ALARM_STYLE),
    "tls": ("MQTT TLS", ALARM_STYLE),
    "stopped": ("MQTT STOPPED", ALARM_STYLE),
}


def _mqtt(state: str) -> _Field:
    text, style = MQTT_BADGES.get(state, MQTT_BADGES["connecting"])
    return _badge(text, style, essential=style is ALARM_STYLE)


#: How the status line names each reason a connection could not be opened.
CANNOT_CONNECT = {
    "refused": ("connection refused", "refused"),
    "unreachable": ("host unreachable", "unreachable"),
    "timed out": ("connect timed out", "timed out"),
    "unknown host": ("unknown host", "no host"),
    "failed": ("cannot connect", "no connect"),
}


def _connection(status: Status) -> _Field:
    """The connection's state; during a backoff, the countdown to the next try. A
    connection that never opened says why (refused, unreachable, …), never a state that
    reads as quiet and healthy."""
    state = status.connection
    if status.retry_at is not None and (state in ("lost", "dropped") or state in CANNOT_CONNECT):
        wait = max(0.0, status.retry_at - time.monotonic())
        what, short = {"lost": ("lost", "lost"), "dropped": ("dropped early", "dropped")}.get(
            state, CANNOT_CONNECT.get(state, (state, state))
        )
        return _figure(
            Text(f"{what}, retrying in {wait:.1f} s (backoff)", style="bold red"),
            Text(f"{what}, retrying in {wait:.1f} s", style="bold red"),
            Text(f"{short}, retry {wait:.1f} s", style="bold red"),
            Text(f"retry {wait:.1f} s", style="bold red"),
            essential=True,
            droppable=False,
            last_resort=1,
        )
    if state == "engine stopped":  # its thread died: nothing polls or answers
        return _figure(
            Text("ENGINE STOPPED: restart rac-console", style="bold white on red"),
            Text("ENGINE STOPPED", style="bold white on red"),
            essential=True,
            droppable=False,
            last_resort=1,
        )
    if state == "lost":  # found dead while idle: nothing retries until a command
        return _figure(
            Text("lost, the next command reconnects", style="bold red"),
            Text("connection lost", style="bold red"),
            Text("lost", style="bold red"),
            essential=True,
            droppable=False,
            last_resort=1,
        )
    if state in CANNOT_CONNECT:
        long, short = CANNOT_CONNECT[state]
        return _figure(
            Text(f"{long}, the next command retries", style="bold red"),
            Text(long, style="bold red"),
            Text(short, style="bold red"),
            essential=True,
            droppable=False,
            last_resort=1,
        )
    if state == "connected":
        shown = Text("connected", style="green")
    elif state == "connecting":
        shown = Text("connecting…", style="yellow")
    elif not status.has_session:
        shown = Text("disconnected", style="dim")
    elif status.ever_connected:  # closed after a timeout or a bad reply: reopened on use
        shown = Text("closed, reopened when needed", style="yellow")
    else:
        shown = Text("not connected yet", style="yellow")
    return _figure(shown, essential=True, droppable=False)


def _running(line: str, seconds: float, queued: int) -> _Field:
    """The way out of a long line: ``Esc cancels``, the line, how long, how many wait;
    shorter forms drop the line, then words, never the countdown."""
    safe = terminal_safe(line)
    count = f" ({seconds:.0f} s) "
    forms: list[Text] = []
    for what, waiting in (
        (f" Esc cancels: {_cut(safe, RUNNING_WIDTH)}", f" +{queued} queued"),
        (f" Esc cancels: {_cut(safe, 12)}", f" +{queued} queued"),
        (" Esc cancels", f" +{queued} queued"),
        (" Esc cancels", f" +{queued}"),
        (" Esc", f" +{queued}"),
    ):
        form = Text(what + count, style=RUNNING_STYLE)
        if queued:
            form.append(waiting, style="bold yellow")
        if form not in forms:
            forms.append(form)
    return _Field(forms, badge_start=True, badge_end=not queued, essential=True, last_resort=1)


def _separator(before: _Field, after: _Field) -> str:
    return " " if before.badge_end or after.badge_start else " · "


def _joined(fields: list[_Field], forms: list[int]) -> Text:
    text = Text()
    for n, field in enumerate(fields):
        if n:
            text.append(_separator(fields[n - 1], field))
        text.append_text(field.forms[forms[n]])
    return text


def _width(fields: list[_Field], forms: list[int]) -> int:
    seps = sum(cell_len(_separator(a, b)) for a, b in pairwise(fields))
    return seps + sum(f.forms[i].cell_len for f, i in zip(fields, forms, strict=True))


def status_text(
    status: Status,
    waiting_since: float | None,
    frames_per_second: float,
    running: tuple[str, float, int] | None = None,
    width: int | None = None,
) -> Text:
    """The line for ``status``; ``waiting_since`` is when the request in flight left
    (``time.perf_counter()``), from the outbox; ``running``: the typed line running for
    how many seconds, and how many lines wait behind it.

    Within ``width`` cells (None: no limit) the line is made of whole fields: the
    lowest in priority (rightmost) go first; then the label, the ``Esc cancels`` badge
    and a retry's countdown take shorter forms; then the badge and the label go. The
    target, the writes mode and the connection's state stay. The label never takes more
    than a quarter of the line (:data:`LABEL_MIN` to :data:`LABEL_WIDTH` cells)."""
    label_width = LABEL_WIDTH if width is None else max(LABEL_MIN, min(LABEL_WIDTH, width // 4))
    fields = _fields(status, waiting_since, frames_per_second, running, label_width)
    forms = [0] * len(fields)
    if width is None or _width(fields, forms) <= width:
        return _joined(fields, forms)
    kept = list(range(len(fields)))

    def fits() -> bool:
        return _width([fields[i] for i in kept], [forms[i] for i in kept]) <= width

    for i in reversed(range(len(fields))):  # whole fields, lowest priority first
        if not fields[i].essential:
            kept.remove(i)
            if fits():
                break
    for last_resort in (False, True):  # then shorter forms, lowest priority first
        for i in reversed(kept):
            shortest = len(fields[i].forms) - 1 - (0 if last_resort else fields[i].last_resort)
            while not fits() and forms[i] < shortest:
                forms[i] += 1
    for i in reversed(kept[:]):
        if fits():
            break
        if fields[i].droppable:
            kept.remove(i)
    for i in kept:  # what a dropped field left room for: longer forms, highest first
        while forms[i] > 0:
            forms[i] -= 1
            if not fits():
                forms[i] += 1
                break
    return _joined([fields[i] for i in kept], [forms[i] for i in kept])


def writes_refused(status: Status | None) -> bool:
    """True on a read-only target (``--read-only``, or a profile's ``writes``)."""
    return status is not None and (status.read_only or status.writes == "read-only")


#: The command line's placeholder: examples that work on the target. A write is
#: suggested on the built-in simulator only: on a controller, the first thing a newcomer
#: reads is a read.
PLACEHOLDER = "get P 1 · put IO 20 on · watch IO 0-7 · help"
READ_ONLY_PLACEHOLDER = "get P 1 · watch IO 0-7 · help"


def placeholder_for(status: Status | None) -> str:
    """The examples for this target (the reads alone until its status is known)."""
    if status is None or writes_refused(status) or not status.is_simulator:
        return READ_ONLY_PLACEHOLDER
    return PLACEHOLDER


#: How long the status line says what the console's watchdog did.
NOTICE_SECONDS = 10.0


def caught_up_notice(seconds: float) -> Text:
    """The status line's word after a stall: the screen was behind, and is not now."""
    return Text(f"SCREEN WAS {seconds:.0f} s BEHIND, caught up", style="bold black on yellow")


def caught_up_alert(seconds: float) -> str:
    """The frame log's line after a stall (kept after the status line's has gone)."""
    return (
        f"the screen had not shown what the engine published for {seconds:.1f} s:"
        " brought up to date"
    )


def engine_stopped_text(name: str | None, why: str | None) -> str:
    """Said once when a target's engine has died: nothing is polled or answered."""
    whose = f"{name}'s engine" if name else "the engine"
    cause = f" ({terminal_safe(why)})" if why else ""
    return (
        f"{whose} has stopped{cause}: nothing is polled or sent any more, and the values"
        " shown are old. Restart rac-console."
    )
