"""Everything that pretends to be hardware: CiA 402 drive model, I/O, MPG, spindle, and the
wire-level simulators (EtherCAT slaves on a raw socket, CANopen nodes on python-can).
Imports only wire formats from `fieldbus`; never imported by `nc` or `mlc`."""
