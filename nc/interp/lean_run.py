"""The lean lane's runs (issue 17, decisions bench B173): the lines after a plain line of one shape, read in one pass.

A CAM program is thousands of lines of one shape (`X.. Y..`). `nc.interp.lean` runs each as a call from the
program counter: the counter's checks, the call, one regular-expression match, its groups and two `float` calls a
line. Once a line of a shape has run there and its Move is handed out, the shape's `stream` (built here once per
shape and profile, as its `run` is) reads the next lines in chunks of CHUNK: two `str.translate` calls over the
chunk's text (its letters alone must be the shape's, line after line; its numbers alone, split, are every word's
number), `map(float)` a column's values; then it hands the Moves out one by one, each made, and the interpreter's
state left, as the shape's `run` makes and leaves them for that line (the same code, line by line: the lean lane
on and off give the same events and the same state at every event, tests/test_lean33_runs.py). One thing differs:
a run's lines are written into one LineBlock of its own (decisions bench B200), so `Interpreter.block` is the same
object, read as each line's block, from one line of a run to the next (a caller keeps `block.plain()`).

Before each line it asks what the program counter and `run` ask: the frame on top and its counter where the last
line left them (an M96 interrupt, a `--at` event, a macro call change them), no interrupt pending, no corner
waiting, the statement budget not spent, the block limit not reached, the plain state and work origin kept
(`Interpreter._lean_origin`: cleared by every block the general path runs, a system variable written, a run begun)
and, for a shape with G, the code-call tables `LeanLane.g_ok` was found with. Anything else stops the run at that
line, before anything of it is done: the program counter takes it as before (block by block, or the lean lane's
`run`). A chunk is taken only when each of its items is a plain line of its own, one line break apart, of the
shape, with a decimal point in every axis word and every axis inside +-1e9 (else its lines run one by one, as
before: a line of another shape, N8.018's rule for a word without a point, 0x120E at its line).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

CHUNK = 64  # lines a `findall` reads: a run interrupted mid-chunk has read at most this many lines for nothing
# A chunk of plain lines (nc.program.blocks `_PLAIN_ITEM`: an optional N, then words, each a letter and its number
# with nothing between, blanks around) seen two ways: its letters alone, upper case, a line break after each line
# but the last (SKELETON), and its numbers alone (NUMBERS: every letter a blank), each word's number a run of
# [-+.0-9] (the lean lane's `_NUM`: the run after its letter)
_LOWER = "abcdefghijklmnopqrstuvwxyz"
SKELETON = str.maketrans(_LOWER, _LOWER.upper(), "-+.0123456789 \t")
NUMBERS = str.maketrans(_LOWER + _LOWER.upper(), " " * 52)


def chunk_at(text: str, starts: Sequence[int], lengths: Sequence[int], pc: int, count: int, letters: str, k: int,
             expect: str) -> tuple[int, str, list[str]] | None:
    """The longest chunk of CHUNK, CHUNK / 2, ... (at least 2) lines from item `pc` that are plain lines of their own, one
    line break apart, of the shape whose letters are `letters` (`k` of them; `expect` those of CHUNK lines): (its
    number of lines, its text, every word's number in order), or None."""
    n = count - pc
    if n > CHUNK:
        n = CHUNK
    while n >= 2:
        end = pc + n
        s0 = starts[pc]
        e1 = starts[end - 1] + lengths[end - 1]
        # each item a plain line of its own (start >= 0), one line break after the other
        if min(starts[pc:end]) >= 0 and e1 - s0 == sum(lengths[pc:end]) + n - 1:
            chunk = text[s0:e1]
            # the letters of every line, in order, nothing else (the numbers and blanks out, upper case)
            if chunk.translate(SKELETON) == (expect if n == CHUNK else "\n".join([letters] * n)):
                nums = chunk.translate(NUMBERS).split()  # each word's number, line after line
                if len(nums) == n * k:
                    return n, chunk, nums
        n //= 2  # a shorter run (the program's last lines of this shape before a block of another)
    return None


def axes_dict(axes: Sequence[str], p: str) -> str:
    """The source of the dict of the axes' values `p0`, `p1`, ... (`{'X': m0, 'Y': m1}`)."""
    return "{" + ", ".join(f"{a!r}: {p}{i}" for i, a in enumerate(axes)) + "}"


def move_lines(pad: str, axes: Sequence[str]) -> list[str]:
    """The source of a line's Move, made as Move(...) makes it, each of its fields set (no __init__ frame with 23
    arguments, issue 17), indented by `pad`: the lean lane's `run` (nc.interp.lean) and a run's `stream` make it
    alike. Its end (the axes' `m0`, `m1`, ...) is also bound to `end_` and its work coordinates to `work`. Its start
    is the dict `position` was, which the caller rebinds and nothing else reads (no consumer changes a move's start
    or end in place)."""
    return [pad + x for x in (
        "ip.unit_locked = True",
        "mv = NEW(Move)",
        "if motion == 0:",
        "    mv.kind = 'rapid'",
        "    mv.feed = None",
        "    mv.per_rev = False",
        "else:",
        "    mv.kind = 'line'",
        "    mv.feed = mfeed",
        "    mv.per_rev = st.per_rev",
        "mv.line = line",
        "mv.block = raw",
        "mv.start = position",
        f"mv.end = end_ = {axes_dict(axes, 'm')}",
        f"mv.work = work = {axes_dict(axes, 'w')}",
        "mv.center = mv.dir = mv.duration = mv.lead = mv.comp = None",
        "mv.plane = PLANES[st.plane]",
        "mv.exact_stop = st.exact_stop_modal",
        "mv.lead_change = mv.start_angle = mv.turns = mv.comp_radius = 0.0",
        "mv.program = name",
        "mv.tags = ()",
        "mv.tip = 0",
        "mv.css = st.surface_speed if st.css else None")]


def streamed(letters: tuple[str, ...], g: int | None, f: int | None, programmed: tuple[tuple[str, int], ...],
             axes: tuple[str, ...], diameter: frozenset[str] | tuple[str, ...], space: dict) -> Callable[..., object]:
    """The run generator of a shape that moves (`programmed` not empty): `lean._compiled`'s line, step for step,
    over the lines of a chunk (`space`: the names `_compiled`'s code reads)."""
    words = dict(programmed)
    src = ["def stream(lane, ip, fr, pc, limit, text, starts, lengths, file_lines, count, budget):",
           "    origin = ip._lean_origin",
           "    if origin is None:",
           "        return",
           "    st = ip.state",
           "    stack = ip.stack",
           "    name = fr.program.name"]
    for i, a in enumerate(axes):
        src.append(f"    o{i} = origin[{a!r}]")
    # the run's one LineBlock, each line's written into it (B200: a LineBlock made and freed a line was 1.5k of the
    # stream's 18.5k instructions a CAM block). Nothing holds `Interpreter.block` past the next line but the run's
    # own checks stop it first (an M96 program's saved block, `_run`'s `last` once the run is done)
    src += ["    b = NEW(LineBlock)",
            "    b._shape = SHAPE",
            "    while True:",
            f"        got = CHUNK_AT(text, starts, lengths, pc, count, {''.join(letters)!r}, {len(letters)}, EXPECT)",
            "        if got is None:",
            "            lane.retry = range(pc, pc + CHUNK)  # not of this shape: line by line up to there",
            "            return",
            "        n, chunk, nums = got",
            "        end = pc + n",
            "        raws = chunk.split('\\n')",
            "        fl = file_lines[pc:end]"]
    k_all = len(letters)
    # a line's numbers as a tuple, as the shape's match gives them (LineBlock reads its words from it)
    src.append(f"        found = list(zip(*[iter(nums)] * {k_all}))")
    cols = []
    for a, k in programmed:
        src += [f"        t_{a} = nums[{k}::{k_all}]",
                f"        if ''.join(t_{a}).count('.') != n:  # N8.018: a point in every axis word (one at most)",
                "            lane.retry = range(pc, pc + CHUNK)",
                "            return",
                f"        c_{a} = list(map(float, t_{a}))"]
        cols.append(a)
    if f is not None:
        src.append(f"        c_F = list(map(float, nums[{f}::{k_all}]))")
        cols.append("F")
    if g is not None:
        src.append(f"        c_G = nums[{g}::{k_all}]")
        cols.append("G")
    for i, a in enumerate(axes):
        if a in words:  # the chunk's extremes inside +-1e9, so is every line's (`run`'s check: x -> x + o is monotone)
            half = " / 2.0" if a in diameter else ""
            src += [f"        if not (-1e9 <= min(c_{a}){half} + o{i} and max(c_{a}){half} + o{i} <= 1e9):",
                    "            lane.retry = range(pc, pc + CHUNK)  # line by line: the general path's 0x120E at its line",
                    "            return"]
    src += ["        lane.runs += 1",
            f"        for vals, raw, line, {', '.join('v_' + c for c in cols)} in zip(found, raws, fl, "
            f"{', '.join('c_' + c for c in cols)}):",
            "            if (ip._lean_origin is not origin or fr.pc != pc or stack[-1] is not fr or ip._interrupt_pending",
            "                    or ip.corner_pending or ip._executed >= limit",
            "                    or (budget is not None and budget.used >= budget.limit)):",
            "                return  # the program counter takes this line"]
    if g is None:
        src.append("            motion = st.motion")
    else:
        src += ["            motion = _G_MOTION.get(v_G)",
                "            if motion is None or ip._call_tables is not lane.tables or not lane.g_ok:",
                "                return"]
    if f is None:
        src.append("            feed = st.feed")
    else:
        src += ["            feed = v_F",
                "            if feed < 0:",
                "                return"]
    src.append("            position = ip.position")
    for i, a in enumerate(axes):
        if a in words:
            src.append(f"            w{i} = v_{a}")
        elif a in diameter:
            src.append(f"            w{i} = (position.get({a!r}, 0.0) - o{i}) * 2.0")
        else:
            src.append(f"            w{i} = position.get({a!r}, 0.0) - o{i}")
    src += ["            if motion == 1:",
            "                if feed is None or feed == 0.0:",
            "                    return",
            "                mfeed = feed * 1.0"]
    for i, a in enumerate(axes):
        src.append(f"            m{i} = " + (f"w{i} / 2.0 + o{i}" if a in diameter else f"w{i} + o{i}"))
        if a not in words:
            src += [f"            if not -1e9 <= m{i} <= 1e9:",
                    "                return"]

    src += ["            pc += 1",
            "            fr.pc = pc",
            "            ip._executed += 1",
            "            ip.program_name = name",
            "            ip.block = b  # the run's LineBlock, this line's (its words read again from `_vals` when asked)",
            "            b.line = line",
            "            b.text = raw",
            "            b._vals = vals"]
    if g is not None:
        src += ["            st.groups[1] = float(v_G)", "            st.motion = motion"]
    if f is not None:
        src.append("            st.feed = feed")
    src += move_lines("            ", axes)
    src += ["            ip.position = {**end_}  # a copy (cloned: half the cost of building it)",
            "            ip.last_target = work",
            "            yield mv"]
    space = dict(space, CHUNK=CHUNK, CHUNK_AT=chunk_at, EXPECT="\n".join(["".join(letters)] * CHUNK))
    exec(compile("\n".join(src) + "\n", f"<lean run {''.join(letters)}>", "exec"), space)
    return space["stream"]
