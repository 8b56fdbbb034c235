"""NC5 Appendix A.2, one program per alarm: the code comes back with the line that caused it.

Each case cites the App. A row (and the chapter that states the rule) and is written from the manual's
"wrong example" where the table gives one. docs/alarms.md (python docs/build_alarms.py) lists these
cases as the tests that raise their codes.
"""

from __future__ import annotations

from dataclasses import dataclass

import pytest

from lang_helpers import run_path


@dataclass(frozen=True)
class Case:
    code: str
    program: str
    line: int
    cite: str
    profile: str = "nc5-mill"
    files: tuple[tuple[str, str], ...] = ()
    args: tuple[str, ...] = ()  # hil path options (--param NAME=VALUE)


SUB = "O2000\nG01 X1. F100\nM99\n"
ALARM_CASES = [
    Case("0x0203", "G01 IF [#1 EQ 0] GOTO 5\nM30\n", 1, "App. A 0x0203 wrong example 'G01 IF'"),
    Case("0x0204", "DO 1\nM30\n", 1, "App. A 0x0204 'Ex: DO, THEN' at the beginning of the line"),
    Case("0x0205", "#1=1\nWHILE [#1 LT 3] DO 1\n#1=#1+1\nEND 1 X100.\nM30\n", 4, "App. A 0x0205 wrong example 'END 1 X100.'"),
    Case("0x020E", "IF GOTO 5\nM30\n", 1, "App. A 0x020E 'no condition after the IF judgement'"),
    Case("0x020F", "WHILE DO 1\nEND 1\nM30\n", 1, "App. A 0x020F 'no condition after the WHILE statement'"),
    Case("0x0211", "#1\nM30\n", 1, "App. A 0x0211 incorrect '=' syntax (a # variable with no assignment)"),
    Case("0x0213", "#1=0\nWHILE [#1 LT 3]\n#1=#1+1\nM30\n", 2, "App. A 0x0213 'WHILE statement lacks the END instruction' "
         "(lathe guide WHILE ... ENDW form)", profile="lathe-2018"),
    Case("0x0216", "G90 G00 X0 Y0\nG42 X100.\nM30\n", 2, "App. A 0x0216 wrong example 'G42 X100.'"),
    Case("0x0217", "G42 D1234567 X10.\nM30\n", 1, "App. A 0x0217 wrong example 'G42 D1234567.'"),
    Case("0x0218", "G43 Z100.\nM30\n", 1, "App. A 0x0218 wrong example 'G43 X100.' (tool length on the mill's Z)"),
    Case("0x0219", "G43 H1234567 Z100.\nM30\n", 1, "App. A 0x0219 wrong example 'G43 H1234567.'"),
    Case("0x021C", "M06 T123456789\nM30\n", 1, "App. A 0x021C wrong example 'M06 T1234567.' (beyond the T range)"),
    Case("0x0225", "#1=0\nWHILE [#1 LT 3] DO 1\n#1=#1+1\nEND\nM30\n", 4, "App. A 0x0225 'No value specified after END'"),
    Case("0x0226", "WHILE [#1 LT 3] DO\nEND 1\nM30\n", 1, "App. A 0x0226 'WHILE DO No value specified after DO'"),
    Case("0x0229", "M98 Q10\nM30\n", 1, "App. A 0x0229 wrong example 'M98 Q10' beyond the program's lines"),
    Case("0x0231", "G00 X0 Z10.\nG83 R-2. F100\nM30\n", 2, "App. A 0x0231 drilling cycle axis (hole bottom Z/W) missing; "
         "N§3.7 lathe G83 format", profile="nc5-lathe-a"),
    Case("0x0233", "G00 X50. Z5.\nG70\nM30\n", 2, "App. A 0x0233 G70 cannot find the P/Q blocks; N§3.7 G70 format", profile="nc5-lathe-a"),
    Case("0x0238", "IF [#1 EQ 0] X10.\nM30\n", 1, "App. A 0x0238 IF command error (IF without GOTO/THEN)"),
    Case("0x023A", "ELSEIF [#1 EQ 0]\nM30\n", 1, "App. A 0x023A ELSEIF command error (no THEN)"),
    Case("0x023B", "ELSE\nENDIF\nM30\n", 1, "App. A 0x023B ELSE command error (ELSE with no IF...THEN)"),
    Case("0x0241", "G65 A1.\nM30\n", 1, "App. A 0x0241 'The P command is not marked' (N§3.11.4.4 G65 P_ L_ format)"),
    Case("0x0242", "G65 P123456 A1.\nM30\n", 1, "App. A 0x0242 'value of P exceeds the maximum value'"),
    Case("0x0249", "M70000\nM30\n", 1, "App. A 0x0249 M code usage error (M out of range)"),
    Case("0x024B", "G65 P2000 M98 P2000\nM30\n" + SUB, 1, "App. A 0x024B 'Call instruction usage error' (two calls in a block)"),
    Case("0x024E", "G31 P300 X10. F100\nM30\n", 1, "App. A 0x024E HSI value usage error (G31 P mask 0-255; N§3.5.4)"),
    Case("0x0256", "#1=POW[2]\nM30\n", 1, "App. A 0x0256 arithmetic command usage error (POW takes two arguments)"),
    Case("0x025D", "G19\nG02 Z10. R5. F100\nM30\n", 2, "App. A 0x025D working plane setting error (G19 needs Y and Z)",
         profile="nc5-lathe-a"),
    Case("0x120E", "G91 G00 X900000000.\nX900000000.\nM30\n", 2, "App. A 0x120E interpolation distance exceeds the maximum travel"),
    Case("0x021A", "T0170\nM30\n", 1, "App. A 0x021A lathe tool compensation T value above the limit (lathe guide: offsets 1-64)",
         profile="lathe-2018"),
    Case("0x022E", "M98 L2\nM30\n", 1, "App. A 0x022E 'Missing P command in M98' (lathe guide M98 P_ L_ format)",
         profile="lathe-2018"),
    Case("0x0232", "G00 X30. Z5.\nG76 P010060 Q100 R0.1\nG76 X20. Z-20. F1.5\nM30\n", 3,
         "App. A 0x0232 'Missing P_ or Q_' in the cycle's second block (N§3.7 G76 two-block format)", profile="nc5-lathe-a"),
    Case("0x1203", "G10 L12 P1 R4.\nG00 X0 Y0\nG41 D1 G01 X10. F100\nG18 X20.\nM30\n", 4,
         "App. A 0x1203 'Plane changing after enabling tool compensation' (N§3.6.2)"),
    Case("0x1206", "G10 L12 P1 R4.\nG10 L12 P2 R2.\nG00 X0 Y0\nG41 D1 G01 X10. F100\nG02 X30. R10. D2\nM30\n", 5,
         "App. A 0x1206 'Changing tool diameter during arc command performing'"),
    Case("0x025B", "G90 G00 X0 Y0 Z0\nG2.4 X10. Y0 Z0 F300\nG2.4 X20. Y0 Z0\nM30\n", 3,
         "App. A 0x025B 3-dimension arc command error: three points on one line make no circle (N§3.3.4)"),
    Case("0x0004", "G100 X1.\nM30\n", 1, "App. A 0x0004 'Macro file call error. Macro number error.': G100 calls "
         "O9100 through N1.200 (N§3.11.4.8 G-code macro call), and no such program exists", args=("--param", "N1.200=100")),
    Case("0x020D", "#1>G01\nM30\n", 1, "App. A 0x020D error example '#1>G01' (judgement operator as a statement)"),
    Case("0x0239", "#1=0\nWHILE [#1 LT 3] THEN\n#1=#1+1\nEND 1\nM30\n", 2,
         "App. A 0x0239 THEN command error: THEN after a WHILE condition (N§3.11.3.3 WHILE [] DO; THEN only after IF/ELSEIF)"),
    Case("0x0247", "G00 X50. Z5.\nG71 U2. R1.\nG00 X60.\nM30\n", 2,
         "App. A 0x0247 / N§3.15.2 G71 note (4): 'two continuous blocks as one complete instruction'", profile="nc5-lathe-a"),
    Case("0x0245", "G00 X50. Z5.\nG72 W2. R1.\nG72 U0.5 W0.2 F100\nN10 G01 Z-10.\nN20 X30.\nM30\n", 2,
         "App. A 0x0245 'The command P or Q is not used in the nested loop': the second G72 block (N§3.15.3 "
         "format G72 P_ Q_ U_ W_ F_) names neither", profile="nc5-lathe-a"),
    Case("0xB6A5", "G21 G98\nG00 X30. Z10.\nM03 S500\nG83 X20. Z-12. R5. F100.\nG80\nM30\n", 4,
         "App. A 0xB6A5 / N§3.14 G83 note (3), lathe guide G83 'X(U)_C_: hole position': a face hole off X0 on a "
         "lathe without a C axis (never in turn-mill mode)", profile="nc5-lathe-a"),
    Case("0x0C03", "G97 S2000 M03\nG00 X10.\nS4500\nM30\n", 3,
         "App. A 0x0C03: N0.1000 bit7 on and S above N0.1008 (the spindle's maximum speed)", profile="nc5-lathe-a",
         args=("--param", "N0.1000 Bit7=1", "--param", "N0.1008=4000")),
    Case("0x1204", "G10 L12 P1 R2.\nG90 G00 X-50. Y-50.\nG42 D1 G01 X0 Y0 F100\nG02 X28.2 Y28.2 R32.1\n"
         "G01 X16.7 Y23.5\nG40 G01 X-50. Y-50.\nM30\n", 5,
         "App. A 0x1204: arc then line at an inner corner whose compensated elements do not meet (N§3.6.2 G41/G42)"),
    Case("0x1207", "G10 L12 P1 R4.\nG90 G00 X-50. Y-50.\nG42 D1 G01 X0 Y0 F100\nG02 X-24.8 Y9.8 R22.3\n"
         "G02 X-6.4 Y-0.6 R14.4\nG40 G01 X-50. Y-50.\nM30\n", 5,
         "App. A 0x1207: arc then arc at an inner corner whose compensated circles do not meet (N§3.6.2)"),
    Case("0x1209", "G10 L12 P1 R6.\nG90 G00 X-50. Y-50.\nG42 D1 G01 X0 Y0 F100\nG01 X-15.2 Y-23.9\n"
         "G02 X18.5 Y-24.5 R17.9\nG40 G01 X-50. Y-50.\nM30\n", 5,
         "App. A 0x1209: line then arc at an inner corner whose compensated elements do not meet (N§3.6.2)"),
    Case("0x021B", "G90 G00 X10. Y10.\nG53.1\nM30\n", 2,
         "App. A 0x021B 'The G53.1 command must be used after the G68.2 command': G53.1 with no G68.2 before it "
         "(G68.2 is not in the N§2 G code list, so it is never active)"),
    Case("0x021B", "G00 X10. Z5.\nG53.1\nM30\n", 2, "App. A 0x021B on the lathe profile too", profile="nc5-lathe-a"),
]


@pytest.mark.parametrize("case", ALARM_CASES, ids=[c.code for c in ALARM_CASES])
def test_appendix_a_alarm_is_raised_at_its_line(capsys, tmp_path, case: Case):
    r = run_path(capsys, tmp_path, case.program, *case.args, profile=case.profile, files=dict(case.files))
    assert r.code == 1, (case.cite, r.moves[-1:] if r.moves else None)
    assert r.alarm["code"] == case.code, (case.cite, r.alarm)
    assert r.alarm["line"] == case.line, (case.cite, r.alarm)


RUN_ALARM_CASES = [
    Case("0x0C02", "G00 X30. Z5.\nG32 Z-20. F1.5\nM30\n", 2,
         "App. A 0x0C02 'Spindle is not rotating before cutting': a thread (N§3.3 G32) with the spindle stopped",
         profile="nc5-lathe-a"),
    Case("0xB01D", "G00 X30. Z5.\nM03 S3000\nG32 Z-20. F100.\nM30\n", 3,
         "App. A 0xB01D 'Spindle speed is over speed': 100 mm/rev at 3000 rpm is beyond the Z axis' feed",
         profile="nc5-lathe-a"),
]


@pytest.mark.parametrize("case", RUN_ALARM_CASES, ids=[c.code for c in RUN_ALARM_CASES])
def test_appendix_a_alarm_of_the_planner_on_the_bench(capsys, tmp_path, case: Case):
    """Alarms the motion planner raises: `hil run` on the built-in lathe bench ends with the code (exit 1)."""
    import json

    from hil.cli import main

    f = tmp_path / "p.nc"
    f.write_text(case.program)
    capsys.readouterr()
    assert main(["run", str(f), "--json"]) == 1, case.cite
    summary = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert [(a["code"], a["line"]) for a in summary["alarms"]] == [(case.code, case.line)], case.cite
