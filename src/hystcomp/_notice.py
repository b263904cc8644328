"""Report lines and warnings that name a remedy, with the remedy kept as data.

A library sentence that tells the user what to do next ("record a signal with turning points
across the range", "try another model family") names a function argument for a Python
caller and an option for the command line. A :class:`Notice` holds the sentence as a template
whose remedies are keys of a vocabulary: ``str(notice)`` words them the Python way
(:data:`PYTHON`), and a front end words them its own way with :meth:`Notice.worded`. The
library so holds no command-line text, and the command line no copy of the sentences.
"""

from __future__ import annotations

import string
from collections.abc import Mapping
from typing import Any, Self

__all__ = ["PYTHON", "Notice", "worded"]

#: The remedies as a Python caller names them; each is formatted with the notice's data.
PYTHON = {
    "excite_rich": "hystcomp.identify.excitation.excitation_signal('rich')",
    "excite_mpi": "excitation_signal('mpi')",
    "excite_dynamics": "excitation_signal('dynamics')",
    "excite_multiaxis": "hystcomp.identify.excitation.multiaxis_sequence",
    "transient": "the 'transient' argument",
    "model": "the model {others}",
    "initial_memory": "the 'initial_memory' parameter",
    "fs": "the sample rate",
    "columns": "the column mapping",
    "allow_extrapolation": "allow_extrapolation=True",
    "strict": "refused (strict=True)",
    "drop_strict": "pass strict=False",
    "method_exact": "method='exact'",
    "drop_method": "Leave out 'method'",
    "narrow": "narrow the output with voltage_range=({lo}, {hi})",
    "drop_dynamics": "Leave out the dynamics",
    "dynamics_option": "the dynamics",
    "identify_dynamics": "a LinearDynamics model (hystcomp.workflows.pair.identify_dynamics_record)",
    "pair_alone": "the hysteresis model alone (the pair's hysteresis)",
    "identify_pair": "hystcomp.workflows.pair.identify_pair_record",
    "slew": "The slew-rate limit",
    "give_fs": "give the sample rate",
    "excite_preisach": "excitation_signal('preisach')",
    "excite_pi": "excitation_signal('pi')",
    "excite_any": "hystcomp.identify.excitation.excitation_signal",
    "fit_lsq": "fit_method='least-squares'",
    "fit_rc": "fit_method='reversal-curves'",
    "zero_diagonal": "zero_diagonal=True",
    "clamp": "the compensator's voltage_range, as in Preisach.inverse(voltage_range=...)",
    "same_rate": "at the same sample rate",
    "columns_eg": "columns='{eg}'",
    "axis_columns": "columns={{'v1': 2, 'x1': 3, ...}}",
    "x_unit": "x_unit",
    "drop_x_unit": "Leave out x_unit",
    "fs_hz": "sample_rate=HZ",
    "rate_name": "sample_rate",
    "saved_by": "hystcomp.save_model",
    "export_model": "generate_c(model.inverse(), ...)",
    "not_read": "which is not read",
    "to_file": "Write it to a file",
    # an argument, ``{arg_NAME}`` (where the vocabulary has no ``arg_NAME`` of its own),
    # and the argument given the notice's ``value``, ``{set_NAME}``
    "arg_": "'{name}'",
    "set_": "{name}={value!r}",
}


def _keys(template: str) -> set[str]:
    return {name for _, name, _, _ in string.Formatter().parse(template) if name}


def _word(key: str, words: Mapping[str, str], data: Mapping[str, Any]) -> str:
    if key in words:
        return words[key].format(**data)
    name = key[4:]  # an argument (arg_NAME), or one with its value (set_NAME)
    arg = words.get(f"arg_{name}") or words["arg_"].format(name=name, dashed=name.replace("_", "-"))
    return (
        arg if key[:4] == "arg_" else words["set_"].format(arg=arg, name=name, value=data["value"])
    )


def _fill(template: str, words: Mapping[str, str], data: Mapping[str, Any]) -> str:
    keys = [k for k in _keys(template) if k not in data and (k in words or k[:4] in _ARGS)]
    return template.format(**data, **{k: _word(k, words, data) for k in keys})


_ARGS = ("arg_", "set_")


class Notice(str):
    """A sentence whose remedies are keys of a vocabulary, worded on demand.

    Parameters
    ----------
    template : str
        The sentence, with ``{key}`` where a remedy is named (a key of :data:`PYTHON`),
        ``{arg_NAME}`` where the argument NAME is, ``{set_NAME}`` where it is given the
        value ``data['value']``, and ``{name}`` for a value of ``data`` (which a remedy of the same
        key gives way to); no other braces.
    kind : str, optional
        What it is about (``'line'``, ``'coverage'``, ...), for a caller that sorts them.
    **data
        Values the template and the remedies are formatted with.

    Returns
    -------
    Notice
        A ``str``: the sentence in Python's words.

    Examples
    --------
    >>> note = Notice("try {model}.", kind="line", others="mpi")
    >>> str(note), note.worded({"model": "--model {others}"})
    ('try the model mpi.', 'try --model mpi.')
    """

    template: str
    kind: str
    data: dict[str, Any]

    def __new__(cls, template: str, kind: str = "", **data: Any) -> Self:
        self = super().__new__(cls, _fill(template, PYTHON, data))
        self.template, self.kind, self.data = template, kind, data
        return self

    def __reduce__(self):
        return (_rebuild, (self.template, self.kind, self.data))

    def worded(self, words: Mapping[str, str]) -> str:
        """The sentence with its remedies named by ``words`` (others the Python way).

        Parameters
        ----------
        words : mapping of str to str
            ``{key: words}``, each formatted with the notice's data.

        Returns
        -------
        str
        """
        return _fill(self.template, {**PYTHON, **words}, self.data)


def _rebuild(template: str, kind: str, data: dict[str, Any]) -> Notice:
    return Notice(template, kind, **data)


def worded(text: str, words: Mapping[str, str]) -> str:
    """``text`` in the vocabulary ``words`` if it is a :class:`Notice`, else unchanged.

    Parameters
    ----------
    text : str or Notice
        A sentence.
    words : mapping of str to str
        The vocabulary (see :meth:`Notice.worded`).

    Returns
    -------
    str
    """
    return text.worded(words) if isinstance(text, Notice) else str(text)
