O0102 (campaign test: an unknown G code on line 4 raises an alarm)
G21 G18 G98
G00 X58. Z98.
G07.7 X50.
M30
