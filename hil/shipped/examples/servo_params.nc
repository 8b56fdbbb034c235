(Servo parameters from a program: G10 L40 read, G10 L41 write, #20023 value, #20024 result)
(Station I: 1 = first axis of the bench, 2 = second ...; hil run --servo-modbus DEVICE: RS-485 station)
O0100
G00 X10. Z5.
(raise X's position loop gain KPP, P2-00, once the rapid above has finished)
G10 L41 I1 P2 D0 R150
(read Z's electronic gear numerator P1-44)
G10 L40 I2 P1 D44
#100 = #20023
#101 = #20024
IF [#101 NE 0] GOTO 90
(factory gear ratio: finish normally, otherwise stop with macro alarm MR2)
IF [#100 NE 16777216] GOTO 80
G98 G01 X20. F500.
M30
N80 #20020 = 2
N90 #20020 = 1
M30
