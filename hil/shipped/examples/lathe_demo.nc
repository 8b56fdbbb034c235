O0001 (deltahil demo: face, turn and profile a shaft on a type A lathe)
G21 G18 G98              (mm, ZX plane, feed per minute)
T0101                    (tool 1, offset 1)
S1200 M03                (spindle CW 1200 rpm)
G00 X62. Z2.             (approach)
G01 Z0. F600             (to the face)
X-1.6 F300               (face to centre)
G00 X52. Z2.
G01 Z-40. F900           (rough turn diameter 52)
G00 U2. Z2.
X40.
G01 Z-15. F900           (turn diameter 40)
G02 X50. Z-20. R5. F600  (convex fillet R5 into the shoulder)
G01 X52.
G00 X62.
Z2.
G04 P250                 (dwell 0.25 s)
M05
G00 X100. Z50.           (retract)
M30
