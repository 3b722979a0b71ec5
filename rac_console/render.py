"""Rich renderings of outcomes, shared by the one-shot CLI, ``run`` and the REPL."""

from __future__ import annotations

from rich.console import Console
from rich.text import Text

from .commands.language import VarRef
from .commands.outcome import Outcome
from .protocol import Variant, vt_name
from .protocol.text import describe_response


def value_text(var: VarRef, variant: Variant) -> Text:
    """``X 350  Y 0  Z 450 ...`` with dim labels; IO as a coloured ON/OFF."""
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
    elif var is not None and outcome.written is not None:
        line.append(f"{var} ← ", style="bold")
        line.append_text(value_text(var, outcome.written))
        line.append("  S_OK", style="green")
    else:
        line.append(outcome.response_text or "")
    detail = [vt_name(variant.vt)] if variant is not None and var is not None else []
    if var is None and response is not None:
        detail = [describe_response(response)]
    detail.append(rtt_text(outcome))
    line.append("   " + "  ".join(d for d in detail if d), style="dim")
    return line


def error_text(outcome: Outcome, prefix: str = "") -> str:
    """One clear line: what failed and why, with the request and raw reply."""
    parts = [prefix + outcome.summary()]
    if outcome.request and outcome.response_text is None:
        parts.append(f"(request {outcome.request})")
    elif outcome.request:
        parts.append(f"(request {outcome.request}, reply {outcome.response_text})")
    return " ".join(parts)


def print_outcome(out: Console, err: Console, outcome: Outcome, prefix: str = "") -> None:
    if outcome.ok:
        out.print(outcome_text(outcome), soft_wrap=True, highlight=False)
    else:
        err.print(
            Text("rac-console: " + error_text(outcome, prefix)), soft_wrap=True, highlight=False
        )
