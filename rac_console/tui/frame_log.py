"""The raw frame log: one line per frame, written in batches, bounded in memory.

Besides the lines drawn, the log keeps the last :data:`KEPT` poll frames it was given and,
apart, the last :data:`KEPT_OTHERS` others (typed exchanges and notes), each with its gap
and each kind within :data:`KEPT_BYTES` of frames (a frame
carries its request), so the hex view (F7), the frame times, the filter (``/``) and the poll
frames (F3) redraw what is on screen, not only what comes; a fast poll cannot push the
typed exchanges out (with polls hidden they would vanish at the next redraw).
Lines are plain strings (cheap to write at thousands a second); the few on screen are
styled as they are drawn, by :class:`FrameHighlighter`; where the hex goes is
:mod:`.frame_lines`', the formatting of a line :mod:`rac_console.present.frames`'.
"""

from __future__ import annotations

import heapq
import itertools
import time
from collections import deque
from operator import itemgetter
from typing import TYPE_CHECKING, ClassVar

from rich.text import Text
from textual.binding import BindingType
from textual.message import Message as TextualMessage

from ..present.filtering import FrameFilter, log_title
from ..present.frames import (
    clock_text,
    frame_body,
    frame_times_said,
    gap_text,
    hex_text,
    hex_view_said,
    poll_frames_said,
)
from ..protocol.text import terminal_safe
from ..session.types import Frame
from . import frame_lines, keys
from .compat import InlineWidthLog, forget_drawn_lines, forget_split_segments
from .frame_lines import HEX_SEPARATOR, FrameHighlighter, hex_fits, hex_plan, hex_under

if TYPE_CHECKING:
    from ..engine.published.events import Alert, Note

MAX_LINES = 5000
MAX_PENDING = 50_000
#: Lines drawn per flush at most: past it only the newest are drawn, and one
#: line says how many were not (drawing them cost the poller its CPU, unread).
MAX_LINES_PER_FLUSH = 500
#: Poll frames kept to be drawn again (by the hex view, the frame times, the filter and
#: F3). The filter looks through these. A poll frame costs 350 to 500 B kept (its bytes,
#: its parsed reply, its gap): 7 to 10 MB when full, seconds into a flood.
KEPT = 20_000
#: Other events kept (typed exchanges, notes): as many as the log draws, so with polls
#: hidden (F3) every one it can show is there. About 450 B a typed frame (a ``put``
#: makes four with its readbacks): 2.2 MB when full, after a thousand lines typed.
KEPT_OTHERS = MAX_LINES
#: Bytes of frames kept, at most, of each kind: the oldest go past it as past the
#: count. Frames of a few dozen bytes never reach it; a reply may be 64 KiB, and
#: 20,000 of them held 1.3 GB (about three times this in memory with their parse).
KEPT_BYTES = 4 * 1024 * 1024

#: What the log holds: a frame, or a note (its time and text).
Event = Frame | tuple[float, str]
#: An event as drawn: with its gap (seconds since the frame before it on the wire).
Drawn = tuple[Event, float | None]
#: A kept event: its place in the order events came, and the event as drawn.
Kept = tuple[int, Drawn]


class FrameLog(InlineWidthLog):
    """Frames are queued as they cross the wire and written by :meth:`flush` when the
    app drains the engine (30 times a second at most): one ``write_lines`` per flush
    instead of one per frame."""

    BINDINGS: ClassVar[list[BindingType]] = keys.FRAME_LOG

    class OptionsChanged(TextualMessage):
        """(log → app) Polls shown, the hex view or the frame times changed: settings
        the console keeps."""

    def __init__(self, **kwargs: object) -> None:
        super().__init__(highlight=True, max_lines=MAX_LINES, auto_scroll=True, **kwargs)  # type: ignore[arg-type]
        self.highlighter: FrameHighlighter = FrameHighlighter()
        self._pending: deque[Event] = deque(maxlen=MAX_PENDING)
        # Kept apart, so polls push out polls only; merged back in order when drawn.
        self._kept_polls: deque[Kept] = deque()
        self._kept_others: deque[Kept] = deque()
        self._order = itertools.count()
        # The newest frame's time: the next frame's gap follows from it.
        self._last_time: float | None = None
        self._bodies: dict[int, str] = {}  # kept frames' lines after their time, by id
        #: In a cell: each kept frame's target, by id, and the width of their column
        #: (0: one target, no column).
        self._origin: dict[int, str] = {}
        self.target_width = 0
        self._frames_kept = 0
        self._kept_bytes = [0, 0]  # of the kept polls' frames, of the others'
        self._frames_shown = 0  # counted while narrowed (a filter, or polls hidden)
        self._show_polls = True
        self._hex_view = False
        self._show_gaps = True
        self._filter = FrameFilter()
        self._narrowed = False  # a filter, or poll frames hidden: not every frame shows
        self._hex_width = 0  # the width the hex was laid out for
        #: The column the hex starts at for the frames drawn: their longest text among the
        #: frames whose bytes fit beside it; None: every frame has its bytes under its text
        #: (a request and its reply are never laid out two ways).
        self._hex_column: int | None = 0
        self._hex_placed = [0, 0]  # frames drawn since the last redraw: beside, under
        self._title: Text | None = None

    # ------------------------------------------------------------- options

    @property
    def show_polls(self) -> bool:
        """Poll frames shown (F3); hiding them hides the ones on screen too."""
        return self._show_polls

    @show_polls.setter
    def show_polls(self, shown: bool) -> None:
        if shown != self._show_polls:
            self._show_polls = shown
            self._rematch()
            self.post_message(self.OptionsChanged())

    @property
    def hex_view(self) -> bool:
        """Each frame's bytes in hex, beside its text (under it when both do not fit)."""
        return self._hex_view

    @hex_view.setter
    def hex_view(self, shown: bool) -> None:
        if shown != self._hex_view:
            self._hex_view = shown
            self._redraw()
            self.post_message(self.OptionsChanged())

    @property
    def hex_laid_out(self) -> bool:
        """The hex view's lines are laid out for the log's width now (after a resize,
        once the log has drawn them again)."""
        return self._hex_width == self._width_now()

    @property
    def hex_placement(self) -> str:
        """Where the hex view draws the bytes of the frames on screen: ``beside``,
        ``under``, ``mixed`` (under the lines too long), or ``none`` (no frame yet)."""
        beside, under = self._hex_placed
        if beside and under:
            return "mixed"
        return "beside" if beside else "under" if under else "none"

    @property
    def show_gaps(self) -> bool:
        """The time since the previous frame, on each frame's line."""
        return self._show_gaps

    @show_gaps.setter
    def show_gaps(self, shown: bool) -> None:
        if shown != self._show_gaps:
            self._show_gaps = shown
            self._redraw()
            self.post_message(self.OptionsChanged())

    def toggle_polls(self) -> str:
        """F3: poll frames shown or hidden; what to say of it."""
        self.show_polls = not self.show_polls
        return poll_frames_said(self.show_polls)

    def toggle_hex(self) -> str:
        """F7: the bytes in hex, or not; what to say of it."""
        self.hex_view = not self.hex_view
        return hex_view_said(self.hex_view, self.hex_placement)

    def toggle_gaps(self) -> str:
        """``t``: the time since the previous frame on each line, or not."""
        self.show_gaps = not self.show_gaps
        return frame_times_said(self.show_gaps)

    @property
    def slow_after(self) -> float:
        """A reply this many seconds after its request has its gap highlighted."""
        return self.highlighter.slow_after

    @slow_after.setter
    def slow_after(self, seconds: float) -> None:
        if seconds != self.highlighter.slow_after:
            self.highlighter.slow_after = seconds
            forget_drawn_lines(self)

    @property
    def filter_text(self) -> str:
        return self._filter.typed

    def set_filter(self, text: str) -> None:
        """Show only the frames that name a variable (and their replies), or hold a text."""
        new = FrameFilter.of(text)
        old = self._filter
        if (new.needle, new.var, new.target) == (old.needle, old.var, old.target):
            self._filter = new  # as typed, for the title
            self.update_title()
            return
        self._filter = new
        self._rematch()

    @property
    def frames_kept(self) -> int:
        return self._frames_kept

    @property
    def title_text(self) -> str:
        """The border title as plain text."""
        return self._title.plain if self._title is not None else ""

    def update_title(self) -> None:
        """Frozen or following, the hex view, the filter and how many frames pass it."""
        shown = (self._frames_shown, self._frames_kept)
        title = log_title(
            not self.auto_scroll, self._hex_view, self._filter.typed, self._show_polls, shown
        )
        if title != self._title:
            self._title = title
            self.border_title = title

    # ---------------------------------------------------------- the frames

    def on_mount(self) -> None:
        self.update_title()
        self._redraw()

    def on_resize(self) -> None:
        """A resize moves the end away from the view: bring it back while following.
        The hex view lays its bytes out for the width: again at a new one."""
        if self._hex_view and self._width_now() != self._hex_width:
            self._redraw()
        if self.auto_scroll:
            self.call_after_refresh(self._follow)

    def _follow(self) -> None:
        """To the end, unless F4 froze the view meanwhile (a resize's refresh comes
        after the key that came after it)."""
        if self.auto_scroll:
            self.scroll_end(animate=False, x_axis=False)

    def add(self, event: Frame | Note | Alert, target: str | None = None) -> None:
        """Queue one event drained from the engine's outbox; cheap, written at the next flush.

        A note carries the time it happened, so it sits in time order among the frames
        around it. ``target``: in a cell, the target it came from (a column of its own
        for a frame, a prefix for a note).
        """
        if isinstance(event, Frame):
            if target is not None:  # a name from the config file: never raw to the screen
                self._origin[id(event)] = terminal_safe(target)
            self._pending.append(event)
            return
        from ..engine.published.events import (
            Note,  # notes and alerts are few: loaded with the first
        )

        text = event.text if target is None else f"{target}: {event.text}"
        when = event.time if isinstance(event, Note) else time.time()
        self._pending.append((when, text))

    def clear(self) -> FrameLog:
        """Ctrl+L: the lines and the frames kept go (a filter finds nothing older)."""
        self._kept_polls.clear()
        self._kept_others.clear()
        self._bodies.clear()
        self._origin.clear()
        self._frames_kept = self._frames_shown = 0
        self._kept_bytes = [0, 0]
        super().clear()
        self.update_title()
        return self

    def flush(self) -> int:
        """Write what arrived since the last flush; returns the number of events."""
        if not self._pending:
            return 0
        events = list(self._pending)
        self._pending.clear()
        if self.target_width:  # a cell: each target's batch came apart; in time order
            events.sort(key=lambda event: event.time if isinstance(event, Frame) else event[0])
        count, shown = self._keep(events)
        if self._narrowed:
            self.update_title()
        if not self.is_mounted:
            return len(events)  # drawn from what is kept once mounted
        if self._hex_view and self._hex_moves(shown[-MAX_LINES_PER_FLUSH:]):
            self._redraw()  # the hex column moves (or goes under), for every line
            return len(events)
        lines = self._draw(shown[-MAX_LINES_PER_FLUSH:])
        if count > MAX_LINES_PER_FLUSH:
            skipped = count - MAX_LINES_PER_FLUSH
            stamp = shown[-MAX_LINES_PER_FLUSH - 1][0]
            when = stamp.time if isinstance(stamp, Frame) else stamp[0]
            lines.insert(
                0,
                f"{self._head(when, None)} ── {skipped} earlier lines not drawn (faster than "
                "anyone reads): --record FILE keeps every frame ──",
            )
        if lines:
            # The lines drawn before, cut at the view's edge, were kept by Rich for good.
            forget_split_segments()
            # Log follows only when the view already sat at the end, and any layout
            # change (a resize, the candidate list) moves the end away from the view:
            # follow by this widget's own flag instead, until F4 freezes it.
            before = self.line_count
            self.write_lines(lines, scroll_end=False)
            if self.auto_scroll:
                self.scroll_end(animate=False, immediate=True, x_axis=False)
            elif dropped := before + len(lines) - self.line_count:
                # Past MAX_LINES the oldest lines go: a frozen view stays on its lines
                # (until they go themselves), it does not slide on to newer ones.
                y = max(0.0, self.scroll_y - dropped)
                self.scroll_to(y=y, animate=False, immediate=True)
        return len(events)

    def _keep(self, events: list[Event]) -> tuple[int, list[Drawn]]:
        """Keep new events with their gap (the oldest of their kind go past KEPT or
        KEPT_OTHERS, or KEPT_BYTES); how many of them are shown, and the newest of those
        (all a flush may draw)."""
        polls, others, order = self._kept_polls, self._kept_others, self._order
        narrowed, passes = self._narrowed, self._passes
        last_time = self._last_time
        poll_bytes, other_bytes = self._kept_bytes
        tail = 0 if narrowed else len(events) - MAX_LINES_PER_FLUSH - 1
        shown: list[Drawn] = []
        count = frames = 0
        for n, event in enumerate(events):
            if isinstance(event, Frame):
                frames += 1
                gap = None if last_time is None else event.time - last_time
                last_time = event.time
                drawn: Drawn = (event, gap)
                if event.poll:
                    polls.append((next(order), drawn))
                    poll_bytes += len(event.data)
                else:
                    others.append((next(order), drawn))
                    other_bytes += len(event.data)
                if narrowed:
                    if not passes(event):
                        continue
                    self._frames_shown += 1
            else:
                drawn = (event, None)
                others.append((next(order), drawn))
            count += 1
            if n >= tail:
                shown.append(drawn)
        self._last_time = last_time
        self._frames_kept += frames
        self._kept_bytes = [poll_bytes, other_bytes]
        for kind, (kept, most) in enumerate(((polls, KEPT), (others, KEPT_OTHERS))):
            if len(kept) > most or self._kept_bytes[kind] > KEPT_BYTES:
                self._forget(kept, kind, most)
        return count, shown

    def _forget(self, kept: deque[Kept], kind: int, most: int) -> None:
        """The oldest events of one kind (0: polls, 1: others) go while there are more
        than ``most`` or their frames' bytes pass KEPT_BYTES, and their share of the
        counts."""
        bodies = self._bodies
        narrowed = self._narrowed
        size = self._kept_bytes[kind]
        while kept and (len(kept) > most or size > KEPT_BYTES):
            _, (event, _) = kept.popleft()
            if not isinstance(event, Frame):
                continue
            size -= len(event.data)
            self._frames_kept -= 1
            if narrowed and self._passes(event):
                self._frames_shown -= 1
            if bodies:
                bodies.pop(id(event), None)
            self._origin.pop(id(event), None)
        self._kept_bytes[kind] = size

    def _walk(self) -> list[Drawn]:
        """Every kept event with its gap, in the order they came."""
        merged = heapq.merge(self._kept_polls, self._kept_others, key=itemgetter(0))
        return [drawn for _, drawn in merged]

    def _passes(self, frame: Frame) -> bool:
        if frame.poll and not self._show_polls:
            return False
        if not self._filter:
            return True
        target = self._origin.get(id(frame))
        if self._filter.var is not None or not self._filter.needle:
            return self._filter.matches(frame.request, "", target)
        return self._filter.matches(frame.request, self._body(frame), target)

    def _rematch(self) -> None:
        """The filter or F3 changed: which kept frames pass, counted, and drawn again."""
        self._narrowed = bool(self._filter) or not self._show_polls
        self._redraw()

    def _redraw(self) -> None:
        """Draw again the kept events that pass (the newest MAX_LINES); count them."""
        passes = self._passes
        shown = [
            drawn for drawn in self._walk() if not isinstance(drawn[0], Frame) or passes(drawn[0])
        ]
        self._frames_shown = sum(isinstance(drawn[0], Frame) for drawn in shown)
        self.update_title()
        if not self.is_mounted:
            return
        shown = shown[-MAX_LINES:]
        self._hex_width = self._width_now()
        width = self._hex_width
        self._hex_column = hex_plan(self._hex_sizes(shown), width) if self._hex_view else 0
        self._hex_placed = [0, 0]
        lines = self._draw(shown)
        super().clear()
        if lines:
            self.write_lines(lines, scroll_end=False)
        if self.auto_scroll:
            self.scroll_end(animate=False, immediate=True, x_axis=False)

    # ------------------------------------------------------------ the lines

    def _body(self, frame: Frame) -> str:
        """The line after its time, kept for a kept frame once a text filter read it."""
        body = self._bodies.get(id(frame))
        if body is None:
            body = self._bodies[id(frame)] = frame_body(frame)
        return body

    def _head(self, when: float, gap: float | None) -> str:
        return f"{clock_text(when)} {gap_text(gap)}" if self._show_gaps else clock_text(when)

    def _width_now(self) -> int:
        return self.scrollable_content_region.width if self.is_mounted else 0

    def _frame_line(self, event: Frame, gap: float | None) -> tuple[str, int]:
        """A frame's line, and where its text starts (after the time and the gap)."""
        head = self._head(event.time, gap)
        if self.target_width:
            head = f"{head} {self._origin.get(id(event), ''):<{self.target_width}}"
        return f"{head} {self._bodies.get(id(event)) or frame_body(event)}", len(head) + 1

    def _hex_sizes(self, shown: list[Drawn]) -> list[tuple[int, int]]:
        """Each frame's text and hex lengths, as the hex layout weighs them."""
        return [
            (len(self._frame_line(event, gap)[0]), len(event.data) * 3 - 1)
            for event, gap in shown
            if isinstance(event, Frame)
        ]

    def _hex_moves(self, shown: list[Drawn]) -> bool:
        """True when new frames change where the bytes go (or the width changed)."""
        width = self._width_now()
        moved = frame_lines.hex_moves(self._hex_sizes(shown), self._hex_column, width)
        return width != self._hex_width or moved

    def _draw(self, shown: list[Drawn]) -> list[str]:
        lines: list[str] = []
        hex_view = self._hex_view
        width = self._hex_width
        column = self._hex_column
        placed = self._hex_placed
        for event, gap in shown:
            if not isinstance(event, Frame):
                stamp, text = event
                lines.append(f"{self._head(stamp, None)} ── {terminal_safe(text)} ──")
                continue
            line, indent = self._frame_line(event, gap)
            if not hex_view:
                lines.append(line)
                continue
            hexed = hex_text(event.data)
            if column is not None and hex_fits(width, f"{line:<{column}}", hexed):
                lines.append(f"{line:<{column}}" + HEX_SEPARATOR + hexed)
                placed[0] += 1
            else:
                lines.append(line)
                lines.extend(hex_under(hexed, indent, width))
                placed[1] += 1
        return lines

    def lines_width(self, lines: list[str]) -> int:
        return frame_lines.lines_width(lines)
