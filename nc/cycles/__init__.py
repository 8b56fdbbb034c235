"""Canned cycles (lathe G70–G76, G90/G92/G94, G32/G34, hole cycles; milling hole cycles).

`nc.cycles.dispatch.run_cycle(host, code, block)` is the interpreter's entry point; the geometry
modules (`turning`, `threading`, `lathe_single`, `holes`) are pure functions on plane elements.
"""
