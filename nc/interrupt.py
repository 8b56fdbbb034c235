"""M96 program interruption in the channel (NC5 §3.11.4.6): what happens after the MLC's M2x019.

The channel has read blocks ahead of the motion (look-ahead queue, preview), so the interpreter is
already past the block the axes are executing when the trigger comes. The channel therefore stops
the axes along the path, takes the suspended block and everything queued behind it out of the
planner, and runs this stream instead of the program's:

1. the interrupt program's events, interpreted at once from the stop point (`Interpreter.interrupt_events`);
2. a Sync: its motion ends at rest, and only then M3x031 drops;
3. the way back (note 2): a straight line from where the interrupt program left the tool to the
   suspended block's end point — a rapid after G00, a cutting line at the block's feed otherwise,
   also for G02/G03; when no block had begun (trigger between blocks), back to where the axes stood;
4. the moves and the M/S/T code or program end that were read ahead, unchanged;
5. the rest of the program.
The decisions are in docs/decisions/mlc.md (M96 interruption).
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import Any

from nc.alarms import NcAlarm
from nc.moves import Event, Move, Sync


@dataclass
class M96Link:
    """What the channel needs of the interpreter for M96: whether M96 P_ is in force, the interrupt
    program's events from a stop point (machine coordinates), and work coordinates of a point."""

    enabled: Callable[[], bool]
    program: Callable[[dict[str, float]], Iterator[Event]]
    to_work: Callable[[dict[str, float]], dict[str, float]]


def m96_link(interp: Any) -> M96Link:
    """Channel.m96 for an Interpreter."""
    return M96Link(lambda: interp.interrupt_program is not None, interp.interrupt_events, interp.to_work)


def suspended(held: list[Event], stop: dict[str, float]) -> tuple[Move | None, list[Event]]:
    """Split what the planner held when the axes stopped at `stop` into (the suspended block, the
    events that follow it). A first move the axes had not left the start of was not begun: it runs
    again whole after the return, so the suspended block is None then."""
    first = held[0] if held else None
    if isinstance(first, Move) and first.kind != "dwell" and _moved(first.start, stop):
        return first, held[1:]
    return None, held


def return_move(block: Move | None, follow: list[Event], here: dict[str, float], stop: dict[str, float],
                link: M96Link) -> Move | None:
    """The straight move from `here` back into the suspended program (note 2), None if already there."""
    if block is not None:
        end, work, ref = dict(block.end), dict(block.work), block
    else:
        ref = next((e for e in follow if isinstance(e, Move)), None)
        if ref is None:
            return None  # nothing of the main program's motion left: it goes on from here
        end = {a: stop.get(a, v) for a, v in ref.start.items()}
        work = link.to_work(end)
    start = {a: here.get(a, v) for a, v in end.items()}
    if not _moved(start, end):
        return None
    cut = ref.kind not in ("rapid", "dwell") and ref.feed
    return Move("line" if cut else "rapid", ref.line, ref.block, start, end, work,
                feed=ref.feed if cut else None, per_rev=ref.per_rev if cut else False, plane=ref.plane,
                program=ref.program, tags=("M96", "resume"), css=ref.css)


def interrupt_stream(ch: Any, held: list[Event], stop: dict[str, float],
                     rest: Iterator[Event] | None) -> Iterator[Event]:
    """The events the channel reads after the trigger (steps 1–5 above); `ch` is the Channel."""
    link: M96Link = ch.m96
    block, follow = suspended(held, stop)
    ref = block or next((e for e in follow if isinstance(e, Move)), None)
    if ref is not None and ref.comp:  # note 3, judged on the suspended block (the reading is ahead)
        raise NcAlarm(0x0005, f"M96 interrupt while {ref.comp} is active", line=ref.line, block=ref.block,
                      program=ref.program)
    ch._m96_running = True
    yield from link.program(stop)
    yield Sync(0, "M99", "M96 interrupt program ends")  # runs on only once its motion is done
    ch._m96_running = False
    here = dict(zip(ch.planner.axes, ch.planner.position.tolist()))
    back = return_move(block, follow, here, stop, link)
    if back is not None:
        yield back
    yield from follow
    if rest is not None:
        yield from rest


def _moved(a: dict[str, float], b: dict[str, float]) -> bool:
    return any(abs(v - b.get(k, v)) > 1e-9 for k, v in a.items())
