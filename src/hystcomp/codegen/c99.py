"""The C99 file pair that every compensator template fills in.

A template (see :mod:`hystcomp.codegen.chain` and :mod:`hystcomp.codegen.preisach`)
describes one compensator as a :class:`CTemplate`: the fields of its state, its constant
tables, helper functions, the body of ``reset`` and the body of ``step``. :func:`render`
wraps them in the same files for every template::

    NAME.h   the state struct NAME_state and the three functions
    NAME.c   the constant tables and the functions

    void   NAME_init(NAME_state *s);               before the first step
    void   NAME_reset(NAME_state *s);              back to the initial state
    double NAME_step(NAME_state *s, double x_ref); one sample: reference (um) -> voltage (V)

The generated code is C99 with nothing beyond ``<math.h>`` (its ``isfinite``, and ``fma``
where a template mirrors the fused multiply-adds of a compiled kernel), no allocation, no
global state, and its numbers written with 17 significant digits so that a double holds
exactly the value the Python compensator uses.
"""

from __future__ import annotations

import hashlib
import re
from dataclasses import dataclass, field

import numpy as np

from hystcomp import paper
from hystcomp._kernels.chain import CLAMP_TOLERANCE
from hystcomp.errors import InvalidParameterError

# A C identifier that does not start with '_' (reserved at file scope, C99 7.1.3).
_PREFIX = re.compile(r"[A-Za-z][A-Za-z0-9_]*\Z")
#: The standard headers of C99 and C11: a NAME.h of one of these names (in any case, for
#: file systems that ignore it) would shadow it for every file of the build that includes it.
STANDARD_HEADERS = frozenset(
    [
        "assert",
        "complex",
        "ctype",
        "errno",
        "fenv",
        "float",
        "inttypes",
        "iso646",
        "limits",
        "locale",
        "math",
        "setjmp",
        "signal",
        "stdalign",
        "stdarg",
        "stdatomic",
        "stdbool",
        "stddef",
        "stdint",
        "stdio",
        "stdlib",
        "stdnoreturn",
        "string",
        "tgmath",
        "threads",
        "time",
        "uchar",
        "wchar",
        "wctype",
    ]
)
#: The keywords of C99 and C11 (those without a leading '_'), and C++'s, since the header
#: is meant to be included from C++ too.
C_KEYWORDS = frozenset(
    [
        "auto",
        "break",
        "case",
        "char",
        "const",
        "continue",
        "default",
        "do",
        "double",
        "else",
        "enum",
        "extern",
        "float",
        "for",
        "goto",
        "if",
        "inline",
        "int",
        "long",
        "register",
        "restrict",
        "return",
        "short",
        "signed",
        "sizeof",
        "static",
        "struct",
        "switch",
        "typedef",
        "union",
        "unsigned",
        "void",
        "volatile",
        "while",
        "bool",
        "class",
        "delete",
        "new",
        "namespace",
        "operator",
        "private",
        "protected",
        "public",
        "template",
        "this",
        "throw",
        "try",
        "catch",
        "virtual",
    ]
)


@dataclass
class CTemplate:
    """What a compensator template contributes to the generated files.

    Strings are C99 lines in which ``{p}`` stands for the prefix. ``state_fields`` are
    declarations inside the state struct (``last``, ``nonfinite_count`` and
    ``clamped_count`` are always there); ``tables`` the ``static const`` tables of NAME.c; ``locals`` the declarations
    at the top of ``NAME_step``; ``reset_body`` the statements of ``NAME_reset``.
    ``step_body`` runs for a finite ``x_ref`` and assigns the voltage to ``v``; the common
    part then applies the slew-rate limit (``max_step`` V per sample, if finite) and the
    clamp to ``[low, high]`` V, and ``after_body`` runs last, with the final ``v`` (for
    state that follows the applied voltage).

    ``functions`` are C function definitions (``static``, named ``{p}_...``) placed after
    the tables and before ``NAME_reset``, for helpers that the bodies call. If
    ``hold_on_overflow`` (the default), a non-finite ``v`` from a finite ``x_ref`` holds
    the last output, as the play chain does; a template whose Python kernel instead takes
    ``v = +-inf`` through the slew-rate limit and the clamp (to the range ends) sets it to
    False, and its ``step_body`` must then never assign NaN. If ``count_clamped`` (the
    default), an output that the clamp moves by more than
    :data:`~hystcomp._kernels.chain.CLAMP_TOLERANCE` of the range counts in
    ``clamped_count``, as the chain kernel counts it; a template with a rule of its own (the
    Preisach compensators count a reference out of reach) sets it False and counts in its
    ``after_body``.

    ``public`` are further functions of the interface, each ``(comment lines, definition)``:
    the header declares them after ``NAME_step``, with the comment, and the source defines
    them last. ``defines`` are lines of the header before the state struct (constants).

    Parameters
    ----------
    kind : str
        The kind of the compensator (``"pi"``, ``"mpi"``, ``"preisach"``), for the comments.
    summary : list of str
        Comment lines that describe the compensator in the header.
    low : float
        The lower end of the output clamp, V.
    high : float
        The upper end of the output clamp, V.
    max_step : float, optional
        Largest output change per sample, V (``inf``: no slew-rate limit).
    initial_output : float, optional
        The output before the first sample, V.
    state_fields : list of str, optional
        Declarations inside the state struct.
    tables : list of str, optional
        The ``static const`` tables of NAME.c.
    locals : list of str, optional
        Declarations at the top of ``NAME_step``.
    reset_body : list of str, optional
        The statements of ``NAME_reset``.
    step_body : list of str, optional
        The statements that assign the voltage ``v`` for a finite ``x_ref``.
    after_body : list of str, optional
        Statements run last, with the final ``v``.
    functions : list of str, optional
        Static helper functions, placed after the tables.
    hold_on_overflow : bool, optional
        Whether a non-finite ``v`` from a finite ``x_ref`` holds the last output.
    count_clamped : bool, optional
        Whether the common part counts clamped outputs.
    public : list of (list of str, str), optional
        Further interface functions, each ``(comment lines, definition)``.
    defines : list of str, optional
        Header lines before the state struct.
    """

    kind: str
    summary: list[str]
    low: float
    high: float
    max_step: float = np.inf
    initial_output: float = 0.0
    state_fields: list[str] = field(default_factory=list)
    tables: list[str] = field(default_factory=list)
    locals: list[str] = field(default_factory=list)
    reset_body: list[str] = field(default_factory=list)
    step_body: list[str] = field(default_factory=list)
    after_body: list[str] = field(default_factory=list)
    functions: list[str] = field(default_factory=list)
    hold_on_overflow: bool = True
    count_clamped: bool = True
    public: list[tuple[list[str], str]] = field(default_factory=list)
    defines: list[str] = field(default_factory=list)


def check_prefix(prefix: str) -> str:
    """Return ``prefix`` if it can start C identifiers, else raise :class:`InvalidParameterError`.

    Parameters
    ----------
    prefix : str
        The name of the generated files, state type and functions.

    Returns
    -------
    str
        ``prefix``, unchanged.

    Examples
    --------
    >>> check_prefix("stage_x")
    'stage_x'
    >>> check_prefix("2axis")
    Traceback (most recent call last):
    ...
    hystcomp.errors.InvalidParameterError: The prefix must be a C identifier ...
    """
    if not isinstance(prefix, str) or not _PREFIX.match(prefix):
        raise InvalidParameterError(
            "The prefix must be a C identifier that starts with a letter (then letters, digits "
            f"or '_'), as it names the C files, type and functions. Got {prefix!r}; "
            "for example 'stage_x' or 'piezo_comp'."
        )
    if prefix.lower() in STANDARD_HEADERS:
        raise InvalidParameterError(
            f"The prefix {prefix!r} would name the file {prefix}.h after the standard header "
            f"<{prefix.lower()}.h>, which it would shadow in the build. Choose another name, "
            f"for example '{prefix.lower()}_comp'."
        )
    if prefix in C_KEYWORDS:
        raise InvalidParameterError(
            f"The prefix {prefix!r} is a C (or C++) keyword. Choose another name, for example "
            f"'{prefix}_comp'."
        )
    return prefix


def c_double(value: float) -> str:
    """A C double literal that reads back exactly (17 significant digits).

    Parameters
    ----------
    value : float
        A finite number.

    Returns
    -------
    str
        The C literal.

    Examples
    --------
    >>> c_double(0.1), c_double(3.0), c_double(-1e-20)
    ('0.10000000000000001', '3.0', '-9.9999999999999995e-21')
    """
    value = float(value)
    if not np.isfinite(value):
        raise ValueError(f"C99 has no literal for {value!r}")  # templates never ask for one
    text = f"{value:.17g}"
    return text if any(c in text for c in ".e") else text + ".0"


def c_table(name: str, values, comment: str) -> str:
    """A ``static const double`` table, four numbers to a line, with a comment above.

    Parameters
    ----------
    name : str
        The table's C name (``{p}`` for the prefix).
    values : array_like
        The numbers, as doubles.
    comment : str
        The comment line above the table.

    Returns
    -------
    str
        The C definition.
    """
    values = [c_double(v) for v in values]
    rows = [", ".join(values[i : i + 4]) for i in range(0, len(values), 4)]
    body = ",\n    ".join(rows)
    return f"/* {comment} */\nstatic const double {name}[{len(values)}] = {{\n    {body}\n}};"


def render(
    template: CTemplate,
    prefix: str,
    *,
    source: str | None = None,
    sample_rate: float = paper.SAMPLE_RATE,
) -> tuple[str, str]:
    """The texts of ``NAME.h`` and ``NAME.c`` for ``template``.

    ``source`` (the model file) and ``sample_rate`` (Hz, at which ``NAME_step`` is called)
    only go into the comments.

    Parameters
    ----------
    template : CTemplate
        The compensator's contribution.
    prefix : str
        NAME, a C identifier.
    source : str, optional
        The model file, named in the comments.
    sample_rate : float, optional
        Hz at which ``NAME_step`` is called, for the comments.

    Returns
    -------
    header : str
        The text of ``NAME.h``.
    source : str
        The text of ``NAME.c``.
    """
    p = check_prefix(prefix)
    guard = f"{p.upper()}_H"
    pair_id = f"{p.upper()}_PAIR_ID"
    comment = _header_comment(template, p, source, sample_rate)
    fields = [
        "double last; /* last output, V (held while x_ref is not finite) */",
        "unsigned long nonfinite_count; /* non-finite x_ref samples since the last reset */",
        "unsigned long clamped_count; /* outputs the voltage range cut since the last reset */",
        *template.state_fields,
    ]
    header = "\n".join(
        [
            comment,
            f"#ifndef {guard}",
            f"#define {guard}",
            "",
            "#ifdef __cplusplus",
            'extern "C" {',
            "#endif",
            "",
            *template.defines,
            *([""] if template.defines else []),
            "typedef struct {",
            *(f"    {line}" for line in fields),
            f"}} {p}_state;",
            "",
            "/* Prepare a state before its first step (the same as a reset). */",
            f"void {p}_init({p}_state *s);",
            "",
            "/* Return to the initial state: the output the amplifier holds at rest and the",
            "   operator states the model starts from. */",
            f"void {p}_reset({p}_state *s);",
            "",
            "/* One sample: reference x_ref in um -> piezo voltage in V, always inside the",
            "   voltage range. A non-finite x_ref (NaN, +-inf) holds the last output. */",
            f"double {p}_step({p}_state *s, double x_ref);",
            "",
            *(
                line
                for comment_lines, definition in template.public
                for line in (*comment_lines, definition.split("\n", 1)[0] + ";", "")
            ),
            "#ifdef __cplusplus",
            "}",
            "#endif",
            "",
            f"#endif /* {guard} */",
            "",
        ]
    )
    check = [
        f"#if !defined({pair_id}) || {pair_id} != PAIR_ID_VALUE",
        f'#error "{p}.h and {p}.c come from different exports: export them again together"',
        "#endif",
        "#if defined(__FAST_MATH__) || (defined(__FINITE_MATH_ONLY__) && __FINITE_MATH_ONLY__)",
        (
            f'#error "build {p}.c without -ffast-math or -ffinite-math-only: they remove the '
            'tests that hold the output on a non-finite reference"'
        ),
        "#endif",
    ]
    local_lines = [f"    {line}" for line in template.locals]
    source_text = "\n".join(
        [
            comment,
            f'#include "{p}.h"',
            "",
            *check,
            "",
            "#include <math.h>",
            "",
            *(f"{t}\n" for t in template.tables),
            *(f"{f}\n" for f in template.functions),
            f"void {p}_reset({p}_state *s)",
            "{",
            *(f"    {line}" for line in template.reset_body),
            f"    s->last = {c_double(template.initial_output)};",
            "    s->nonfinite_count = 0;",
            "    s->clamped_count = 0;",
            "}",
            "",
            f"void {p}_init({p}_state *s)",
            "{",
            f"    {p}_reset(s);",
            "}",
            "",
            f"double {p}_step({p}_state *s, double x_ref)",
            "{",
            *local_lines,
            "    double v;",
            "",
            "    if (!isfinite(x_ref)) { /* a broken sensor or reference: hold the output */",
            "        s->nonfinite_count++;",
            "        return s->last;",
            "    }",
            *(f"    {line}" if line else "" for line in template.step_body),
            *(_overflow_hold() if template.hold_on_overflow else []),
            *(f"    {line}" if line else "" for line in _limits(template)),
            *(f"    {line}" if line else "" for line in template.after_body),
            "    s->last = v;",
            "    return v;",
            "}",
            "",
            *(f"{definition}\n" for _, definition in template.public),
        ]
    )
    header, source_text = (
        text.replace("{p}", p).replace("{P}", p.upper()) for text in (header, source_text)
    )
    # A hash of both texts, defined in the header and checked in the source: a NAME.h and a
    # NAME.c from two different exports (two runs into one folder) do not compile together.
    digest = hashlib.sha256((header + "\0" + source_text).encode()).hexdigest()[:12]
    value = f"0x{digest}"
    marker = f"#define {guard}\n"
    header = header.replace(
        marker,
        f"{marker}\n/* identifies this export; {p}.c checks it (do not edit) */\n"
        f"#define {pair_id} {value}\n",
        1,
    )
    return header, source_text.replace("PAIR_ID_VALUE", value)


def _overflow_hold() -> list[str]:
    return [
        "    if (!isfinite(v)) { /* overflow on a huge finite x_ref: hold the output */",
        "        s->nonfinite_count++;",
        "        return s->last;",
        "    }",
    ]


def _limits(template: CTemplate) -> list[str]:
    """Slew-rate limit, then clamp: the order of the Python compensators."""
    lines = [""]
    if np.isfinite(template.max_step):
        step = c_double(template.max_step)
        lines += [
            f"/* slew-rate limit: at most {step} V per sample */",
            f"if (v < s->last - {step}) {{",
            f"    v = s->last - {step};",
            "}",
            f"if (v > s->last + {step}) {{",
            f"    v = s->last + {step};",
            "}",
        ]
    lo, hi = c_double(template.low), c_double(template.high)
    if template.count_clamped:  # the chain kernel's rule (Stepper.clamped_count)
        tol = CLAMP_TOLERANCE * (template.high - template.low)
        lines += [
            f"if (v < {c_double(template.low - tol)} || v > {c_double(template.high + tol)}) {{",
            "    s->clamped_count++; /* the clamp cuts more than a rounding */",
            "}",
        ]
    return [
        *lines,
        "/* the amplifier's range: never drive the piezo outside it */",
        f"if (v < {lo}) {{",
        f"    v = {lo};",
        "}",
        f"if (v > {hi}) {{",
        f"    v = {hi};",
        "}",
    ]


def _header_comment(template: CTemplate, p: str, source: str | None, sample_rate: float) -> str:
    if np.isfinite(template.max_step):
        slew = (
            f"  slew-rate limit {template.max_step:.9g} V per sample "
            f"({template.max_step * sample_rate:.9g} V/s at {sample_rate:.9g} Hz)"
        )
    else:
        slew = "  no slew-rate limit"
    period_us = 1e6 / sample_rate
    lines = [
        f"{p}: hysteresis compensator generated by hystcomp (do not edit; re-export instead).",
        "",
        f"Model: {template.kind}" + (f", from {source}" if source else ""),
        *template.summary,
        slew,
        "",
        "Units: x_ref in um (micrometres), output in V (piezo voltage).",
        "Build: any C99 compiler, e.g. cc -std=c99 -O2 -c " + f"{p}.c; no allocation, no",
        "libraries beyond <math.h>. Do not build with -ffast-math or -ffinite-math-only:",
        "they remove the isfinite() test that holds the output on a non-finite x_ref.",
        "",
        f"Use, for example from a {sample_rate / 1000:.6g} kHz timer interrupt:",
        "",
        f"    static {p}_state comp;",
        f"    void controller_init(void) {{ {p}_init(&comp); }}",
        f"    void timer_isr(void)   // every {period_us:.6g} us",
        "    {",
        "        double x_ref = next_reference_um();      // your reference, um",
        f"        double v = {p}_step(&comp, x_ref);",
        "        dac_write_volts(v);                      // your DAC, V",
        "    }",
    ]
    body = "\n".join(f" * {line}".rstrip() for line in lines)
    return f"/*\n{body}\n */"
