"""A minimal user MLC: finishes every M/S/T code 50 ms after its strobe, switches coolant on M08/M09.

    hil run part.nc --mlc examples/mlc/coolant_only.py --trace t.csv --trace-signals M31064,M21016,D31048
"""

NAME = "coolant-only example"


def setup(mlc):
    mlc.state["job"] = None


def scan(mlc):
    strobe = mlc.m("M_STROBE") or mlc.m("S_STROBE") or mlc.m("T_STROBE")
    if not strobe:
        mlc.set("MST_FINISH", False)
        mlc.state["job"] = None
        return
    if mlc.state["job"] is None:
        code = int(mlc.d("M_CODE")) if mlc.m("M_STROBE") else -1
        mlc.state["job"] = code
        if code in (8, 9):
            mlc.io.out(0, 0, code == 8)
    if mlc.timer("finish", 0.05, True):
        mlc.timer("finish", 0, False)
        mlc.set("MST_FINISH")
