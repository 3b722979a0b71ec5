"""What the console holds of each target of its cell: the last status, the rows, the
trend samples and the toggles under way, by target name (a cell of one holds one)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from rich.text import Text

from ..present.cell_status import Badge
from ..present.table_rows import RowKey
from ..present.toggles import PendingToggles
from ..present.trends import TrendStore
from ..protocol.text import terminal_safe

if TYPE_CHECKING:  # the first paint loads no engine module
    from ..commands.language import VarRef
    from ..engine import EngineLike, RowView, Status
    from ..engine.cell.cell import Cell, Member


@dataclass
class MemberState:
    """One target as the console last heard of it."""

    member: Member
    status: Status | None = None
    rows: dict[VarRef, RowView] = field(default_factory=dict)
    removed: set[VarRef] = field(default_factory=set)  # gone since the table's refresh
    trends: TrendStore = field(default_factory=TrendStore)
    toggles: PendingToggles = field(default_factory=PendingToggles)

    @property
    def name(self) -> str:
        return self.member.name

    @property
    def colour(self) -> str | None:
        profile = self.member.target.profile
        return profile.colour if profile is not None else None

    @property
    def label(self) -> str | None:
        return self.member.target.label

    def badge(self, current: bool) -> Badge:
        return Badge(self.name, self.status, self.colour, current)


class Members:
    """The console's targets, by name, and the current one's state as the console's own
    (``status``, ``rows``, ``trends``, ``toggles``: in a cell of one, the console's)."""

    def __init__(self, cell: Cell) -> None:
        self.cell = cell
        self.states = {member.name: MemberState(member) for member in cell.members}
        #: More than one target: the table names each row's, the prompt the current.
        self.cell_mode = len(cell.members) > 1

    @property
    def current(self) -> MemberState:
        """The target lines without ``@NAME`` go to (``use NAME``, F8)."""
        return self.states[self.cell.current]

    @property
    def engine(self) -> EngineLike:
        return self.current.member.engine

    @property
    def status(self) -> Status | None:
        """The current target's status (in a cell of one: the status)."""
        return self.current.status

    @status.setter
    def status(self, status: Status | None) -> None:
        self.current.status = status

    @property
    def rows(self) -> dict[VarRef, RowView]:
        """The current target's rows (the I/O grid's; the table shows every target's)."""
        return self.current.rows

    @property
    def trends(self) -> TrendStore:
        return self.current.trends

    @property
    def toggles(self) -> PendingToggles:
        return self.current.toggles

    def trend_store(self, name: str) -> TrendStore:
        """A target's trend samples, by name."""
        return self.states[name].trends if name in self.states else self.trends

    def state_of(self, name: str | None) -> MemberState:
        """A target by name (None, or a name not in the cell: the current one)."""
        return self.states.get(name or "", self.current)

    def prompt_text(self) -> Text:
        """The prompt naming the current target (a cell's only)."""
        shown = f"{terminal_safe(self.current.name)} ›"
        return Text.assemble((shown, "bold cyan"), " ")

    def row_groups(self) -> list[tuple[str, dict[VarRef, RowView]]]:
        """Every target's rows, in cell order, for the table."""
        return [(state.name, state.rows) for state in self.states.values()]

    def take_removed(self) -> set[RowKey]:
        """The rows unwatched since the table's last refresh, by target."""
        removed = {(state.name, var) for state in self.states.values() for var in state.removed}
        for state in self.states.values():
            state.removed = set()
        return removed

    def badges(self) -> list[Badge]:
        current = self.cell.current
        return [state.badge(state.name == current) for state in self.states.values()]

    def members_timed(self) -> bool:
        """Whether any target shows something that changes with time alone: its rows'
        ages, a reply waited for, a retry's countdown."""
        return any(
            state.rows
            or state.member.engine.outbox.waiting_since is not None
            or (state.status is not None and state.status.retry_at is not None)
            for state in self.states.values()
        )
