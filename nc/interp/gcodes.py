"""G-code tables per profile: code number -> (modal group, function name).

Function names are dialect-independent ("set" = G92 mill/B/C and G50 type A; "permin"/"perrev" =
G94/G95 or G98/G99 type A; cycle names as in `nc.interp.context`).  Seed-catalog §1.2–§1.4.
"""

from __future__ import annotations

from functools import lru_cache

from nc.cycles.codes import LATHE_CYCLES, MILL_CYCLES, MODAL_CYCLES
from nc.profiles import Profile

COMMON: dict[float, tuple[int, str]] = {
    0: (1, "G00"), 1: (1, "G01"), 2: (1, "G02"), 3: (1, "G03"), 4: (0, "G04"), 5: (0, "G05"), 9: (0, "G09"),
    10: (0, "G10"), 11: (0, "G11"), 17: (2, "G17"), 18: (2, "G18"), 19: (2, "G19"), 28: (0, "G28"),
    29: (0, "G29"), 30: (0, "G30"), 31: (0, "G31"), 40: (7, "G40"), 41: (7, "G41"), 42: (7, "G42"),
    52: (0, "G52"), 53: (0, "G53"), 54: (12, "G54"), 55: (12, "G55"), 56: (12, "G56"), 57: (12, "G57"),
    58: (12, "G58"), 59: (12, "G59"), 61: (13, "G61"), 64: (13, "G64"), 65: (0, "G65"), 66: (14, "G66"),
    67: (14, "G67"), 80: (9, "G80"), 96: (17, "G96"), 97: (17, "G97"),
}
STOP_PREVIEW = {"G05", "G10", "G11", "G31", "G53"}  # N§3.2.4 "Stop preview" column


@lru_cache(maxsize=16)
def _table(name: str, machine: str, lathe_type: str | None, legacy: bool) -> dict[float, tuple[int, str]]:
    t = dict(COMMON)
    if not legacy:
        t[900] = (0, "G900")
    if machine == "mill":
        t.update({2.4: (1, "G2.4"), 3.4: (1, "G3.4"), 15: (16, "G15"), 16: (16, "G16"), 20: (6, "inch"),
                  21: (6, "metric"), 24: (18, "mirror"), 25: (18, "mirror_off"), 43: (8, "G43"), 44: (8, "G44"),
                  49: (8, "G49"), 50: (11, "scale_off"), 51: (11, "scale"), 68: (15, "G68"), 69: (15, "G69"),
                  90: (3, "abs"), 91: (3, "inc"), 92: (0, "set"), 94: (5, "permin"), 95: (5, "perrev"),
                  98: (10, "ret98"), 99: (10, "ret99"),
                  84.48: (0, "G84.48")})  # N§3.13.2 note (6): retraction of an interrupted tap (M26-3)
        for n, fn in MILL_CYCLES.items():
            t[n] = (9, fn)
        return t
    t.update({50.1: (18, "mirror_off"), 51.1: (18, "mirror")})
    for n, fn in LATHE_CYCLES[lathe_type or "A"].items():
        grp = 1 if fn in ("G32", "G34") else 9 if fn in MODAL_CYCLES else 0
        t[n] = (grp, fn)
    if lathe_type == "A":
        t.update({20: (6, "inch"), 21: (6, "metric"), 50: (0, "set"), 98: (5, "permin"), 99: (5, "perrev")})
    else:
        t.update({50: (11, "scale_off"), 51: (11, "scale"), 90: (3, "abs"), 91: (3, "inc"), 92: (0, "set"),
                  94: (5, "permin"), 95: (5, "perrev"), 98: (10, "ret98"), 99: (10, "ret99")})
        if lathe_type == "B":
            t.update({20: (6, "inch"), 21: (6, "metric")})
        else:
            t.update({70: (6, "inch"), 71: (6, "metric")})
    return t


def g_table(profile: Profile) -> dict[float, tuple[int, str]]:
    return _table(profile.name, profile.machine, profile.lathe_type, profile.legacy)


def lookup(profile: Profile, value: float) -> tuple[int, str] | None:
    code = round(value, 2)  # two decimals: G84.48
    return g_table(profile).get(code if code != int(code) else int(code))
