O8301 (face drilling with C positioning: run on benches/lathe-c-axis.toml)
G98 G00 X100. Z10.        (feed per minute: the spindle becomes the C axis)
M66                       (spindle -> C axis: stop, find the index, drive to CSP)
G00 X30. C0.
G83 X30. C0. Z-10. R2. Q4. F3000. L1   (deep peck: 4 mm pecks, back to R after each)
C90.                      (the next holes: C indexes, the cycle repeats)
C180.
C270.
G80
G00 Z20.
M77                       (C axis -> spindle: drive back to CSV)
M03 S300
G04 X0.3
M05
M30
