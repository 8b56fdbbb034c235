O0103 (campaign test: calls the subprogram O0104 beside it)
G21 G18 G98
M98 P0104
G00 X60. Z100.
M30
