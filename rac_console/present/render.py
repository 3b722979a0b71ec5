"""Rich renderings of outcomes, shared by the one-shot CLI, ``run``, the REPL and the console.

Text from outside (the wire, a file, a typed line) reaches a terminal only through
here: every piece passes :func:`terminal_safe` and is put in a ``Text``, which Rich
never reads as markup, and the consoles made here never expand emoji codes.
"""

from __future__ import annotations

import sys
from typing import Any

from rich.console import Console
from rich.text import Text

from ..commands.cells import split_address
from ..commands.language import VarRef
from ..commands.line import MAX_LINE
from ..commands.outcome import Outcome
from ..protocol import Variant, vt_name
from ..protocol.text import describe_response, quoted_text, terminal_safe, terminal_safe_lines

#: Characters of a reply quoted in an error line.
MAX_QUOTED_REPLY = 200


def make_console(*, stderr: bool = False, **options: Any) -> Console:
    """A console that prints text as given: no markup, no emoji codes, no highlighting;
    to a pipe or a file, never wrapped (one result is one line for grep and awk)."""
    stream = options.get("file") or (sys.stderr if stderr else sys.stdout)
    if not _is_terminal(stream):
        options.setdefault("soft_wrap", True)
    return Console(stderr=stderr, highlight=False, markup=False, emoji=False, **options)


def _is_terminal(stream: Any) -> bool:
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError, OSError):  # closed, or not a real stream
        return False


def notice_text(text: str, *, error: bool = False, style: str = "") -> Text:
    """Our own message (which may quote a file, a host or a reply), made safe."""
    return Text(terminal_safe_lines(text), style="red" if error else style)


def print_error(console: Console, text: str) -> None:
    """``rac-console: ...`` on one line, escaped."""
    console.print(Text("rac-console: " + terminal_safe(text)), soft_wrap=True)


def value_text(var: VarRef, variant: Variant) -> Text:
    """``X 350  Y 0  Z 450 ...`` with dim labels; IO as a coloured ON/OFF; a string in
    quotes (``""``, ``" x "``: what it holds, spaces and all)."""
    if isinstance(variant.value, str):
        return Text(quoted_text(variant.value))
    out = Text()
    for n, (label, text) in enumerate(var.kind.fields(variant)):
        if n:
            out.append("  ")
        if label:
            out.append(label + " ", style="dim")
        style = {"ON": "bold green", "OFF": "red"}.get(text, "") if var.kind.code == "IO" else ""
        out.append(text, style=style)
    return out


def rtt_text(outcome: Outcome) -> str:
    return "" if outcome.rtt_ms is None else f"{outcome.rtt_ms:.2f} ms"


def outcome_text(outcome: Outcome) -> Text:
    """The human result of a successful exchange, one line."""
    var, variant, response = outcome.var, outcome.variant, outcome.response
    line = Text()
    if var is not None and variant is not None:
        line.append(f"{var} = ", style="bold")
        line.append_text(value_text(var, variant))
    elif var is not None and outcome.written is not None and read_back_checked(outcome):
        line.append_text(write_text(var, outcome))
    elif var is not None and outcome.written is not None:
        line.append(f"{var} ← ", style="bold")
        line.append_text(value_text(var, outcome.written))
        line.append("  S_OK", style="green")
    else:
        line.append(terminal_safe(outcome.response_text or ""))
    detail = [vt_name(variant.vt)] if variant is not None and var is not None else []
    if var is None and response is not None:
        detail = [describe_response(response)]
    detail.append(rtt_text(outcome))
    line.append("   " + "  ".join(d for d in detail if d), style="dim")
    if outcome.waited is not None:
        line.append(f"   ✓ {terminal_safe(outcome.waited.text())}", style="green")
    return line


def read_back_checked(outcome: Outcome) -> bool:
    """True for a PUT read back (or whose read-back failed): not one sent --no-verify."""
    return outcome.read_back is not None or outcome.read_back_error is not None


def write_text(var: VarRef, outcome: Outcome) -> Text:
    """``I10: 14 → 15  S_OK  read back 15 ✓`` (``?`` for a value before not known)."""
    line = Text()
    line.append(f"{var}: ", style="bold")
    if outcome.before is not None:
        line.append_text(value_text(var, outcome.before))
    else:
        line.append("?", style="dim")
    line.append(" → ")
    if outcome.written is not None:
        line.append_text(value_text(var, outcome.written))
    response = outcome.response
    if response is not None:
        line.append(f"  {describe_response(response)}", style="green" if response.ok else "red")
    if outcome.read_back is not None:
        line.append("  read back ")
        line.append_text(value_text(var, outcome.read_back))
        if response is not None and not response.ok:
            line.append(" (the PUT was refused)", style="red")
        elif outcome.verified is True:
            line.append(" ✓", style="bold green")
        elif outcome.verified is False:
            line.append(" ✗", style="bold red")
    elif outcome.read_back_error is not None:
        line.append(f"  {terminal_safe(outcome.read_back_error)}", style="red")
    return line


def error_text(outcome: Outcome, prefix: str = "") -> str:
    """One clear line: what failed and why, with the request and raw reply."""
    var = outcome.var
    if var is not None and outcome.response is not None and read_back_checked(outcome):
        # The PUT was answered: the write line says it all, and why it is a failure (a
        # failed read-back is already on it: said once).
        said = outcome.error == outcome.read_back_error
        why = f" ({outcome.error})" if outcome.error and outcome.response.ok and not said else ""
        if not outcome.response.ok:
            why = f" ({outcome.summary()})"
        return terminal_safe(prefix + write_text(var, outcome).plain + why)
    parts = [prefix + outcome.summary()]
    if outcome.request and outcome.response_text is None:
        parts.append(f"(request {outcome.request})")
    elif outcome.request:
        reply = outcome.response_text or ""
        if len(reply) > MAX_QUOTED_REPLY:  # the whole reply is in --json, the log and --record
            reply = f"{reply[:MAX_QUOTED_REPLY]}… ({len(reply)} characters)"
        parts.append(f"(request {outcome.request}, reply {reply})")
    if var is not None and outcome.read_back is not None:  # a PUT that got no answer
        parts[-1] += ";"
        parts.append(f"read back {value_text(var, outcome.read_back).plain}")
        if outcome.verified is None:  # it timed out: it may land after this read
            parts.append("just after, which proves nothing")
        else:
            parts.append("(the value written)" if outcome.verified else "(not the value written)")
    return terminal_safe(" ".join(parts))


def print_outcome(out: Console, err: Console, outcome: Outcome, prefix: str = "") -> None:
    if outcome.ok:
        out.print(outcome_text(outcome), soft_wrap=True, highlight=False)
    else:
        print_error(err, error_text(outcome, prefix))


def too_long_text(count: int | None) -> str:
    """What a command line says of characters typed or pasted past its end (``count``
    of them, when known)."""
    if count is None:
        were = "what was typed or pasted past that was"
    elif count == 1:
        were = "1 character typed or pasted past that was"
    else:
        were = f"{count:,} characters typed or pasted past that were"
    return f"the command line holds at most {MAX_LINE:,} characters: {were} not taken"


def echo_text(line: str, target: str | None = None) -> Text:
    """A line echoed over its result: ``› get I 1``; in a cell, after the target it ran
    on (``robotB › put I 10 5``: an ``@robotB`` is said by the name). A line too long
    to run is shown by its start and its length."""
    if len(line) > MAX_LINE:
        line = f"{line[:60]}… ({len(line):,} characters)"
    if target is None:
        return Text(f"› {terminal_safe(line)}", style="bold cyan")
    if line.lstrip().startswith("@"):
        line = split_address(line)[1]
    return Text.assemble(
        (f"{terminal_safe(target)} ", "bold"), (f"› {terminal_safe(line)}", "bold cyan")
    )
