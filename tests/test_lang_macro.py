"""Macro B: expressions (E-N29, E-L39–E-L43), control flow (E-N30–E-N37, E-L40, E-L41), NULL rules."""

from __future__ import annotations

import pytest

from lang_helpers import run_path


def var(capsys, tmp_path, stmt: str, n: int = 100, profile: str = "nc5-mill"):
    r = run_path(capsys, tmp_path, stmt + "\nM30\n", "--vars", str(n), profile=profile)
    assert r.code == 0, r.alarm
    return r.vars[str(n)]


E_N29 = [
    ("#100=1+2", 3), ("#100=1-2", -1), ("#100=2*3", 6), ("#100=5MOD3", 2), ("#100= SQRT [4.]", 2.0),
    ("#100= ABS [-2.5]", 2.5), ("#100= ROUND [2.5]", 3.0), ("#100= ROUND [-2.5]", -3.0), ("#100= FIX [2.5]", 2.0),
    ("#100= FIX [-2.5]", -2.0), ("#100=FUP [2.5]", 3.0), ("#100=FUP [-2.5]", -3.0), ("#100= POW [2.,3.]", 8.0),
    ("#100 = 3AND6", 2.0), ("#100 = 3OR6", 7.0), ("#100 = 3XOR6", 5.0), ("#100 = 3.56 AND 6", 2.0),
    ("#100=BSL [0]", 1.0), ("#100=BSL [1]", 2.0), ("#100=BSL [2]", 4.0), ("#100=BSL [3]", 8.0),
    ("#100=BIT [2,0]", 0.0), ("#100=BIT [2,1]", 1.0), ("#100=!0", 1), ("#100=!1", 0), ("#100=1&&0", 0),
    ("#100=1&&1", 1), ("#100=1||0", 1), ("#100=0||0", 0), ("#100=9LT5", 0), ("#100=0LT5", 1),
]


@pytest.mark.parametrize("stmt,expected", E_N29)
def test_e_n29_arithmetic_and_logic(capsys, tmp_path, stmt, expected):
    assert var(capsys, tmp_path, stmt) == pytest.approx(expected)


def test_e_n29_rounded_values(capsys, tmp_path):
    assert var(capsys, tmp_path, "#100=2/3") == pytest.approx(0.667, abs=5e-4)
    assert var(capsys, tmp_path, "#100=LN [86.]") == pytest.approx(4.454, abs=5e-4)
    assert var(capsys, tmp_path, "#100=EXP [2.]") == pytest.approx(7.389, abs=5e-4)


@pytest.mark.parametrize("stmt", ["#100=ASIN[2]", "#100=ACOS[-1.5]", "#100=LN[-1]", "#100=POW[-2,3]"])
def test_domain_errors_raise_0x0257(capsys, tmp_path, stmt):
    r = run_path(capsys, tmp_path, stmt + "\n")
    assert r.code == 1 and r.alarm["code"] == "0x0257" and r.alarm["line"] == 1


def test_division_by_zero_is_0x0210(capsys, tmp_path):
    r = run_path(capsys, tmp_path, "#1=0\n#100=5/#1\n")
    assert r.alarm["code"] == "0x0210" and r.alarm["line"] == 2


def test_precedence_and_degrees(capsys, tmp_path):
    assert var(capsys, tmp_path, "#100=1+2*3-4/2") == 5
    assert var(capsys, tmp_path, "#100=[1+2]*3") == 9
    assert var(capsys, tmp_path, "#100=SIN[30.]") == pytest.approx(0.5)
    assert var(capsys, tmp_path, "#100=ATAN[1.,1.]") == pytest.approx(45.0)
    assert var(capsys, tmp_path, "#100=2+3>4") == 1  # comparisons bind looser than arithmetic
    assert var(capsys, tmp_path, "#100=-2*-3") == 6


def test_if_not_zero_jumps(capsys, tmp_path):
    r = run_path(capsys, tmp_path, "IF [!0] GOTO2\n#100=1\nN2 #101=1\nM30\n", "--vars", "100-101")
    assert r.vars == {"100": None, "101": 1.0}


@pytest.mark.parametrize("cond,jumps", [("1&&0", False), ("1||0", True), ("1LT0", False)])
def test_a14_false_conditions_do_not_jump(capsys, tmp_path, cond, jumps):
    r = run_path(capsys, tmp_path, f"IF [{cond}] GOTO2\n#100=1\nN2 M30\n", "--vars", "100")
    assert (r.vars["100"] is None) is jumps


def test_null_semantics_b311(capsys, tmp_path):
    prog = """#1=#100==#0
#2=#100!=#0
#3=#100>=#0
#4=#100<=#0
#5=#100>0
#6=#100<0
#7=#100!=0
#101=#1+#2*10+#3*100+#4*1000+#5*10000+#6*100000+#7*1000000
#102=#100
#103=#100*5
G90 G00 X99. Y#100
M30
"""
    r = run_path(capsys, tmp_path, prog, "--vars", "101-103")
    assert r.vars["101"] == 1 + 0 + 100 + 1000 + 0 + 0 + 1000000
    assert r.vars["102"] is None and r.vars["103"] == 0.0
    assert r.moves[0]["work"]["X"] == 99.0 and r.moves[0]["work"]["Y"] == 0.0  # Y word dropped, Y stays


def test_e_n30_goto(capsys, tmp_path):
    r = run_path(capsys, tmp_path, "N001G90G00X0.Y0.\nN002GOTO4\nN003X100.\nN004Y100.\nN005M30\n")
    assert r.ends("X", "Y")[-1] == (0.0, 100.0)
    assert all(m["line"] != 3 for m in r.moves)


def test_e_n31_goto_variable(capsys, tmp_path):
    r = run_path(capsys, tmp_path, "#100=5.0\nN001G90G00X0.Y0.\nN002GOTO#100\nN003X100.\nN004Y100.\nN005M30\n")
    assert r.ends("X", "Y") == [(0.0, 0.0)]


@pytest.mark.parametrize("v,final", [(0, None), (1, 5.0)])
def test_e_n32_if_goto(capsys, tmp_path, v, final):
    r = run_path(capsys, tmp_path, f"#1={v}\nIF [#1==0] GOTO 999\nG90 G00 X5.\nN999 M30\n")
    assert (r.moves[-1]["work"]["X"] if r.moves else None) == final


@pytest.mark.parametrize("v,which", [(1, "100"), (2, "101"), (3, "102"), (7, "103")])
def test_e_n35_if_elseif_else(capsys, tmp_path, v, which):
    prog = f"""#1={v}
IF[#1==1] THEN
#100=1
ELSEIF[#1=2] THEN
#101=1
ELSEIF[#1=3] THEN
#102=1
ELSE
#103=1
ENDIF
M30
"""
    r = run_path(capsys, tmp_path, prog, "--vars", "100-103")
    assert {k for k, x in r.vars.items() if x is not None} == {which}


@pytest.mark.parametrize("a,b,x", [(1, 0, 1.0), (1, 1, 1.1), (1, 5, 1.9), (2, 0, 2.0)])
def test_e_n36_nested_if(capsys, tmp_path, a, b, x):
    prog = f"""#1={a}
#2={b}
IF[#1==1] THEN
IF[#2==0]THEN
G0X1.0
ELSEIF[#2==1] THEN
G0X1.1
ELSE
G0X1.9
ENDIF
ELSE
G0X2.
ENDIF
M30
"""
    r = run_path(capsys, tmp_path, prog)
    assert r.ends("X") == [(x,)]


def test_e_n34_compound_condition_balanced(capsys, tmp_path):
    prog = "#1=1\n#2=1\n#3=2\n#4=2\nIF[[#1==#2]AND[#3==#4]]THEN\n#100=0\nENDIF\nM30\n"
    assert run_path(capsys, tmp_path, prog, "--vars", "100").vars["100"] == 0.0
    bad = run_path(capsys, tmp_path, "IF[#1==#2]AND[#3==#4]]THEN\n#100=0\nENDIF\n")
    assert bad.code == 1 and bad.alarm["line"] == 1


def test_e_n37_while_loops_nest_and_exit(capsys, tmp_path):
    prog = """#1=0
#10=0
WHILE[#1LT3]DO1
#2=0
WHILE[#2LT2]DO2
#3=0
WHILE[#3LT2]DO3
#10=#10+1
#3=#3+1
END3
#2=#2+1
END2
#1=#1+1
END1
#4=0
WHILE[1]DO1
#4=#4+1
IF[#4GE5]EXITW
END1
#100=#10
#101=#4
M30
"""
    r = run_path(capsys, tmp_path, prog, "--vars", "100-101")
    assert r.vars == {"100": 12.0, "101": 5.0}


@pytest.mark.parametrize("prog,code", [
    ("WHILE[1]DO1\nWHILE[1]DO2\nEND1\nEND2\n", "0x022C"),
    ("WHILE[1]DO4\nEND4\n", "0x0214"),
    ("#1=0\nWHILE[#1LT2]DO1\n#1=#1+1\nGOTO9\nEND1\nN9 M30\n", "0x0224"),
    ("WHILE[1]DO1\n#1=1\n", "0x022C"),
    ("END1\n", "0x022B"),
    ("IF[1]THEN\n#1=1\n", "0x023D"),
    ("ENDIF\n", "0x023C"),
    ("GOTO 77\n", "0x022A"),
    ("IF[1]THEN\nIF[1]THEN\nIF[1]THEN\nIF[1]THEN\nIF[1]THEN\nIF[1]THEN\nENDIF\nENDIF\nENDIF\nENDIF\nENDIF\nENDIF\n",
     "0x023E"),
    ("#20005=10\n", "0x0254"),
    ("#20020=40000\n", "0x0244"),
    ("##20=1\n", "0x0206"),
    ("#1=2 G01 X10.\n", "0x0208"),
    ("#12000=1\n", "0x0235"),
])
def test_e_n37_and_a21_instruction_errors(capsys, tmp_path, prog, code):
    r = run_path(capsys, tmp_path, prog)
    assert r.code == 1 and r.alarm["code"] == code, r.alarm
    assert r.alarm["line"] is not None and r.alarm["block"]


def test_macro_alarm_20020(capsys, tmp_path):
    r = run_path(capsys, tmp_path, "G90 G00 X1.\n#20020=12\nX2.\n")
    assert r.alarm["code"] == "MR12" and r.alarm["line"] == 2
    assert r.ends("X") == [(1.0,)]


def test_e_l40_if_goto_with_single_equals(capsys, tmp_path):
    body = """#10=20.
#11=5.
#3=2.
#4=1.
#5=0
N10 #12=#10
#13=#11+2;
IF[#2=1]GOTO200;
#12=#10-#3;
#13=#11-#4;
N200 X#12 Z#13;
#5=#5+2;
M30
"""
    r1 = run_path(capsys, tmp_path, "#2=1\n" + body, "--vars", "5", profile="lathe-2018")
    assert r1.ends("X", "Z") == [(20.0, 7.0)] and r1.vars["5"] == 2.0
    r2 = run_path(capsys, tmp_path, "#2=0\n" + body, profile="lathe-2018")
    assert r2.ends("X", "Z") == [(18.0, 4.0)]


def test_e_l41_nested_while_endw(capsys, tmp_path):
    prog = """#80=0
#60=30.
#50=10.
WHILE [#80<=360.] (outer)
WHILE[#60>=20.] (inner)
#60=#60-2.
ENDW
#80=#80+15.
#50=#50-0.05
ENDW
M30
"""
    r = run_path(capsys, tmp_path, prog, "--vars", "50,60,80", profile="lathe-2018")
    assert r.vars["80"] == 375.0 and r.vars["60"] == 18.0 and r.vars["50"] == pytest.approx(8.75)


def test_lathe_2018_rejects_do_and_nc5_rejects_endw(capsys, tmp_path):
    assert run_path(capsys, tmp_path, "WHILE[0]DO1\nEND1\n", profile="lathe-2018").code == 1
    assert run_path(capsys, tmp_path, "WHILE[0]\nENDW\n", profile="nc5-lathe-a").alarm["code"] == "0x0215"


@pytest.mark.parametrize("op,expected", [(">", 1), ("<", 0), ("==", 0), (">=", 1), ("<=", 0), ("!=", 1)])
def test_e_l42_comparison_assignment(capsys, tmp_path, op, expected):
    assert var(capsys, tmp_path, f"#1=5\n#2=3\n#100=#1{op}#2", profile="lathe-2018") == expected


def test_e_l39_e_l43_substitution_forms(capsys, tmp_path):
    prog = """#20=10.1
#21=1
#100=1.234
#101=4.
#102=30.
#103=500.
G#21 Z-#20 F100.
#100 = [#101+#102]/2.0
G1X#100Y#101
G1X[#100]
G1X[#100+#101]
G1X-#100
#[#21+1]=7.
#[-#21+3]=8.
G1Z#100F#102S#103
M30
"""
    r = run_path(capsys, tmp_path, prog, "--vars", "2", profile="nc5-mill")
    assert r.code == 0, r.alarm
    assert r.moves[0]["kind"] == "line" and r.moves[0]["work"]["Z"] == -10.1
    xs = [m["work"]["X"] for m in r.moves[1:5]]
    assert xs == [17.0, 17.0, 21.0, -17.0]
    assert r.moves[5]["work"]["Z"] == 17.0 and r.moves[5]["feed"] == 30.0
    assert r.vars["2"] == 8.0


def test_vacant_index_and_variable_classes(capsys, tmp_path):
    r = run_path(capsys, tmp_path, "#1=1\n#100=2\n#2000=3\n#4000=4\n#11999=5\nM30\n",
                 "--vars", "1,100,2000,4000,11999")
    assert r.vars == {"1": 1.0, "100": 2.0, "2000": 3.0, "4000": 4.0, "11999": 5.0}
    legacy = run_path(capsys, tmp_path, "#51=1\n#1601=2\n#10001=3\n#100=1\nM30\n", "--vars", "51,1601,10001",
                      profile="lathe-2018")
    assert legacy.vars == {"51": 1.0, "1601": 2.0, "10001": 3.0}
