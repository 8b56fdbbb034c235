"""A stretch whose NC steps inside it (issue 17, decision bench B27): block ends, solves and feeds included.

A CAM program's blocks last a cycle or two; where its speed dips below the cap (the 0.0001 mm rounding of its
points makes junctions slower) every block is solved, and the stretches of B20/B25 (at most to the end of the
planner's buffer, or across a cruise's blocks) stay shorter than two cycles, so those cycles were stepped: the
runner's cycle, the bus and the drive models one cycle at a time around the NC's work. Here the stretch runs the
NC's steps itself, in stepping's order, cycle by cycle where they do more than hand out a buffered row:
- the channel's feed where it reads (only plain moves, `hil.stretch_reads.Ahead`, as B26);
- the planner's step: a cruise's next block checked (`_chain_ok`/`_break_chain`), the refill where the buffer ran
  out (`Planner._refill`: block ends, solves, samples), then its rows at once (`sample_stretch`, to the next cycle
  whose feed may read or whose step refills), filtered as step() filters them.
What cannot be taken back is a feed's push, so the drive models are stepped a part at a time, over the cycles up to
each reading cycle before its feed runs (`CspRun`/`CsvRun` carry the drives' state from one part to the next); a drive
fault or the bench's overspeed check found there ends the stretch before its cycle, the planner put back to the
last save after a feed and its steps made again (they are deterministic; everything but a push is saved:
the planner's fields, queue, filter, share zones and plan). The stretch ends before a cycle whose step would
stand (no row after the refill), raise, or start a block a stretch does not sample (feed per revolution, G96,
thread, G31, dwell): that cycle is stepped from the planner as it was before it. Taken only where nothing cuts the
stretch after a feed: lock-step, the basic MLC, the bulk part from the first cycle (as B26).
"""

from __future__ import annotations

from itertools import chain
from typing import Any

import numpy as np

from hil.stretch_reads import ahead, may_read
from hil.stretch_state import _across, _restore_planner, _save_planner
from nc.alarms import NcAlarm
from nc.channel import READS_PER_CYCLE, Channel
from nc.motion.planner import Planner
from nc.motion.stretch import Samples, cut_rows, refuses
from virtual_bus.drive_stretch import CspRun, CsvRun, Stretch
from virtual_bus.kernels import drive_kernel

PLAN_KINDS = ("path", "ramp", "cruise")
FEW = 12  # rows below which the filter takes them one by one (Pass._flush)
REMARK = 4  # parts between two marks of a pass that reads nothing (Pass._group, decision bench B199)


def _save(pl: Planner, filt: bool = True) -> dict:
    """Everything a planner step but a push changes (module doc); `filt` False: not the position filter's state,
    which a step here leaves as it is (the pass filters its rows itself, `Pass._flush`)."""
    saved = _save_planner(pl, filt)
    if "blocks" not in saved:
        saved["blocks"] = list(pl.blocks)
    if pl.plan is not None:
        saved["plan"] = (pl.plan, dict(pl.plan.__dict__))
    return saved


def _feed_due(pl: Planner) -> bool:
    """The next cycle's feed reads (`not Planner.full` without its side effect, which that feed has)."""
    n = len(pl.blocks)
    return n < pl.depth or (pl._filling and n < pl.depth + pl._batch)


def no_reads(ch: Channel) -> bool:
    """The channel's feed reads nothing while the planner moves: the program's end, a barrier or a limit alarm was
    read, or a single block waits (Channel._feed_planner)."""
    return ch.end is not None or ch._deferred is not None or ch._limit_alarm is not None \
        or (ch.single_block and bool(ch._block_moves))


class Pass:
    """The NC pass of one stretch and its drive models, a part at a time (module doc).

    What a part costs is fixed, not per row: a CAM program's part is a cycle or two (a refill every block that is
    not a cruise's, a feed every fourth cycle), so the pass keeps per part only what it must (issue 17, decision
    bench B137): the drives' targets are converted at a drive check (not at each flush), the planner's `output` set
    at the pass's end (nothing in the pass reads it), and a take's rows, lines and speeds are kept as the planner's
    buffer has them (views, no Samples) and joined once in `samples()`."""

    def __init__(self, st: Any, ch: Channel, pl: Planner, rx0: list, saved_drives: list[dict],
                 soft: int | None = None) -> None:
        self.st, self.ch, self.pl = st, ch, pl
        # from `soft` cycles on, the stretch ends before the first cycle whose feed reads nothing (decision B68: the
        # next stretch can start there; one cannot start at a reading cycle)
        self.soft = soft
        self.rx0, self.saved_drives = rx0, saved_drives
        self.parts: list[tuple] = []  # each take's (raw rows, λ, lines, path speeds, move, moves) (take_parts)
        self.out_rows: list[list[float]] = []  # the filtered rows, `filtered` of them
        self.pend = 0  # parts[pend:] are not filtered yet (their raw rows and λ: a part's first two)
        self.filtered = 0
        self.rows = 0
        self.runs: list[CspRun | CsvRun] | None = None  # the drive models over the cycles driven (made at the first part)
        self.cores: list = []  # what drive_kernel.drive_parts steps of them (_make_runs)
        self.driven = 0  # cycles the drives were stepped through
        self.targets: list[list[int]] = [[rx.target_position] for rx in rx0[:st.n_axes]]
        self.converted = 0  # filtered rows whose targets are in `targets` (after the pending one: `_convert`)
        # each axis's AxisScaling.to_counts factor and origin (the runner's: nothing in a pass shifts it)
        org = st.r.origin.tolist()
        self.to_counts = [(sc._cpu, org[i]) for i, sc in enumerate(st.r.scales[:st.n_axes])]
        self.feeds = 0
        self.reads = not no_reads(ch)  # (constant over the stretch: its feeds read plain moves only)
        # Planner.full's bounds (_feed_due inline); nothing in a pass changes the depth
        self.depth, self.fill_to = pl.depth, pl.depth + pl._batch

    @property
    def outs(self) -> list[Stretch]:
        """Each drive's feedback over the cycles driven (after run(): the drives' state written, `last` set)."""
        return [Stretch() for _ in self.rx0] if self.runs is None else [run.out for run in self.runs]

    def run(self, n: int) -> int:
        """The stretch's cycles, at most n: how many (the planner after that many steps, `outs` over them)."""
        m = self._run(n, n if self.soft is None else self.soft)
        for run in self.runs or ():
            run.finish()
        if self.out_rows:  # the last filtered row, as step() leaves it (nothing in the pass reads it before)
            self.pl.output = np.array(self.out_rows[-1])
        return m

    def _run(self, n: int, soft: int) -> int:
        ch, pl = self.ch, self.pl
        src = ahead(ch)
        fed_at = -1
        reads = self.reads
        depth, fill_to = self.depth, self.fill_to
        # [rows, the planner then, parts then]: where a drive fault puts it back. The planner's save is the one the
        # next _group makes before its step (the same state: a feed's drive check flushed the filter), not one more
        self._mark = [0, None, 0]
        while self.rows < n:
            due = reads and ((q := len(pl.blocks)) < depth or (pl._filling and q < fill_to))
            if self.rows >= soft and not due:
                break
            if due and self.rows:  # this cycle's feed reads: the drives up to it first
                stop = self._drive(self.rows + 1)
                if stop is not None:
                    return self._back(stop)
                if self.rows < 2 or not may_read(ch, pl) or not src.peek(READS_PER_CYCLE):
                    break
                ch._feed_planner()  # plain moves only: it pushes them, nothing else changes
                self.feeds, fed_at = self.feeds + 1, self.rows
                self._mark = [self.rows, None, len(self.parts)]
            if not self._group(n - self.rows):
                break
        if fed_at == self.rows:  # the stretch ends before the cycle whose feed it ran: its step must not read
            ch._fed = True
        if self.driven > self.rows:  # stepped up to a reading cycle the stretch then ends before: again to here
            self._redrive()
            return self.rows
        stop = self._drive(self.rows)
        return self.rows if stop is None else self._back(stop)

    def _group(self, limit: int) -> bool:
        """One planner step as Planner._step_path makes it before its take, then the rows that follow it with no
        feed or refill between (at least one, at most `limit`), as `take_parts` hands them out (not filtered yet);
        False where the step cannot be taken here (module doc), the planner then as before it."""
        pl = self.pl
        pos, i = pl._buf_pos, pl._buf_i
        refill = pos is None or i >= len(pos)  # (Planner._buf_done, spelt out: a property call a part)
        if refill and self.pend < len(self.parts):
            # a refill reads the filter: at rest whether it settled, and a solve its state (a filter start or stop
            # is checked on a copy of it, decision motion 52)
            self._flush()
        mark = self._mark
        if mark[1] is None:  # the first step after a feed (or the start): the planner saved, its filter too
            mark[1] = _save(pl)
        elif refill and not self.reads and len(self.parts) - mark[2] >= REMARK and self._drive(self.rows) is None:
            # No feed moves the mark in a pass that reads nothing (a program's tail): a refused step replayed every
            # refill since the pass's start (a CAM program's last pass: 29 parts, ≈ 1 % of its run). A mark before
            # a refill every REMARK parts instead (issue 17, decision bench B199), where the drives ran without a
            # fault up to it (as a feed's check: a fault found later is after it; one found here is found again
            # at the pass's end, its drive stopped, and `_back` cuts from the mark before)
            self._mark = mark = [self.rows, _save(pl), len(self.parts)]
        # A step that may change the planner (a refill, a cruise's next block) is not saved before it (issue 17,
        # decision bench B159): the one refused (once a stretch) is undone from the mark's save, the steps since
        # made again (`_rewind`; they are deterministic, as `_back` makes them)
        changes = refill or pl._buf_blk is not None
        got = None
        try:
            pl._before_take()
            # `take_parts(pl, limit', cruise)` of a plan the pass samples, its checks made once here (a part is a
            # cycle or two of a CAM program; issue 17, decision bench B165), the rows taken by the same `refuses`
            # and `cut_rows`; none where the pass cannot take them. limit' is 1 where the next cycle's feed reads, a
            # cruise's `_across` bound otherwise (the rows up to the first cycle whose feed would read). Inline, not
            # a method of its own: a call and the planner's fields read again a part (B178)
            pos, i, p, blocks = pl._buf_pos, pl._buf_i, pl.plan, pl.blocks
            if pos is not None and i < len(pos) and p is not None and p.kind in PLAN_KINDS and blocks \
                    and not pl._integrate_angle:
                mv = blocks[0].move
                if mv.css is None and not refuses(pl, mv):
                    blk = pl._buf_blk
                    if self.reads and ((q := len(blocks)) < self.depth or (pl._filling and q < self.fill_to)):
                        limit = 1  # the next cycle reads: a feed comes between
                    elif blk is not None:
                        limit = _across(self.ch, pl, limit)
                    if blk is None:  # (Planner._block_rows outside a cruise: the buffer's rows left)
                        m = len(pos) - i
                        if limit < m:
                            m = limit
                    else:
                        m = pl._cruise_rows(limit)
                    if m > 0:  # (else the next row starts the cruise's next block: step() finishes this one)
                        got = cut_rows(pl, i, m, mv)
        except NcAlarm:  # the step raises: stepping raises it in its own cycle
            got = None
        if got is None:
            if changes:
                self._rewind()
            return False
        self.parts.append(got)
        self.rows += len(got[0])
        return True

    def _rewind(self) -> None:
        """The planner as before the step just refused: from the mark's save, the steps since made again (they
        are deterministic; what they pushed through the filter is pushed again, the same rows)."""
        rows = self.rows
        if not self._cut_to_mark():
            return  # the mark's save was taken before that very step
        while self.rows < rows and self._group(rows - self.rows):
            pass

    def _cut_to_mark(self) -> bool:
        """The planner, the rows and the parts as at the last mark; False where nothing was taken since."""
        rows, saved, nparts = self._mark
        assert saved is not None  # (a _group follows every mark)
        _restore_planner(self.pl, saved)  # (a mark is taken after a feed, whose drive check flushed the filter)
        moved = self.rows != rows
        del self.parts[nparts:]
        self.pend = nparts
        self.rows = self.filtered = rows
        del self.out_rows[rows:]
        if self.converted > rows:
            self.converted = rows
            for t in self.targets:
                del t[rows + 1:]
        return moved

    def _flush(self) -> None:
        """The rows taken since the last flush through the position filter (push_many at once, push_rows row by
        row: each gives what step()'s push gives row by row)."""
        parts, k = self.parts, self.pend
        n = len(parts)
        if k == n:
            return
        self.pend = n
        f = self.pl.filter
        if k == n - 1:  # (most flushes: a part of one take)
            raw, lam = parts[k][0], parts[k][1]
            if f is not None and len(raw) >= FEW:
                rows = f.push_many(raw, lam).tolist()
            else:  # push_many's numpy costs ≈ 35 µs whatever the rows; push_rows ≈ 1.5 µs a row, the same bits
                rows = raw.tolist()
                if f is not None:
                    rows = f.push_rows(rows, None if lam is None else lam.tolist())
            self.out_rows += rows  # (an array once, in samples())
            self.filtered += len(rows)
            return
        pending = parts[k:]
        if f is not None and sum(len(p[0]) for p in pending) >= FEW:
            raw = np.concatenate([p[0] for p in pending])
            lam = None if all(p[1] is None for p in pending) else \
                np.concatenate([np.ones(len(p[0])) if p[1] is None else p[1] for p in pending])
            rows = f.push_many(raw, lam).tolist()
        else:
            rows = []
            for p in pending:
                rows += p[0].tolist()
            if f is not None:
                lams: list[float] | None = None
                if any(p[1] is not None for p in pending):
                    lams = []
                    for p in pending:
                        lams += [1.0] * len(p[0]) if p[1] is None else p[1].tolist()
                rows = f.push_rows(rows, lams)
        self.out_rows += rows  # (an array once, in samples())
        self.filtered += len(rows)

    def _convert(self) -> None:
        """The drives' targets of the rows filtered since the last conversion (AxisScaling.to_counts, inline)."""
        out, c = self.out_rows, self.converted
        if c == len(out):
            return
        drive_kernel.to_counts(out, c, self.to_counts, self.targets)  # (the drive kernel: round() on C doubles)
        self.converted = len(out)

    def _drive(self, upto: int) -> int | None:
        """The drive models over cycles driven … upto-1 (cycle k steps to the setpoint of cycle k-1); the first
        cycle a drive or the bench's overspeed check would fault in, else None."""
        if self.pend < len(self.parts):
            self._flush()
        if self.converted != len(self.out_rows):
            self._convert()
        if upto <= self.driven:
            return None
        if self.runs is None:
            self.runs = self._make_runs()
        # each drive over cycles driven … upto-1 (the drive kernel's loop over the drives, CspCore's parts: B198);
        # the first cycle a drive stops before (its `done`) or whose 0x606C is above the bench's bound (its
        # `over_at`, kept by the drive kernel as it writes the cycles: none before `driven`, or an earlier part
        # ended there); a still drive's cycles not written yet (CspCore.lag) repeat its last
        m = drive_kernel.drive_parts(self.cores, self.targets, self.driven, upto, self.st.n_axes)
        self.driven = upto
        return m if m < upto else None

    def _make_runs(self) -> list[CspRun | CsvRun]:
        """The drive models from the stretch's start, each axis's with the bench's overspeed bound (App. A 0x0602,
        `Stretch.limit`)."""
        r, n_axes = self.st.r, self.st.n_axes
        dt = r.bench.cycle
        runs: list[CspRun | CsvRun] = []
        for i, (d, rx) in enumerate(zip(self.st.drives, self.rx0)):
            if i < n_axes:
                run: CspRun | CsvRun = CspRun(d, rx, dt)
                run.out.limit = r._overspeed[i]
            else:
                run = CsvRun(d, rx, dt)
            runs.append(run)
        # what the drive kernel steps: a CSP axis's CspCore, else the run (decision bench B198)
        self.cores = [run.core if type(run) is CspRun and run.core is not None else run for run in runs]
        return runs

    def _back(self, stop: int) -> int:
        """A drive faults in cycle `stop`: the stretch ends before it. The planner from the last save (after a
        feed, or the start), its steps made again up to there; the drives stepped again from the start."""
        self._cut_to_mark()
        while self.rows < stop and self._group(stop - self.rows):
            pass
        self._redrive()
        return self.rows

    def _redrive(self) -> None:
        """The drives from the start again, over the stretch's cycles as they now are."""
        self.runs = None  # dropped, not finished: the drives as they were at the stretch's start
        self.st._restore_drives(self.saved_drives)
        self.driven = 0
        self._drive(self.rows)

    def samples(self) -> Samples:
        """The stretch's rows (filtered), with their raw positions (`Samples.raw`)."""
        self._flush()
        self._convert()
        parts = self.parts
        lines: list[int] = []
        moves: list[Any] = []
        for _, _, ln, _, mv, mvs in parts:
            lines += ln
            moves += mvs if mvs is not None else [mv] * len(ln)
        out = self.out_rows
        # the rows as one flat run of floats: numpy's conversion of a list of row lists costs ≈ 4× (B165)
        positions = np.fromiter(chain.from_iterable(out), np.float64, len(out) * len(out[0])).reshape(len(out), -1) \
            if out else np.array(out)
        return Samples(positions, lines, np.concatenate([p[3] for p in parts]).astype(float, copy=False),
                       parts[0][4], moves, np.concatenate([p[0] for p in parts]))
