"""Program text → blocks of words (lexing and parsing)."""

from nc.program.blocks import Block, Word, parse_program, Program

__all__ = ["Block", "Word", "Program", "parse_program"]
