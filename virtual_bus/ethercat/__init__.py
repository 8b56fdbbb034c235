"""Software EtherCAT slaves: ESC register files that answer real frames (EtherType 0x88A4) on a raw
socket, with SII EEPROM, AL state machine, SyncManagers/FMMUs, CoE mailbox and DC registers,
generated from ESI-like device descriptions and backed by the CiA 402 drive model."""
