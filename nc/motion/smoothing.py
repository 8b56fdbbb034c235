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

from array import array

import numpy as np

try:
    import cython  # compiled: the types below (setup.py, decision bench B115)
except ImportError:  # run as Python without Cython: they do nothing
    from nc.motion import cython_shadow as cython

# The filter's state is one buffer of doubles (an array.array; compiled, smoothing.pxd reads it through a typed
# memoryview, decision bench B141), m the number of axes, rows of m doubles at these offsets in units of m:
# LAST the last input row, S1 and S2 the two moving sums, REC the last three outputs (oldest first, the newest
# the output), then the two windows as rings of n1 and n2 rows (`_h1`, `_h2` the oldest row of each).
# Each operation is the IEEE one the former lists of Python floats made, in the same order.
LAST, S1, S2, REC, W1 = 0, 1, 2, 3, 6


class PositionFilter:
    def __init__(self, n1: int, n2: int, position: np.ndarray) -> None:
        self.n1 = max(1, int(n1))
        self.n2 = max(1, int(n2))
        self.span = self.n1 + self.n2 - 2  # cycles after which a constant input is reproduced exactly
        # The filter's share λ (decision motion 43): out = p(t − D) + λ·(F(p) − p(t − D)), D the group
        # delay. Only where D is a whole number of cycles that the first window still holds (n1 + n2
        # even, n2 ≤ n1: p(t − D) is w1[n1 − 1 − D]); elsewhere λ is ignored and F is output. (-1: none)
        self._lag = self.span // 2 if self.span % 2 == 0 and self.n2 <= self.n1 else -1
        self._m = -1
        self.reset(position)

    @property
    def lag(self) -> int | None:
        """D in cycles where the share λ acts, else None."""
        return None if self._lag < 0 else self._lag

    @cython.locals(m=cython.Py_ssize_t, i=cython.Py_ssize_t, x=cython.double)
    def reset(self, position: np.ndarray) -> None:
        """Forget the history: the output is `position`, as if it had stood there forever."""
        row = np.asarray(position, dtype=float).tolist()
        m = len(row)
        if m != self._m:  # (the first reset: the buffer for m axes)
            self._m = m
            self._st = array("d", bytes(8 * (W1 + self.n1 + self.n2) * m))
            self._v = self._st
        v = self._v
        for i in range(m):
            x = row[i]
            v[LAST * m + i] = x
            v[REC * m + i] = x
            v[(REC + 1) * m + i] = x
        self._fill()

    @cython.locals(m=cython.Py_ssize_t, i=cython.Py_ssize_t, k=cython.Py_ssize_t, x=cython.double,
                   n1=cython.Py_ssize_t, n2=cython.Py_ssize_t, w=cython.Py_ssize_t)
    def _fill(self) -> int:
        """The state of an input that stood at LAST forever: both windows full of it, the sums of them, the output
        it (the two older recent rows are left as they are)."""
        v, m, n1, n2 = self._v, self._m, self.n1, self.n2
        for i in range(m):
            x = v[LAST * m + i]
            v[S1 * m + i] = x * n1
            v[S2 * m + i] = x * n2
            v[(REC + 2) * m + i] = x
            w = W1 * m + i
            for k in range(n1 + n2):
                v[w] = x
                w += m
        self._h1 = self._h2 = 0
        self._still = self.span
        return 0

    def snapshot(self) -> tuple:
        """The filter's state as it is now, for `restore` (hil.stretch_state saves the planner with it)."""
        return (self._st[:], self._m, self._h1, self._h2, self._still)

    def restore(self, snap: tuple) -> None:
        """The state a `snapshot` took (it can be restored again: a copy is taken)."""
        self._st = snap[0][:]
        self._v = self._st
        self._m, self._h1, self._h2, self._still = snap[1], snap[2], snap[3], snap[4]

    def same_state(self, snap: tuple) -> bool:
        """The state is the `snapshot` bit for bit (its next outputs are the same for the same inputs)."""
        return (self._m, self._h1, self._h2, self._still) == snap[1:] and self._st.tobytes() == snap[0].tobytes()

    def copy(self) -> PositionFilter:
        """An independent filter in the same state (nc.motion.filter_ramps tries a stop on one)."""
        g = PositionFilter.__new__(PositionFilter)
        g.n1, g.n2, g.span, g._lag = self.n1, self.n2, self.span, self._lag
        g._st = self._st[:]
        g._v = g._st
        g._m, g._h1, g._h2, g._still = self._m, self._h1, self._h2, self._still
        return g

    def __copy__(self) -> PositionFilter:
        return self.copy()

    @property
    def output(self) -> np.ndarray:
        """The last output."""
        m = self._m
        return np.array(self._st[(REC + 2) * m:(REC + 3) * m])

    @property
    def recent(self) -> np.ndarray:
        """The last three outputs, oldest first (as the stream had them: rows before the first are the start)."""
        m = self._m
        return np.array(self._st[REC * m:(REC + 3) * m]).reshape(3, m)

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

    @cython.locals(k=cython.Py_ssize_t, n=cython.Py_ssize_t)
    def push_rows(self, rows: list[list[float]], lams: list[float] | None = None) -> list[list[float]]:
        """push() of each row (lists of Python floats; lams[k] the share of row k, None: 1), the outputs as lists
        (never changed in place): the same values, without two numpy conversions a row (hil/stretch_pass.py)."""
        n = len(rows)
        if lams is None:
            return [self._push(rows[k], 1.0) for k in range(n)]
        return [self._push(rows[k], lams[k]) for k in range(n)]

    @cython.locals(m=cython.Py_ssize_t, i=cython.Py_ssize_t, same=cython.bint, r=cython.Py_ssize_t)
    def _push(self, row: list, lam: float) -> list:
        """push() of a row as a list of floats, the output as a new list."""
        v, m = self._v, self._m
        if len(row) != m:
            raise ValueError(f"the position filter has {m} axes, a row {len(row)}")
        same = True
        for i in range(m):
            if row[i] != v[LAST * m + i]:
                same = False
                break
        if not same:  # (equal rows keep the last one's values: -0.0 stays 0.0, as the lists had it)
            for i in range(m):
                v[LAST * m + i] = row[i]
        self._take(same, lam)
        r = (REC + 2) * m
        return [v[r + i] for i in range(m)]

    @cython.locals(m=cython.Py_ssize_t, i=cython.Py_ssize_t, still=cython.Py_ssize_t, n1=cython.Py_ssize_t,
                   n2=cython.Py_ssize_t, w1=cython.Py_ssize_t, w2=cython.Py_ssize_t, d=cython.Py_ssize_t,
                   h1=cython.Py_ssize_t, h2=cython.Py_ssize_t, r=cython.Py_ssize_t, x=cython.double,
                   s=cython.double, y=cython.double, t=cython.double, p=cython.double)
    def _take(self, same: bool, lam: float) -> int:
        """One push of the input row at LAST (`same`: it equals the row before): the output is REC's newest."""
        v, m = self._v, self._m
        r = REC * m
        for i in range(2 * m):  # the recent rows move up one
            v[r + i] = v[r + m + i]
        still = self._still
        if same and still >= self.span:  # settled: the output stays
            return 0
        still = still + 1 if same else 0
        self._still = still
        n1, n2, h1, h2 = self.n1, self.n2, self._h1, self._h2
        w1 = (W1 + h1) * m  # the oldest row of each window, which the new one replaces
        w2 = (W1 + n1 + h2) * m
        for i in range(m):
            x = v[LAST * m + i]
            s = v[S1 * m + i] + (x - v[w1 + i])
            v[S1 * m + i] = s
            v[w1 + i] = x
            y = s / n1
            t = v[S2 * m + i] + (y - v[w2 + i])
            v[S2 * m + i] = t
            v[w2 + i] = y
        h1 += 1
        h2 += 1
        self._h1 = 0 if h1 == n1 else h1
        self._h2 = 0 if h2 == n2 else h2
        if still >= self.span:
            # Constant input for a whole window: the exact value, free of summation round-off.
            return self._fill()
        r = (REC + 2) * m
        if lam != 1.0 and self._lag >= 0:
            d = (W1 + (self._h1 + n1 - 1 - self._lag) % n1) * m  # p(t − D): the window's row n1 − 1 − D
            for i in range(m):
                p = v[d + i]
                v[r + i] = p + lam * (v[S2 * m + i] / n2 - p)
        else:
            for i in range(m):
                v[r + i] = v[S2 * m + i] / n2
        return 0

    def push_many(self, xs: np.ndarray, lam: np.ndarray | None = None) -> np.ndarray:
        """push() each row of `xs` (cycles × axes) in turn (with lam[k] the share of row k; None: 1), the
        outputs as rows: the same values bit for bit.
        Compiled, push's C loop row by row. As Python, a run of rows that each differ from the one before goes
        through both moving averages as one cumulative sum with the carried sums and windows (numpy's accumulate
        adds in order, as push does); rows equal to the one before (the still count, the snap at rest) go
        through push."""
        xs = np.ascontiguousarray(xs, dtype=float)
        out = np.empty_like(xs)
        if cython.compiled:
            self._many(xs, None if lam is None else np.ascontiguousarray(lam, dtype=float), out)
            return out
        k, m = 0, len(xs)
        repeats = np.flatnonzero(np.all(xs[1:] == xs[:-1], axis=1)) + 1  # rows equal to the one before
        while k < m:
            if self.span == 0 or xs[k].tolist() == self._st[LAST * self._m:(LAST + 1) * self._m].tolist():
                out[k] = self.push(xs[k], 1.0 if lam is None else float(lam[k]))
                k += 1
                continue
            r = int(np.searchsorted(repeats, k, side="right"))
            j = int(repeats[r]) if r < len(repeats) else m  # the run ends before the next repeated row
            out[k:j] = self._moving(xs[k:j], None if lam is None else np.asarray(lam[k:j], dtype=float))
            k = j
        return out

    def _many(self, xs: np.ndarray, lam: np.ndarray | None, out: np.ndarray) -> int:
        """push_many compiled: each row through `_take` (C memoryviews: smoothing.pxd)."""
        v, m, n = self._v, self._m, xs.shape[0]
        if n and xs.shape[1] != m:
            raise ValueError(f"the position filter has {m} axes, a row {xs.shape[1]}")
        xv, ov, lv = xs, out, lam
        r = (REC + 2) * m
        for k in range(n):
            same = True
            for i in range(m):
                if xv[k, i] != v[LAST * m + i]:
                    same = False
                    break
            if not same:
                for i in range(m):
                    v[LAST * m + i] = xv[k, i]
            self._take(same, 1.0 if lam is None else lv[k])
            for i in range(m):
                ov[k, i] = v[r + i]
        return 0

    def _moving(self, x: np.ndarray, lam: np.ndarray | None = None) -> np.ndarray:
        """Rows each unlike the one before: no still count, no snap (see push_many)."""
        n, m, n1, n2 = len(x), self._m, self.n1, self.n2
        st = np.frombuffer(self._st, dtype=float)  # (the buffer itself: written below)
        w1 = np.roll(st[W1 * m:(W1 + n1) * m].reshape(n1, m), -self._h1, axis=0)  # oldest row first
        w2 = np.roll(st[(W1 + n1) * m:(W1 + n1 + n2) * m].reshape(n2, m), -self._h2, axis=0)
        h1 = np.vstack([w1, x])  # the window's oldest row is what each push subtracts
        s1 = np.cumsum(np.vstack([st[S1 * m:(S1 + 1) * m], x - h1[:n]]), axis=0)[1:]
        y1 = s1 / n1
        h2 = np.vstack([w2, y1])
        s2 = np.cumsum(np.vstack([st[S2 * m:(S2 + 1) * m], y1 - h2[:n]]), axis=0)[1:]
        y = s2 / n2
        if lam is not None and self._lag >= 0 and np.any(lam != 1.0):
            d = h1[n1 + np.arange(n) - self._lag]  # p(t − D) of each row
            y = np.where((lam == 1.0)[:, None], y, d + lam[:, None] * (y - d))
        rec = np.vstack([st[REC * m:(REC + 3) * m].reshape(3, m), y[-3:]])[-3:]
        st[W1 * m:(W1 + n1) * m] = h1[-n1:].ravel()
        st[(W1 + n1) * m:(W1 + n1 + n2) * m] = h2[-n2:].ravel()
        st[S1 * m:(S1 + 1) * m], st[S2 * m:(S2 + 1) * m] = s1[-1], s2[-1]
        st[LAST * m:(LAST + 1) * m], st[REC * m:(REC + 3) * m] = x[-1], rec.ravel()
        self._h1 = self._h2 = self._still = 0
        return y


def smoothstep(x: np.ndarray) -> np.ndarray:
    """The quintic smoothstep 10x³ − 15x⁴ + 6x⁵ of x clipped to 0 … 1: a ramp of the filter's share λ
    with zero first and second derivatives at both ends (decision motion 43)."""
    x = np.clip(np.asarray(x, dtype=float), 0.0, 1.0)
    return x ** 3 * (10.0 - 15.0 * x + 6.0 * x * x)
