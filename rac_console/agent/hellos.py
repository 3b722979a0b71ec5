"""What a client's hello says of itself, as the agent takes it: a word for its kind,
and a served console's poll bounds."""

from __future__ import annotations

from ..engine.setup.poll_bounds import UNBOUNDED, PollBounds, bounds_for
from ..engine.setup.where import Where


def client_kind(said: object) -> str:
    """What kind of client it says it is (``console``, ``REPL``), as the others' frame
    logs and the agent's show it: a short word or two, else just ``client``."""
    text = str(said or "")
    plain = text.replace(" ", "").replace("-", "")
    return text if 0 < len(text) <= 24 and plain.isascii() and plain.isalnum() else "client"


def served_bounds(where: Where, given: object) -> PollBounds:
    """A served console's poll bounds as ``serve`` gave them to it (in its environment,
    which is not the agent's); serve's defaults when it sent none; none for any other
    client."""
    if where is not Where.SERVED:
        return UNBOUNDED
    if isinstance(given, dict):
        rows = given.get("max_rows")
        return PollBounds(float(given["min_interval"]), None if rows is None else int(rows))
    return bounds_for(Where.SERVED, {})
