"""The bench: configuration, the cyclic loop and its clocks, traces, checks, reports, the `hil` CLI.
Wires nc, mlc, fieldbus and virtual_bus together; holds no G-code or bus logic of its own."""
