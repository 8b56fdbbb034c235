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
        x = np.array(position, dtype=float)
        self._w1: deque[np.ndarray] = deque([x] * self.n1, maxlen=self.n1)
        self._w2: deque[np.ndarray] = deque([x] * self.n2, maxlen=self.n2)
        self._s1 = x * self.n1
        self._s2 = x * self.n2
        self.output = x.copy()
        self._last = x
        self._still = self.span

    @property
    def settled(self) -> bool:
        """The output equals the input and stays there while the input does not move."""
        return self._still >= self.span

    @property
    def delay(self) -> float:
        """Group delay of the filter in cycles (a constant-speed move lags by this much)."""
        return (self.n1 - 1 + self.n2 - 1) / 2.0

    def push(self, x: np.ndarray) -> np.ndarray:
        same = np.array_equal(x, self._last)
        if same and self._still >= self.span:
            return self.output.copy()
        if same:
            self._still += 1
        else:
            self._still = 0
            self._last = np.array(x, dtype=float)
        x = self._last
        self._s1 += x - self._w1[0]
        self._w1.append(x)
        y1 = self._s1 / self.n1
        self._s2 += y1 - self._w2[0]
        self._w2.append(y1)
        if self._still >= self.span:
            # Constant input for a whole window: the exact value, free of summation round-off.
            self.reset(x)
            return x.copy()
        self.output = self._s2 / self.n2
        return self.output.copy()
