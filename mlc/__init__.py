"""The MLC (Delta's machine PLC): device memory, the NC5 special M/D map, NC↔MLC handshakes and
user scan logic. Never plans motion."""
