"""The C template of the PI and MPI compensators, read from their packed operator chain.

The code follows the stages of :mod:`hystcomp._kernels.chain` (offset, dead-zones, plays,
dead-zones, offset), each emitted only if the chain has it, so that it exports whatever
the chain can express: the inverse PI (eqs. 24-26) is plays alone, the inverse MPI (eq. 23)
dead-zones then plays.
"""

from __future__ import annotations

from hystcomp._kernels import chain as ck
from hystcomp.codegen.c99 import CTemplate, c_double, c_table


def chain_template(compensator) -> CTemplate:
    """The :class:`~hystcomp.codegen.c99.CTemplate` of a PI or MPI :class:`Compensator`.

    Parameters
    ----------
    compensator : Compensator
        A PI or MPI model's ``inverse()``: plays, and for MPI the dead-zones of ``S^-1``.

    Returns
    -------
    CTemplate
        Its tables (thresholds, weights, initial states) and step.
    """
    c = ck.unpack_chain(compensator.packed)
    lo, hi = compensator.voltage_range
    n_pre, n_play, n_post = c.pre_r.size, c.play_r.size, c.post_r.size
    template = CTemplate(
        kind=_kind_text(compensator.kind),
        summary=_summary(c, compensator),
        low=lo,
        high=hi,
        max_step=c.max_step,
        initial_output=c.state[ck.STATE_LAST],
        locals=["double z;"] + (["int i;"] if n_pre > 1 or n_play or n_post > 1 else []),
    )
    if n_play:
        template.state_fields.append(f"double play[{n_play}]; /* play operator states */")
        template.reset_body += [
            "int i;",
            f"for (i = 0; i < {n_play}; i++) {{",
            "    s->play[i] = {p}_play_y0[i];",
            "}",
        ]
    template.step_body.append(_offset("z = x_ref", -c.in_offset, "reference offset, um"))
    if n_pre:
        _deadzones(template, "pre", c.pre_r, c.pre_w, "inverse saturation S^-1, eqs. 13-14")
    if n_play:
        template.tables += [
            c_table("{p}_play_r", c.play_r, "play thresholds r_i (eq. 24)"),
            c_table("{p}_play_w", c.play_w, "play weights w_i (eq. 25)"),
            c_table("{p}_play_y0", c.plays, "initial play states (eq. 26)"),
        ]
        template.step_body += [
            "",
            "/* NaN, +-inf or a huge x_ref (the plays' sum would overflow): hold, plays unmoved */",
            f"if (!(fabs(z) < {c_double(ck.PLAY_INPUT_LIMIT)})) {{",
            "    s->nonfinite_count++;",
            "    return s->last;",
            "}",
            "",
            "/* play operators, eq. 11, and their weighted sum, eq. 12 */",
            "{",
            "    double acc = 0.0;",
            f"    for (i = 0; i < {n_play}; i++) {{",
            "        double y = s->play[i];",
            "        double hi = z + {p}_play_r[i];",
            "        double lo = z - {p}_play_r[i];",
            "        if (y > hi) {",
            "            y = hi;",
            "        }",
            "        if (y < lo) {",
            "            y = lo;",
            "        }",
            "        s->play[i] = y;",
            "        acc += {p}_play_w[i] * y;",
            "    }",
            "    z = acc;",
            "}",
        ]
    if n_post:
        _deadzones(template, "post", c.post_r, c.post_w, "saturation S, eqs. 13-14")
    template.step_body += ["", _offset("v = z", c.out_offset, "voltage offset, V")]
    return template


def _deadzones(template: CTemplate, name: str, r, w, what: str) -> None:
    """One-sided dead-zones ``w_0 z + sum_j w_j max(z - r_j, 0)`` (``r_0 = 0``)."""
    if r.size > 1:  # r_0 = 0 is implied
        template.tables.append(c_table(f"{{p}}_{name}_r", r, f"{what}: thresholds"))
    template.tables.append(c_table(f"{{p}}_{name}_w", w, f"{what}: weights"))
    template.step_body += ["", f"/* {what} */", "{", f"    double acc = {{p}}_{name}_w[0] * z;"]
    if r.size > 1:
        template.step_body += [
            f"    for (i = 1; i < {r.size}; i++) {{",
            f"        if (z > {{p}}_{name}_r[i]) {{",
            f"            acc += {{p}}_{name}_w[i] * (z - {{p}}_{name}_r[i]);",
            "        }",
            "    }",
        ]
    template.step_body += ["    z = acc;", "}"]


def _offset(assignment: str, offset: float, what: str) -> str:
    if offset == 0.0:
        return f"{assignment};"
    sign = "-" if offset < 0 else "+"
    return f"{assignment} {sign} {c_double(abs(offset))}; /* {what} */"


def _kind_text(kind: str) -> str:
    return {
        "pi": "inverse Prandtl-Ishlinskii (PI) compensator, paper eqs. 24-26",
        "mpi": "inverse Modified Prandtl-Ishlinskii (MPI) compensator, paper eq. 23",
    }.get(kind, f"inverse {kind} compensator")


def _summary(c, compensator) -> list[str]:
    lo, hi = compensator.voltage_range
    lines = ["Parameters (the identified values are tables in the .c file):"]
    if c.pre_r.size:
        lines.append(f"  {c.pre_r.size} inverse dead-zones (thresholds in um)")
    if c.play_r.size:
        lines.append(f"  {c.play_r.size} play operators")
    if c.post_r.size:
        lines.append(f"  {c.post_r.size} dead-zones")
    lines.append(f"  reference offset {c.in_offset:.9g} um, voltage offset {c.out_offset:.9g} V")
    lines.append(f"  output clamped to [{lo:.9g}, {hi:.9g}] V")
    return lines
