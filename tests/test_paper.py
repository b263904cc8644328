"""The paper's numbers live in hystcomp.paper only: a leaf, consistent, and never copied."""

import ast
import re
from pathlib import Path

import numpy as np
import pytest

from hystcomp import paper, presets
from hystcomp.experiment import calibration
from hystcomp.identify import excitation
from hystcomp.models.base import DEFAULT_VOLTAGE_RANGE
from hystcomp.plant import TwinParameters

SRC = Path(paper.__file__).parent
PAPER_FILE = Path(paper.__file__)


def _sources():
    """Every module of the package except paper.py: (path relative to src/, text, tree)."""
    out = []
    for path in sorted(SRC.rglob("*.py")):
        if path == PAPER_FILE:
            continue
        text = path.read_text(encoding="utf-8")
        out.append((path.relative_to(SRC.parent), text, ast.parse(text)))
    return out


SOURCES = _sources()


def _number(node):
    """The value of a numeric literal (with its sign), or None."""
    if isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.USub | ast.UAdd):
        inner = _number(node.operand)
        return None if inner is None else (-inner if isinstance(node.op, ast.USub) else inner)
    if isinstance(node, ast.Constant) and type(node.value) in (int, float):
        return node.value
    return None


def _significant_digits(value: float) -> int:
    mantissa = f"{abs(value):.12e}".split("e")[0].replace(".", "").rstrip("0")
    return len(mantissa)


def _distinctive_numbers() -> set[float]:
    """Coefficients and Table I values with 3 or more significant digits: never a coincidence."""
    values = {
        *paper.PREISACH_THETA,
        *paper.PI_WEIGHTS,
        *paper.MPI_WEIGHTS,
        *paper.MPI_INVERSE_DEADZONE_WEIGHTS,
        *(x for row in paper.TABLE_I.values() for pair in row.values() for x in pair),
    }
    return {v for v in values if _significant_digits(v) >= 3}


def _published_numbers() -> set[float]:
    """The distinctive numbers, and the rig of Section II and the range as code literals."""
    rig = {paper.DATASHEET_GAIN, float(round(1e3 * paper.DATASHEET_GAIN)), paper.PIEZO_BANDWIDTH}
    rig |= {paper.SENSOR_BANDWIDTH, paper.SAMPLE_RATE, float(paper.VOLTAGE_RANGE[1])}
    return _distinctive_numbers() | rig


#: Names whose value equals a published number by coincidence (the line is not flagged).
COINCIDENCES = {"MAT_TIMEOUT"}  # io/_formats.py: 120 s to parse a MAT file, not 120 V

#: Literal tuples/lists that are the paper's, written out.
PUBLISHED_SEQUENCES = {
    "the voltage range": paper.VOLTAGE_RANGE,
    "the identification amplitudes": paper.PI_AMPLITUDES,
    "the reference frequencies": paper.FREQUENCIES,
}


def test_paper_is_a_leaf():
    tree = ast.parse(PAPER_FILE.read_text(encoding="utf-8"))
    imported = [
        alias.name if isinstance(node, ast.Import) else f"{node.module}"
        for node in ast.walk(tree)
        if isinstance(node, ast.Import | ast.ImportFrom)
        for alias in node.names
    ]
    assert all(name == "__future__" for name in imported), imported


def test_no_stray_copies_of_published_numbers_in_code():
    """A float or tuple of the paper's typed into code instead of taken from paper.py."""
    published = _published_numbers()
    found = []
    for rel, text, tree in SOURCES:
        lines = text.splitlines()
        for node in ast.walk(tree):
            value = _number(node)
            line = lines[node.lineno - 1] if hasattr(node, "lineno") else ""
            if any(name in line for name in COINCIDENCES):
                continue
            if isinstance(value, float) and value in published:
                found.append(f"{rel}:{node.lineno}: {value!r}")
            if isinstance(node, ast.Tuple | ast.List):
                values = tuple(_number(e) for e in node.elts)
                for what, seq in PUBLISHED_SEQUENCES.items():
                    if None not in values and values == tuple(seq):
                        found.append(f"{rel}:{node.lineno}: {what} {values}")
    assert not found, "take these from hystcomp.paper:\n" + "\n".join(found)


def _text_pattern() -> re.Pattern:
    digits = sorted({f"{v:g}".lstrip("-") for v in _distinctive_numbers()})
    return re.compile(
        r"(?<![\d.])(?:" + "|".join(re.escape(d) for d in digits) + r")0*(?!\d)"
        r"|\(\s*0\.0\s*,\s*120\.0\s*\)"  # the 0..120 V range typed as a tuple
        r"|range\(\s*5\s*,\s*125\s*,\s*5\s*\)"  # the Preisach amplitudes
    )


def test_no_stray_copies_of_published_numbers_in_text():
    """The paper's distinctive digits, even inside strings, docstrings or comments."""
    pattern = _text_pattern()
    found = [
        f"{rel}:{text.count(chr(10), 0, m.start()) + 1}: {m.group(0)!r}"
        for rel, text, _ in SOURCES
        for m in pattern.finditer(text)
    ]
    assert not found, "take these from hystcomp.paper:\n" + "\n".join(found)


def test_the_guard_would_catch_a_copy():
    """The scanner's own check: the copies that the review found are flagged."""
    published = _published_numbers()
    for code in ("theta = (0.00298,)", "X = 4.6996", "k = 0.235", "fs = 20_000.0"):
        tree = ast.parse(code)
        assert any(_number(n) in published for n in ast.walk(tree)), code
    assert 120.0 in published
    pattern = _text_pattern()
    for text in ("rms 4.6996", "X = 1.1560", "theta = [0.00298]", "voltage_range=(0.0, 120.0)"):
        assert pattern.search(text), text
    assert not pattern.search("0..120 V, 16 plays, 0.15 s, 14.6996")


def test_the_numbers_agree_with_each_other():
    assert len(paper.PI_WEIGHTS) == len(paper.MPI_WEIGHTS) == paper.N_OPERATORS == 16
    assert len(paper.MPI_INVERSE_DEADZONE_WEIGHTS) == paper.N_DEADZONES == 16
    assert len(paper.PREISACH_THETA) == 9  # eq. (5), degree 3
    assert paper.PREISACH_AMPLITUDES == tuple(5.0 * k for k in range(1, 25))
    assert paper.FIG5_AMPLITUDES == paper.PI_AMPLITUDES == (30.0, 60.0, 90.0, 120.0)
    assert tuple(paper.TABLE_I) == paper.FREQUENCIES == (1.0, 10.0, 50.0)
    assert all(tuple(row) == paper.METHODS for row in paper.TABLE_I.values())
    assert set(paper.SATURATION_ZONE_PCT) == set(paper.METHODS) == set(paper.LABELS)
    assert paper.FIG9_FREQUENCY in paper.FREQUENCIES
    assert paper.VOLTAGE_RANGE == (0.0, 120.0)


def test_the_package_takes_its_defaults_from_paper():
    assert DEFAULT_VOLTAGE_RANGE is paper.VOLTAGE_RANGE
    twin = TwinParameters()
    assert twin.voltage_range == paper.VOLTAGE_RANGE
    assert twin.sample_rate == paper.SAMPLE_RATE
    assert twin.resonance_hz == paper.PIEZO_BANDWIDTH
    assert twin.sensor_gain == paper.SENSOR_GAIN
    assert excitation.PI_AMPLITUDES is paper.PI_AMPLITUDES
    np.testing.assert_array_equal(presets.PAPER_PREISACH_THETA, paper.PREISACH_THETA)
    np.testing.assert_array_equal(presets.PAPER_PI_WEIGHTS, paper.PI_WEIGHTS)
    np.testing.assert_array_equal(presets.PAPER_MPI_WEIGHTS, paper.MPI_WEIGHTS)
    np.testing.assert_array_equal(
        presets.PAPER_MPI_INVERSE_DEADZONE_WEIGHTS, paper.MPI_INVERSE_DEADZONE_WEIGHTS
    )


@pytest.mark.parametrize("seed", [0, 1])
def test_calibration_uses_the_models_eq5(seed):
    """calibration.paper_everett is eq. (5) with eq. (6), through the Preisach model's code."""
    rng = np.random.default_rng(seed)
    lo, hi = paper.VOLTAGE_RANGE
    a = rng.uniform(lo, hi, 200)
    b = rng.uniform(lo, a)
    t = paper.PREISACH_THETA
    eq5 = (
        t[0] * b + t[1] * a + t[2] * b**2 + t[3] * b * a + t[4] * a**2
        + t[5] * b**3 + t[6] * b**2 * a + t[7] * b * a**2 + t[8] * a**3
    )  # fmt: skip
    np.testing.assert_allclose(calibration.paper_everett(a, b), eq5, rtol=1e-12, atol=1e-12)
    assert round(float(calibration.paper_everett(hi, lo)), 2) == 36.72
