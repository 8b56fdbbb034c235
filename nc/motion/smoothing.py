"""Post-interpolation position filter: two moving averages in cascade on every axis' setpoints.

Delta's look-ahead filter time (N1.036) and look-ahead S-curve time (N1.037) smooth the
interpolated setpoints of the whole channel. Filtering every axis with the same kernel keeps the
path's shape; it rounds a corner instead of demanding an infinite jerk there:
  a velocity step Δv becomes an acceleration of Δv/T1 and a jerk of Δv/(T1·T2),
which is what lets the planner take corners and tightly curved short segments at speed while the
setpoint stream still meets every per-cycle limit. A moving average never raises the peak of a
signal, so the planned profile's own velocity/acceleration/jerk pass through unchanged in size.

The filter is exact at rest: once its input has been constant for a full window the output is
snapped to the input, so programs end bit-exactly where they are programmed.
"""

from __future__ import annotations

from collections import deque

import numpy as np

try:
    import cython  # compiled: the types below (setup.py, decision bench B115)
except ImportError:  # run as Python without Cython: they do nothing
    from nc.motion import cython_shadow as cython


class PositionFilter:
    def __init__(self, n1: int, n2: int, position: np.ndarray) -> None:
        self.n1 = max(1, int(n1))
        self.n2 = max(1, int(n2))
        self.span = self.n1 + self.n2 - 2  # cycles after which a constant input is reproduced exactly
        # The filter's share λ (decision motion 43): out = p(t − D) + λ·(F(p) − p(t − D)), D the group
        # delay. Only where D is a whole number of cycles that the first window still holds (n1 + n2
        # even, n2 ≤ n1: p(t − D) is w1[n1 − 1 − D]); elsewhere λ is ignored and F is output.
        self.lag: int | None = self.span // 2 if self.span % 2 == 0 and self.n2 <= self.n1 else None
        self.reset(position)

    def reset(self, position: np.ndarray) -> None:
        """Forget the history: the output is `position`, as if it had stood there forever."""
        # The state is kept in Python floats, one list per axis row: on 1–6 axes a list op costs a
        # fraction of a numpy call, with the same IEEE arithmetic in the same order (issue 17).
        x = np.asarray(position, dtype=float).tolist()
        self._w1: deque[list[float]] = deque([x] * self.n1, maxlen=self.n1)
        self._w2: deque[list[float]] = deque([x] * self.n2, maxlen=self.n2)
        self._s1 = [v * self.n1 for v in x]
        self._s2 = [v * self.n2 for v in x]
        self._out = x
        self._last = x  # rows are never changed in place: the windows share them
        self._still = self.span
        # The last three outputs (nc.motion.filter_ramps joins a candidate's outputs to them: finite differences);
        # a tuple rebound, never changed in place, so a shallow copy of the state keeps it (hil.stretch_state)
        self._recent: tuple[list[float], ...] = (x, x, x)

    @property
    def output(self) -> np.ndarray:
        """The last output."""
        return np.array(self._out)

    @property
    def recent(self) -> np.ndarray:
        """The last three outputs, oldest first (as the stream had them: rows before the first are the start)."""
        return np.array(self._recent)

    @property
    def settled(self) -> bool:
        """The output equals the input and stays there while the input does not move."""
        return self._still >= self.span

    @property
    def delay(self) -> float:
        """Group delay of the filter in cycles (a constant-speed move lags by this much)."""
        return (self.n1 - 1 + self.n2 - 1) / 2.0

    def push(self, x: np.ndarray, lam: float = 1.0) -> np.ndarray:
        """The next output for input row x; lam: the filter's share (1 = the filter's own output)."""
        return np.array(self._push(np.asarray(x, dtype=float).tolist(), lam))

    def push_rows(self, rows: list[list[float]], lams: list[float] | None = None) -> list[list[float]]:
        """push() of each row (lists of Python floats; lams[k] the share of row k, None: 1), the outputs as lists
        (never changed in place): the same values, without two numpy conversions a row (hil/stretch_pass.py)."""
        p = self._push
        if lams is None:
            return [p(row, 1.0) for row in rows]
        return [p(row, lam) for row, lam in zip(rows, lams)]

    @cython.locals(n1=cython.Py_ssize_t, n2=cython.Py_ssize_t, x0=cython.double, x1=cython.double,
                   x2=cython.double, s0=cython.double, s1=cython.double, s2=cython.double, o0=cython.double,
                   o1=cython.double, o2=cython.double, t0=cython.double, t1=cython.double, t2=cython.double)
    def _push(self, row: list[float], lam: float) -> list[float]:
        same = row == self._last
        if same and self._still >= self.span:
            self._recent = (self._recent[1], self._recent[2], self._out)
            return self._out
        if same:
            self._still += 1
            row = self._last
        else:
            self._still = 0
            self._last = row
        n1, n2 = self.n1, self.n2
        if len(row) == 3:  # the comprehensions below spelt out for 3 axes: once a cycle (session 13)
            x0, x1, x2 = row
            s0, s1, s2 = self._s1
            o0, o1, o2 = self._w1[0]  # read before the append drops it
            s0 += x0 - o0  # s + (a - b)
            s1 += x1 - o1
            s2 += x2 - o2
            self._s1 = [s0, s1, s2]
            self._w1.append(row)
            x0, x1, x2 = s0 / n1, s1 / n1, s2 / n1
            y1 = [x0, x1, x2]
            t0, t1, t2 = self._s2
            o0, o1, o2 = self._w2[0]
            self._s2 = sums = [t0 + (x0 - o0), t1 + (x1 - o1), t2 + (x2 - o2)]
            self._w2.append(y1)
        else:
            self._s1 = sums1 = [s + (a - b) for s, a, b in zip(self._s1, row, self._w1[0])]
            self._w1.append(row)
            y1 = [s / n1 for s in sums1]
            self._s2 = sums = [s + (a - b) for s, a, b in zip(self._s2, y1, self._w2[0])]
            self._w2.append(y1)
        if self._still >= self.span:
            # Constant input for a whole window: the exact value, free of summation round-off.
            recent = self._recent
            self.reset(row)
            self._recent = (recent[1], recent[2], row)
            return row
        out = [sums[0] / n2, sums[1] / n2, sums[2] / n2] if len(sums) == 3 else [s / n2 for s in sums]
        if lam != 1.0 and self.lag is not None:
            d = self._w1[n1 - 1 - self.lag]
            out = [p + lam * (f - p) for p, f in zip(d, out)]
        self._out = out
        self._recent = (self._recent[1], self._recent[2], out)
        return out

    def push_many(self, xs: np.ndarray, lam: np.ndarray | None = None) -> np.ndarray:
        """push() each row of `xs` (cycles × axes) in turn (with lam[k] the share of row k; None: 1), the
        outputs as rows: the same values bit for bit.
        A run of rows that each differ from the one before goes through both moving averages as one
        cumulative sum with the carried sums and windows (numpy's accumulate adds in order, as push
        does); rows equal to the one before (the still count, the snap at rest) go through push."""
        xs = np.asarray(xs, dtype=float)
        out = np.empty_like(xs)
        k, m = 0, len(xs)
        repeats = np.flatnonzero(np.all(xs[1:] == xs[:-1], axis=1)) + 1  # rows equal to the one before
        while k < m:
            if self.span == 0 or xs[k].tolist() == self._last:
                out[k] = self.push(xs[k], 1.0 if lam is None else float(lam[k]))
                k += 1
                continue
            r = int(np.searchsorted(repeats, k, side="right"))
            j = int(repeats[r]) if r < len(repeats) else m  # the run ends before the next repeated row
            out[k:j] = self._moving(xs[k:j], None if lam is None else np.asarray(lam[k:j], dtype=float))
            k = j
        return out

    def _moving(self, x: np.ndarray, lam: np.ndarray | None = None) -> np.ndarray:
        """Rows each unlike the one before: no still count, no snap (see push_many)."""
        n = len(x)
        h1 = np.vstack([np.array(self._w1), x])  # the window's oldest row is what each push subtracts
        s1 = np.cumsum(np.vstack([self._s1, x - h1[:n]]), axis=0)[1:]
        y1 = s1 / self.n1
        h2 = np.vstack([np.array(self._w2), y1])
        s2 = np.cumsum(np.vstack([self._s2, y1 - h2[:n]]), axis=0)[1:]
        y = s2 / self.n2
        if lam is not None and self.lag is not None and np.any(lam != 1.0):
            d = h1[self.n1 + np.arange(n) - self.lag]  # p(t − D) of each row
            y = np.where((lam == 1.0)[:, None], y, d + lam[:, None] * (y - d))
        self._w1.extend(h1[-self.n1:].tolist())
        self._w2.extend(h2[-self.n2:].tolist())
        self._s1, self._s2 = s1[-1].tolist(), s2[-1].tolist()
        self._last, self._out, self._still = x[-1].tolist(), y[-1].tolist(), 0
        self._recent = (self._recent + tuple(y[-3:].tolist()))[-3:]
        return y


def smoothstep(x: np.ndarray) -> np.ndarray:
    """The quintic smoothstep 10x³ − 15x⁴ + 6x⁵ of x clipped to 0 … 1: a ramp of the filter's share λ
    with zero first and second derivatives at both ends (decision motion 43)."""
    x = np.clip(np.asarray(x, dtype=float), 0.0, 1.0)
    return x ** 3 * (10.0 - 15.0 * x + 6.0 * x * x)
