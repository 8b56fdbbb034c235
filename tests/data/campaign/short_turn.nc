O0101 (campaign test: a short turning pass, about 0.6 s)
G21 G18 G98
G00 X58. Z98.
G01 Z90. F900
X56. Z88.
G00 X60. Z100.
M30
