O1001 (lathe part: rough G71, finish G70 with nose radius compensation, thread G76)
(stock: bar 42 mm diameter; part: chamfered M24x2 thread, taper, radius, shoulder)
(tool 1: OD turning, nose radius 0.8, imaginary tip 3 -- tool 3: 60 deg threading)
G10 L10 P1 R0.8 Q3
G10 L10 P3 R0 Q0
G21 G99
G50 S2500
T0101
G96 S180 M03
G00 X45. Z5.
G71 U1.5 R0.5
G71 P100 Q200 U0.4 W0.1 F0.25
N100 G00 X18.
G01 Z0. F0.12
X24. Z-3.
Z-25.
X28.
X32. Z-35.
G02 X38. Z-38. R3.
G01 Z-50.
N200 X44.
G00 X60. Z50.
T0101
G00 X45. Z5.
G42 G00 X45. Z2.
G70 P100 Q200
G40 G00 X60. Z50.
T0303
G97 S800 M03
G00 X28. Z5.
G76 P011060 Q50 R0.05
G76 X21.4 Z-22. P1300 Q400 F2.
G00 X60. Z50.
M05
M30
