"""Canned-cycle code tables: which G number is which cycle on each lathe type and on a mill.
Plain data, imported by the interpreter (nc.interp.gcodes, nc.interp.context) and by
nc.cycles.dispatch alike, so neither imports the other for them (issue 16)."""

from __future__ import annotations

# lathe code per type -> function name handed to run_cycle (NC5 §3.2 command table, seed §1.2/§1.3)
LATHE_CYCLES: dict[str, dict[int, str]] = {
    "A": {70: "G70", 71: "G71", 72: "G72", 73: "G73", 74: "G74", 75: "G75", 76: "G76",
          90: "G90", 92: "G92", 94: "G94", 32: "G32", 34: "G34",
          83: "G83", 84: "G84", 85: "G85", 87: "G87", 88: "G88", 89: "G89"},
    "B": {70: "G70", 71: "G71", 72: "G72", 73: "G73", 74: "G74", 75: "G75", 76: "G76",
          77: "G90", 78: "G92", 79: "G94", 33: "G32", 34: "G34",
          83: "G83", 84: "G84", 85: "G85", 87: "G87", 88: "G88", 89: "G89"},
    "C": {72: "G70", 73: "G71", 74: "G72", 75: "G73", 76: "G74", 77: "G75", 78: "G76",
          20: "G90", 21: "G92", 24: "G94", 33: "G32", 34: "G34",
          83: "G83", 84: "G84", 85: "G85", 87: "G87", 88: "G88", 89: "G89"},
}
"""Cycle function names are the type-A lathe numbers (G90 = OD turning cycle, G92 = threading cycle,
G94 = face cycle) for every lathe type; milling cycles keep their own numbers, prefixed "M":
"MG73", "MG74", "MG76", "MG81" … "MG89"."""

MILL_CYCLES: dict[int, str] = {n: f"MG{n}" for n in (73, 74, 76, 81, 82, 83, 84, 85, 86, 87, 88, 89)}

# cycles that stay active for following blocks (group 09 modal); G70–G76 and G32/G34 are one block
MODAL_CYCLES = {"G90", "G92", "G94", "G83", "G84", "G85", "G87", "G88", "G89"} | set(MILL_CYCLES.values())


LATHE_HOLES = ("G83", "G84", "G85", "G87", "G88", "G89")


def lathe_hole_clamp(profile, code: str | None, block) -> int | None:
    """The M_ of a lathe guide hole cycle block (L§2.1 G83-G89: "M-code call, usually C-axis clamping"): that
    M goes out at the hole position and M+1 back at R (nc.cycles.holes), not as the block's ordinary M.
    The NC5 formats have no M_ (N§3.14): there an M stays an ordinary M code of the block."""
    m = block.get("M")
    if m is None or code not in LATHE_HOLES or not profile.legacy or not profile.is_lathe:
        return None
    return int(m.value)
