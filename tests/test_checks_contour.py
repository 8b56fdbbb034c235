"""The contour check over all cycles at once (hil/contour_distance.py) gives each cycle the distance a
plain per-cycle reading of its rule gives: the nearest candidate move's path, the candidates being the
moves of every line seen within the lag before the cycle's run of cycles, and their neighbours."""

import math

import numpy as np
import pytest

from hil.checks import _Cols, check_contour
from hil.contour_distance import contour_distances
from nc.motion.path import Segment
from nc.moves import Move
from tests.test_bench_checks import base, write

LAG = 6


def zigzag(n: int, arcs: bool = True, stalls: bool = False) -> list[Move]:
    """n short lines (0.1–0.3 mm, turning), a quarter arc after every 40th, a dwell and a rapid; with
    `stalls` a zero-length line (a block to where the tool stands, its own line) after every 37th."""
    rng = np.random.default_rng(7)
    moves, p, heading = [], (0.0, 0.0), 0.0
    for k in range(n):
        heading += rng.normal(0.0, 0.6)
        q = (p[0] + rng.uniform(0.1, 0.3) * math.cos(heading), p[1] + rng.uniform(0.1, 0.3) * math.sin(heading))
        moves.append(Move("line", k + 1, "G01", {"X": p[0], "Z": p[1]}, {"X": q[0], "Z": q[1]}, {}, feed=600.0))
        p = q
        if arcs and k % 40 == 39:
            c = (p[0] + 0.5, p[1])
            q = (c[0], c[1] + 0.5)
            moves.append(Move("arc", k + 1, "G02", {"X": p[0], "Z": p[1]}, {"X": q[0], "Z": q[1]}, {}, feed=600.0,
                              center={"X": c[0], "Z": c[1]}, dir="cw", plane=("Z", "X")))
            p = q
        if stalls and k % 37 == 36:
            moves.append(Move("line", 10_000 + k, "G01", {"X": p[0], "Z": p[1]}, {"X": p[0], "Z": p[1]}, {},
                              feed=600.0))
    moves.append(Move("dwell", n + 1, "G04", {"X": p[0], "Z": p[1]}, {"X": p[0], "Z": p[1]}, {}))
    moves.append(Move("rapid", n + 2, "G00", {"X": p[0], "Z": p[1]}, {"X": p[0] + 5.0, "Z": p[1] + 3.0}, {}))
    return moves


def seg_distance(p, a, b) -> float:
    ab = [y - x for x, y in zip(a, b)]
    ab2 = sum(v * v for v in ab) or 1.0
    u = min(1.0, max(0.0, sum((pi - ai) * v for pi, ai, v in zip(p, a, ab)) / ab2))
    return math.dist(p, [ai + u * v for ai, v in zip(a, ab)])


def move_segments(m: Move):
    """A move's path as chords: a line's one, an arc's 2,000 (the check's own are within 0.1 µm)."""
    if m.kind == "dwell":
        return []
    seg = Segment.of(m, ("X", "Z"))
    pts = seg.points(np.linspace(0.0, seg.length, 2 if m.kind != "arc" else 2001)).tolist()
    return list(zip(pts[:-1], pts[1:]))


def reference(act, line, moves, lag):
    """Each cycle by the rule, in plain Python."""
    by_line: dict[int, set[int]] = {}
    has_path = [m.kind not in ("line", "rapid") or m.start != m.end for m in moves]
    for i, m in enumerate(moves):
        by_line.setdefault(m.line, set()).update(j for j in (i - 1, i, i + 1) if 0 <= j < len(moves))
        # and the nearest moves before and after with a path: a zero-length block is no corner
        by_line[m.line].update(next((j for j in range(i - 1, -1, -1) if has_path[j]), i) for _ in (0,))
        by_line[m.line].update(next((j for j in range(i + 1, len(moves)) if has_path[j]), i) for _ in (0,))
    judged = {m.line for m in moves if m.kind in ("line", "arc", "thread")}
    segs = [move_segments(m) for m in moves]
    out = np.zeros(len(line))
    r0 = 0
    for i in range(len(line)):
        if i and line[i] != line[i - 1]:
            r0 = i
        if int(line[i]) not in judged:
            continue
        r1 = i
        while r1 < len(line) and line[r1] == line[i]:
            r1 += 1
        cand = set().union(*(by_line.get(int(ln), set()) for ln in set(line[max(0, r0 - lag):r1].tolist())))
        out[i] = min((seg_distance(act[i], a, b) for j in cand for a, b in segs[j]), default=math.inf)
    return out


def trace_along(moves, seed: int = 3):
    """1–3 cycles a line (a CAM program's pace), the line met again in a loop near the end, each
    actual position off the path by up to 5 µm and trailing the line column by 5 cycles (the filter
    and the drive's lag: its candidates come from the lines of the window before its run)."""
    rng = np.random.default_rng(seed)
    feeds = [m for m in moves if m.kind in ("line", "arc")]
    order = feeds + feeds[100:110]
    line, act = [], []
    for m in order:
        seg = Segment.of(m, ("X", "Z"))
        for p in seg.points(np.linspace(0.0, seg.length, int(rng.integers(1, 4)), endpoint=False)):
            line.append(m.line)
            act.append(p + rng.uniform(-5e-3, 5e-3, 2))
    act = act[:1] * 5 + act[:-5]
    last = moves[-1]
    line += [last.line] * 5
    act += [[last.start["X"] + 2.0, last.start["Z"] + 2.0]] * 5
    return np.array(act), np.array(line, dtype=np.int64)


@pytest.mark.parametrize("arcs, within, stalls", [(False, 1e-15, False), (True, 1.01e-4, False),
                                                  (True, 1.01e-4, True)])
def test_every_cycle_has_the_distance_its_rule_gives(arcs, within, stalls):
    """Lines to the last bits; arcs within the check's chord error (1e-4 mm, the reference's ≈ 0); zero-length
    blocks between moves leave the moves on either side each other's neighbours (fuzz21)."""
    moves = zigzag(300, arcs, stalls)
    act, line = trace_along(moves)
    got = contour_distances(act, line, moves, ["X", "Z"], LAG, False)
    want = reference(act, line, moves, LAG)
    assert np.all(np.isfinite(got[:-5])) and np.all(got[-5:] == 0.0)  # the rapid's line is not judged
    assert np.max(np.abs(got - want)) <= within
    assert 0.002 < float(np.max(got)) < 0.0071


@pytest.mark.parametrize("lag", [0, 1, 40])
def test_the_candidates_are_the_rules_at_any_lag(lag):
    """A run's candidates are gathered as intervals of moves merged run by run (B139): with no lag (the run's own
    lines), one cycle, and a window of dozens of lines (overlapping neighbours, the loop's lines met again, the
    zero-length blocks' neighbours), each cycle's distance is the plain rule's to the last bits."""
    moves = zigzag(300, arcs=False, stalls=True)
    act, line = trace_along(moves, seed=5)
    got = contour_distances(act, line, moves, ["X", "Z"], lag, False)
    want = reference(act, line, moves, lag)
    assert np.all(got[-5:] == 0.0) and np.max(np.abs(got - want)) <= 1e-15
    assert (float(np.max(got)) > 0.0071) == (lag < 5)  # the drive's 5 cycles of trail: within the rule's window


def test_the_worst_cycle_is_named_with_its_line(tmp_path):
    moves = zigzag(120)
    act, line = trace_along(moves)
    act = act[:-5]
    line = line[:-5]
    k = 200
    act[k] = act[k] + 0.3  # 0.3 mm off in X and Z
    d = base(len(line))
    d["line"], d["X_act"], d["Z_act"] = line, act[:, 0].copy(), act[:, 1].copy()
    r = check_contour(_Cols(write(tmp_path, d)), ["X", "Z"], moves, 0.05, LAG)
    assert not r.ok and r.cycle == k + 1 and r.line == int(line[k])
    assert r.value == pytest.approx(reference(act, line, moves, LAG)[k], abs=1e-12)
    assert "1 cycles over, first at cycle" in r.detail


def test_independent_rapids_are_judged_against_their_box():
    moves = zigzag(60)
    rapid = Move("rapid", 30, "G00", moves[29].end, {"X": moves[29].end["X"] + 4.0, "Z": moves[29].end["Z"] + 4.0}, {})
    moves.insert(30, rapid)
    act, line = trace_along(moves)
    i = int(np.flatnonzero(line == 30)[0])
    act[i] = [rapid.start["X"] + 4.0, rapid.start["Z"]]  # the box's corner: off the straight rapid by 2.8 mm
    straight = contour_distances(act, line, moves, ["X", "Z"], LAG, False)
    boxed = contour_distances(act, line, moves, ["X", "Z"], LAG, True)
    assert straight[i] == pytest.approx(math.sqrt(8.0), rel=1e-9)
    assert boxed[i] == 0.0
    others = np.arange(len(line)) != i
    assert np.all(boxed[others] <= straight[others])


@pytest.mark.parametrize("program, bench", [("examples/lathe_part_g71_g70_g76.nc", None),
                                            ("cam", "benches/mill-3axis.toml")])
def test_the_programmed_path_read_in_bulk_is_the_moves_one_by_one(tmp_path, program, bench):
    """program_moves reads plain G0/G1 runs and a cycle's moves in bulk: the same Moves as one by one."""
    from benchmarks.bench_motion import cam_program
    from hil import api
    from hil.checks import program_moves
    from hil.session import load_program
    from nc.interp import Interpreter
    from nc.profiles import make_profile

    if program == "cam":
        program = tmp_path / "cam.nc"
        program.write_text(cam_program(400).replace("M30", "G02 I5 J0\nG01 X1\nM30"))
    b = api._bench(bench, None, None)
    got = program_moves(load_program(str(program), []), b)
    interp = Interpreter(make_profile(b.profile, b.axis_names, b.params), {a.name: a.start for a in b.axes})
    want = [ev for ev in interp.run(load_program(str(program), [])) if isinstance(ev, Move)]
    assert len(got) > 100 and got == want
    assert any(m.kind == "arc" for m in got)


def test_an_estops_quick_stop_is_said_not_judged_as_contour_error(tmp_path, capsys):
    """B102: after an E-stop the drives brake on their own ramps (stop category 1) and leave the path; the contour
    check judges the path the NC commanded up to there and says how far the braking went off it."""
    from hil.cli import main
    from tests.conftest import ROOT

    x, lines = 0.0, ["G90 G17 G94 G01 F3000"]
    for k in range(300):  # bench_loop's CAM curve: 0.01–0.1 mm lines along a sine
        x += 0.01 + 0.09 * ((k * 7919) % 100) / 100.0
        lines.append(f"X{x:.4f} Y{20.0 * math.sin(x / 40.0):.4f}")
    prog = tmp_path / "cam.nc"
    prog.write_text("\n".join(lines + ["M30"]) + "\n")
    code = main(["run", str(prog), "--bench", str(ROOT / "benches" / "mill-3axis.toml"), "--at", "t=0.3:estop"])
    out = capsys.readouterr().out
    contour = next(ln for ln in out.splitlines() if "contour error" in ln)
    assert code == 1 and "ALARM 0x0401" in out  # the E-stop is the run's alarm, not a failed check
    assert contour.lstrip().startswith("ok") and "not judged:" in contour, contour
    off = float(contour.split("up to ")[1].split(" mm")[0])
    assert off > 0.05, contour  # the braking left the path by more than the limit: said, with its size
    assert "quick stop deceleration X" in out and "FAIL" not in out, out
