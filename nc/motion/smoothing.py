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


class PositionFilter:
    def __init__(self, n1: int, n2: int, position: np.ndarray) -> None:
        self.n1 = max(1, int(n1))
        self.n2 = max(1, int(n2))
        self.span = self.n1 + self.n2 - 2  # cycles after which a constant input is reproduced exactly
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

    @property
    def output(self) -> np.ndarray:
        """The last output."""
        return np.array(self._out)

    @property
    def settled(self) -> bool:
        """The output equals the input and stays there while the input does not move."""
        return self._still >= self.span

    @property
    def delay(self) -> float:
        """Group delay of the filter in cycles (a constant-speed move lags by this much)."""
        return (self.n1 - 1 + self.n2 - 1) / 2.0

    def push(self, x: np.ndarray) -> np.ndarray:
        row = np.asarray(x, dtype=float).tolist()
        same = row == self._last
        if same and self._still >= self.span:
            return np.array(self._out)
        if same:
            self._still += 1
            row = self._last
        else:
            self._still = 0
            self._last = row
        self._s1 = s1 = [s + (a - b) for s, a, b in zip(self._s1, row, self._w1[0])]
        self._w1.append(row)
        n1, n2 = self.n1, self.n2
        y1 = [s / n1 for s in s1]
        self._s2 = s2 = [s + (a - b) for s, a, b in zip(self._s2, y1, self._w2[0])]
        self._w2.append(y1)
        if self._still >= self.span:
            # Constant input for a whole window: the exact value, free of summation round-off.
            self.reset(row)
            return np.array(row)
        self._out = [s / n2 for s in s2]
        return np.array(self._out)
