"""Executes blocks: modal state, coordinate systems, and emission of canonical Moves and Aux events."""

from nc.interp.interpreter import Interpreter

__all__ = ["Interpreter"]
