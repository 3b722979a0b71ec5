"""A client's hello: made and sent for a target (:func:`greet_agent`), and what it says
of itself as the agent takes it (a word for its kind, a served console's poll bounds)."""

from __future__ import annotations

import os

from ..commands.target import Target
from ..engine.setup.poll_bounds import UNBOUNDED, PollBounds, bounds_for
from ..engine.setup.where import Where
from . import endpoint as endpoints
from .wire import Channel, Message, greet


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


def greet_agent(target: Target, client: str, **fields: object) -> tuple[Channel, Message] | None:
    """The running agent reached and greeted for ``target`` as ``client`` (this process,
    its ``--read-only``, and ``fields``): the channel and the agent's answer, or None when
    no agent answers (none runs, or not the agent: :func:`greet`)."""
    reached = endpoints.reach()
    if reached is None:
        return None
    sock, endpoint = reached
    channel = Channel(sock)
    answer = greet(
        channel,
        endpoint.token,
        client=client,
        pid=os.getpid(),
        host=target.host,
        port=target.port,
        read_only=target.read_only_flag,
        **fields,
    )
    return None if answer is None else (channel, answer)
