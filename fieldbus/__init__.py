"""Fieldbus side: CiA 402 master state machine, PDO layouts, unit scaling, and the bus links
(in-process SimLink, EtherCAT via pysoem, CANopen via python-canopen). Knows nothing of G-code."""
