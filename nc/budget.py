"""The interpreter's per-cycle macro statement budget (issue 15, decisions B2).

Macro statements run when the interpreter reads a block, inside the channel's cycle. A
100,000-iteration WHILE would otherwise hold one cycle for seconds (overruns in real time, an
SM-watchdog alarm on EtherCAT in lock-step). The channel opens a new budget every cycle; the
interpreter counts its statements and, once `limit` are spent, hands out a `nc.moves.Busy` mark and
goes on in the next cycle. Motion already in the look-ahead keeps running; the loop's time shows
up as cycles of simulated time, as on a real NC whose macro task is time-sliced.
"""

from __future__ import annotations

from dataclasses import dataclass

DEFAULT_STATEMENTS_PER_CYCLE = 40  # profile parameter "macro statements per cycle"


@dataclass
class StatementBudget:
    limit: int = DEFAULT_STATEMENTS_PER_CYCLE  # statements per cycle, ≥ 1
    used: int = 0  # this cycle
    peak: int = 0  # the most any cycle used
    held_cycles: int = 0  # cycles that ended with the budget spent (macro execution went on later)

    def new_cycle(self) -> None:
        self.used = 0

    def spend(self) -> None:
        self.used += 1
        if self.used > self.peak:
            self.peak = self.used

    @classmethod
    def for_profile(cls, profile) -> "StatementBudget":
        """From the profile parameter "macro statements per cycle" (at least 1; a non-number: default)."""
        v = profile.param("macro statements per cycle", DEFAULT_STATEMENTS_PER_CYCLE)
        try:
            return cls(max(1, int(v)))
        except (TypeError, ValueError, OverflowError):
            return cls()

    @property
    def spent(self) -> bool:
        return self.used >= self.limit
