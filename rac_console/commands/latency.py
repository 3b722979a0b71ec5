"""Round-trip statistics for ``latency``, in the manner of ``redis-cli --latency`` (pure)."""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True)
class LatencySummary:
    count: int
    errors: int
    min_ms: float | None
    avg_ms: float | None
    p50_ms: float | None
    p95_ms: float | None
    max_ms: float | None
    requests_per_s: float | None

    def to_json(self) -> dict[str, float | int | None]:
        return {k: (round(v, 4) if isinstance(v, float) else v) for k, v in self.__dict__.items()}

    def text(self, what: str) -> str:
        if not self.count:
            return f"latency of {what}: no replies ({self.errors} errors)"
        rate = f"{self.requests_per_s:,.0f} requests/s" if self.requests_per_s else ""
        return (
            f"latency of {what}, {self.count} samples: min {self.min_ms:.3f}  "
            f"avg {self.avg_ms:.3f}  p50 {self.p50_ms:.3f}  p95 {self.p95_ms:.3f}  "
            f"max {self.max_ms:.3f} ms  ({rate}, {self.errors} errors)"
        )


def percentile(ordered: list[float], fraction: float) -> float:
    """Nearest-rank percentile of sorted values."""
    rank = max(1, math.ceil(fraction * len(ordered)))
    return ordered[rank - 1]


def summarize(samples_s: list[float], errors: int, elapsed_s: float) -> LatencySummary:
    """Round trips in seconds to a summary in milliseconds."""
    if not samples_s:
        return LatencySummary(0, errors, None, None, None, None, None, None)
    ordered = sorted(s * 1000 for s in samples_s)
    return LatencySummary(
        count=len(ordered),
        errors=errors,
        min_ms=ordered[0],
        avg_ms=sum(ordered) / len(ordered),
        p50_ms=percentile(ordered, 0.50),
        p95_ms=percentile(ordered, 0.95),
        max_ms=ordered[-1],
        requests_per_s=(len(ordered) + errors) / elapsed_s if elapsed_s > 0 else None,
    )
