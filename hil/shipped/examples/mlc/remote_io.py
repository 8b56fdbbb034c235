"""The default lathe MLC plus remote I/O logic on the stations of benches/lathe-io.toml.

    hil run part.nc --bench benches/lathe-io.toml --mlc examples/mlc/remote_io.py --trace t.csv \
        --trace-signals X0,X2,Y0,Y1,A1
    hil script examples/scripts/remote_io.py --bench benches/lathe-io.toml --mlc examples/mlc/remote_io.py

  Y0   coolant pump (the lathe MLC switches it on M08 / M09)
  X0   coolant pressure switch: A1 (user alarm) when Y0 has been on 0.5 s without pressure
  X2   chuck foot switch → Y1 chuck clamp valve, only while the spindle is stopped
  X16  door closed → Y16 door lock while the spindle turns
"""

from mlc import lathe

NAME = "lathe MLC with remote I/O"


def setup(mlc):
    lathe.setup(mlc)


def scan(mlc):
    lathe.scan(mlc)
    turning = mlc.m("SPINDLE1_FWD") or mlc.m("SPINDLE1_REV")
    if not turning:
        mlc.y(1, mlc.x(2))
    mlc.y(16, turning and mlc.x(16))
    no_pressure = mlc.y(0) and not mlc.x(0)
    mlc.alarm(1, mlc.timer("coolant-pressure", 0.5, no_pressure))
