"""The parser's and interpreter's fast paths read a block exactly as the general paths do."""

from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from nc.alarms import NcAlarm
from nc.program.blocks import _parse_general, parse_block

LETTERS = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz"
number = st.one_of(
    st.integers(-10**13, 10**13).map(str),
    st.decimals(-10**7, 10**7, places=4, allow_nan=False, allow_infinity=False).map(str),
    st.sampled_from([".5", "-.25", "+3.", "1.", "0", "-0", "007", "+12", "1.2.3", "1 2", "- 4", "1e5"]),
)
word = st.tuples(st.sampled_from(list(LETTERS)), number).map(lambda t: t[0] + t[1])
sep = st.sampled_from(["", " ", "  ", "\t"])
block_text = st.lists(st.tuples(sep, word), min_size=1, max_size=6).map(
    lambda ws: "".join(s + w for s, w in ws)) | st.text(alphabet="GXYZNO0123456789.-+ #=[]();/%,", max_size=20)


def _outcome(parse, text):
    try:
        return parse(7, text)
    except NcAlarm as exc:
        return ("alarm", exc.alarm)


@settings(max_examples=600, deadline=None)
@given(block_text)
def test_plain_blocks_parse_as_the_general_parser_does(text):
    assert _outcome(parse_block, text) == _outcome(_parse_general, text)


@pytest.mark.parametrize("text", ["G01 X12.5 Y-3", "N10 G1 X.5", "x1y2", "N1 N2 X3", "X1 N5", "N-5 X1",
                                  "N1.5 X1", "O12 X1", "X1234567890123", "X-123456789.123", "G01X1.Y2."])
def test_examples_parse_as_the_general_parser_does(text):
    assert _outcome(parse_block, text) == _outcome(_parse_general, text)
