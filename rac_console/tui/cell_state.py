"""What the console holds of each target of its cell: the last status, the rows, the
trend samples and the toggles under way, by target name (a cell of one holds one)."""

from __future__ import annotations

from dataclasses import dataclass, field

from ..commands.language import VarRef
from ..engine import RowView, Status
from ..engine.cell import Member
from ..present.cell_status import Badge
from ..present.row_actions import PendingToggles
from ..present.trends import TrendStore


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
