"""The frame log's own cost: queueing and drawing frames as the console does.

    python benchmarks/frame_log_bench.py [--frames 10000] [--batch 1000] [--rounds 5]

A headless app holding only a :class:`FrameLog` (120x40). FRAMES polled frames (a GET
and its reply, alternately) are queued with ``add`` and drawn by ``flush`` in batches of
BATCH (what one flush sees at 10 flushes a second when frames arrive at 10 BATCH a
second); the visible lines are then rendered as the compositor would. Printed: the
least over ROUNDS of CPU microseconds per frame for ``add`` and ``flush``, and CPU
milliseconds to render the screen's lines, with the log's options as they are by default,
then with the hex view on, then with a filter typed. The least, in CPU time: on a shared
machine the median swings with the neighbours.
"""

from __future__ import annotations

import argparse
import asyncio
import time

from textual.app import App, ComposeResult

from rac_console.protocol import parse_response
from rac_console.session import Frame
from rac_console.tui.frame_log import FrameLog


def frames(count: int) -> list[Frame]:
    out = []
    start = time.time()
    for n in range(count):
        t = start + n * 0.0001
        if n % 2 == 0:
            out.append(Frame(t, "tx", f"GET:RC8:{n % 100}:I:\r".encode(), poll=True))
        else:
            text = f"0,3,{n}"
            reply = parse_response(text)
            out.append(Frame(t, "rx", f"{text}\r".encode(), 0.0001, poll=True, response=reply))
    return out


class Bench(App[None]):
    def compose(self) -> ComposeResult:
        yield FrameLog(id="log")


def run_round(log: FrameLog, sample: list[Frame], batch: int) -> tuple[float, float, float]:
    log.clear()
    add = flush = 0.0
    for at in range(0, len(sample), batch):
        t0 = time.process_time()
        for frame in sample[at : at + batch]:
            log.add(frame)
        t1 = time.process_time()
        log.flush()
        t2 = time.process_time()
        add += t1 - t0
        flush += t2 - t1
    t0 = time.process_time()
    for y in range(log.size.height):
        log.render_line(y)
    render = time.process_time() - t0
    n = len(sample)
    return add / n * 1e6, flush / n * 1e6, render * 1e3


async def main(args: argparse.Namespace) -> None:
    app = Bench()
    async with app.run_test(size=(120, 40)) as pilot:
        log = app.query_one(FrameLog)
        sample = frames(args.frames)
        modes: list[tuple[str, dict[str, object]]] = [("default", {})]
        modes += [("hex view", {"hex_view": True}), ("filter I 5", {"filter": "I 5"})]
        for name, options in modes:
            if "hex_view" in options:
                log.hex_view = True
            if "filter" in options:
                log.set_filter(str(options["filter"]))
            rounds = [run_round(log, sample, args.batch) for _ in range(args.rounds)]
            await pilot.pause()
            add, flush, render = (min(r[i] for r in rounds) for i in range(3))
            print(
                f"{name:>12}: add {add:.2f} µs/frame, flush {flush:.2f} µs/frame, "
                f"render {log.size.height} lines {render:.2f} ms"
            )


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=10_000)
    parser.add_argument("--batch", type=int, default=1000)
    parser.add_argument("--rounds", type=int, default=9)
    asyncio.run(main(parser.parse_args()))
