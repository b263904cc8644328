"""The compiled parser reads exactly what Python's ``float`` and ``numpy.loadtxt`` read, or
gives up (and numpy reads it)."""

import io
import warnings

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from hystcomp.io._floatparse import parse_text


def _bits(values) -> np.ndarray:
    return np.asarray(values, dtype=np.float64).view(np.uint64)


def _read_each(tokens: list[str]) -> tuple[np.ndarray, np.ndarray]:
    """Each token parsed alone: the values, and where the parser gave up."""
    values = np.full(len(tokens), np.nan)
    gave_up = np.zeros(len(tokens), dtype=bool)
    for i, tok in enumerate(tokens):
        out = parse_text(tok.encode() + b"\n", 1)
        if out is None:
            gave_up[i] = True
        else:
            values[i] = out[0, 0]
    return values, gave_up


def test_every_kind_of_float64_in_every_format(rng):
    bits = rng.integers(0, 2**64, size=20_000, dtype=np.uint64, endpoint=False)
    anything = bits.view(np.float64)  # every exponent, subnormals, nan and inf included
    lab = np.concatenate(
        [
            np.arange(2000) / 2e4,
            rng.standard_normal(2000) * 50.0,
            np.round(rng.standard_normal(2000), 3),
            rng.standard_normal(2000) * 10.0 ** rng.integers(-30, 30, 2000),
        ]
    )
    edges = [0.0, -0.0, 5e-324, 2.2250738585072014e-308, 1.7976931348623157e308, 0.1, 0.3]
    edges += [1e-4, 9.999999999999999e-05, 1e15, 1e16, 1e22, 1e23, 2.0**53 + 2, 2.0**-30]
    edges += [148464748120430784.0, 123456789012345678.0, 0.5, 1.5, 100.0, 2 / 3]
    formats = [repr, "{:.17g}".format, "{:.6e}".format, "{:.3f}".format, "{:g}".format]
    formats += ["{:+.25e}".format, "{:.20f}".format]
    for values in (anything, lab, np.array(edges)):
        for fmt in formats:
            tokens = [fmt(float(v)) for v in values]
            parsed, gave_up = _read_each(tokens)
            expected = np.array([float(tok) for tok in tokens])
            assert np.array_equal(_bits(parsed[~gave_up]), _bits(expected[~gave_up])), fmt
            # what hystcomp writes is read without numpy, but for the extremes and the rare
            # near-ties and powers of two (among the edges: 1e23 and 2**-30)
            if fmt is repr and values.size > len(edges):
                normal = np.isfinite(values) & (np.abs(values) > 1e-250) & (np.abs(values) < 1e250)
                assert gave_up[normal].mean() < 1e-3


def test_a_lab_table_is_read_whole_and_exactly(rng):
    table = np.column_stack(
        [np.arange(5000) / 2e4, 60 + 50 * rng.standard_normal(5000), rng.standard_normal(5000)]
    )
    text = "\n".join(",".join(repr(float(v)) for v in row) for row in table) + "\n"
    out = parse_text(text.encode(), 3)
    assert out is not None
    assert np.array_equal(_bits(out.T), _bits(table))


_NUMBER = r"[+-]?[0-9]{0,22}(\.[0-9]{0,22})?([eE][+-]?[0-9]{0,4})?"


@given(st.from_regex(_NUMBER, fullmatch=True))
def test_a_number_is_read_as_float_reads_it_or_not_at_all(token):
    out = parse_text(token.encode() + b"\n", 1)
    if out is None:
        return
    if out.shape[1] == 0:  # a blank line
        assert token == ""
        return
    assert np.array_equal(_bits(out[0]), _bits([float(token)]))  # float() must accept it


_VALID = st.builds(
    str.format,
    st.sampled_from(["{!r}", "{:.17g}", "{:g}", "{:.3f}", "{:+.4e}"]),
    st.floats(allow_nan=False, allow_infinity=False),
)
_ODD = st.from_regex(_NUMBER, fullmatch=True) | st.sampled_from(["nan", "-inf", '"1"', "#", ""])
_SEPARATORS = {",": [",", ";"], ";": [";", ","], "\t": ["\t", " "], None: [" ", "\t", ","]}


@st.composite
def _texts(draw, delimiter):
    """Rows of numbers with the variants and mistakes of lab files, or any text (the tables
    that read: :func:`test_lab_tables_are_read_as_numpy_reads_them`)."""
    if draw(st.integers(0, 4)) == 0:
        return draw(st.text(alphabet='0123456789.eE+-, ;\t\r\n"#nai', max_size=60))
    lines = []
    for _ in range(draw(st.integers(0, 5))):
        pad = st.sampled_from(["", "", " ", "  "])
        tokens = draw(st.lists(_VALID | _ODD, min_size=1, max_size=3))
        row = draw(pad)
        for k, tok in enumerate(tokens):
            if k:
                row += draw(pad) + draw(st.sampled_from(_SEPARATORS[delimiter])) + draw(pad)
            row += tok
        if delimiter is not None and draw(st.booleans()):
            row += delimiter  # a trailing separator
        lines.append(row + draw(pad) + draw(st.sampled_from(["\n", "\r\n", "\r", ""])))
    return "".join(lines)


@pytest.mark.parametrize(
    ("delimiter", "comma", "trailing"),
    [(",", False, False), (",", False, True), (";", True, False), ("\t", True, True), (None, False, False)],
)  # fmt: skip
@given(data=st.data())
def test_any_text_is_read_as_numpy_reads_it_or_not_at_all(delimiter, comma, trailing, data):
    # as hystcomp.io._text reads a chunk with numpy (a trailing separator: the first columns)
    text = data.draw(_texts(delimiter))
    out = parse_text(text.encode(), 2, delimiter, comma=comma, trailing=trailing)
    if out is None:
        return
    source = text.replace(",", ".") if comma else text
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # "input contained no data"
        expected = np.loadtxt(
            io.StringIO(source),
            delimiter=delimiter,
            ndmin=2,
            usecols=range(2) if trailing else None,
        )
    if out.shape[1] == 0:
        assert expected.size == 0
    else:
        assert np.array_equal(_bits(out.T), _bits(expected))


@pytest.mark.parametrize(
    ("delimiter", "comma", "trailing"),
    [(",", False, True), (";", True, False), (None, False, False)],
)
def test_lab_tables_are_read_as_numpy_reads_them(rng, delimiter, comma, trailing):
    formats = ["{!r}", "{:.17g}", "{:g}", "{:.3f}", "{:+.4e}", "{:.0f}"]
    read = 0
    for _ in range(300):
        lines = []
        for _ in range(rng.integers(1, 6)):
            values = rng.standard_normal(2) * 10.0 ** rng.integers(-8, 9, 2)
            tokens = [formats[rng.integers(len(formats))].format(float(v)) for v in values]
            tokens = [tok.replace(".", ",") if comma else tok for tok in tokens]
            pads = [" " * rng.integers(0, 2) for _ in range(4)]
            sep = (
                f"{pads[1]}{delimiter}{pads[2]}"
                if delimiter
                else pads[1] + " " + "\t" * rng.integers(2)
            )
            end = ["\n", "\r\n", delimiter + "\n" if trailing else "\n"][rng.integers(3)]
            lines.append(pads[0] + sep.join(tokens) + pads[3] + end + "\n" * (rng.random() < 0.1))
        text = "".join(lines)
        out = parse_text(text.encode(), 2, delimiter, comma=comma, trailing=trailing)
        if out is None:
            continue
        read += 1
        source = text.replace(",", ".") if comma else text
        usecols = range(2) if trailing else None
        expected = np.loadtxt(io.StringIO(source), delimiter=delimiter, ndmin=2, usecols=usecols)
        assert np.array_equal(_bits(out.T), _bits(expected)), text
    assert read == 300  # every such table read without numpy
